// Slit-type barriers (seed §4.1, Fig. 17): wall placement, the solids, the effective opening
// ratio, and the run-up at the barrier.
#pragma once

#include <vector>

#include "scene/scene.hpp"
#include "solver/particles.hpp"

namespace sphdem {

struct BarrierWall {
  Vec3 center;     // centre of the wall's footprint, on the floor
  Real angle = 0;  // rotation about +z, radians
};

// Sets layout and angle from a preset name (P00, P30, P45, V30, V45); false if unknown.
bool apply_barrier_preset(Barrier& b, const std::string& preset);

// The walls in y order (barrier_1 first).
std::vector<BarrierWall> barrier_walls(const Barrier& b);

// The walls as box solids named barrier_1 .. barrier_n.
std::vector<Solid> barrier_solids(const Barrier& b);

// Effective opening ratio: the part of the channel width [y_lo, y_hi] not covered by the walls'
// projections on the cross-channel (y) axis (union of the footprints' shadows, so overlapping
// walls are not counted twice), over the channel width.
Real barrier_opening_ratio(const Barrier& b);

// The opening as the particle lattice resolves it (3D): of the lattice columns (i + 1/2) dp
// across the channel's width, those that hold no boundary particle of a barrier wall (over the
// whole row and height), and of the gaps between the walls' shadows (barrier_opening_ratio's,
// the channel's sides included) those that hold no such open column: fluid cannot pass there.
// is_wall: per solid index (ParticleSet::body), whether it is a barrier wall.
struct LatticeOpening {
  Index columns = 0, open = 0;
  int gaps = 0, closed_gaps = 0;
  Real ratio() const { return columns > 0 ? Real(open) / Real(columns) : Real(0); }
};
LatticeOpening barrier_lattice_opening(const Barrier& b, const ParticleSet<Host>& ps,
                                       const std::vector<bool>& is_wall, Real dp);

// Run-up: the highest fluid elevation (z above the floor, the bed-normal height in a channel
// along x) near the barrier, over fluid particles from runup_band upstream of the first wall to
// the last wall's downstream face that have at least 6 fluid neighbours within 2h (a lone splash
// droplet does not count). Returns the particle's z + dp/2 - floor_z, or 0 if there is none.
struct Runup {
  Real height = 0;
  Vec3 where;
};
Runup barrier_runup(const Barrier& b, const ParticleSet<Host>& ps, Real h2, Real dp);

// What the barrier holds back: fluid mass upstream of the row's upstream-most face and
// downstream of it (fluid that left the domain is in neither), and the grains whose boundary
// particles' centroid lies upstream or downstream of that line.
struct Trap {
  Real fluid_upstream = 0, fluid_downstream = 0;
  int grains_upstream = 0, grains_downstream = 0;
};
Trap barrier_trap(const Barrier& b, const ParticleSet<Host>& ps);

}  // namespace sphdem
