// Resolved SPH-DEM coupling (seed §2.3; DESIGN.md §1): every grain carries boundary particles,
// placed once in its body frame on the dp lattice where -depth < phi < 0, with their mDBC ghost
// nodes r_G = r_B - 2 phi grad phi and normals. Each step they are moved with the grain's pose
// (position, ghost node and normal rotated; velocity v + w x r), so the fluid sees a moving mDBC
// wall. The fluid force on a grain is the sum of m a over its boundary particles (the boundary
// slots' acceleration from compute_rates), and the torque the sum of (r - x_c) x m a.
//
// Boundary particles live in the solver's grain range [wall_begin + n_wall, size), with
// body = kGrainBodyBase - grain slot (so they never match a solid index) and global ids from
// first_id on, grain by grain: grain g's point k has id first_id + first_point(g) + k.
//
// On many ranks (DESIGN.md §5, "Grains") no rank holds every grain particle: at each neighbour
// rebuild the solver asks generate() for the particles of the grains that reach its box, and
// place() and loads() work on whichever grain slots a rank holds (loads() then gives this rank's
// share of each grain's force and torque, summed over ranks by the caller).
#pragma once

#include <cstdint>
#include <vector>

#include "coupling/grain_pose.hpp"
#include "dem/dem_system.hpp"
#include "solver/particles.hpp"

namespace sphdem {

struct GrainBoundaryShape {
  std::vector<Vec3> pos, ghost, normal;  // body frame
};

// Lattice points (i + 1/2) dp of the template's grid box with -depth < phi < 0.
GrainBoundaryShape make_grain_boundary(const dem::GrainTemplate& t, Real dp, Real depth);

class GrainCoupling {
 public:
  GrainCoupling(const dem::DemSystem& sys, Real dp, Real depth, Real rho0, int dim);

  // Removes the fluid inside any grain (phi < 0) and appends the grain boundary particles (ids
  // after every existing id) posed from `sys`. Returns the fluid removed.
  Index append(ParticleSet<Host>& ps, const dem::DemSystem& sys);
  // As above, the ids from first_id on (a set that holds only some of the scene's walls: the
  // scene's particle count).
  Index append(ParticleSet<Host>& ps, const dem::DemSystem& sys, GlobalId first_id);
  // Poses the grain slots of ps from the bodies' current state. every: ps must hold every grain
  // particle (one rank); otherwise any subset (many ranks).
  void place(ParticleSet<Host>& ps, const dem::DemSystem& sys, bool every = true) const;
  // The fluid force and torque (about the centroid) on every grain, from the grain slots' m a.
  // mine (many ranks): one flag per slot from wall_begin(); only the slots this rank owns count,
  // and the caller sums the result over ranks.
  void loads(const ParticleSet<Host>& ps, const dem::DemSystem& sys, std::vector<Vec3>& force,
             std::vector<Vec3>& torque, const std::uint8_t* mine = nullptr) const;
  // The posed grain particles (every field set, as append(): a set of n_grain slots only) of the
  // grains whose boundary points or ghost nodes may lie in the box [lo, hi] (a bounding-sphere
  // test: some returned points lie outside it).
  ParticleSet<Host> generate(const dem::DemSystem& sys, const Vec3& lo, const Vec3& hi) const;

  Index particle_count() const { return Index(first_point_.back()); }
  // Per template: the boundary point count (reporting).
  const std::vector<GrainBoundaryShape>& shapes() const { return shapes_; }
  // Restart: the first grain particle id of a set written by append().
  void set_first_id(GlobalId id) {
    first_id_ = id;
    table_.first_id = id;
  }
  // The body-frame points for posing in the solver's execution space (SolverBase::pose_grains).
  const GrainPointTable& table() const { return table_; }

 private:
  // The grain and template point of grain particle k (id - first_id).
  void locate(std::size_t k, std::size_t& grain, std::size_t& point) const;
  // Grain particle slot i of ps: position, ghost node, normal and velocity from `body`.
  void pose(ParticleSet<Host>& ps, std::size_t i, const dem::RigidBody& body,
            std::size_t point) const;

  std::vector<GrainBoundaryShape> shapes_;  // per template
  std::vector<Real> reach_;                 // per template: max |point| and |ghost node|
  std::vector<Index> first_point_;          // per grain, and the total: a prefix sum
  GrainPointTable table_;
  GlobalId first_id_ = 0;
  Real mass_ = 0, rho0_ = 1000;
};

}  // namespace sphdem
