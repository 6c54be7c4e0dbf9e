// Stability guards (DESIGN.md §7): each test drives the method to a failure on purpose and checks
// that the right guard fires, with its cause in the message, that the run stops at once, that
// summary.json says "unstable" and that the emergency state was written. Where it is cheap, a
// control run with the cause removed shows the same case does not trip the guard.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "io/scene_yaml.hpp"
#include "validation/run_files.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

std::string dam_break() {
  return std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";
}
std::string thin_floor() {
  return std::string(SPHDEM_TEST_DATA) + "/scenes/guard_thin_floor_2d.yaml";
}

// The coarse 2D dam break (20 x 40 particles) with the guard settings the tests rely on.
std::vector<std::string> coarse_dam_break(std::vector<std::string> extra) {
  std::vector<std::string> ov = {"sph.dp=0.0073",
                                 "time.end=0.5",
                                 "time.cfl=0.2",  // the step counts below were set at 0.2
                                 "guards.mach_max=0.15",
                                 "guards.rho_min_ratio=0.7",
                                 "guards.rho_max_ratio=1.3",
                                 "guards.check_every=1"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return ov;
}

struct GuardRun {
  RunResult r;
  std::string out;
  Scene scene;
};

GuardRun run_case(const std::string& scene_path, const std::vector<std::string>& overrides,
                  const std::string& name, std::int64_t max_steps = -1) {
  GuardRun g;
  g.out = (fs::path(testing::TempDir()) / ("sphdem_guards_" + name)).string();
  fs::remove_all(g.out);
  RunOptions opt;
  opt.out_dir = g.out;
  opt.backend = Backend::kHost;
  opt.quiet = true;
  opt.max_steps = max_steps;
  g.scene = load_scene(scene_path, overrides);
  g.r = run_scene(g.scene, opt);
  return g;
}

// guards.csv of a run: its rows (t, steps, max_speed, mach, rho_min, rho_max, dt_min).
std::vector<std::vector<double>> guard_rows(const GuardRun& g) {
  const std::string path = g.out + "/guards.csv";
  std::ifstream f(path);
  std::string header;
  std::getline(f, header);
  EXPECT_EQ(header, "t,steps,max_speed,mach,rho_min,rho_max,dt_min");
  auto rows = runfiles::read_numeric_csv(path);
  for (const auto& v : rows) EXPECT_EQ(v.size(), 7u);
  return rows;
}

// What guards.csv must hold for any run: the rows' spans cover every step once (their step counts
// sum to the run's, and none is empty), time grows, each row's mach is its max_speed over the one
// c0, the density range is ordered, and dt_min is positive. A run that a guard stopped ends with
// the row of the step the guard judged, at the run's last time.
void expect_guard_rows(const GuardRun& g) {
  const auto rows = guard_rows(g);
  ASSERT_FALSE(rows.empty());
  double steps = 0, t = -1;
  double c0 = -1;  // from the first row that moves
  for (const auto& v : rows)
    if (c0 < 0 && v[3] > 0) c0 = v[2] / v[3];
  ASSERT_GT(c0, 0);
  for (const auto& v : rows) {
    EXPECT_GT(v[0], t);
    t = v[0];
    EXPECT_GE(v[1], 1);
    steps += v[1];
    EXPECT_NEAR(v[2], v[3] * c0, 1e-8 * v[2]);
    EXPECT_LE(v[4], v[5]);
    EXPECT_GT(v[6], 0);
  }
  EXPECT_EQ(steps, double(g.r.steps));
  if (g.r.unstable) {
    EXPECT_NEAR(rows.back()[0], g.r.sim_time, 1e-9 * g.r.sim_time);
  }
}

// What every guard must do: stop the run with "unstable: <cause> at t = ... (step N)", record it
// in summary.json and write emergency_stepN.csv with every particle.
void expect_guard(const GuardRun& g, const std::string& cause, std::int64_t max_steps) {
  const RunResult& r = g.r;
  std::printf("guard '%s': %lld steps, t = %.4g s: %s\n", cause.c_str(), (long long)r.steps,
              r.sim_time, r.failure.c_str());
  ASSERT_TRUE(r.unstable) << "no guard fired; " << r.steps << " steps to t = " << r.sim_time;
  EXPECT_EQ(r.failure.rfind("unstable: " + cause + " at t = ", 0), 0u) << r.failure;
  EXPECT_NE(r.failure.find("(step " + std::to_string(r.steps) + ")"), std::string::npos)
      << r.failure;
  EXPECT_GT(r.steps, 0);
  EXPECT_LE(r.steps, max_steps);
  const std::string summary = runfiles::slurp(g.out + "/summary.json");
  EXPECT_NE(summary.find("\"status\": \"unstable\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"failure\": \"unstable: " + cause), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"steps\": " + std::to_string(r.steps) + ","), std::string::npos)
      << summary;
  // The guards the run was judged by, as the scene set them (a study's table reads them here).
  std::ostringstream gj;
  gj << std::setprecision(10) << "\"guards\": {\"mach_max\": " << g.scene.guards.mach_max
     << ", \"rho_min_ratio\": " << g.scene.guards.rho_min_ratio
     << ", \"rho_max_ratio\": " << g.scene.guards.rho_max_ratio << "}";
  EXPECT_NE(summary.find(gj.str()), std::string::npos) << summary;
  const std::string dump = g.out + "/emergency_step" + std::to_string(r.steps) + ".csv";
  ASSERT_TRUE(fs::exists(dump)) << dump;
  std::ifstream f(dump);
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line, "id,role,x,y,z,vx,vy,vz,rho,p");
  Index rows = 0;
  while (std::getline(f, line))
    if (!line.empty()) ++rows;
  EXPECT_EQ(rows, r.fluid + r.wall + r.grain);
  expect_guard_rows(g);
}

