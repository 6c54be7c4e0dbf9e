// Chung & Ooi (2011) DEM benchmarks (Granular Matter 13:643-656) with the sphere fast path of
// DemSystem. Reference data: tests/data/reference/dem_chung_ooi2011/ and FORMULAS.md §7-8.
//   Test 1: elastic normal impact of two identical spheres (Hertz): peak force, max overlap and
//           contact duration within 2 % of the analytic Hertz values.
//   Test 2: elastic normal impact of a sphere on a rigid plane: the same.
//   Test 3: normal impact with damping: restitution out = restitution in, within 2 %.
//   Test 4: oblique impact with friction (Hertz-Mindlin): tangential restitution and spin against
//           the published DEM curves.
//   Test 7: two spheres with equal and opposite spins (no slip at the contact): spins and
//           tangential velocity unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "dem/dem_system.hpp"

namespace sphdem::dem {
namespace {

const std::string kDir = std::string(SPHDEM_REFERENCE_DATA) + "/dem_chung_ooi2011/";

// Rows of a CSV (comments and the header skipped), as strings.
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  std::vector<std::vector<std::string>> rows;
  std::string line;
  bool header = true;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<std::string> r;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) r.push_back(cell);
    rows.push_back(r);
  }
  return rows;
}

struct Material {
  Real young, poisson, rho;
};

ContactModel hertz(const Material& m, Real e, Real mu) {
  ContactModel c;
  c.law = NormalLaw::kHertz;
  c.young = m.young;
  c.poisson = m.poisson;
  c.restitution = e;
  c.mu = mu;
  c.wall_young = 0;  // rigid wall
  return c;
}

struct Impact {
  Real f_max = 0, d_max = 0, t_contact = 0;
  Vec3 v_after, w_after;  // of the first body
  Vec3 v2_after, w2_after;
};

// Two spheres (wall = false) or one sphere and the plane z = 0 (wall = true), integrated with
// dt = t_c / steps_per_contact until they separate.
Impact collide(const Material& mat, Real radius, bool wall, Vec3 v1, Vec3 w1, Vec3 v2, Vec3 w2,
               Real e, Real mu, int steps_per_contact, NormalLaw law = NormalLaw::kHertz,
               Real kn = 0) {
  DemParams p;
  p.gravity = Vec3(0, 0, 0);
  p.grain_grain = hertz(mat, e, mu);
  p.grain_wall = hertz(mat, e, mu);
  p.grain_grain.law = p.grain_wall.law = law;
  p.grain_grain.kn = p.grain_wall.kn = kn;
  DemSystem sys(p);
  const int s = sys.add_template(GrainTemplate::sphere(radius));
  // First contact at t = 0: the spheres (or sphere and wall) just touch.
  Real m_eff, tc;
  if (wall) {
    sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
    sys.add_body(s, mat.rho, Vec3(0, 0, radius), Quat{}, v1, w1);
  } else {
    sys.add_body(s, mat.rho, Vec3(-radius, 0, 0), Quat{}, v1, w1);
    sys.add_body(s, mat.rho, Vec3(radius, 0, 0), Quat{}, v2, w2);
  }
  const Real m = sys.bodies()[0].mass;
  m_eff = wall ? m : m / 2;
  const Real vn = wall ? -v1.z : (v1.x - v2.x);
  if (law == NormalLaw::kHertz) {
    const Real e_star = wall ? effective_young(mat.young, mat.poisson, 0, 0)
                             : effective_young(mat.young, mat.poisson, mat.young, mat.poisson);
    const Real r_star = wall ? radius : radius / 2;
    tc = hertz_contact_time(e_star, r_star, m_eff, vn);
  } else {
    tc = contact_time(m_eff, kn);
  }
  const Real dt = tc / steps_per_contact;
  Impact out;
  Real d_prev = 0, t_prev = 0;
  bool touched = false;
  for (int k = 0; k < 20 * steps_per_contact; ++k) {
    sys.step(dt);
    out.f_max = std::max(out.f_max, norm(sys.force(0)));
    const auto& b = sys.bodies();
    const Real d = wall ? radius - b[0].x.z : 2 * radius - norm(b[1].x - b[0].x);
    if (d > 0) touched = true;
    out.d_max = std::max(out.d_max, d);
    if (touched && d <= 0) {
      out.t_contact = t_prev + dt * d_prev / (d_prev - d);
      // One more step so the separating forces are done.
      sys.step(dt);
      break;
    }
    d_prev = d;
    t_prev = sys.time();
  }
  out.v_after = sys.bodies()[0].v;
  out.w_after = world_omega(sys.bodies()[0]);
  if (!wall) {
    out.v2_after = sys.bodies()[1].v;
    out.w2_after = world_omega(sys.bodies()[1]);
  }
  return out;
}

double rel(double a, double b) {
  return std::fabs(a - b) / std::fabs(b);
}

// ---- Tests 1 and 2 -------------------------------------------------------------------------

