// Rigid-body state and time integration of DEM grains (seed §2.2, Eqs. 16-17).
//
//   m dv/dt = F + m g                                   (Eq. 16; F: contact + external forces)
//   d(I w)/dt = T                                       (Eq. 17, written in the body frame:)
//   I_b dw_b/dt = (I_b w_b) x w_b + T_b                 (Euler's equations, principal axes)
//   dq/dt = 1/2 q (0, w_b)                              (unit quaternion, body -> world)
//
// Scheme (one step of length dt, forces F, T evaluated before the step):
//   translation, symplectic Euler (= leapfrog with v at half steps):
//     v <- v + dt (F/m + g);   x <- x + dt v
//   rotation, implicit midpoint for Euler's equations in the body frame:
//     I_b (w+ - w) / dt = (I_b w_m) x w_m + T_b,   w_m = (w + w+)/2,   T_b = R(q)^T T
//   solved by fixed-point iteration to round-off, then the orientation is advanced by the Cayley
//   rotation of the same midpoint rate:
//     q <- q (1, dt w_m / 2) / |(1, dt w_m / 2)|
// Why: the implicit midpoint rule conserves every quadratic invariant of Euler's equations, so a
// torque-free body keeps its kinetic energy 1/2 w.I w and |I w| exactly (to the iteration
// tolerance). Moreover the midpoint update of the body angular momentum L_b = I_b w is exactly
// L_b+ = cay(-dt w_m) L_b, and the quaternion above applies cay(+dt w_m) to the body frame, so the
// world angular momentum R(q) L_b is conserved exactly too, and the integrator is time-reversible.
// (The Cayley rotation turns by 2 atan(|w_m| dt / 2) instead of |w_m| dt: an O(dt^3) phase error.)
#pragma once

#include <cmath>
#include <cstdint>

#include "core/hd.hpp"
#include "core/quat.hpp"
#include "core/types.hpp"

namespace sphdem::dem {

// How a body moves.
enum class Motion : std::int32_t {
  kFree = 0,        // integrated from forces (Eqs. 16-17)
  kFixed = 1,       // never moves; infinite mass for contacts
  kPrescribed = 2,  // moves with its stored v and w (set by the caller), ignores forces
};

struct RigidBody {
  Vec3 x;                 // centroid, world frame
  Vec3 v;                 // centroid velocity, world frame
  Quat q;                 // unit quaternion, body -> world
  Vec3 w;                 // angular velocity, BODY frame (principal axes)
  Real mass = 1;          // kg
  Vec3 inertia{1, 1, 1};  // principal moments of inertia, body frame, kg m^2
  Motion motion = Motion::kFree;
  std::int32_t shape = 0;  // index of the grain template
  GlobalId id = 0;         // global id: contact history and output are keyed by it
};

// Angular velocity in the world frame, R(q) w_b.
SPHDEM_HD inline Vec3 world_omega(const RigidBody& b) {
  return rotate(b.q, b.w);
}

// Velocity of the material point at world position p.
SPHDEM_HD inline Vec3 point_velocity(const RigidBody& b, const Vec3& p) {
  return b.v + cross(world_omega(b), p - b.x);
}

// Angular momentum about the centroid in the world frame, R(q) I_b w_b.
SPHDEM_HD inline Vec3 angular_momentum(const RigidBody& b) {
  return rotate(b.q, Vec3(b.inertia.x * b.w.x, b.inertia.y * b.w.y, b.inertia.z * b.w.z));
}

// Kinetic energy 1/2 m v^2 + 1/2 w.I w.
SPHDEM_HD inline Real kinetic_energy(const RigidBody& b) {
  return Real(0.5) * b.mass * norm2(b.v) +
         Real(0.5) * (b.inertia.x * b.w.x * b.w.x + b.inertia.y * b.w.y * b.w.y +
                      b.inertia.z * b.w.z * b.w.z);
}

// Mass seen by a contact: infinite (returned as 0, meaning "a wall") for fixed and prescribed
// bodies.
SPHDEM_HD inline Real contact_mass(const RigidBody& b) {
  return b.motion == Motion::kFree ? b.mass : Real(0);
}

// Inverse of the mass that a contact at world point p with unit normal n sees on this body:
// 1/m + u.I_b^-1 u with u = R(q)^T ((p - x) x n), the rotation about the centroid included
// (a force at a lever arm moves the point more than the centroid). 0 for fixed and prescribed
// bodies (infinite mass).
SPHDEM_HD inline Real inverse_point_mass(const RigidBody& b, const Vec3& p, const Vec3& n) {
  if (b.motion != Motion::kFree) return Real(0);
  const Vec3 u = rotate(conjugate(b.q), cross(p - b.x, n));
  return Real(1) / b.mass + u.x * u.x / b.inertia.x + u.y * u.y / b.inertia.y +
         u.z * u.z / b.inertia.z;
}

// Implicit-midpoint update of the body-frame angular velocity (see header). torque_body: the
// torque in the body frame. Returns the midpoint rate w_m; writes w+ into *w.
SPHDEM_HD inline Vec3 euler_midpoint(Vec3* w, const Vec3& inertia, const Vec3& torque_body,
                                     Real dt) {
  const Vec3 w0 = *w;
  Vec3 w1 = w0;
  for (int it = 0; it < 100; ++it) {
    const Vec3 wm = Real(0.5) * (w0 + w1);
    const Vec3 lm(inertia.x * wm.x, inertia.y * wm.y, inertia.z * wm.z);
    const Vec3 rhs = cross(lm, wm) + torque_body;
    const Vec3 wn(w0.x + dt * rhs.x / inertia.x, w0.y + dt * rhs.y / inertia.y,
                  w0.z + dt * rhs.z / inertia.z);
    const Real change = norm2(wn - w1);
    w1 = wn;
    const Real scale = norm2(w1) + norm2(w0);
    if (change <= Real(1e-30) * scale || change == Real(0)) break;
  }
  *w = w1;
  return Real(0.5) * (w0 + w1);
}

// Rotates the orientation by the Cayley rotation of the body-frame rate w_m over dt.
SPHDEM_HD inline Quat advance_orientation(const Quat& q, const Vec3& w_m, Real dt) {
  const Real h = Real(0.5) * dt;
  const Quat dq = normalize(Quat{Real(1), h * w_m.x, h * w_m.y, h * w_m.z});
  return normalize(multiply(q, dq));
}

// One step of length dt under world-frame force f and torque t (about the centroid) and gravity g.
// Fixed bodies do not move; prescribed bodies move with their own v and (body-frame) w.
SPHDEM_HD inline void integrate_body(RigidBody& b, const Vec3& f, const Vec3& t, const Vec3& g,
                                     Real dt) {
  if (b.motion == Motion::kFixed) return;
  if (b.motion == Motion::kFree) {
    b.v += dt * (f / b.mass + g);  // Eq. 16
    const Vec3 tb = rotate(conjugate(b.q), t);
    const Vec3 wm = euler_midpoint(&b.w, b.inertia, tb, dt);  // Eq. 17
    b.x += dt * b.v;
    b.q = advance_orientation(b.q, wm, dt);
    return;
  }
  // Prescribed: constant rates over the step, rotation by the exact angle |w| dt.
  b.x += dt * b.v;
  b.q = normalize(multiply(b.q, from_axis_angle(b.w, norm(b.w) * dt)));
}

}  // namespace sphdem::dem