// The Mach guard names the fastest fluid particle, the density guard the densest or the
// lightest; the emergency state (the state the guard judged) holds it with the value the message
// gives for it, which is the message's own figure (the max speed, or the density range's end) and
// the extreme of every fluid row in the file.
enum class Named { fastest, densest, lightest };
void expect_named(const GuardRun& g, Named what) {
  const std::string& m = g.r.failure;
  const char* figure = what == Named::fastest ? "max speed " : "fluid density range [";
  const char* intro = what == Named::fastest   ? "the fastest is fluid particle id "
                      : what == Named::densest ? "the densest is fluid particle id "
                                               : "the lightest is fluid particle id ";
  const char* field = what == Named::fastest ? ", speed " : ", density ";
  const std::size_t at_fig = m.find(figure), at_id = m.find(intro);
  ASSERT_NE(at_fig, std::string::npos) << m;
  ASSERT_NE(at_id, std::string::npos) << m;
  double fig = std::stod(m.substr(at_fig + std::strlen(figure)));  // speed, or the range's low end
  if (what == Named::densest) {
    const std::size_t comma = m.find(", ", at_fig);
    ASSERT_NE(comma, std::string::npos) << m;
    fig = std::stod(m.substr(comma + 2));  // the range's high end
  }
  const std::string id = std::to_string(std::stoull(m.substr(at_id + std::strlen(intro))));
  const std::size_t at_val = m.find(field, at_id);
  ASSERT_NE(at_val, std::string::npos) << m;
  const double named = std::stod(m.substr(at_val + std::strlen(field)));
  EXPECT_NEAR(named, fig, 1e-5 * fig) << m;
  // guards.csv's last row spans the judged step: its extreme is the message's figure.
  const auto rows = guard_rows(g);
  ASSERT_FALSE(rows.empty());
  const int col = what == Named::fastest ? 2 : what == Named::densest ? 5 : 4;
  EXPECT_NEAR(rows.back()[col], fig, 1e-5 * fig) << m;
  std::ifstream f(g.out + "/emergency_step" + std::to_string(g.r.steps) + ".csv");
  std::string line;
  std::getline(f, line);  // header
  // The row's value as the guard ranks it: speed, density, or minus the density.
  auto key = [&](const std::vector<double>& v) {
    return what == Named::fastest   ? std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5])
           : what == Named::densest ? v[6]
                                    : -v[6];
  };
  double row = -1e300, extreme = -1e300;
  bool seen = false;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string cell, role;
    std::vector<double> v;
    std::string first;
    for (int k = 0; std::getline(ss, cell, ','); ++k) {
      if (k == 0) first = cell;
      if (k == 1) role = cell;
      if (k >= 2) v.push_back(std::stod(cell));
    }
    if (role != "fluid") continue;
    extreme = std::max(extreme, key(v));
    if (first == id) {
      row = key(v);
      seen = true;
    }
  }
  ASSERT_TRUE(seen) << "particle " << id << " not in the emergency state";
  EXPECT_NEAR(std::fabs(row), named, 1e-5 * named) << m;
  EXPECT_EQ(row, extreme) << "a more extreme fluid particle is in the file: " << extreme;
}

void expect_completed(const GuardRun& g) {
  EXPECT_FALSE(g.r.unstable) << g.r.failure;
  EXPECT_NE(runfiles::slurp(g.out + "/summary.json").find("\"status\": \"completed\""),
            std::string::npos);
  expect_guard_rows(g);
}

// (a) No density diffusion and CFL = 1 (the schema's maximum) on the dam break: the acoustic
// step is five times too long and the pressure field blows up within a few dozen steps. The
// first guard to see it is the Mach guard: max speed 5.3 m/s (Mach 0.157) at step 16, where the
// physical flow is still at a few cm/s.
TEST(Guards, NoDiffusionHugeCflTripsMachGuard) {
  const GuardRun g =
      run_case(dam_break(), coarse_dam_break({"fluid.diffusion.model=none", "time.cfl=1.0"}),
               "no_diffusion_cfl1");
  expect_guard(g, "Mach number too high", 60);
  expect_named(g, Named::fastest);
  // The cause is the CFL number: the same scene at CFL 0.2 runs past that time.
  const GuardRun c =
      run_case(dam_break(),
               coarse_dam_break({"fluid.diffusion.model=none", "time.cfl=0.2", "time.end=0.02"}),
               "no_diffusion_cfl02");
  expect_completed(c);
}