TEST(DemChungOoi, Tests1And2ElasticHertzImpacts) {
  const auto rows = read_csv(kDir + "chung_ooi_tests_1_2_hertz_analytic.csv");
  ASSERT_EQ(rows.size(), 4u);
  // Digitised peaks of the published force-time curves, per material.
  std::map<std::string, double> digitised_peak;
  for (const char* f :
       {"test1_two_spheres_force_time_digitised.csv", "test2_sphere_wall_force_time_digitised.csv"})
    for (const auto& r : read_csv(kDir + f))
      digitised_peak[r[0]] = std::max(digitised_peak[r[0]], std::stod(r[2]) * 1e3);
  for (const auto& r : rows) {
    const bool wall = r[0].find("wall") != std::string::npos;
    const Material mat{Real(std::stod(r[2])), Real(std::stod(r[3])), Real(std::stod(r[4]))};
    const Real radius = std::stod(r[5]), v = std::stod(r[7]);
    const Impact im = wall ? collide(mat, radius, true, Vec3(0, 0, -v), {}, {}, {}, 1, 0, 1000)
                           : collide(mat, radius, false, Vec3(v / 2, 0, 0), {}, Vec3(-v / 2, 0, 0),
                                     {}, 1, 0, 1000);
    const double d_ref = std::stod(r[11]), f_ref = std::stod(r[12]), t_ref = std::stod(r[13]);
    std::printf(
        "%s %s: F_max %.5g N (ref %.5g, err %.2e), delta_max %.5g m (ref %.5g, err %.2e), "
        "t_c %.5g s (ref %.5g, err %.2e), digitised peak %.5g N\n",
        r[0].c_str(), r[1].c_str(), im.f_max, f_ref, rel(im.f_max, f_ref), im.d_max, d_ref,
        rel(im.d_max, d_ref), im.t_contact, t_ref, rel(im.t_contact, t_ref), digitised_peak[r[1]]);
    EXPECT_LT(rel(im.f_max, f_ref), 0.02) << r[1];
    EXPECT_LT(rel(im.d_max, d_ref), 0.02) << r[1];
    EXPECT_LT(rel(im.t_contact, t_ref), 0.02) << r[1];
    EXPECT_LT(rel(im.f_max, digitised_peak[r[1]]), 0.02) << r[1];
    // Elastic: the rebound speed equals the approach speed.
    const double v_out = wall ? im.v_after.z : im.v2_after.x - im.v_after.x;
    EXPECT_LT(rel(v_out, v), 0.01) << r[1];
  }
}

// ---- Test 3 --------------------------------------------------------------------------------

TEST(DemChungOoi, Test3RestitutionOutEqualsIn) {
  // Alumina sphere (R = 2.5 mm, E = 380 GPa, nu = 0.23, rho = 4000) on a rigid plane at 3.9 m/s.
  const Material alumina{3.8e11, 0.23, 4000};
  for (Real e : {0.2, 0.4, 0.6, 0.8, 1.0}) {
    const Impact im = collide(alumina, 0.0025, true, Vec3(0, 0, -3.9), {}, {}, {}, e, 0, 500);
    const double e_out = im.v_after.z / 3.9;
    std::printf("Hertz + damping, e_in %.2f: e_out %.5f (err %.2e)\n", e, e_out, rel(e_out, e));
    EXPECT_LT(rel(e_out, e), 0.02) << "e = " << e;
  }
  // The linear spring-dashpot law (Eq. 19 + damping) between two spheres.
  for (Real e : {0.1, 0.3, 0.5, 0.9}) {
    const Impact im = collide(alumina, 0.0025, false, Vec3(1, 0, 0), {}, Vec3(-1, 0, 0), {}, e, 0,
                              200, NormalLaw::kLinear, 1e6);
    const double e_out = (im.v2_after.x - im.v_after.x) / 2;
    std::printf("linear, e_in %.2f: e_out %.5f (err %.2e)\n", e, e_out, rel(e_out, e));
    EXPECT_LT(rel(e_out, e), 0.02) << "e = " << e;
  }
}

// The same linear impact at the steps the DEM stability map sweeps: dem.dt_factor 0.5, 1 (the
// default), 5, 10 and about 17 (100, 50, 10, 5 and 3 steps per contact). Printed for
// docs/SPEED_ACCURACY.md: a run at a coarse step completes, and this is how far off its impacts
// are. Measured at the default step: e_out/e - 1 = +2.3 % (e 0.3), +0.4 % (0.5), 0.0 % (0.9);
// the dashpot sees a velocity predicted from the last step's acceleration, which misses the jump
// at first touch (first order in dt, largest for strong damping). Asserted: within 2 % at 100
// steps per contact, and the error at 3 steps per contact is far beyond it (the map's unstable
// side).
TEST(DemChungOoi, RestitutionAgainstStepsPerContact) {
  const Material glass{7e10, 0.25, 2500};
  for (Real e : {0.3, 0.5, 0.9}) {
    for (int spc : {100, 50, 10, 5, 3}) {
      const Impact im = collide(glass, 0.004, false, Vec3(1, 0, 0), {}, Vec3(-1, 0, 0), {}, e, 0,
                                spc, NormalLaw::kLinear, 2e4);
      const double e_out = (im.v2_after.x - im.v_after.x) / 2;
      std::printf(
          "linear, e_in %.2f, %3d steps per contact (dt_factor %4.1f): e_out %.4f "
          "(err %+.1f %%)\n",
          e, spc, 50.0 / spc, e_out, 100 * (e_out / e - 1));
      if (spc == 100) {
        EXPECT_LT(rel(e_out, e), 0.02) << "e = " << e;
      }
      if (spc == 3) {
        EXPECT_GT(rel(e_out, e), 0.1) << "e = " << e;
      }
    }
  }
}

