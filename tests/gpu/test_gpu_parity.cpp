// Host and Device spaces run the same functors: after N steps of a small dam break, every
// particle (matched by global id) agrees to round-off. Skips without a GPU unless
// SPHDEM_REQUIRE_GPU=1, in which case a missing GPU is a failure.
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <sstream>

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
  for (int s = 0; s < 200; ++s) {
    const StepStats a = host->step();
    const StepStats b = dev->step();
    ASSERT_NEAR(a.dt, b.dt, 1e-9 * a.dt) << "step " << s;
  }
  const auto h = by_id(host->host_particles());
  const auto d = by_id(dev->host_particles());
  ASSERT_EQ(h.size(), d.size());
  const Real dp = scene.sph.dp;
  for (const auto& [id, hv] : h) {
    const auto it = d.find(id);
    ASSERT_NE(it, d.end()) << "id " << id;
    // FMA contraction on the GPU changes the last bits; 200 steps keep that far below dp.
    EXPECT_NEAR(norm(hv.first - it->second.first), 0, 1e-6 * dp) << "id " << id;
    EXPECT_NEAR(hv.second, it->second.second, 1e-6 * hv.second) << "id " << id;
  }
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

}  // namespace
}  // namespace sphdem
