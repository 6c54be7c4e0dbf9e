// SPH-DEM coupling (issue #6): a floating box settles at the draft Archimedes gives, and a
// neutrally buoyant box stays where it is. inputs/floating_box.yaml: a 0.08 m cube, water 0.12 m
// deep, periodic in x and y, dp = 0.01 (8 particles across the cube).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "app/simulation.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/floating_box.yaml";

// Columns of a CSV file with a header row.
std::vector<std::vector<double>> read_csv(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(f, line)) {
    std::vector<double> r;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

RunResult run(const std::vector<std::string>& overrides, const std::string& out,
              std::int64_t max_steps = -1, const std::string& restart = "") {
  if (restart.empty()) fs::remove_all(out);
  RunOptions o;
  o.out_dir = out;
  o.backend = Backend::kHost;
  o.quiet = true;
  o.handle_signals = false;
  o.max_steps = max_steps;
  o.restart = restart;
  return run_scene(load_scene(kScene, overrides), o);
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

TEST(Coupling, FloatingBoxSettlesAtHalfDraft) {
  const RunResult r = run({}, "coupling_float");
  ASSERT_FALSE(r.unstable) << r.failure;
  const auto body = read_csv("coupling_float/bodies.csv");   // t,id,x,y,z,...,fx,fy,fz,...
  const auto surf = read_csv("coupling_float/surface.csv");  // t,h
  ASSERT_GT(body.size(), 150u);
  const double end = body.back()[0], period = 0.5;  // heave period about 0.45-0.5 s
  const Window z_end = window(body, 4, end - period, end);
  const Window s_end = window(surf, 1, end - period, end);
  const Window z_start = window(body, 4, 0, period);
  const double draft = s_end.mean - (z_end.mean - 0.04);
  std::printf(
      "draft %.5f m (Archimedes 0.04, err %.2f %%), heave range %.4f m first period, "
      "%.4f m last\n",
      draft, 100 * (draft / 0.04 - 1), z_start.hi - z_start.lo, z_end.hi - z_end.lo);
  EXPECT_NEAR(draft, 0.04, 0.03 * 0.04);
  // Coming to rest: the heave has decayed to well under half its first swing.
  EXPECT_LT(z_end.hi - z_end.lo, 0.5 * (z_start.hi - z_start.lo));
  // Over a period the fluid force averages the weight (500 kg/m^3 x 0.08^3 m^3 x 9.81).
  const double weight = 500 * 0.08 * 0.08 * 0.08 * 9.81;
  const Window fz = window(body, 13, end - period, end);
  std::printf("mean fluid force %.4f N, weight %.4f N\n", fz.mean, weight);
  EXPECT_NEAR(fz.mean, weight, 0.03 * weight);
  // It stays upright and in place across the channel.
  const Window x = window(body, 2, 0, end);
  EXPECT_NEAR(x.lo, 0.12, 1e-3);
  EXPECT_NEAR(x.hi, 0.12, 1e-3);
}

TEST(Coupling, NeutrallyBuoyantBoxStaysPut) {
  // Fully submerged (top 0.02 m under the surface), the density of water.
  const RunResult r =
      run({"dem.bodies[0].density=1000", "dem.bodies[0].position=[0.12,0.12,0.06]", "time.end=0.6"},
          "coupling_neutral");
  ASSERT_FALSE(r.unstable) << r.failure;
  const auto body = read_csv("coupling_neutral/bodies.csv");
  double drift = 0;
  for (const auto& row : body)
    drift = std::max(drift, std::sqrt(std::pow(row[2] - 0.12, 2) + std::pow(row[3] - 0.12, 2) +
                                      std::pow(row[4] - 0.06, 2)));
  std::printf("neutral box: largest displacement %.5f m over %.2f s\n", drift, body.back()[0]);
  EXPECT_LT(drift, 0.1 * 0.01);  // a tenth of a particle spacing
}

TEST(Coupling, RestartContinuesBitIdentically) {
  // Grains and fluid: 60 steps straight against 30, a checkpoint, and 30 more.
  const std::vector<std::string> ov = {"checkpoint.every_steps=30", "checkpoint.keep=10"};
  run(ov, "coupling_straight", 60);
  run(ov, "coupling_split", 30);
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
}

}  // namespace
}  // namespace sphdem