// ---- Test 4 --------------------------------------------------------------------------------

TEST(DemChungOoi, Test4ObliqueImpactWithFriction) {
  // R = 2.5 mm on a rigid plane at 3.9 m/s, mu = 0.092, e_n = 0.98 (Chung & Ooi; Yade Test4.py).
  const std::map<std::string, Material> mats{{"Al_oxide", {3.8e11, 0.23, 4000}},
                                             {"Al_alloy", {7.0e10, 0.33, 2700}}};
  const auto rows = read_csv(kDir + "test4_oblique_impact_kratos_paperdata.csv");
  double worst_et = 0, worst_w = 0;
  int n = 0;
  for (const auto& r : rows) {
    std::string series = r[1];
    if (r[0] == "et")
      series = series == "Oxide" ? "Al_oxide" : (series == "Alloy" ? "Al_alloy" : "");
    if (!mats.count(series)) continue;
    const double theta = std::stod(r[2]) * kPi / 180, ref = std::stod(r[3]);
    const Real v = 3.9;
    const Vec3 v0(v * std::sin(theta), 0, -v * std::cos(theta));
    const Impact im = collide(mats.at(series), 0.0025, true, v0, {}, {}, {}, 0.98, 0.092, 400);
    if (r[0] == "et") {
      const double et = im.v_after.x / v0.x;
      const double err = std::fabs(et - ref);
      std::printf("Test 4 %s theta %5.1f: e_t %.4f (ref %.4f)\n", series.c_str(), std::stod(r[2]),
                  et, ref);
      worst_et = std::max(worst_et, err);
      EXPECT_LT(err, 0.03) << series << " theta " << r[2];
    } else {
      // The published spin is negative in their frame; here the ball moves along +x on the plane
      // z = 0, so friction spins it about +y.
      const double w = -im.w_after.y;
      const double err = std::fabs(w - ref) / 617.0;  // relative to the largest spin of the curve
      std::printf("Test 4 %s theta %5.1f: omega %.2f rad/s (ref %.2f)\n", series.c_str(),
                  std::stod(r[2]), w, ref);
      worst_w = std::max(worst_w, err);
      EXPECT_LT(err, 0.03) << series << " theta " << r[2];
    }
    ++n;
  }
  EXPECT_EQ(n, 52);
  std::printf("Test 4: worst |e_t - ref| %.4f, worst |omega - ref|/617 %.4f\n", worst_et, worst_w);
}

// ---- Test 7 --------------------------------------------------------------------------------

TEST(DemChungOoi, Test7EqualAndOppositeSpinsDoNotSlip) {
  // Al alloy spheres R = 0.1 m approaching at 0.2 m/s each, mu = 0.4, e_n = 0.5; spins chosen so
  // the contact points move identically: R w / v_n = x of the reference table.
  const Material al{7.0e10, 0.33, 2700};
  const auto rows = read_csv(kDir + "test7_test8_expected.csv");
  int n = 0;
  for (const auto& r : rows) {
    if (r[0] != "test7" || r[1] != "graph2") continue;
    const double x = std::stod(r[3]);
    const Real radius = 0.1, vn = 0.2;
    const Real w = Real(x) * vn / radius;
    const Impact im = collide(al, radius, false, Vec3(vn, 0, 0), Vec3(0, 0, w), Vec3(-vn, 0, 0),
                              Vec3(0, 0, -w), 0.5, 0.4, 400);
    // Post-collision tangential velocity 0 and spin unchanged (graph1 y = 0, graph2 y = x).
    EXPECT_NEAR(im.v_after.y / vn, 0.0, 1e-9) << "x = " << x;
    EXPECT_NEAR(im.w_after.z * radius / vn, std::stod(r[4]), 1e-9 * x) << "x = " << x;
    EXPECT_NEAR(im.w2_after.z * radius / vn, -std::stod(r[4]), 1e-9 * x) << "x = " << x;
    EXPECT_NEAR(-(im.v2_after.x - im.v_after.x) / (2 * vn), -0.5, 0.01) << "e_n";
    ++n;
  }
  EXPECT_EQ(n, 17);
  // Control: equal spins make the contact points slide against each other, and then the
  // comparator above does see a tangential velocity.
  const Impact slip = collide(al, 0.1, false, Vec3(0.2, 0, 0), Vec3(0, 0, 2), Vec3(-0.2, 0, 0),
                              Vec3(0, 0, 2), 0.5, 0.4, 400);
  EXPECT_GT(std::fabs(slip.v_after.y) / 0.2, 1e-3);
}

}  // namespace
}  // namespace sphdem::dem
