// 2D granular column collapse (Bui et al. 2008 set-up) with HBP + Mohr-Coulomb: run-out, height
// and failure line against the scaling laws and the Rankine angle, the end of the collapse and
// the time to rest. Writes <prefix>_final.csv (x0, z0, x, z, final displacement, displacement at
// the end of the collapse, final velocity and pressure per particle) for app/plot_collapse.py, and
// <prefix>_history.csv (t, KE/(m g H0), front, height at the wall every 5 ms).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "diagnostics/guards.hpp"
#include "diagnostics/probes.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

constexpr double kH0 = 0.1, kL0 = 0.2;
// At rest: kinetic energy below 1e-4 m g H0, i.e. an RMS speed under 1.4 cm/s (1.4% of
// sqrt(g H0)). The time to rest is the last time the heap was above it.
constexpr double kRestRatio = 1e-4;
// Moved / unmoved: 2.5 mm (H0/40), the same at every resolution.
constexpr double kMoved = 0.0025;
// End of the collapse: kinetic energy back below 1e-3 m g H0 after its peak. The failure line is
// measured on the displacements at that time, before any later creep of the heap moves the
// whole deposit.
constexpr double kStopRatio = 1e-3;

struct Collapse {
  double runout = 0, height = 0, failure_deg = 0, kinetic_ratio = 0;
  double slope_deg = 0;  // free surface of the deposit, fitted where 0.2 H < h < 0.8 H
  double t_rest = std::numeric_limits<double>::quiet_NaN();  // NaN: not at rest at the end
  double t_stop = std::numeric_limits<double>::quiet_NaN();  // NaN: still collapsing at the end
  std::int64_t steps = 0;
  double wall = 0;
  double dp = 0;
};

double kinetic_ratio(const ParticleSet<Host>& ps) {
  double ke = 0, mass = 0;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    ke += 0.5 * ps.mass[i] * norm2(ps.vel[i]);
    mass += ps.mass[i];
  }
  return ke / (mass * 9.81 * kH0);
}

