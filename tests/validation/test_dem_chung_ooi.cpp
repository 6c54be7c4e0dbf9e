// Chung & Ooi (2011) DEM benchmarks (Granular Matter 13:643-656) with the sphere fast path of
// DemSystem. Reference data: tests/data/reference/dem_chung_ooi2011/ and FORMULAS.md §7-8.
//   Test 1: elastic normal impact of two identical spheres (Hertz): peak force, max overlap and
//           contact duration within 2 % of the analytic Hertz values.
//   Test 2: elastic normal impact of a sphere on a rigid plane: the same.
//   Test 3: normal impact with damping: restitution out = restitution in, within 2 %.
//   Test 4: oblique impact with friction (Hertz-Mindlin): tangential restitution and spin against
//           the published DEM curves.
//   Tests 5, 6, 8: oblique impacts at a constant normal speed with a tangential velocity (5) or a
//           spin (6: on a plane, 8: on a larger fixed sphere): the rigid-body limits of gross
//           sliding and the digitised curves; below the sliding threshold, what every model obeys.
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

ContactModel hertz(const Material& m, Real e, Real mu, bool tangential_damping = false) {
  ContactModel c;
  c.law = NormalLaw::kHertz;
  c.young = m.young;
  c.poisson = m.poisson;
  c.restitution = e;
  c.mu = mu;
  c.wall_young = 0;  // rigid wall
  c.tangential_damping = tangential_damping;
  return c;
}

struct Impact {
  Real f_max = 0, d_max = 0, t_contact = 0;
  Vec3 v_after, w_after;  // of the first body
  Vec3 v2_after, w2_after;
};

