// Shared helpers for the MPI decomposition tests: a deterministic global particle set that every
// rank can regenerate, chunks of it as ParticleSets, and collective assertions.
#pragma once

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "decomposition/domain_decomposition.hpp"
#include "neighbor/cell_grid.hpp"
#include "solver/particles.hpp"

namespace sphdem::mpitest {

inline MPI_Comm comm() {
  return MPI_COMM_WORLD;
}
inline int rank() {
  int r = 0;
  MPI_Comm_rank(comm(), &r);
  return r;
}
inline int size() {
  int s = 1;
  MPI_Comm_size(comm(), &s);
  return s;
}

// True on every rank iff true on all ranks: assertions that all ranks agree on.
inline bool all_ranks(bool ok) {
  int v = ok ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, MPI_LAND, comm());
  return v != 0;
}

inline std::int64_t sum_ranks(std::int64_t v) {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT64_T, MPI_SUM, comm());
  return v;
}

// A global particle set, the same on every rank (fixed seed, fixed generator).
struct GlobalSet {
  std::vector<Vec3> pos;
  std::vector<Real> mass, f;
  std::size_t size() const { return pos.size(); }
};

// Uniform in [lo, hi) (y = 0 in 2D); `warp` maps each uniform coordinate u in [0, 1) before
// scaling (identity by default), for skewed sets.
template <class Warp>
GlobalSet make_global(std::size_t n, unsigned seed, int dim, Vec3 lo, Vec3 hi, Warp warp) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  GlobalSet g;
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 x;
    for (int k = 0; k < 3; ++k) x[k] = lo[k] + Real(warp(u(rng), k)) * (hi[k] - lo[k]);
    if (dim == 2) x.y = 0;
    for (int k = 0; k < 3; ++k)
      if (x[k] >= hi[k]) x[k] = lo[k];  // guard the rounding of the scaling
    g.pos.push_back(x);
    g.mass.push_back(Real(0.5 + u(rng)));
    g.f.push_back(Real(u(rng) * 2 - 1));
  }
  return g;
}
inline GlobalSet make_global(std::size_t n, unsigned seed, int dim, Vec3 lo, Vec3 hi) {
  return make_global(n, seed, dim, lo, hi, [](double v, int) { return v; });
}

// Values of the fields other than pos/mass/f (press), derived from the id so that any copy can
// be checked anywhere.
inline Vec3 vel_of(GlobalId id) {
  return Vec3(Real(id) * 1e-3, -Real(id) * 2e-3, Real(id % 97));
}
inline Real rho_of(GlobalId id) {
  return Real(1000) + Real(id % 1013) * Real(0.25);
}

// Sets every field of slot i from the global set entry `id`.
inline void set_particle(ParticleSet<Host>& ps, Index i, const GlobalSet& g, GlobalId id) {
  const std::size_t s = std::size_t(i);
  ps.id[s] = id;
  ps.pos[s] = g.pos[id];
  ps.vel[s] = vel_of(id);
  ps.rho[s] = rho_of(id);
  ps.mass[s] = g.mass[id];
  ps.press[s] = g.f[id];
  ps.acc[s] = Vec3(1, 2, Real(id));
  ps.drho[s] = -Real(id);
  ps.vel_prev[s] = vel_of(id) * Real(0.5);
  ps.rho_prev[s] = rho_of(id) - 1;
  ps.ghost[s] = Vec3();
  ps.normal[s] = Vec3();
  ps.vel_bc[s] = Vec3();
  ps.body[s] = -1;
}