Collapse run_collapse(const std::vector<std::string>& ov, const std::string& prefix) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/column_collapse_2d.yaml", ov);
  std::ostringstream log;
  auto solver = make_solver(scene, Backend::kHost, log);
  std::map<GlobalId, Vec3> start;
  {
    const auto& ps = solver->host_particles();
    for (Index i = 0; i < ps.n_fluid; ++i) start[ps.id[i]] = ps.pos[i];
  }
  Collapse c;
  c.dp = scene.sph.dp;
  std::ofstream hist(prefix + "_history.csv");
  hist << "t,kinetic_ratio,front,back_height\n";
  double next_sample = 0, last_moving = 0, ke_peak = 0;
  std::map<GlobalId, double> stop_disp;  // displacement at the end of the collapse
  while (solver->time() < scene.time.end) {
    const StepStats st = solver->step();
    check_step_guards(scene, solver->params(), st, solver->time(), solver->step_count());
    ++c.steps;
    if (solver->time() >= next_sample) {
      next_sample += 0.005;
      const auto& ps = solver->host_particles();
      const double ke = kinetic_ratio(ps);
      if (ke > kRestRatio) last_moving = solver->time();
      ke_peak = std::max(ke_peak, ke);
      if (stop_disp.empty() && ke_peak > 10 * kStopRatio && ke < kStopRatio) {
        c.t_stop = solver->time();
        for (Index i = 0; i < ps.n_fluid; ++i)
          stop_disp[ps.id[i]] = norm(ps.pos[i] - start.at(ps.id[i]));
      }
      hist << solver->time() << ',' << ke << ',' << probe_front(ps, Vec3(0, 0, 0), Vec3(1, 0, 0))
           << ',' << probe_surface_height(ps, solver->params(), 0.5 * c.dp, 0) << '\n';
    }
  }
  const auto& ps = solver->host_particles();
  const StepParams& p = solver->params();
  const double dp = scene.sph.dp;
  c.kinetic_ratio = kinetic_ratio(ps);
  if (c.kinetic_ratio < kRestRatio) c.t_rest = last_moving;
  // Run-out: where the free surface (kernel-sum height) falls below dp/2 along the floor.
  for (double x = 0.005; x < 0.6; x += dp / 4) {
    const double h = probe_surface_height(ps, p, x, 0);
    if (!(h > dp / 2)) break;
    c.runout = x;
  }
  c.height = probe_surface_height(ps, p, 0.5 * dp, 0);
  // Surface slope: a line fitted to the kernel surface height h(x) where it lies between 0.2 and
  // 0.8 of the height at the wall (the flank between the plateau and the toe).
  {
    double n = 0, sx = 0, sh = 0, sxx = 0, sxh = 0;
    for (double x = 0.005; x < c.runout; x += dp / 4) {
      const double h = probe_surface_height(ps, p, x, 0);
      if (!(h > 0.2 * c.height && h < 0.8 * c.height)) continue;
      n += 1;
      sx += x;
      sh += h;
      sxx += x * x;
      sxh += x * h;
    }
    c.slope_deg = n > 2 ? -std::atan((n * sxh - sx * sh) / (n * sxx - sx * sx)) * 180 / kPi
                        : std::numeric_limits<double>::quiet_NaN();
  }
  // Failure line: at the end of the collapse (or at the end of the run if it never stopped),
  // in each initial row, the unmoved particles (displacement under kMoved) that
  // reach out from the wall without a moved one between; a line fitted to the rows' outermost
  // unmoved x0 gives the angle. Rows with fewer than two unmoved particles at the wall have no
  // wedge; if more than half the rows between 0.1 H0 and 0.9 H0 have none, there is no unmoved
  // wedge and the angle is NaN.
  std::map<long, std::map<double, double>> rows;  // row -> x0 -> displacement
  std::ofstream f(prefix + "_final.csv");
  f << "x0,z0,x,z,displacement,displacement_at_stop,vx,vz,pressure\n";
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const Vec3 x0 = start.at(ps.id[i]);
    const double d_end = norm(ps.pos[i] - x0);
    const double d = stop_disp.empty() ? d_end : stop_disp.at(ps.id[i]);
    f << x0.x << ',' << x0.z << ',' << ps.pos[i].x << ',' << ps.pos[i].z << ',' << d_end << ',' << d
      << ',' << ps.vel[i].x << ',' << ps.vel[i].z << ',' << ps.press[i] << '\n';
    rows[std::lround(x0.z / dp - 0.5)][x0.x] = d;
  }
  std::vector<double> zs, xs;
  int rows_in_range = 0;
  for (const auto& [row, line] : rows) {
    const double z = (row + 0.5) * dp;
    if (z < 0.1 * kH0 || z > 0.9 * kH0) continue;  // skip the floor layer and the top corner
    ++rows_in_range;
    double edge = -1;
    int count = 0;
    for (const auto& [x0, d] : line) {
      if (d >= kMoved) break;
      edge = x0;
      ++count;
    }
    if (count < 2) continue;
    zs.push_back(z);
    xs.push_back(edge);
  }
  c.failure_deg = std::numeric_limits<double>::quiet_NaN();  // no unmoved wedge
  if (2 * zs.size() > std::size_t(rows_in_range)) {
    double sz = 0, sx = 0, szz = 0, szx = 0;
    for (std::size_t k = 0; k < zs.size(); ++k) {
      sz += zs[k];
      sx += xs[k];
      szz += zs[k] * zs[k];
      szx += zs[k] * xs[k];
    }
    const double n = double(zs.size());
    const double dxdz = (n * szx - sz * sx) / (n * szz - sz * sz);
    c.failure_deg = std::atan2(1.0, -dxdz) * 180 / kPi;
  }
  c.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "column collapse dp=%.4f: %lld steps, %.0f s wall, run-out %.3f m ((L-L0)/L0 = %.2f), "
      "height %.4f m (H/H0 = %.2f), surface slope %.1f deg, failure line %.1f deg, KE/(m g H0) = "
      "%.2e, collapse ends %.2f s, rest at %.2f s\n",
      dp, static_cast<long long>(c.steps), c.wall, c.runout, (c.runout - kL0) / kL0, c.height,
      c.height / kH0, c.slope_deg, c.failure_deg, c.kinetic_ratio, c.t_stop, c.t_rest);
  return c;
}

