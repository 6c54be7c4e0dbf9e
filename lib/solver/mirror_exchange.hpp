// A symmetry plane on one rank (scene key `symmetry`, core/symmetry.hpp) as an Exchange: its halo
// is the mirror image of the owned fluid within `width` of the plane, refreshed every step like a
// rank's halo (positions and velocities reflected, the SPS stress's off-diagonal signs flipped,
// scalars copied). The fluid near the plane thus sees a complete kernel support, and the plane
// acts as a free-slip wall without boundary particles. Every wall is kept and owned; no
// migration, no wall plan, reductions are identities.
//
// The width covers the kernel support 2h plus the skin, and also reaches 2h plus half the skin
// past the deepest kept wall particle and mDBC ghost node (both of a thin solid's) on the
// mirrored side: a wall particle just across the plane interpolates its state from mirror fluid
// around its ghost nodes, which stand still while the fluid moves up to skin/2 between rebuilds.
#pragma once

#include <cstring>
#include <type_traits>
#include <vector>

#include "core/symmetry.hpp"
#include "solver/exchange.hpp"

namespace sphdem {

// The mirror image of one value of the ParticleSet field `name` (for_each_field's names): the
// point fields (pos, ghost, ghost_alt) reflect as points, the other Vec3 fields as vectors, and
// scalars are copied.
template <class T>
T mirror_field_value(const SymmetryPlane& plane, const char* name, const T& x) {
  if constexpr (std::is_same_v<T, Vec3>) {
    const bool point =
        !std::strcmp(name, "pos") || !std::strcmp(name, "ghost") || !std::strcmp(name, "ghost_alt");
    return point ? plane.reflect_point(x) : plane.reflect_vector(x);
  } else {
    return x;
  }
}

class MirrorExchange final : public Exchange {
 public:
  // width: the halo width on the fluid's side of the plane (2h + skin); support: 2h (so the
  // skin is width - support).
  MirrorExchange(const SymmetryPlane& plane, Real width, Real support);

  int rank() const override { return 0; }
  int size() const override { return 1; }
  bool owns(const Vec3&) const override { return true; }
  void migrate(ParticleSet<Host>&) override {}
  bool rebalance(ParticleSet<Host>&) override { return false; }
  void build_halo(ParticleSet<Host>& ps) override;
  Index halo_count() const override { return Index(source_.size()); }
  void bcast(const Real* owned, Real* halo) override;
  void bcast(const Vec3* owned, Vec3* halo) override;
  void bcast_positions(const Vec3* owned, Vec3* halo) override;
  void bcast_field(const Vec3* owned, Vec3* halo, HaloField kind) override;
  // Keeps every wall; records how far the walls and, by_ghost, both of each wall's mDBC ghost
  // nodes reach across the plane.
  std::vector<std::uint8_t> keep_walls(const Vec3* pos, const Vec3* ghost, const Vec3* ghost_alt,
                                       Index n, bool by_ghost) const override;
  void build_wall_plan(const GlobalId*, const std::uint8_t*, Index) override {}
  void wall_slots(std::vector<Index>& roots, std::vector<Index>& leaves) const override {
    roots.clear();
    leaves.clear();
  }
  void wall_bcast(const Real*, Real*) override {}
  void wall_bcast(const Vec3*, Vec3*) override {}
  void wall_reduce(const Real*, Real*) override {}
  void wall_reduce(const Vec3*, Vec3*) override {}
  void sum(Real*, Index) override {}
  void max(Real*, Index) override {}
  std::int64_t sum(std::int64_t v) override { return v; }

  const SymmetryPlane& plane() const { return plane_; }
  // The halo width in use (grows with the walls' ghost nodes).
  Real width() const;

 private:
  SymmetryPlane plane_;
  Real width_, support_;
  mutable Real ghost_reach_ = 0;  // deepest kept ghost node across the plane
  std::vector<Index> source_;     // owned slot (at the build) of each mirror copy
};

}  // namespace sphdem
