// Host and Device spaces run the same functors: after N steps of a small dam break, every
// particle (matched by global id) agrees to round-off. Skips without a GPU unless
// SPHDEM_REQUIRE_GPU=1, in which case a missing GPU is a failure.
#include <gtest/gtest.h>

#include <algorithm>
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
#include "cuda/device.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

bool gpu_available() {
  std::string why;
  const bool have = !cuda::list_gpus(&why).empty();
  const char* req = std::getenv("SPHDEM_REQUIRE_GPU");
  if (!have && req && std::string(req) == "1") {
    ADD_FAILURE() << "SPHDEM_REQUIRE_GPU=1 but no GPU is usable: " << why;
  }
  return have;
}

std::map<GlobalId, std::pair<Vec3, Real>> by_id(const ParticleSet<Host>& ps) {
  std::map<GlobalId, std::pair<Vec3, Real>> m;
  for (Index i = 0; i < ps.n_fluid; ++i) m[ps.id[i]] = {ps.pos[i], ps.rho[i]};
  return m;
}

TEST(GpuParity, DamBreakHostEqualsDevice) {
  if (!gpu_available()) GTEST_SKIP() << "no GPU";
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml", {"sph.dp=0.0073"});
  std::ostringstream log;
  auto host = make_solver(scene, Backend::kHost, log);
  auto dev = make_solver(scene, Backend::kDevice, log);
  ASSERT_STREQ(dev->space_name(), "device");
  // FMA contraction on the GPU changes the last bits of each step. Tolerances are in units of the
  // build's rounding (epsilon of Real): 1e-9 and 1e-6 dp in double, as before, and the same
  // multiple of epsilon in float.
  const double eps = double(std::numeric_limits<Real>::epsilon());
  const double dt_tol = std::max(1e-9, 1e3 * eps);
  const double pos_tol = std::max(1e-6, 1e3 * eps);
  double worst_dt = 0;
  for (int s = 0; s < 200; ++s) {
    const StepStats a = host->step();
    const StepStats b = dev->step();
    worst_dt = std::max(worst_dt, std::abs(double(a.dt - b.dt)) / double(a.dt));
    ASSERT_LE(std::abs(double(a.dt - b.dt)), dt_tol * double(a.dt)) << "step " << s;
  }
  const auto h = by_id(host->host_particles());
  const auto d = by_id(dev->host_particles());
  ASSERT_EQ(h.size(), d.size());
  const Real dp = scene.sph.dp;
  double worst_pos = 0, worst_rho = 0;
  for (const auto& [id, hv] : h) {
    const auto it = d.find(id);
    ASSERT_NE(it, d.end()) << "id " << id;
    worst_pos = std::max(worst_pos, double(norm(hv.first - it->second.first)) / double(dp));
    worst_rho = std::max(worst_rho, std::abs(double(hv.second - it->second.second)) / hv.second);
  }
  std::printf(
      "host vs device after 200 steps (%s): max |dt| rel %.3g, max |dx|/dp %.3g, "
      "max |drho|/rho %.3g\n",
      SPHDEM_PRECISION_NAME, worst_dt, worst_pos, worst_rho);
  EXPECT_LE(worst_pos, pos_tol);
  EXPECT_LE(worst_rho, pos_tol);
}

TEST(GpuParity, DeviceSortMatchesHostSort) {
  if (!gpu_available()) GTEST_SKIP() << "no GPU";
  // The cell order of both spaces is (cell, id): the id sequence after one step is identical.
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml", {"sph.dp=0.0073"});
  std::ostringstream log;
  auto host = make_solver(scene, Backend::kHost, log);
  auto dev = make_solver(scene, Backend::kDevice, log);
  host->step();
  dev->step();
  const auto& a = host->host_particles();
  const auto& b = dev->host_particles();
  ASSERT_EQ(a.size(), b.size());
  for (Index i = 0; i < a.size(); ++i) ASSERT_EQ(a.id[i], b.id[i]) << "slot " << i;
}

// Grains in a fluid on the device: the grain slots are posed in the execution space
// (pose_grains) and only the grain range comes back for the loads (grain_particles). 200 steps of
// the settling beads on the host and on the device: every bead's position and the fluid force on
// it (bodies.csv, last row) agree to round-off scaled by the steps.
std::map<long, std::vector<double>> last_rows(const std::string& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);  // header: t,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz
  std::map<long, std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    if (v.size() >= 17) rows[long(v[1])] = v;
  }
  return rows;
}

TEST(GpuParity, CoupledGrainsHostEqualsDevice) {
  if (!gpu_available()) GTEST_SKIP() << "no GPU";
  const Scene scene = load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/beads_settling.yaml",
                                 {"diagnostics.every=0.0005"});
  RunOptions o;
  o.max_steps = 200;
  o.quiet = true;
  o.handle_signals = false;
  o.backend = Backend::kHost;
  o.out_dir = "gpu_parity_grains_host";
  run_scene(scene, o);
  o.backend = Backend::kDevice;
  o.out_dir = "gpu_parity_grains_device";
  run_scene(scene, o);
  const auto h = last_rows("gpu_parity_grains_host/bodies.csv");
  const auto d = last_rows("gpu_parity_grains_device/bodies.csv");
  ASSERT_FALSE(h.empty());
  ASSERT_EQ(h.size(), d.size());
  const double eps = double(std::numeric_limits<Real>::epsilon());
  const double dp = double(scene.sph.dp);
  double worst_x = 0, worst_f = 0;
  for (const auto& [id, hv] : h) {
    const auto& dv = d.at(id);
    ASSERT_NEAR(hv[0], dv[0], 1e-9 * std::max(1.0, hv[0])) << "rows at different times";
    double fscale = 1e-12;
    for (int k = 11; k < 14; ++k) fscale = std::max(fscale, std::abs(hv[std::size_t(k)]));
    for (int k = 2; k < 5; ++k)
      worst_x = std::max(worst_x, std::abs(hv[std::size_t(k)] - dv[std::size_t(k)]) / dp);
    for (int k = 11; k < 14; ++k)
      worst_f = std::max(worst_f, std::abs(hv[std::size_t(k)] - dv[std::size_t(k)]) / fscale);
  }
  std::printf("grains host vs device after 200 steps (%s): max |dx|/dp %.3g, max |dF|/|F| %.3g\n",
              SPHDEM_PRECISION_NAME, worst_x, worst_f);
  EXPECT_LE(worst_x, std::max(1e-6, 1e3 * eps));
  EXPECT_LE(worst_f, std::max(1e-4, 1e4 * eps));
}

}  // namespace
}  // namespace sphdem