std::vector<std::string> split(const char* s) {
  std::vector<std::string> out;
  if (!s) return out;
  std::string item;
  for (std::istringstream in(s); std::getline(in, item, ';');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The shipped scene (inputs/column_collapse_2d.yaml: dp = 5 mm, m = 100 s, mu_max = 1000 Pa s,
// no tension) comes to rest, and its deposit is what a frictional material with phi = 19.8 deg
// can hold: the column's height stays (Nguyen et al. 2015, H/H0 = 1 within 10%), the flank is
// no steeper than the friction angle (a cohesionless slope at rest cannot be; +2 deg for a line
// fitted to kernel surface heights good to ~dp/4 over ~0.1 m), and an unmoved wedge stands at the
// wall with its edge steeper than the friction angle. The run-out against Lube et al. (2005) and
// the wedge against Rankine are printed, not asserted: the HBP fluid misses both
// (DISABLED_HeapAgainstScalingLawsAndRankine; docs/VALIDATION.md).
TEST(ColumnCollapse, ShippedSceneComesToRestHoldingItsHeight) {
  const Collapse c = run_collapse({}, "column_collapse_shipped");
  const double phi = 19.8;
  std::printf(
      "against the references: run-out %.2f (Lube 0.60), H/H0 %.2f (Nguyen 1.0), wedge "
      "%.1f deg (Rankine %.1f), flank %.1f deg (phi %.1f)\n",
      (c.runout - kL0) / kL0, c.height / kH0, c.failure_deg, 45 + phi / 2, c.slope_deg, phi);
  EXPECT_LT(c.kinetic_ratio, kRestRatio) << "not at rest at the end";
  EXPECT_FALSE(std::isnan(c.t_rest));
  EXPECT_NEAR(c.height / kH0, 1.0, 0.1);
  EXPECT_GT(c.slope_deg, 0.0);
  EXPECT_LE(c.slope_deg, phi + 2.0);
  ASSERT_FALSE(std::isnan(c.failure_deg)) << "no unmoved wedge at the wall";
  EXPECT_GT(c.failure_deg, phi);
  EXPECT_LT(c.failure_deg, 90.0);
}

// Disabled: no setting measured reaches the references (docs/VALIDATION.md, "Granular column
// collapse"). The seed's m = 0.15 s never comes to rest (run-out 1.21, H/H0 0.58). This runs the
// shipped scene with mu_max = 3000 Pa s (100,573 steps), the stiffest setting measured at rest:
// it held the height (H/H0 0.94) but ran out 0.80 and its unmoved region's edge fitted 32 deg, so
// it fails the run-out and failure-line checks (measured before fluid.p_min = 0 entered the
// scene; a fitted K = 10 Pa s with mu_max = 1000 met run-out and height, not the failure line).
// The tolerances are what a passing model must meet, not fitted to these runs:
//   build/tests/validation_tests --gtest_also_run_disabled_tests
//     --gtest_filter='ColumnCollapse.DISABLED_HeapAgainstScalingLawsAndRankine'
TEST(ColumnCollapse, DISABLED_HeapAgainstScalingLawsAndRankine) {
  const Collapse c = run_collapse({"fluid.rheology.mu_max=3000"}, "column_collapse");
  EXPECT_LT(c.kinetic_ratio, kRestRatio);  // at rest
  const double a = 0.5;
  // Lube et al. 2005: (L - L0)/L0 = 1.2 a = 0.6, within 20% (the scatter of the fit).
  EXPECT_NEAR((c.runout - kL0) / kL0, 1.2 * a, 0.2 * 1.2 * a);
  // Nguyen et al. 2015 (aluminium rods, a <= 0.65): the top of the column stays, H/H0 = 1.
  EXPECT_NEAR(c.height / kH0, 1.0, 0.1);
  // Rankine active failure line 45 + phi/2 = 54.9 deg; +-5 deg: a line fitted to row edges
  // quantised to dp = 5 mm over 80 mm of height has a slope error of ~3.6 deg at 55 deg.
  EXPECT_NEAR(c.failure_deg, 54.9, 5.0);
}

// One point of the measured chart: the scene with the overrides in SPHDEM_COLLAPSE_SET
// (';'-separated key=value), appended to column_collapse_study.csv. E.g.
//   SPHDEM_COLLAPSE_SET='sph.dp=0.005;fluid.rheology.m=100' build/tests/validation_tests
//     --gtest_also_run_disabled_tests --gtest_filter='ColumnCollapse.DISABLED_Study'
TEST(ColumnCollapse, DISABLED_Study) {
  const char* set = std::getenv("SPHDEM_COLLAPSE_SET");
  const char* tag = std::getenv("SPHDEM_COLLAPSE_TAG");
  const std::string prefix = std::string("column_collapse_") + (tag ? tag : "study");
  const Collapse c = run_collapse(split(set), prefix);
  std::ofstream f("column_collapse_study.csv", std::ios::app);
  f << '"' << (set ? set : "") << "\"," << c.dp << ',' << (c.runout - kL0) / kL0 << ','
    << c.height / kH0 << ',' << c.failure_deg << ',' << c.kinetic_ratio << ',' << c.t_stop << ','
    << c.t_rest << ',' << c.steps << ',' << c.wall << std::endl;
}

}  // namespace
}  // namespace sphdem