// Two spheres (wall = false) or one sphere and the plane z = 0 (wall = true), integrated with
// dt = t_c / steps_per_contact until they separate. The second sphere has radius radius2 (0: the
// first's) and motion motion2 (kFixed: infinite mass, it never moves).
Impact collide(const Material& mat, Real radius, bool wall, Vec3 v1, Vec3 w1, Vec3 v2, Vec3 w2,
               Real e, Real mu, int steps_per_contact, NormalLaw law = NormalLaw::kHertz,
               Real kn = 0, Real radius2 = 0, Motion motion2 = Motion::kFree,
               bool tangential_damping = false) {
  if (!(radius2 > 0)) radius2 = radius;
  DemParams p;
  p.gravity = Vec3(0, 0, 0);
  p.grain_grain = hertz(mat, e, mu, tangential_damping);
  p.grain_wall = hertz(mat, e, mu, tangential_damping);
  p.grain_grain.law = p.grain_wall.law = law;
  p.grain_grain.kn = p.grain_wall.kn = kn;
  DemSystem sys(p);
  const int s = sys.add_template(GrainTemplate::sphere(radius));
  const int s2 = radius2 == radius ? s : sys.add_template(GrainTemplate::sphere(radius2));
  // First contact at t = 0: the spheres (or sphere and wall) just touch.
  Real m_eff, tc;
  if (wall) {
    sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
    sys.add_body(s, mat.rho, Vec3(0, 0, radius), Quat{}, v1, w1);
  } else {
    sys.add_body(s, mat.rho, Vec3(-radius, 0, 0), Quat{}, v1, w1);
    sys.add_body(s2, mat.rho, Vec3(radius2, 0, 0), Quat{}, v2, w2, motion2);
  }
  const Real m = sys.bodies()[0].mass;
  m_eff = wall || motion2 == Motion::kFixed ? m : effective_mass(m, sys.bodies()[1].mass);
  const Real vn = wall ? -v1.z : (v1.x - v2.x);
  if (law == NormalLaw::kHertz) {
    const Real e_star = wall ? effective_young(mat.young, mat.poisson, 0, 0)
                             : effective_young(mat.young, mat.poisson, mat.young, mat.poisson);
    const Real r_star = wall ? radius : effective_radius(radius, radius2);
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
    const Real d = wall ? radius - b[0].x.z : radius + radius2 - norm(b[1].x - b[0].x);
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

// ---- Tests 5, 6 and 8: oblique impacts, normalised ---------------------------------------------
// The quantities are those of the Kratos DEMApplication benchmarks that the digitised curves come
// from (DEM_benchmarks_class.py, Benchmark5/6/8): Vst is the tangential velocity of the sphere's
// contact point (centre velocity plus w x r), Vcn the normal approach speed, primes after the
// impact.
//   Test 5: x = Vst/(mu Vcn), graph1 y = Vst'/(mu Vcn'), graph2 y = R w'/(mu Vcn) (sign: negative
//           when the spin opposes the slip).
//   Tests 6, 8: graph1 x = 3.5 mu (1 + e) Vcn / Vst (the inverse of a normalised incident angle),
//           y = beta = -Vst'/Vst; graph2 x = Vst/Vcn, y = Vst'/Vcn'.
// Rigid-body impulses give these curves exactly in gross sliding (Coulomb friction for the whole
// contact): a solid sphere's contact point changes speed by 3.5 J_t/m, and J_t = mu J_n with
// J_n = m (1 + e) Vcn, so sliding lasts the whole contact while Vst >= 3.5 mu (1 + e) Vcn, and then
//   Test 5 (e = 1): Vst'/(mu Vcn') = x - 7,  R w'/(mu Vcn) = -5;
//   Tests 6, 8: beta = x - 1 (x <= 1), Vst'/Vcn' = (x - 3.5 mu (1 + e)) / e.
// Those points are asserted against both the analytic limit and the digitised curves. Below the
// threshold (stick and micro-slip) the result depends on the tangential compliance model, and the
// published curves disagree with one another (Test 5: FEM near 0, DEM codes -0.8 x at small x);
// sphdem's values are printed for docs/VALIDATION.md and held only to what every model obeys: the
// rigid-body link between the spin and the contact point's velocity, no gain in tangential
// speed, the spin bounded by its sliding value and growing with the incident angle.

// Linear interpolation of one digitised series at x (the nearest end outside it).
double interpolate(const std::vector<std::pair<double, double>>& xy, double x) {
  if (xy.empty()) return std::nan("");
  if (x <= xy.front().first) return xy.front().second;
  for (std::size_t i = 1; i < xy.size(); ++i)
    if (x <= xy[i].first) {
      const double t = (x - xy[i - 1].first) / (xy[i].first - xy[i - 1].first);
      return xy[i - 1].second + t * (xy[i].second - xy[i - 1].second);
    }
  return xy.back().second;
}

// The digitised series of one file: (graph, series) -> points in file order. Test 7/8's file has a
// leading "test" column, selected by `test` (empty: no such column).
std::map<std::pair<std::string, std::string>, std::vector<std::pair<double, double>>> series_of(
    const std::string& file, const std::string& test = "") {
  std::map<std::pair<std::string, std::string>, std::vector<std::pair<double, double>>> out;
  for (const auto& r : read_csv(kDir + file)) {
    const std::size_t o = test.empty() ? 0 : 1;
    if (!test.empty() && r[0] != test) continue;
    out[{r[o], r[o + 1]}].push_back({std::stod(r[o + 2]), std::stod(r[o + 3])});
  }
  return out;
}

TEST(DemChungOoi, Test5ConstantNormalVelocityVaryingTangentialVelocity) {
  // R = 10 um on a rigid plane at Vcn = 5 m/s, mu = 0.3, e_n = 1 (elastic); steel and polyethylene.
  const std::map<std::string, Material> mats{{"Steel", {2.08e11, 0.30, 7850}},
                                             {"Polyethylene", {1.0e9, 0.40, 1400}}};
  const Real radius = 1e-5, vn = 5, mu = 0.3;
  const auto ref = series_of("test5_kratos_paperdata.csv");
  int sliding = 0, n = 0;
  for (const auto& [name, mat] : mats) {
    // graph1 and graph2 are digitised at slightly different x; run every x of both.
    for (const char* graph : {"graph1", "graph2"}) {
      double y2_prev = 1;
      for (const auto& [x, y_ref] : ref.at({graph, name})) {
        const Impact im =
            collide(mat, radius, true, Vec3(Real(x) * mu * vn, 0, -vn), {}, {}, {}, 1, mu, 400);
        // Contact point at -R z: its x velocity is v_x - R w_y.
        const double vst = im.v_after.x - radius * im.w_after.y;
        const double y1 = vst / (mu * im.v_after.z);
        const double y2 = -radius * im.w_after.y / (mu * vn);
        const double y = graph[5] == '1' ? y1 : y2;
        const double fem = interpolate(ref.at({graph, "FEM"}), x);
        std::printf("Test 5 %-12s %s x %6.3f: sphdem %7.3f, DEM curve %7.3f, FEM %7.3f\n",
                    name.c_str(), graph, x, y, y_ref, fem);
        // Rigid-body kinematics, whatever the friction law: Vst' = Vst + 1.4 R w' (e = 1) for a
        // lever arm R. sphdem's contact point is the middle of the overlap (arm R - d/2), which
        // moves the spin's share by up to 0.4 |y2| d_max/(2R) (2.7 % of R for polyethylene).
        const double arm = im.d_max / (2 * radius);
        EXPECT_NEAR(y1, x + 1.4 * y2, 0.4 * std::fabs(y2) * arm / (1 - arm) + 1e-3 * x)
            << name << " x " << x;
        EXPECT_LE(std::fabs(y1), x * (1 + 1e-6)) << name << " x " << x;  // no gain
        EXPECT_LE(y2, 1e-9) << name << " x " << x;                       // spin opposes slip
        EXPECT_GE(y2, -5 * (1 + 2e-3)) << name << " x " << x;            // bounded by sliding
        EXPECT_LE(y2, y2_prev + 1e-3) << name << " x " << x;  // more spin at larger angles
        y2_prev = y2;
        if (x >= 7.5) {  // gross sliding: the rigid-body limits and the digitised curve
          // With the arm R - d/2 the spin's share of the impulse (5 of the 7) shrinks by up to
          // d_max/(2R): y1 in [x - 7, x - 7 + 5 arm], y2 in [-5, -5 + 5 arm].
          const double limit = graph[5] == '1' ? x - 7 : -5.0;
          EXPECT_GE(y, limit - 2e-3 * x) << name << " x " << x;
          EXPECT_LE(y, limit + 5 * arm + 2e-3 * x) << name << " x " << x;
          EXPECT_NEAR(y, y_ref, 0.03 * std::max(1.0, std::fabs(y_ref))) << name << " x " << x;
          ++sliding;
        }
        ++n;
      }
    }
  }
  EXPECT_EQ(n, 60);
  EXPECT_EQ(sliding, 8);
}

// Tests 6 and 8 share the spin-only set-up: a sphere of radius R approaching at Vcn with a spin
// that gives its contact point the tangential speed Vst, and no tangential centre velocity.
// partner_radius 0: the rigid plane z = 0 (Test 6); otherwise a fixed sphere of that radius
// (Test 8, case A: the larger sphere does not move).
struct SpinImpact {
  double beta, recoil;
  double kinematics;  // Vst' - (Vst + 3.5 v_t'): zero for a lever arm R
  double v_t;         // tangential centre velocity after the impact
  double v_n;         // normal centre velocity after the impact (away from the partner)
  double arm;         // d_max / (2R): sphdem's contact point has the lever arm R - d/2
  double tilt;        // bound on the turn of the centre line during the contact [rad]
};
SpinImpact spin_impact(const Material& mat, Real radius, Real vn, Real vst, Real e, Real mu,
                       Real partner_radius, bool tdamp) {
  if (!(partner_radius > 0)) {
    // Contact point at -R z: its x velocity is v_x - R w_y, so w_y = -Vst/R.
    const Impact im = collide(mat, radius, true, Vec3(0, 0, -vn), Vec3(0, -vst / radius, 0), {}, {},
                              e, mu, 400, NormalLaw::kHertz, 0, 0, Motion::kFree, tdamp);
    const double vst1 = im.v_after.x - radius * im.w_after.y;
    return {-vst1 / vst,
            vst1 / im.v_after.z,
            vst1 - (vst + 3.5 * im.v_after.x),
            im.v_after.x,
            im.v_after.z,
            im.d_max / (2 * radius),
            0};
  }
  // Moving along +x onto the fixed sphere; contact point at +R x: its z velocity is
  // v_z - R w_y.
  const Impact im =
      collide(mat, radius, false, Vec3(vn, 0, 0), Vec3(0, -vst / radius, 0), {}, {}, e, mu, 400,
              NormalLaw::kHertz, 0, partner_radius, Motion::kFixed, tdamp);
  const double vst1 = im.v_after.z - radius * im.w_after.y;
  return {-vst1 / vst,
          -vst1 / im.v_after.x,
          vst1 - (vst + 3.5 * im.v_after.z),
          im.v_after.z,
          -im.v_after.x,
          im.d_max / (2 * radius),
          std::fabs(im.v_after.z) * im.t_contact / (radius + partner_radius)};
}

// Rigid-body kinematics, whatever the friction law: the tangential impulse J changes the centre
// velocity by -J/m and the contact point's by -3.5 J/m for a lever arm R. With sphdem's arm
// R - d/2 the spin's share (2.5 of the 3.5) shrinks by up to d_max/(2R). Against a sphere the
// centre line also turns as the grain slides, by at most tilt, and tips part of the normal
// impulse (m (Vcn + Vcn')) into the tangent without a torque.
double kinematics_tolerance(const SpinImpact& s, Real vn) {
  return 2.5 * std::fabs(s.v_t) * s.arm / (1 - s.arm) + 2.5 * (vn + s.v_n) * s.tilt + 1e-9;
}

// In gross sliding the tangential impulse J_t is mu J_n, never more (Coulomb); sphdem's is up to 2
// % less near the threshold because the contact sticks for its first steps: the Tsuji dashpot
// (d^{1/4} d') makes the normal force, and so the cap, jump at first touch while the Mindlin spring
// (k_t ~ sqrt(d)) builds from zero. Measured: J_t/(mu J_n) 0.998 at Vst = 5.7 x the threshold,
// 0.985 at 1.03 x (Al alloy, e 0.5); unchanged at 10 x more steps per contact.
constexpr double kSlidingShortfall = 0.02;
void check_sliding_impulse(const SpinImpact& s, Real vn, Real mu, const std::string& name,
                           double x) {
  const double ratio = std::fabs(s.v_t) / (mu * (vn + s.v_n));
  EXPECT_LE(ratio, 1 + 1e-3) << name << " x " << x;
  EXPECT_GE(ratio, 1 - kSlidingShortfall) << name << " x " << x;
}

// Runs both graphs of one spin test against its digitised series; returns the sliding points.
int check_spin_test(const char* test, const Material& mat, const std::string& name,
                    const std::vector<std::pair<double, double>>& beta_ref,
                    const std::vector<std::pair<double, double>>& recoil_ref, Real partner_radius,
                    bool tdamp = false) {
  const Real radius = 0.1, vn = 0.2, mu = 0.4, e = 0.5;
  const double kick = 3.5 * mu * (1 + e) * vn;  // Vst at the sliding threshold
  int sliding = 0;
  for (const auto& [xq, ref] : beta_ref) {
    const SpinImpact s =
        spin_impact(mat, radius, vn, Real(kick / xq), e, mu, partner_radius, tdamp);
    std::printf(
        "%s %-9s graph1 x %6.3f: beta sphdem %7.4f, curve %7.4f (e_out %.4f, J_t/(mu J_n) "
        "%.4f)\n",
        test, name.c_str(), xq, s.beta, ref, s.v_n / vn, std::fabs(s.v_t) / (mu * (vn + s.v_n)));
    EXPECT_NEAR(s.kinematics, 0, kinematics_tolerance(s, vn)) << name << " x " << xq;
    EXPECT_LE(std::fabs(s.beta), 1.0) << name << " x " << xq;
    if (xq <= 0.9) {  // sliding throughout: beta = x - 1
      check_sliding_impulse(s, vn, mu, name, xq);
      EXPECT_NEAR(s.beta, xq - 1, kSlidingShortfall * xq + 1e-3) << name << " x " << xq;
      EXPECT_NEAR(s.beta, ref, 0.03) << name << " x " << xq;
      ++sliding;
    }
  }
  for (const auto& [x, ref] : recoil_ref) {
    const SpinImpact s = spin_impact(mat, radius, vn, Real(x) * vn, e, mu, partner_radius, tdamp);
    std::printf("%s %-9s graph2 x %6.3f: Vst'/Vcn' sphdem %7.4f, curve %7.4f\n", test, name.c_str(),
                x, s.recoil, ref);
    EXPECT_NEAR(s.kinematics, 0, kinematics_tolerance(s, vn)) << name << " x " << x;
    if (x * vn >= kick / 0.9) {  // sliding throughout
      check_sliding_impulse(s, vn, mu, name, x);
      // The impulse's shortfall shows in the recoil amplified by kick / (e Vcn) = 4.2.
      const double allowance = kSlidingShortfall * kick / (e * vn);
      const double rigid = (x * vn - kick) / (e * vn);
      EXPECT_GE(s.recoil, rigid - 2e-3 * x) << name << " x " << x;
      EXPECT_LE(s.recoil, rigid + allowance) << name << " x " << x;
      EXPECT_NEAR(s.recoil, ref, 0.03 * std::max(1.0, std::fabs(ref)) + allowance)
          << name << " x " << x;
      ++sliding;
    }
  }
  return sliding;
}

TEST(DemChungOoi, Test6SpinningSphereOnARigidPlane) {
  // R = 0.1 m, Vcn = 0.2 m/s, mu = 0.4, e_n = 0.5; aluminium alloy and nylon.
  const std::map<std::string, Material> mats{{"Al_alloy", {7.0e10, 0.33, 2700}},
                                             {"Nylon", {2.5e9, 0.40, 1000}}};
  const auto ref = series_of("test6_kratos_paperdata.csv");
  int sliding = 0;
  for (const auto& [name, mat] : mats)
    sliding +=
        check_spin_test("Test 6", mat, name, ref.at({"graph1", name}), ref.at({"graph2", name}), 0);
  EXPECT_EQ(sliding, 2 * (4 + 4));
}

// The same with the tangential dashpot (ContactModel::tangential_damping, as Hertz-Mindlin codes
// such as EDEM apply it: alpha sqrt(m* k_t)). Sliding holds the same bounds; in the stick regime
// the dashpot takes the spring's rebound (docs/VALIDATION.md).
TEST(DemChungOoi, Test6WithTangentialDamping) {
  const Material al{7.0e10, 0.33, 2700};
  const auto ref = series_of("test6_kratos_paperdata.csv");
  const int sliding =
      check_spin_test("Test 6 t-damped", al, "Al_alloy", ref.at({"graph1", "Al_alloy"}),
                      ref.at({"graph2", "Al_alloy"}), 0, true);
  EXPECT_EQ(sliding, 4 + 4);
}

TEST(DemChungOoi, Test8SpinningSphereOnALargerFixedSphere) {
  // As Test 6 (aluminium alloy) against a fixed sphere five times larger (case A).
  const Material al{7.0e10, 0.33, 2700};
  const auto ref = series_of("test7_test8_expected.csv", "test8");
  const int sliding = check_spin_test("Test 8", al, "Al_alloy", ref.at({"graph1", "caseA"}),
                                      ref.at({"graph2", "caseA"}), 0.5);
  EXPECT_EQ(sliding, 4 + 4);
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
