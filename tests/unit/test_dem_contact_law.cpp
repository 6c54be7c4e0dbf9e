// Unit tests of the DEM contact laws (lib/dem/contact_law.hpp; seed Eqs. 19-20, FORMULAS.md §7-8).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "dem/contact_law.hpp"
#include "dem/rigid_body.hpp"
#include "precision.hpp"

namespace sphdem::dem {
namespace {

using test::kFloatEps;
using test::tol;

std::vector<std::vector<double>> read_numeric_csv(const std::string& path) {
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  std::vector<std::vector<double>> rows;
  std::string line;
  bool header = true;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<double> r;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

// A linear spring-dashpot contact integrated like DemSystem::step: symplectic Euler, with the
// dashpot fed the velocity predicted to the force time, v + a_prev dt/2. Returns the restitution
// coefficient and the contact duration (overlap > 0).
void bounce_linear(Real e, Real m, Real kn, Real dt, Real* e_out, Real* tc_out) {
  const Real cn = linear_damping(e, m, kn);
  const Real v0 = 1;
  Real d = 0, v = v0;  // v = d' (approach speed), starts at first touch
  Real t = 0;
  Real d_prev = 0, t_prev = 0, a_prev = 0;
  for (int k = 0; k < 10000000; ++k) {
    const Real f = linear_normal_force(kn, cn, d, -(v + Real(0.5) * dt * a_prev));  // v_n = -d'
    a_prev = -f / m;
    v += dt * a_prev;
    d_prev = d;
    t_prev = t;
    d += dt * v;
    t += dt;
    if (d <= 0) break;
  }
  *e_out = -v / v0;
  *tc_out = t_prev + dt * d_prev / (d_prev - d);  // linear interpolation of the exit
}

TEST(DemContactLaw, DampingRatioMatchesReferenceTable) {
  const auto rows = read_numeric_csv(std::string(SPHDEM_REFERENCE_DATA) +
                                     "/analytic/linear_spring_dashpot_restitution.csv");
  ASSERT_GE(rows.size(), 10u);
  for (const auto& r : rows) {
    const Real zeta = damping_ratio_from_restitution(Real(r[0]));
    EXPECT_NEAR(zeta, r[1], 2e-6 * std::max(1.0, r[1])) << "e = " << r[0];
    // t_c sqrt(k/m) = pi / sqrt(1 - zeta^2)
    EXPECT_NEAR(kPi / std::sqrt(1 - zeta * zeta), r[4], 1e-4 * r[4]) << "e = " << r[0];
  }
  EXPECT_EQ(damping_ratio_from_restitution(1), 0);
  EXPECT_EQ(damping_ratio_from_restitution(0), 1);
}

TEST(DemContactLaw, LinearBounceGivesTargetRestitutionAndDuration) {
  const auto rows = read_numeric_csv(std::string(SPHDEM_REFERENCE_DATA) +
                                     "/analytic/linear_spring_dashpot_restitution.csv");
  const Real m = 0.02, kn = 3e4;
  const Real dt = dem_time_step(m, kn) / 4;  // t_c/200
  for (const auto& r : rows) {
    Real e_out, tc;
    bounce_linear(Real(r[0]), m, kn, dt, &e_out, &tc);
    EXPECT_NEAR(e_out, r[2], 0.01 * r[2]) << "e = " << r[0];
    EXPECT_NEAR(tc / std::sqrt(m / kn), r[3], 0.01 * r[3]) << "e = " << r[0];
  }
}

TEST(DemContactLaw, ContactTimeAndStep) {
  const Real m = 0.5, kn = 2e5;
  EXPECT_DOUBLE_EQ(contact_time(m, kn), kPi * std::sqrt(m / kn));
  EXPECT_DOUBLE_EQ(dem_time_step(m, kn), kPi * std::sqrt(m / kn) / 50);
  EXPECT_DOUBLE_EQ(effective_mass(2, 2), 1);
  EXPECT_DOUBLE_EQ(effective_mass(2, 0), 2);  // wall
  EXPECT_REAL_EQ(effective_radius(0.01, 0.01), 0.005);
  EXPECT_DOUBLE_EQ(effective_radius(0.1, 0), Real(0.1));  // plane: the radius itself
}

TEST(DemContactLaw, StiffnessFromYoungForTable2) {
  // Table 2: E = 6e8 Pa, nu = 0.3, grains of 16 mm: E* = E / (2 (1 - nu^2)), R* = 4 mm.
  const Real e_star = effective_young(6e8, 0.3, 6e8, 0.3);
  EXPECT_NEAR(e_star, 6e8 / (2 * 0.91), 1e-6 * e_star);
  EXPECT_NEAR(effective_young(7e10, 0.3, 0, 0), 7.69231e10, 1e-5 * 7.69231e10);  // Chung & Ooi
  const Real kn = linear_stiffness_from_young(e_star, effective_radius(0.008, 0.008), 1e-2);
  EXPECT_NEAR(kn, 1.758e5, 0.001 * 1.758e5);
  // Consistency: the Hertz force at the reference overlap equals kn times that overlap.
  const Real r_star = 0.004, dref = 1e-2 * r_star;
  // Float: both sides are products of ~8 rounded factors (E*, R*, sqrt, 4/3, dref, pow): <= ~8 eps
  // relative.
  EXPECT_NEAR(hertz_constant(e_star, r_star) * std::pow(dref, 1.5), kn * dref,
              tol(1e-9, 8 * kFloatEps) * kn * dref);
}

TEST(DemContactLaw, HertzMatchesChungOoiAnalyticTable) {
  // Glass, Test 1: E* = 2.5e10, R* = 0.005, m* = 0.00586431, v = 20 -> 274.113 um, 10696.9 N.
  const Real d = hertz_max_overlap(2.5e10, 0.005, 0.00586431, 20);
  EXPECT_NEAR(d, 0.000274113, 1e-5 * 0.000274113);
  EXPECT_NEAR(hertz_normal_force(hertz_constant(2.5e10, 0.005), 0, 0, d, 0), 10696.9, 0.5);
  EXPECT_NEAR(hertz_contact_time(2.5e10, 0.005, 0.00586431, 20), 4.03395e-05, 1e-3 * 4.03395e-05);
}

TEST(DemContactLaw, HertzDampingInverts) {
  EXPECT_EQ(hertz_damping_alpha(1), 0);
  EXPECT_NEAR(hertz_restitution(0), 1.0, 1e-6);
  Real prev = 0;
  for (Real e : {0.9, 0.7, 0.5, 0.3, 0.1}) {
    const Real a = hertz_damping_alpha(e);
    EXPECT_GT(a, prev) << "alpha must grow as e falls";
    prev = a;
    EXPECT_NEAR(hertz_restitution(a), e, 1e-6) << "e = " << e;
  }
}

TEST(DemContactLaw, TangentialSpringSticksThenSlidesAtTheCap) {
  const Vec3 n(0, 0, 1);
  const Real kt = 1000, mu = 0.5, fn = 10, dt = 1e-3;
  Vec3 s;
  // Stick: force -kt s, s = v t.
  Vec3 f = tangential_force(s, n, Vec3(1, 0, 0), dt, kt, 0, mu, fn);
  EXPECT_NEAR(s.x, Real(1e-3), 1e-15);  // 1 m/s times dt exactly
  EXPECT_NEAR(f.x, -1.0, 1e-12);
  EXPECT_NEAR(f.y, 0, 1e-15);
  // The normal part of v_rel does not load the spring.
  f = tangential_force(s, n, Vec3(0, 0, 5), dt, kt, 0, mu, fn);
  EXPECT_NEAR(f.x, -1.0, 1e-12);
  // Slide: a large displacement is capped at mu fn and the spring rescaled to match.
  f = tangential_force(s, n, Vec3(0, 100, 0), dt, kt, 0, mu, fn);
  EXPECT_NEAR(norm(f), mu * fn, 1e-12);
  EXPECT_LT(f.y, 0);
  // Float: s = -f / kt with f rescaled to the cap and its norm taken again: ~8 roundings of a
  // value mu fn / kt, 4 eps of it.
  EXPECT_NEAR(norm(s), mu * fn / kt, tol(1e-15, 4 * kFloatEps * mu * fn / kt));
  EXPECT_NEAR(s.y, -f.y / kt, 1e-15);
  // A rotated contact plane: the spring is projected and keeps its length.
  Vec3 s2(1e-3, 0, 0);
  const Vec3 n2 = Vec3(0.1, 0, 1) / norm(Vec3(0.1, 0, 1));
  tangential_force(s2, n2, Vec3(0, 0, 0), dt, kt, 0, mu, fn);
  // Float: the projection s - (s.n) n, its rescaling by |s| / |s_p| and the checks' dot and norm
  // each take a few roundings of values of size |s| = 1e-3 (|n| = 1): 4 eps of 1e-3.
  EXPECT_NEAR(dot(s2, n2), 0, tol(1e-15, 4 * kFloatEps * 1e-3));
  EXPECT_NEAR(norm(s2), 1e-3, tol(1e-15, 4 * kFloatEps * 1e-3));
  // A tensile normal force (the dashpot's pull at the end of a damped contact) carries no
  // friction: the force and the spring are zero, however the contact slides.
  Vec3 s3(1e-3, 0, 0);
  const Vec3 f3 = tangential_force(s3, n, Vec3(1, 0, 0), dt, kt, 0, mu, -fn);
  EXPECT_EQ(norm(f3), 0);
  EXPECT_EQ(norm(s3), 0);
}

TEST(DemContactLaw, ContactForcePushesMasterOutAndDampsApproach) {
  PairLaw p;
  p.kn = 1e4;
  p.cn = 10;
  p.kt = 5e3;
  p.mu = 0.3;
  p.m_eff = 1;
  Vec3 s;
  Real fn;
  // Approaching (v_n < 0): the dashpot adds to the spring.
  const Vec3 f = contact_force(p, 1e-3, Vec3(0, 0, 1), Vec3(0, 0, -1), 1e-4, s, &fn);
  EXPECT_NEAR(fn, 10 + 10, 1e-12);
  EXPECT_NEAR(f.z, 20, 1e-12);
  // Hertz law through the same entry point.
  p.law = NormalLaw::kHertz;
  p.k_hertz = hertz_constant(1e9, 0.01);
  p.g_star = 1e8;
  p.r_star = 0.01;
  Vec3 s2;
  const Vec3 fh = contact_force(p, 1e-4, Vec3(1, 0, 0), Vec3(0, 0, 0), 1e-4, s2, &fn);
  // Float: K d sqrt(d) with d = 1e-4 rounded (1.5 u in d^1.5), sqrt, two products and the sum
  // with the zero tangential force: <= ~4 u = 2 eps relative; 4 eps.
  EXPECT_NEAR(fh.x, p.k_hertz * 1e-6, tol(1e-9, 4 * kFloatEps) * p.k_hertz * 1e-6);
}

// A contact point at a lever arm sees a lighter body: for a rod of mass m and length L
// (I = m L^2 / 12 about its middle) pushed at its end across its axis, 1/m_pt = 1/m + (L/2)^2/I
// = 4/m. Through the centroid, or along the rod, it sees m. The dashpot of the point then scales
// so the point's own oscillator keeps the restitution coefficient: c = 2 zeta sqrt(m_pt k_n).
TEST(DemContactLaw, PointMassIncludesRotationAndRescalesTheDashpot) {
  RigidBody rod;
  rod.mass = 2;
  const Real len = 0.3;
  rod.inertia = Vec3(1e-6, rod.mass * len * len / 12, rod.mass * len * len / 12);  // along x
  rod.q = normalize(Quat{0.8, 0.2, -0.4, 0.1});
  const Vec3 axis = rotate(rod.q, Vec3(1, 0, 0));
  const Vec3 across = rotate(rod.q, Vec3(0, 0, 1));
  rod.x = Vec3(1, 2, 3);
  const Vec3 tip = rod.x + Real(0.5) * len * axis;
  // Float: the lever arm tip - x (0.15 m) is the difference of positions of size |tip| ~ 3.7 m,
  // and tip is rounded to u |tip| per coordinate (u = eps/2): the arm carries a relative error
  // of up to sqrt(3) u |tip| / 0.15 ~ 18 eps, doubled in the rotational part u^2 / I = 3 / m;
  // plus a few eps of the result for the rest of the arithmetic.
  const double arm_err = std::sqrt(3.0) * 0.5 * kFloatEps * norm(tip) / (0.5 * len);
  EXPECT_NEAR(inverse_point_mass(rod, tip, across), 4 / rod.mass,
              tol(1e-12, 2 * arm_err * 3 / rod.mass + 8 * kFloatEps * 4 / rod.mass));
  EXPECT_NEAR(inverse_point_mass(rod, tip, axis), 1 / rod.mass, 1e-12);
  EXPECT_NEAR(inverse_point_mass(rod, rod.x, across), 1 / rod.mass, 1e-12);
  rod.motion = Motion::kFixed;
  EXPECT_EQ(inverse_point_mass(rod, tip, across), 0);

  PairLaw p;
  p.kn = 800;
  p.m_eff = 1e-3;
  p.cn = linear_damping(0.3, p.m_eff, p.kn);
  p.kt = 600;
  p.ct = linear_damping(0.3, p.m_eff, p.kt);
  const PairLaw q = at_point_mass(p, 0.25e-3);
  EXPECT_NEAR(q.cn, linear_damping(0.3, 0.25e-3, p.kn), 1e-12 * p.cn);
  EXPECT_NEAR(q.ct, linear_damping(0.3, 0.25e-3, p.kt), 1e-12 * p.ct);
  EXPECT_EQ(q.m_eff, Real(0.25e-3));
  EXPECT_EQ(q.kn, p.kn);
  // An infinite or unknown point mass keeps the law.
  EXPECT_EQ(at_point_mass(p, Real(1) / Real(0)).cn, p.cn);
  EXPECT_EQ(at_point_mass(p, 0).cn, p.cn);
}

}  // namespace
}  // namespace sphdem::dem
