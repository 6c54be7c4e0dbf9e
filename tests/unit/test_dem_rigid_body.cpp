// Unit tests of rigid-body integration (lib/dem/rigid_body.hpp; seed Eqs. 16-17).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dem/rigid_body.hpp"
#include "precision.hpp"

namespace sphdem::dem {
namespace {

using test::kFloatEps;
using test::tol;

struct SpinResult {
  double e_err = 0, l_err = 0, q_err = 0;  // max relative drifts
  double w_min[3] = {1e300, 1e300, 1e300};
};

// Torque-free body with I = (1, 2, 3), spun about principal axis `axis` at 5 rad/s with a 1e-3
// perturbation on the others, 1e4 steps of dt = 1e-3 (10 s, about 29 e-foldings of the
// intermediate-axis instability growth rate 5 sqrt(1/3) = 2.9/s).
SpinResult spin(int axis) {
  RigidBody b;
  b.inertia = Vec3(1, 2, 3);
  b.q = normalize(Quat{0.9, 0.1, -0.3, 0.2});
  b.w = Vec3(1e-3, 1e-3, 1e-3);
  b.w[axis] = 5;
  const Real e0 = kinetic_energy(b);
  const Vec3 l0 = angular_momentum(b);
  SpinResult r;
  for (int k = 0; k < 10000; ++k) {
    integrate_body(b, Vec3(), Vec3(), Vec3(), 1e-3);
    r.e_err = std::max(r.e_err, double(std::fabs(kinetic_energy(b) - e0) / e0));
    r.l_err = std::max(r.l_err, double(norm(angular_momentum(b) - l0) / norm(l0)));
    r.q_err = std::max(r.q_err, double(std::fabs(norm(b.q) - Real(1))));
    for (int d = 0; d < 3; ++d) r.w_min[d] = std::min(r.w_min[d], double(b.w[d]));
  }
  return r;
}

TEST(DemRigidBody, TorqueFreeConservesEnergyAndAngularMomentum) {
  // Float: the midpoint rule conserves E and L exactly in exact arithmetic, so what drifts is
  // round-off: each step rounds w (u = eps/2 per component, doubled in the quadratic energy) and
  // the orientation (quaternion product and normalisation, a few u, seen by the world L), <= ~4 u
  // = 2 eps of relative error per step, accumulated over the 10^4 steps. |q| is renormalised each
  // step: its error is that of one normalisation plus the check's norm, ~8 u = 4 eps.
  const double drift_tol = tol(1e-6, 10000 * 2 * kFloatEps);
  for (int axis = 0; axis < 3; ++axis) {
    const SpinResult r = spin(axis);
    EXPECT_LT(r.e_err, drift_tol) << "axis " << axis;
    EXPECT_LT(r.l_err, drift_tol) << "axis " << axis;
    EXPECT_LT(r.q_err, tol(1e-12, 4 * kFloatEps)) << "axis " << axis;
    std::printf("axis %d: max relative drift of energy %.2e, of world angular momentum %.2e\n",
                axis, r.e_err, r.l_err);
  }
}

TEST(DemRigidBody, IntermediateAxisIsUnstableOthersAreStable) {
  // Axis 2 (the intermediate moment) flips: w_y reverses sign; axes 1 and 3 hold their spin.
  const SpinResult mid = spin(1);
  EXPECT_LT(mid.w_min[1], -4.0) << "no flip about the intermediate axis";
  const SpinResult low = spin(0), high = spin(2);
  EXPECT_GT(low.w_min[0], 4.99);
  EXPECT_GT(high.w_min[2], 4.99);
}

TEST(DemRigidBody, ConstantTorqueAboutPrincipalAxis) {
  // I_z w_z' = T_z from rest; rotated body, torque given in the world frame along its z axis.
  RigidBody b;
  b.inertia = Vec3(2, 3, 4);
  b.q = from_axis_angle(Vec3(1, 1, 0), 0.7);
  const Vec3 axis_world = rotate(b.q, Vec3(0, 0, 1));
  const Real dt = 1e-4;
  const int n = 10000;
  for (int k = 0; k < n; ++k) integrate_body(b, Vec3(), 8 * axis_world, Vec3(), dt);
  // w = T t / I = 8 * 1 / 4 = 2 rad/s, angle = T t^2 / (2 I) = 1 rad.
  // Float: w_z is a sum of n equal increments dt T / I: the k-th partial sum (k/n) 2 rad/s is
  // rounded by at most u k 2/n (u = eps/2), in all u (n + 1) = (n + 1) eps / 2 of 2 rad/s at most;
  // the increment itself (the torque turned into the body frame, dt, the quotient) carries ~8 u,
  // the same in every step. w_x stays 0 but for the orientation's round-off: q takes a product
  // and a normalisation per step (<= ~4 u of angle), so after k steps the body z axis is off the
  // torque by <= 4 u k and T_x <= 8 N m * 4 u k; w_x <= sum_k dt T_x / I_x = dt 8 4 u n^2 / 2 / 2.
  EXPECT_NEAR(b.w.z, 2.0, tol(1e-9, ((n + 1) / 4.0 + 4) * kFloatEps * 2.0));
  EXPECT_NEAR(b.w.x, 0.0, tol(1e-9, dt * 8 * 2 * kFloatEps * double(n) * n / 4));
  const Vec3 ex =
      rotate(conjugate(from_axis_angle(Vec3(1, 1, 0), 0.7)), rotate(b.q, Vec3(1, 0, 0)));
  EXPECT_NEAR(std::atan2(ex.y, ex.x), 1.0, 2e-4);
}

TEST(DemRigidBody, FreeFallFixedAndPrescribed) {
  RigidBody b;
  b.mass = 2;
  const Real dt = 1e-4;
  const Vec3 g(0, 0, -9.81);
  const int n = 10000;
  for (int k = 0; k < n; ++k) integrate_body(b, Vec3(1, 0, 0), Vec3(), g, dt);  // F/m = 0.5
  // Float: v is a sum of n equal increments dt (F/m + g); the k-th partial sum, (k/n) of the
  // final v, is rounded by at most u (k/n) |v| (u = eps/2): u |v| (n + 1) / 2 = (n + 1) eps |v| / 4
  // in all, plus the increment's own rounding (dt, sum, product: ~2 u = eps of |v|).
  EXPECT_NEAR(b.v.z, -9.81, tol(1e-9, ((n + 1) / 4.0 + 1) * kFloatEps * 9.81));
  EXPECT_NEAR(b.v.x, 0.5, tol(1e-12, ((n + 1) / 4.0 + 1) * kFloatEps * 0.5));
  EXPECT_NEAR(b.x.z, -0.5 * 9.81, 1e-3 * 9.81);  // symplectic Euler: O(dt) in position
  RigidBody f;
  f.motion = Motion::kFixed;
  f.v = Vec3(1, 0, 0);
  integrate_body(f, Vec3(100, 0, 0), Vec3(0, 0, 100), g, 0.1);
  EXPECT_EQ(f.x.x, 0);
  RigidBody p;
  p.motion = Motion::kPrescribed;
  p.v = Vec3(0, 0, 0.04);  // a baffle lifted at 4 cm/s
  p.w = Vec3(0, 0, 1);
  const int steps = 100;
  for (int k = 0; k < steps; ++k) integrate_body(p, Vec3(1e6, 0, 0), Vec3(), g, 0.01);
  // Float: x as v above, (steps + 1) eps |x| / 4 + eps |x|. The angle: each step multiplies q by
  // the rotation of angle 0.01 (its sin and cos rounded) and renormalises, <= ~4 u = 2 eps of
  // angle per step.
  EXPECT_NEAR(p.x.z, 0.04, tol(1e-12, ((steps + 1) / 4.0 + 1) * kFloatEps * 0.04));
  EXPECT_NEAR(p.v.z, Real(0.04), 1e-15);  // the prescribed velocity is kept as given
  const Vec3 ex = rotate(p.q, Vec3(1, 0, 0));
  EXPECT_NEAR(std::atan2(ex.y, ex.x), 1.0, tol(1e-12, steps * 2 * kFloatEps));
  EXPECT_EQ(contact_mass(p), 0);
}

}  // namespace
}  // namespace sphdem::dem
