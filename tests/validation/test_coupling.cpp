// SPH-DEM coupling (issue #6): a floating box settles at the draft Archimedes gives, and a
// neutrally buoyant box stays where it is. inputs/floating_box.yaml: a 0.08 m cube, water 0.12 m
// deep, periodic in x and y, dp = 0.01 (8 particles across the cube); the draft criterion runs
// at dp = 5 mm (16 across).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "core/error.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_yaml.hpp"
#include "validation/run_files.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/floating_box.yaml";

RunResult run(const std::vector<std::string>& overrides, const std::string& out,
              std::int64_t max_steps = -1, const std::string& restart = "") {
  return runfiles::run_host(load_scene(kScene, overrides), out, max_steps, restart);
}

struct Window {
  double mean = 0, lo = 1e30, hi = -1e30;
};
// Mean, min and max of column c of `rows` (bodies.csv: t in column 0) for t in [t0, t1].
Window window(const std::vector<std::vector<double>>& rows, int c, double t0, double t1) {
  Window w;
  int n = 0;
  for (const auto& r : rows) {
    if (r[0] < t0 - 1e-9 || r[0] > t1 + 1e-9) continue;
    w.mean += r[std::size_t(c)];
    w.lo = std::min(w.lo, r[std::size_t(c)]);
    w.hi = std::max(w.hi, r[std::size_t(c)]);
    ++n;
  }
  w.mean /= std::max(n, 1);
  return w;
}

// The floating box, run once for both tests below.
struct Floating {
  double draft = 0, range_first = 0, range_last = 0, force = 0, x_lo = 0, x_hi = 0;
  bool unstable = false;
  std::string failure;
};
const Floating& floating() {
  static const Floating f = [] {
    Floating out;
    const RunResult r = run({"time.end=1.5"}, "coupling_float");  // three heave periods
    out.unstable = r.unstable;
    out.failure = r.failure;
    if (r.unstable) return out;
    const auto body =
        runfiles::read_numeric_csv("coupling_float/bodies.csv");  // t,id,x,y,z,...,fx,fy,fz,...
    const auto surf = runfiles::read_numeric_csv("coupling_float/surface.csv");  // t,h
    const double end = body.back()[0], period = 0.5;  // heave period about 0.45-0.5 s
    const Window z_end = window(body, 4, end - period, end);
    const Window s_end = window(surf, 1, end - period, end);
    const Window z_start = window(body, 4, 0, period);
    out.draft = s_end.mean - (z_end.mean - 0.04);
    out.range_first = z_start.hi - z_start.lo;
    out.range_last = z_end.hi - z_end.lo;
    out.force = window(body, 13, end - period, end).mean;
    const Window x = window(body, 2, 0, end);
    out.x_lo = x.lo;
    out.x_hi = x.hi;
    std::printf(
        "draft %.5f m (Archimedes 0.04, err %.2f %%), heave range %.4f m first period, "
        "%.4f m last; mean fluid force %.4f N\n",
        out.draft, 100 * (out.draft / 0.04 - 1), out.range_first, out.range_last, out.force);
    return out;
  }();
  return f;
}

TEST(Coupling, FloatingBoxComesToRestAfloat) {
  const Floating& f = floating();
  ASSERT_FALSE(f.unstable) << f.failure;
  // Coming to rest: the heave has decayed to well under half its first swing.
  EXPECT_LT(f.range_last, 0.5 * f.range_first);
  // Over its last period the fluid force averages the weight (500 kg/m^3 x 0.08^3 m^3 x 9.81).
  const double weight = 500 * 0.08 * 0.08 * 0.08 * 9.81;
  EXPECT_NEAR(f.force, weight, 0.03 * weight);
  // It floats (neither sinks nor rides on the surface) and stays in place across the channel.
  EXPECT_GT(f.draft, 0.5 * 0.04);
  EXPECT_LT(f.draft, 1.0 * 0.04);
  EXPECT_NEAR(f.x_lo, 0.12, 1e-3);
  EXPECT_NEAR(f.x_hi, 0.12, 1e-3);
}

