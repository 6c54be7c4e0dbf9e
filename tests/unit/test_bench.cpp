// `sphdem bench` (app/bench.cpp): scenes with grains run through the run loop, so the DEM and the
// coupling phases are timed; the phases do not overlap; bad options are refused by name.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <sstream>
#include <string>

#include "app/bench.hpp"
#include "core/error.hpp"
#include "core/types.hpp"

namespace sphdem {
namespace {

std::string input(const std::string& name) {
  return std::string(SPHDEM_SOURCE_DIR) + "/inputs/" + name;
}

// The number after `"key": ` in `text`: in the object `"after": {...}` (a phase), or at the top
// level when `after` is empty.
double number(const std::string& text, const std::string& key, const std::string& after = "") {
  const std::size_t from = after.empty() ? 0 : text.find("\"" + after + "\": {");
  EXPECT_NE(from, std::string::npos) << after;
  std::smatch m;
  const std::string tail = text.substr(from);
  const std::regex re("\"" + key + "\": ([-+0-9.eE]+)");
  EXPECT_TRUE(std::regex_search(tail, m, re)) << key << " after " << after << " in\n" << text;
  return m.empty() ? 0 : std::stod(m[1].str());
}

std::string bench_json(BenchOptions o) {
  o.json = true;
  o.backend = Backend::kHost;
  std::ostringstream os;
  run_bench(o, os);
  return os.str();
}

constexpr const char* kPhases[] = {"cell_list", "dem_contacts", "coupling",
                                   "mdbc",      "fluid_forces", "integration",
                                   "halo",      "io",           "guards"};

double phase_sum(const std::string& j) {
  double sum = 0;
  for (const char* p : kPhases) {
    const double s = number(j, "seconds_per_step", p);
    EXPECT_GE(s, 0) << p;
    sum += s;
  }
  return sum;
}

TEST(Bench, GrainOnlySceneTimesTheDem) {
  BenchOptions o;
  o.scene_path = input("sphere_pile.yaml");
  o.warmup = 2;
  o.steps = 20;
  const std::string j = bench_json(o);
  EXPECT_EQ(number(j, "grains"), 300);
  EXPECT_EQ(number(j, "fluid_particles"), 0);
  EXPECT_GT(number(j, "seconds_per_step", "dem_contacts"), 0);
  EXPECT_EQ(number(j, "seconds_per_step", "fluid_forces"), 0);
  EXPECT_GT(number(j, "grain_steps_per_second"), 0);
  // Phases are disjoint parts of the step.
  EXPECT_LE(phase_sum(j), number(j, "seconds_per_step") * (1 + 1e-9));
}

TEST(Bench, CoupledSceneTimesFluidDemAndCoupling) {
  BenchOptions o;
  o.scene_path = input("floating_box.yaml");
  o.warmup = 1;
  o.steps = 3;
  const auto tmp =
      std::filesystem::temp_directory_path() /
      ("sphdem_test_bench_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::remove_all(tmp);
  o.out_dir = tmp.string();
  const std::string j = bench_json(o);
  EXPECT_EQ(number(j, "grains"), 1);
  EXPECT_GT(number(j, "fluid_particles"), 1000);
  EXPECT_GT(number(j, "pairs_per_step"), number(j, "fluid_particles"));
  for (const char* p :
       {"cell_list", "mdbc", "fluid_forces", "dem_contacts", "coupling", "integration", "guards"})
    EXPECT_GT(number(j, "seconds_per_step", p), 0) << p;
  EXPECT_GT(number(j, "pips", "fluid_forces"), 0);
  // The traffic model covers the fluid phases only, and their rates follow from it.
  for (const char* p : {"cell_list", "mdbc", "fluid_forces", "integration"}) {
    const double bytes = number(j, "model_bytes_per_step", p);
    EXPECT_GT(bytes, 0) << p;
    EXPECT_NEAR(number(j, "gbs", p), bytes / number(j, "seconds_per_step", p) / 1e9,
                1e-5 * number(j, "gbs", p))
        << p;
  }
  EXPECT_EQ(number(j, "model_bytes_per_step", "dem_contacts"), 0);
  // Verlet streams 7 vectors and 5 scalars per fluid particle (position, velocity, previous
  // velocity, density, previous density in and out; acceleration and density rate in).
  // (The JSON has 6 significant digits.)
  const double verlet = number(j, "fluid_particles") * 26 * double(sizeof(Real));
  EXPECT_NEAR(number(j, "model_bytes_per_step", "integration"), verlet, 1e-5 * verlet);
  EXPECT_LE(phase_sum(j), number(j, "seconds_per_step") * (1 + 1e-9));
  // The run went to the given folder, as `sphdem run` would have written it.
  EXPECT_TRUE(std::filesystem::exists(tmp / "run.log"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "summary.json"));
  std::filesystem::remove_all(tmp);
}

TEST(Bench, RefusesBadStepCountsAndAnEndBeforeTheSteps) {
  BenchOptions o;
  o.scene_path = input("sphere_pile.yaml");
  o.steps = 0;
  try {
    bench_json(o);
    FAIL() << "--steps 0 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--steps"), std::string::npos) << e.what();
  }
  // A run folder for a fluid-only scene would never be written: refused, not ignored.
  BenchOptions f;
  f.scene_path = input("dam_break_2d.yaml");
  f.out_dir = "unused_bench_folder";
  try {
    bench_json(f);
    FAIL() << "--out on a fluid-only scene was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--out"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dam_break_2d"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists("unused_bench_folder"));
  o.steps = 5;
  o.warmup = 0;
  o.overrides = {"time.end=1e-5"};  // a handful of DEM steps
  try {
    bench_json(o);
    FAIL() << "a scene that ends before the timed steps was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("time.end"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sphere_pile"), std::string::npos) << e.what();
  }
  // A grain-only run that stops at rest before the timed steps names the check, not time.end.
  o.steps = 1000000;
  o.overrides = {"dem.stop_at_rest={after: 0, kinetic_energy: 1.0e3}"};
  try {
    bench_json(o);
    FAIL() << "a scene that came to rest before the timed steps was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("dem.stop_at_rest"), std::string::npos) << what;
    EXPECT_NE(what.find("came to rest"), std::string::npos) << what;
    EXPECT_EQ(what.find("raise time.end"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace sphdem
