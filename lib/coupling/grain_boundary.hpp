// Resolved SPH-DEM coupling (seed §2.3; DESIGN.md §1): every grain carries boundary particles,
// placed once in its body frame on the dp lattice where -depth < phi < 0, with their mDBC ghost
// nodes r_G = r_B - 2 phi grad phi and normals. Each step they are moved with the grain's pose
// (position, ghost node and normal rotated; velocity v + w x r), so the fluid sees a moving mDBC
// wall. The fluid force on a grain is the sum of m a over its boundary particles (the boundary
// slots' acceleration from compute_rates), and the torque the sum of (r - x_c) x m a.
//
// Boundary particles live in the solver's grain range [wall_begin + n_wall, size), with
// body = kGrainBodyBase - grain slot (so they never match a solid index) and global ids from
// first_id on: id - first_id indexes the table of (grain, body-frame point).
#pragma once

#include <cstdint>
#include <vector>

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
  // Poses every grain particle of ps from the bodies' current state.
  void place(ParticleSet<Host>& ps, const dem::DemSystem& sys) const;
  // The fluid force and torque (about the centroid) on every grain, from the grain slots' m a.
  void loads(const ParticleSet<Host>& ps, const dem::DemSystem& sys, std::vector<Vec3>& force,
             std::vector<Vec3>& torque) const;

  Index particle_count() const { return Index(owner_.size()); }
  // Per template: the boundary point count (reporting).
  const std::vector<GrainBoundaryShape>& shapes() const { return shapes_; }
  // Restart: the first grain particle id of a set written by append().
  void set_first_id(GlobalId id) { first_id_ = id; }

 private:
  std::vector<GrainBoundaryShape> shapes_;  // per template
  std::vector<std::uint32_t> owner_;        // per grain particle: body slot
  std::vector<std::uint32_t> point_;        // per grain particle: point of its template
  GlobalId first_id_ = 0;
  Real mass_ = 0, rho0_ = 1000;
};

}  // namespace sphdem