// The acceptance criterion of issue #6: draft within 3 % of Archimedes. At 8 particles across the
// cube (the test above) the draft is 3.1-3.3 % short; at 16 across (dp = 5 mm) it is within
// 0.5 % (jobs/floating_box/run.sh; docs/VALIDATION.md). This runs the 16-across case in a smaller
// cell to keep it affordable: 0.12 m period, the box released at rest at its Archimedes position
// (centre on the still-water level, 0.08 m), 0.5 s (about one heave period), the draft averaged
// from 0.05 s on. The gauge stands at the cell's corner, 0.02 m from the box.
TEST(Coupling, FloatingBoxDraftWithin3PercentAt16ParticlesAcross) {
  const RunResult r =
      run({"sph.dp=0.005", "time.end=0.5", "domain.hi=[0.12, 0.12, 0.2]",
           "fluid_blocks[0].hi=[0.12, 0.12, 0.08]", "dem.bodies[0].position=[0.06, 0.06, 0.08]",
           "diagnostics.height_gauges=[{name: surface, x: 0, y: 0}]"},
          "coupling_float16");
  ASSERT_FALSE(r.unstable) << r.failure;
  const auto body = runfiles::read_numeric_csv("coupling_float16/bodies.csv");   // t,id,x,y,z,...
  const auto surf = runfiles::read_numeric_csv("coupling_float16/surface.csv");  // t,h (same times)
  ASSERT_EQ(body.size(), surf.size());
  double sum = 0, lo = 1, hi = 0;
  int n = 0;
  for (std::size_t k = 0; k < body.size(); ++k) {
    if (body[k][0] < 0.05) continue;
    const double draft = surf[k][1] - (body[k][4] - 0.04);
    sum += draft;
    lo = std::min(lo, draft);
    hi = std::max(hi, draft);
    ++n;
  }
  ASSERT_GT(n, 20);
  const double draft = sum / n;
  std::printf("16 across: draft %.5f m (Archimedes 0.04, err %.2f %%), range %.5f-%.5f m\n", draft,
              100 * (draft / 0.04 - 1), lo, hi);
  EXPECT_NEAR(draft, 0.04, 0.03 * 0.04);
}

TEST(Coupling, NeutrallyBuoyantBoxStaysPut) {
  // Fully submerged in water 0.16 m deep (0.04 m of water above and below it), the density of
  // water. (At 0.02 m above the floor, a fluid particle squeezed under the box's corner was
  // pushed into the floor: the mDBC ghost nodes of a box's edges and corners fall short of the
  // mirror image, see test_grain_boundary.cpp.)
  const RunResult r = run({"dem.bodies[0].density=1000", "dem.bodies[0].position=[0.12,0.12,0.08]",
                           "fluid_blocks[0].hi=[0.24,0.24,0.16]", "time.end=0.6"},
                          "coupling_neutral");
  ASSERT_FALSE(r.unstable) << r.failure;
  const auto body = runfiles::read_numeric_csv("coupling_neutral/bodies.csv");
  double drift = 0;
  for (const auto& row : body)
    drift = std::max(drift, std::sqrt(std::pow(row[2] - 0.12, 2) + std::pow(row[3] - 0.12, 2) +
                                      std::pow(row[4] - 0.08, 2)));
  std::printf("neutral box: largest displacement %.5f m over %.2f s\n", drift, body.back()[0]);
  EXPECT_LT(drift, 0.1 * 0.01);  // a tenth of a particle spacing
}

TEST(Coupling, GrainOnlyKeysAreRefusedNotIgnored) {
  for (const char* ov : {"dem.settle={until: 1}", "dem.heap={floor: 0}"}) {
    try {
      run({ov}, "coupling_refused", 1);
      ADD_FAILURE() << "accepted " << ov;
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(kScene), std::string::npos) << m;
      EXPECT_NE(m.find(std::string(ov).substr(0, 8)), std::string::npos) << m;
    }
  }
}