// Whether every field of slot i matches entry `id` (positions: shifted by `shift`).
inline bool particle_matches(const ParticleSet<Host>& ps, Index i, const GlobalSet& g,
                             Vec3 shift = Vec3()) {
  const std::size_t s = std::size_t(i);
  const GlobalId id = ps.id[s];
  if (id >= g.size()) return false;
  const Vec3 p = g.pos[id] + shift;
  auto eq = [](const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
  return eq(ps.pos[s], p) && eq(ps.vel[s], vel_of(id)) && ps.rho[s] == rho_of(id) &&
         ps.mass[s] == g.mass[id] && ps.press[s] == g.f[id] &&
         eq(ps.acc[s], Vec3(1, 2, Real(id))) && ps.drho[s] == -Real(id) &&
         eq(ps.vel_prev[s], vel_of(id) * Real(0.5)) && ps.rho_prev[s] == rho_of(id) - 1 &&
         ps.body[s] == -1;
}

// The ids [first, last) of g as owned fluid particles, followed by `n_wall` wall slots
// (ids from 1e9, body 0) that migration must leave in place.
inline ParticleSet<Host> make_set(const GlobalSet& g, GlobalId first, GlobalId last,
                                  Index n_wall = 0) {
  ParticleSet<Host> ps;
  ps.n_fluid = Index(last - first);
  ps.n_wall = n_wall;
  ps.resize(ps.size());
  for (GlobalId id = first; id < last; ++id) set_particle(ps, Index(id - first), g, id);
  for (Index w = 0; w < n_wall; ++w) {
    const std::size_t s = std::size_t(ps.n_fluid + w);
    ps.id[s] = GlobalId(1000000000) + GlobalId(w);
    ps.pos[s] = Vec3(Real(w), 0, 0);
    ps.mass[s] = 7;
    ps.body[s] = 0;
  }
  return ps;
}

// This rank's share of ids when every rank reads a contiguous slice (as a restart does).
inline ParticleSet<Host> make_slice(const GlobalSet& g, Index n_wall = 0) {
  const std::size_t n = g.size(), r = std::size_t(rank()), s = std::size_t(size());
  return make_set(g, GlobalId(n * r / s), GlobalId(n * (r + 1) / s), n_wall);
}

inline CellGrid unit_grid(int dim, Real cell, bool px = false, bool py = false, bool pz = false) {
  const bool per[3] = {px, py, pz};
  return make_cell_grid(dim, Vec3(0, 0, 0), Vec3(1, 1, 1), cell, per);
}

// The process grids the tests run on: along x, along y, along z, and PETSc's choice.
inline std::vector<std::array<int, 3>> line_layouts(int dim) {
  const int s = size();
  std::vector<std::array<int, 3>> v = {{s, 1, 1}, {1, 1, s}, {0, 0, 0}};
  if (dim == 3) v.insert(v.begin() + 1, std::array<int, 3>{1, s, 1});
  return v;
}

inline std::string layout_name(const std::array<int, 3>& p) {
  if (p[0] == 0 && p[1] == 0 && p[2] == 0) return "auto";
  return std::to_string(p[0]) + "x" + std::to_string(p[1]) + "x" + std::to_string(p[2]);
}

// (id, value) pairs of the owned range, gathered on rank 0 (empty elsewhere), sorted by id.
template <class T>
std::vector<std::pair<GlobalId, T>> gather_by_id(const ParticleSet<Host>& ps,
                                                 const std::vector<T>& values) {
  static_assert(std::is_trivially_copyable<T>::value, "plain values only");
  const int n = int(ps.n_fluid);
  std::vector<std::pair<GlobalId, T>> mine(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    mine[std::size_t(i)] = {ps.id[std::size_t(i)], values[std::size_t(i)]};
  const int bytes = n * int(sizeof(mine[0]));
  std::vector<int> counts(static_cast<std::size_t>(size())), displs(std::size_t(size()), 0);
  MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm());
  int total = 0;
  if (rank() == 0)
    for (std::size_t r = 0; r < counts.size(); ++r) {
      displs[r] = total;
      total += counts[r];
    }
  std::vector<std::pair<GlobalId, T>> all(std::size_t(total) / sizeof(mine[0]));
  MPI_Gatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0,
              comm());
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return all;
}

}  // namespace sphdem::mpitest