// The same without diffusion and with a fixed step of 1 ms (14 acoustic limits): the density of a
// particle at the bottom leaves [0.7, 1.3] rho0 at step 4. The same state is past the Mach bound
// too (8.5 m/s on that particle); the density guard, checked first, is the one reported.
TEST(Guards, NoDiffusionFixedLargeStepTripsDensityGuard) {
  const GuardRun g =
      run_case(dam_break(), coarse_dam_break({"fluid.diffusion.model=none", "time.dt_fixed=1e-3"}),
               "no_diffusion_dt1ms");
  expect_guard(g, "density out of bounds", 10);
  EXPECT_NE(g.r.failure.find("] kg/m^3 leaves [700, 1300]"), std::string::npos) << g.r.failure;
  expect_named(g, Named::densest);
}

// The same state judged with the bounds moved to [0.9, 10] rho0: now only its low end, 814 kg/m^3
// on a particle near the surface, is out of bounds, and the guard names the lightest particle.
TEST(Guards, DensityGuardNamesTheLightestWhenTheLowBoundIsLeft) {
  const GuardRun g =
      run_case(dam_break(),
               coarse_dam_break({"fluid.diffusion.model=none", "time.dt_fixed=1e-3",
                                 "guards.rho_min_ratio=0.9", "guards.rho_max_ratio=10"}),
               "no_diffusion_dt1ms_low");
  expect_guard(g, "density out of bounds", 10);
  EXPECT_NE(g.r.failure.find("] kg/m^3 leaves [900, 10000]"), std::string::npos) << g.r.failure;
  expect_named(g, Named::lightest);
}

// (b) A floor one particle layer thick hit by water at 10 m/s: the fluid goes through the floor.
// The emergency state must hold the particle the message names, inside the floor.
TEST(Guards, ThinWallTripsPenetrationGuard) {
  const GuardRun g = run_case(thin_floor(), {}, "thin_floor");
  expect_guard(g, "fluid inside a solid", 400);
  EXPECT_NE(g.r.failure.find("inside solid 'tank'"), std::string::npos) << g.r.failure;
  const std::size_t at = g.r.failure.find("fluid particle id ");
  ASSERT_NE(at, std::string::npos) << g.r.failure;
  const std::string id = std::to_string(std::stoll(g.r.failure.substr(at + 18)));
  std::ifstream f(g.out + "/emergency_step" + std::to_string(g.r.steps) + ".csv");
  std::string line;
  bool found = false;
  while (std::getline(f, line)) {
    if (line.rfind(id + ",fluid,", 0) != 0) continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    for (int k = 0; std::getline(ss, cell, ','); ++k)
      if (k >= 2) v.push_back(std::stod(cell));
    // x, y, z, ...: the particle sits more than dp/2 below the floor's top (z = 0).
    EXPECT_LT(v[2], -0.5 * 0.0075) << line;
    found = true;
  }
  EXPECT_TRUE(found) << "particle " << id << " not in the emergency state";
  // With the default boundary depth (2h: two layers here) the same impact is held.
  const GuardRun c =
      run_case(thin_floor(), {"sph.boundary_layers=0", "time.end=0.003"}, "thick_floor");
  expect_completed(c);
}

// (c) A speed of sound of 10 m/s on the dam break: the collapsing column reaches 1.5 m/s =
// 0.15 c0 at t = 0.086 s.
TEST(Guards, LowSoundSpeedTripsMachGuard) {
  const GuardRun g = run_case(dam_break(), coarse_dam_break({"fluid.c0=10"}), "low_c0");
  expect_guard(g, "Mach number too high", 800);
  expect_named(g, Named::fastest);
  EXPECT_NE(g.r.failure.find("of c0 = 10 m/s"), std::string::npos) << g.r.failure;
  EXPECT_GT(g.r.sim_time, 0.03);  // the flow, not the start, is too fast
}

// (d) A floor time.dt_min above the natural step (7.3e-5 s here): the first step trips it.
TEST(Guards, StepBelowFloorTripsDtGuard) {
  const GuardRun g = run_case(dam_break(), coarse_dam_break({"time.dt_min=1e-4"}), "dt_floor");
  expect_guard(g, "time step at its floor", 1);
  EXPECT_NE(g.r.failure.find("fell below the floor time.dt_min = 0.0001 s"), std::string::npos)
      << g.r.failure;
  // A floor below the natural step is not a fault.
  const GuardRun c =
      run_case(dam_break(), coarse_dam_break({"time.dt_min=1e-5"}), "dt_floor_ok", 20);
  expect_completed(c);
  EXPECT_EQ(c.r.steps, 20);
}

}  // namespace
}  // namespace sphdem
