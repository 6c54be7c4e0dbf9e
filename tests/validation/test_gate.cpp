// Gates (Solid::removed_at; issue #6, the flume's generating box): a solid that goes at a given
// time. A 2D dam-break column (inputs/dam_break_2d.yaml, dp = 10 mm) held by a gate for 0.1 s
// and then released must (1) stay behind the gate until then, (2) lose exactly the gate's
// boundary particles, (3) run on as the column released at t = 0 does, shifted by 0.1 s, to
// within 1.5 dp over 0.25 s (the
// column starts at rest and hydrostatic, so holding it changes nothing), and (4) restart
// bit-identically from a checkpoint written before the gate opened and from one after.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_yaml.hpp"
#include "validation/run_files.hpp"
#include "scene/build.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";
// The column fills 0 < x < 0.146; the gate is 40 mm thick (2h = 34 mm at dp = 10 mm).
const std::vector<std::string> kGate = {
    "solids=[{name: tank, shape: {type: tank, inner_lo: [0, -0.5, 0], inner_hi: [0.584, 0.5, "
    "0.35], thickness: 0.02, closed_top: false}}, {name: gate, shape: {type: box, lo: [0.146, -1, "
    "0], hi: [0.186, 1, 0.34]}, removed_at: 0.1}]"};

Scene scene(const std::vector<std::string>& extra) {
  std::vector<std::string> ov = {"sph.dp=0.01", "diagnostics.every=0.01", "frames.every=0"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return load_scene(kScene, ov);
}

RunResult run(const Scene& s, const std::string& out, const std::string& restart = "") {
  return runfiles::run_host(s, out, -1, restart);
}

// front.csv as t -> x_front (t rounded to the 10 ms diagnostic grid).
std::map<long, double> fronts(const std::string& dir) {
  std::ifstream f(dir + "/front.csv");
  std::string line;
  std::getline(f, line);
  std::map<long, double> m;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string t, x;
    std::getline(ss, t, ',');
    std::getline(ss, x, ',');
    m[std::lround(std::stod(t) * 100)] = std::stod(x);
  }
  return m;
}

TEST(Gate, HoldsTheColumnThenReleasesItAsAColumnReleasedAtZero) {
  const Scene gated = scene(kGate);
  BuildReport rep;
  build_particles(gated, &rep);
  ASSERT_EQ(rep.wall_by_solid.size(), 2u);
  const Index gate_particles = rep.wall_by_solid[1];
  EXPECT_GT(gate_particles, 3 * 30);  // 4 layers of 34
  std::vector<std::string> held_ov = kGate;
  held_ov.push_back("time.end=0.35");
  const RunResult g = run(scene(held_ov), "gate_held", "");
  ASSERT_FALSE(g.unstable) << g.failure;
  EXPECT_EQ(g.wall, rep.wall);
  const std::string log = runfiles::slurp("gate_held/run.log");
  EXPECT_NE(log.find("solid 'gate' removed (removed_at = 0.1 s), " +
                     std::to_string(gate_particles) + " boundary particles"),
            std::string::npos)
      << log;
  // The gate-free release over the same 0.25 s after opening.
  const RunResult f = run(scene({"time.end=0.25"}), "gate_free");
  ASSERT_FALSE(f.unstable) << f.failure;
  const auto held = fronts("gate_held"), free = fronts("gate_free");
  // Behind the gate until 0.1 s: the front stays at the column's face (last centres at 0.145).
  for (const auto& [t, x] : held) {
    if (t < 10) {
      EXPECT_LT(x, 0.146 + 0.005) << "t = " << t / 100.0;
    }
  }
  // After it: the released column's front, shifted by 0.1 s, within 1.5 dp.
  double worst = 0;
  int compared = 0;
  for (const auto& [t, x] : free) {
    if (!held.count(t + 10)) continue;
    worst = std::max(worst, std::fabs(held.at(t + 10) - x));
    ++compared;
  }
  std::printf(
      "gated vs free release: %d rows, largest front difference %.4f m; front at "
      "0.25 s after opening %.3f vs %.3f m\n",
      compared, worst, held.at(35), free.at(25));
  EXPECT_GE(compared, 25);
  EXPECT_LT(worst, 0.015);
  EXPECT_GT(free.at(25), 0.3);  // the comparison can fail: the front has travelled
}

TEST(Gate, RestartsAcrossTheOpeningBitIdentically) {
  const std::vector<std::string> ov = {kGate[0], "time.end=0.16", "checkpoint.every_time=0.04",
                                       "checkpoint.keep=10"};
  const RunResult a = run(scene(ov), "gate_straight");
  ASSERT_FALSE(a.unstable) << a.failure;
  const CheckpointData end_a = read_checkpoint(a.last_checkpoint);
  std::vector<std::string> cps;
  for (const auto& e : fs::directory_iterator("gate_straight"))
    if (e.path().extension() == ".h5") cps.push_back(e.path().string());
  std::sort(cps.begin(), cps.end());
  ASSERT_GE(cps.size(), 4u);  // t = 0.04, 0.08, 0.12, 0.16
  // One checkpoint before the opening (t = 0.04) and one after (t = 0.12).
  for (const std::string& from : {cps[0], cps[2]}) {
    SCOPED_TRACE(from);
    const CheckpointData c = read_checkpoint(from);
    const std::string dir = "gate_resumed";
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::copy_file(from, dir + "/" + fs::path(from).filename().string());
    const RunResult b = run(scene(ov), dir, "latest");
    ASSERT_FALSE(b.unstable) << b.failure;
    const CheckpointData end_b = read_checkpoint(b.last_checkpoint);
    EXPECT_EQ(end_a.counters.time, end_b.counters.time);
    const auto ma = runfiles::state_by_id(end_a), mb = runfiles::state_by_id(end_b);
    ASSERT_EQ(ma.size(), mb.size());
    std::size_t differ = 0;
    for (const auto& [id, bytes] : ma) differ += (!mb.count(id) || mb.at(id) != bytes);
    EXPECT_EQ(differ, 0u);
    // The checkpoint before the opening still holds the gate, the one after does not.
    EXPECT_EQ(c.particles.n_wall > end_a.particles.n_wall, c.counters.time < 0.1);
  }
}

}  // namespace
}  // namespace sphdem
