// Posing grain boundary particles (seed §2.3; DESIGN.md §1): a body-frame point p, its mDBC ghost
// node g and normal n, carried by a rigid body to the world frame. Written once, SPHDEM_HD: the
// coupling's host code (GrainCoupling::place, generate) and the solver's execution space
// (SolverBase::pose_grains, CPU and CUDA) both call pose_grain_point.
#pragma once

#include <cstdint>
#include <vector>

#include "core/hd.hpp"
#include "core/types.hpp"
#include "dem/rigid_body.hpp"

namespace sphdem {

// World-frame position, ghost node, normal and velocity (v + w x r) of body-frame point p.
SPHDEM_HD inline void pose_grain_point(const dem::RigidBody& b, const Vec3& p, const Vec3& g,
                                       const Vec3& n, Vec3& pos, Vec3& ghost, Vec3& normal,
                                       Vec3& vel) {
  pos = b.x + rotate(b.q, p);
  ghost = b.x + rotate(b.q, g);
  normal = rotate(b.q, n);
  vel = dem::point_velocity(b, pos);
}

// Every template's body-frame boundary points in flat arrays, for an execution space. A grain
// slot with global id `id` and body field kGrainBodyBase - grain is point
// id - first_id - grain_first[grain] of template bodies[grain].shape, stored at
// template_first[shape] + that point.
struct GrainPointTable {
  std::vector<Vec3> pos, ghost, normal;
  std::vector<std::uint32_t> template_first;  // per template
  std::vector<std::uint32_t> grain_first;     // per grain: id - first_id of its first point
  GlobalId first_id = 0;
};

}  // namespace sphdem