TEST(Coupling, RestartContinuesBitIdentically) {
  // Grains and fluid: 60 steps straight against 30, a checkpoint, and 30 more. The split run's
  // first leg goes on to step 45 past its checkpoint (a job killed between checkpoints): the
  // restart must drop the bodies.csv rows written after step 30, not repeat them.
  const std::vector<std::string> ov = {"checkpoint.every_steps=30", "checkpoint.keep=10",
                                       "diagnostics.every=1e-4"};
  run(ov, "coupling_straight", 60);
  run(ov, "coupling_split", 45);
  run(ov, "coupling_split", 30, checkpoint_path("coupling_split", 30));
  const CheckpointData a = read_checkpoint(checkpoint_path("coupling_straight", 60));
  const CheckpointData b = read_checkpoint(checkpoint_path("coupling_split", 60));
  ASSERT_EQ(a.dem.bodies.size(), 1u);
  ASSERT_EQ(b.dem.bodies.size(), 1u);
  EXPECT_EQ(std::memcmp(&a.dem.bodies[0].x, &b.dem.bodies[0].x, sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(&a.dem.bodies[0].v, &b.dem.bodies[0].v, sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(&a.dem.bodies[0].q, &b.dem.bodies[0].q, sizeof(Quat)), 0);
  EXPECT_NE(a.dem.bodies[0].x.z, 0.14) << "the box should have moved";
  ASSERT_EQ(a.particles.size(), b.particles.size());
  EXPECT_EQ(a.particles.n_grain, 512);
  // Every particle's position, velocity and density, by global id.
  std::map<GlobalId, Index> at;
  for (Index i = 0; i < b.particles.size(); ++i) at[b.particles.id[std::size_t(i)]] = i;
  for (Index i = 0; i < a.particles.size(); ++i) {
    const auto it = at.find(a.particles.id[std::size_t(i)]);
    ASSERT_NE(it, at.end());
    const std::size_t j = std::size_t(it->second), k = std::size_t(i);
    ASSERT_EQ(std::memcmp(&a.particles.pos[k], &b.particles.pos[j], sizeof(Vec3)), 0) << i;
    ASSERT_EQ(std::memcmp(&a.particles.vel[k], &b.particles.vel[j], sizeof(Vec3)), 0) << i;
    ASSERT_EQ(a.particles.rho[k], b.particles.rho[j]) << i;
  }
  const std::string straight = runfiles::slurp("coupling_straight/bodies.csv");
  EXPECT_GT(std::count(straight.begin(), straight.end(), '\n'), 40)
      << "the test should write bodies.csv rows on both legs";
  EXPECT_EQ(straight, runfiles::slurp("coupling_split/bodies.csv"));
}

// dem.subcycle (issue #6): three glass beads settling in a water tank (inputs/beads_settling.yaml)
// land on the floor and on each other within 0.1 s. Sub-cycling the DEM inside each fluid step
// must give the same motion as running both phases on the DEM step, for less cost (fluid steps:
// machine-independent). Tolerances: 1 % of the bead diameter in position and 2 % of
// sqrt(g d) = 0.63 m/s in velocity; measured over 0.3 s the two agree to 0.2 mm.
TEST(Coupling, SubcyclingMatchesOneStepForLessCost) {
  const std::string scene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/beads_settling.yaml";
  auto go = [&](const char* out, const char* subcycle) {
    return runfiles::run_host(load_scene(scene, {"time.end=0.1", subcycle}), out);
  };
  const RunResult sub = go("beads_subcycled", "dem.subcycle=true");
  const RunResult one = go("beads_one_step", "dem.subcycle=false");
  ASSERT_FALSE(sub.unstable) << sub.failure;
  ASSERT_FALSE(one.unstable) << one.failure;
  std::printf("fluid steps: sub-cycled %lld (%.1f s wall), one step %lld (%.1f s wall)\n",
              static_cast<long long>(sub.steps), sub.wall_seconds,
              static_cast<long long>(one.steps), one.wall_seconds);
  EXPECT_GT(one.steps, 5 * sub.steps) << "one step for both phases should take the DEM step";
  const auto a =
      runfiles::read_numeric_csv("beads_subcycled/bodies.csv");  // t,id,x,y,z,vx,vy,vz,...
  const auto b = runfiles::read_numeric_csv("beads_one_step/bodies.csv");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GE(a.size(), 3u * 10);
  const double d = 0.04, v_scale = std::sqrt(9.81 * d);
  double worst_x = 0, worst_v = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_NEAR(a[k][0], b[k][0], 1e-3) << "diagnostic times differ";
    ASSERT_EQ(a[k][1], b[k][1]);
    for (int c = 2; c < 5; ++c) worst_x = std::max(worst_x, std::fabs(a[k][c] - b[k][c]));
    for (int c = 5; c < 8; ++c) worst_v = std::max(worst_v, std::fabs(a[k][c] - b[k][c]));
  }
  std::printf("largest difference: position %.2e m, velocity %.2e m/s\n", worst_x, worst_v);
  EXPECT_LT(worst_x, 0.01 * d);
  EXPECT_LT(worst_v, 0.02 * v_scale);
  // The beads did land: the lowest is within 1 mm of resting on the floor at the end.
  double z_min = 1;
  for (const auto& r : a)
    if (r[0] > 0.09) z_min = std::min(z_min, r[4]);
  EXPECT_LT(z_min, 0.021);
}

}  // namespace
}  // namespace sphdem
