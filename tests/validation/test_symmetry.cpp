// A symmetry plane (issue #6 §3: "offer a symmetry plane, and show the mirrored force agrees
// with the full run"). tests/data/pillar_3d.yaml is a 3D dam break hitting a square pillar on
// the tank's centre plane y = 0.1; the lattice and the walls are symmetric about it. The run
// with `symmetry: {axis: y, at: 0.1}` models half of it. Because the full run stays symmetric
// to round-off, the mirrored half must reproduce the full run's diagnostics (the pillar force,
// the energy and momentum, the front and a height gauge) to the CSV's 10 digits, at about half
// the cost. A wrong mirror shows at once: the first version, which left the mirror fluid's share
// out of the wall forces, gave a pillar force 15 % off with the fluid identical.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_yaml.hpp"
#include "scene/build.hpp"
#include "validation/run_files.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;
using runfiles::read_numeric_csv;

const std::string kPillar = std::string(SPHDEM_TEST_DATA) + "/pillar_3d.yaml";

RunResult run(const Scene& s, const std::string& out) {
  return runfiles::run_host(s, out);
}

// Largest difference of column c between two runs' rows, over the larger column magnitude.
double max_relative_difference(const std::vector<std::vector<double>>& a,
                               const std::vector<std::vector<double>>& b, std::size_t c,
                               double* scale_out = nullptr) {
  double scale = 0, diff = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    scale = std::max({scale, std::abs(a[i][c]), std::abs(b[i][c])});
    diff = std::max(diff, std::abs(a[i][c] - b[i][c]));
  }
  if (scale_out) *scale_out = scale;
  return scale > 0 ? diff / scale : diff;
}

TEST(Symmetry, MirroredHalfReproducesTheFullRun) {
  // The front reaches the pillar at 0.07 s and the force peaks at 0.09 s.
  const Scene full = load_scene(kPillar, {"frames.every=0", "time.end=0.12"});
  const Scene half =
      load_scene(kPillar, {"frames.every=0", "time.end=0.12", "symmetry={axis: y, at: 0.1}"});
  BuildReport rf, rh;
  build_particles(full, &rf);
  build_particles(half, &rh);
  ASSERT_EQ(2 * rh.fluid, rf.fluid);
  ASSERT_EQ(rh.symmetry_unmatched, 0);
  const RunResult a = run(full, "symmetry_full");
  ASSERT_FALSE(a.unstable) << a.failure;
  const RunResult b = run(half, "symmetry_half");
  ASSERT_FALSE(b.unstable) << b.failure;

  const auto fa = read_numeric_csv("symmetry_full/pillar_force.csv");
  const auto fb = read_numeric_csv("symmetry_half/pillar_force.csv");
  ASSERT_EQ(fa.size(), fb.size());
  ASSERT_GE(fa.size(), 12u);
  double peak = 0;
  // fx (the impact) and fz: the mirrored half gives the full pillar's force. The pillar is hit
  // (peak above 1 N) well before the end, so the comparison covers the impact.
  EXPECT_LT(max_relative_difference(fa, fb, 1, &peak), 1e-8);
  EXPECT_GT(peak, 1.0);
  EXPECT_LT(max_relative_difference(fa, fb, 3), 1e-8);
  // fy of the symmetric pillar is zero: round-off in the full run, the sum of the modelled
  // part and its image in the half.
  for (const auto& r : fb) EXPECT_LT(std::abs(r[2]), 1e-9 * peak);

  const auto ea = read_numeric_csv("symmetry_full/energy.csv");
  const auto eb = read_numeric_csv("symmetry_half/energy.csv");
  ASSERT_EQ(ea.size(), eb.size());
  for (std::size_t c : {1u, 2u, 4u, 6u}) EXPECT_LT(max_relative_difference(ea, eb, c), 1e-8) << c;
  const auto xa = read_numeric_csv("symmetry_full/front.csv");
  const auto xb = read_numeric_csv("symmetry_half/front.csv");
  EXPECT_LT(max_relative_difference(xa, xb, 1), 1e-8);
  const auto ha = read_numeric_csv("symmetry_full/h_mid.csv");
  const auto hb = read_numeric_csv("symmetry_half/h_mid.csv");
  double hmax = 0;
  EXPECT_LT(max_relative_difference(ha, hb, 1, &hmax), 1e-8);
  EXPECT_GT(hmax, 0.01);  // the gauge on the plane is wet
}

// A restart of a half run continues bit-identically: the mirror halo is rebuilt from the
// checkpoint's fluid, and the checkpoint's checksum covers what is written (it summed the halo
// copies too at first, and the restart refused the file as corrupted). The CSV series continue
// without repeating the rows written after the checkpoint (they were appended twice before).
TEST(Symmetry, HalfRunRestartsBitIdentically) {
  const Scene half =
      load_scene(kPillar, {"frames.every=0", "time.end=0.03", "checkpoint.every_time=0.015",
                           "symmetry={axis: y, at: 0.1}"});
  const RunResult a = run(half, "symmetry_restart_a");
  ASSERT_FALSE(a.unstable) << a.failure;
  std::vector<std::string> cps;
  for (const auto& e : fs::directory_iterator("symmetry_restart_a"))
    if (e.path().extension() == ".h5") cps.push_back(e.path().string());
  std::sort(cps.begin(), cps.end());
  ASSERT_EQ(cps.size(), 2u);
  fs::remove_all("symmetry_restart_b");
  fs::create_directories("symmetry_restart_b");
  const std::string first = "symmetry_restart_b/" + fs::path(cps[0]).filename().string();
  fs::copy_file(cps[0], first);
  // The series as a run that died after its last checkpoint leaves them: rows past the first
  // checkpoint. The restart drops those and writes them again, so the files end as run A's.
  fs::copy_file("symmetry_restart_a/energy.csv", "symmetry_restart_b/energy.csv");
  fs::copy_file("symmetry_restart_a/pillar_force.csv", "symmetry_restart_b/pillar_force.csv");
  const RunResult b = runfiles::run_host(half, "symmetry_restart_b", -1, first);
  ASSERT_FALSE(b.unstable) << b.failure;
  const std::string last = "symmetry_restart_b/" + fs::path(cps[1]).filename().string();
  ASSERT_TRUE(fs::exists(last));
  const auto sa = runfiles::state_by_id(read_checkpoint(cps[1]));
  const auto sb = runfiles::state_by_id(read_checkpoint(last));
  ASSERT_EQ(sa.size(), sb.size());
  EXPECT_TRUE(sa == sb);
  EXPECT_EQ(runfiles::slurp("symmetry_restart_b/energy.csv"),
            runfiles::slurp("symmetry_restart_a/energy.csv"));
  EXPECT_EQ(runfiles::slurp("symmetry_restart_b/pillar_force.csv"),
            runfiles::slurp("symmetry_restart_a/pillar_force.csv"));
  EXPECT_EQ(read_numeric_csv("symmetry_restart_b/energy.csv").size(), 4u);  // t = 0 ... 0.03
}

}  // namespace
}  // namespace sphdem
