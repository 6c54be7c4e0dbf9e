// Particle storage: structure of arrays, one buffer per field, typed by execution space
// (DESIGN.md §4). The same field names are used in memory, HDF5 and VTK output.
//
// Slot layout on a rank:
//   [0, n_fluid)                       owned fluid particles
//   [n_fluid, n_fluid + n_halo)         halo copies of other ranks' fluid (empty on one rank)
//   [fluid_end(), fluid_end() + n_wall) fixed-wall boundary particles
//   [..., + n_grain)                    grain boundary particles
// Every particle carries a 64-bit global id; compare, sort and restart by id, never by slot.
#pragma once

#include <algorithm>
#include <type_traits>
#include <vector>

#include <cstdint>
#include <string>

#include "core/exec.hpp"
#include "core/types.hpp"

namespace sphdem {

// Raw pointers to every field, passed by value into kernels.
struct ParticleView {
  Index n = 0;  // all slots
  GlobalId* id = nullptr;
  Vec3* pos = nullptr;
  Vec3* vel = nullptr;
  Real* rho = nullptr;
  Real* mass = nullptr;
  Real* press = nullptr;
  Vec3* acc = nullptr;           // dv/dt of the current step
  Real* drho = nullptr;          // drho/dt of the current step
  Vec3* vel_prev = nullptr;      // Verlet: velocity at the previous step (n-1)
  Real* rho_prev = nullptr;      // Verlet: density at the previous step (n-1)
  Vec3* ghost = nullptr;         // boundary: mDBC ghost node; fluid: unused
  Vec3* ghost_alt = nullptr;     // boundary: ghost node through the solid's other face when the
                                 // solid is thin (both faces within the kernel), else = ghost
  Vec3* normal = nullptr;        // boundary: outward unit normal of the solid; fluid: unused
  Vec3* vel_bc = nullptr;        // boundary: mDBC velocity seen by the viscous term; fluid: unused
  std::int32_t* body = nullptr;  // boundary: solid index; fluid: -1
  // Per-step scratch owned by the solver (not stored, permuted or checkpointed): rebuilt from the
  // velocity field before each force pass when the rheology or SPS needs them.
  Real* visc = nullptr;   // fluid: effective dynamic viscosity mu_eff (Pa s)
  Vec3* sps_d = nullptr;  // fluid: SPS tau/rho, diagonal (xx, yy, zz)
  Vec3* sps_o = nullptr;  // fluid: SPS tau/rho, off-diagonal (xy, xz, yz)
};

// The body field of grain g's boundary particles is kGrainBodyBase - g. The solver keeps grain
// slots after the walls (grains_last), but sets read from files or gathered from ranks may mix
// them: this field, not the slot, tells them apart.
constexpr std::int32_t kGrainBodyBase = -2;
SPHDEM_HD inline bool is_grain_body(std::int32_t body) {
  return body <= kGrainBodyBase;
}

template <class Space>
struct ParticleSet {
  Index n_fluid = 0, n_halo = 0, n_wall = 0, n_grain = 0;

  Buffer<GlobalId, Space> id;
  Buffer<Vec3, Space> pos, vel, acc, vel_prev, ghost, ghost_alt, normal, vel_bc;
  Buffer<Real, Space> rho, mass, press, drho, rho_prev;
  Buffer<std::int32_t, Space> body;  // fluid -1; wall: solid index; grain g: kGrainBodyBase - g

  Index fluid_end() const { return n_fluid + n_halo; }
  Index wall_begin() const { return fluid_end(); }
  Index size() const { return n_fluid + n_halo + n_wall + n_grain; }

  // Calls f(name, buffer) for every field, in a fixed order (I/O, copies and permutation).
  template <class F>
  void for_each_field(F&& f) {
    f("id", id);
    f("pos", pos);
    f("vel", vel);
    f("rho", rho);
    f("mass", mass);
    f("press", press);
    f("acc", acc);
    f("drho", drho);
    f("vel_prev", vel_prev);
    f("rho_prev", rho_prev);
    f("ghost", ghost);
    f("ghost_alt", ghost_alt);
    f("normal", normal);
    f("vel_bc", vel_bc);
    f("body", body);
  }

  void resize(Index n) {
    for_each_field([n](const char*, auto& b) { b.resize(std::size_t(n)); });
  }

  ParticleView view() {
    ParticleView v;
    v.n = size();
    v.id = id.data();
    v.pos = pos.data();
    v.vel = vel.data();
    v.rho = rho.data();
    v.mass = mass.data();
    v.press = press.data();
    v.acc = acc.data();
    v.drho = drho.data();
    v.vel_prev = vel_prev.data();
    v.rho_prev = rho_prev.data();
    v.ghost = ghost.data();
    v.ghost_alt = ghost_alt.data();
    v.normal = normal.data();
    v.vel_bc = vel_bc.data();
    v.body = body.data();
    return v;
  }
};

// Moves the grain slots of a host set's boundary range (told apart by their body field,
// wherever they lie in it) to its end in global-id order, the walls keeping their order, and sets
// n_wall and n_grain.
template <class Set>
void grains_last(Set& ps) {
  const Index wb = ps.wall_begin(), n = ps.size();
  std::vector<Index> walls, grains;
  for (Index i = wb; i < n; ++i)
    (is_grain_body(ps.body[std::size_t(i)]) ? grains : walls).push_back(i);
  if (grains.empty() && ps.n_grain == 0) return;
  std::sort(grains.begin(), grains.end(),
            [&](Index a, Index b) { return ps.id[std::size_t(a)] < ps.id[std::size_t(b)]; });
  std::vector<Index> perm = walls;
  perm.insert(perm.end(), grains.begin(), grains.end());
  ps.for_each_field([&](const char*, auto& b) {
    auto& v = b.vec();
    std::vector<std::decay_t<decltype(v[0])>> t(perm.size());
    for (std::size_t j = 0; j < perm.size(); ++j) t[j] = v[std::size_t(perm[j])];
    std::copy(t.begin(), t.end(), v.begin() + wb);
  });
  ps.n_wall = Index(walls.size());
  ps.n_grain = Index(grains.size());
}

}  // namespace sphdem
