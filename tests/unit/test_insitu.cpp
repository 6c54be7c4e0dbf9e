// The in-situ scene section and adaptor selection (io/insitu.hpp). The Catalyst runs themselves
// are in tests/catalyst/ (built with SPHDEM_ENABLE_CATALYST=ON).
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.hpp"
#include "io/insitu.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";

TEST(InSitu, ScriptsResolveAgainstTheSceneFolder) {
  const Scene s = load_scene(kScene, {"insitu={scripts: [catalyst/impact_force.py, "
                                      "catalyst/runup.py], every_steps: 25}"});
  ASSERT_EQ(s.insitu.scripts.size(), 2u);
  EXPECT_EQ(std::filesystem::path(s.insitu.scripts[0]),
            std::filesystem::path(SPHDEM_SOURCE_DIR) / "inputs/catalyst/impact_force.py");
  EXPECT_EQ(s.insitu.every_steps, 25);
  EXPECT_TRUE(load_scene(kScene).insitu.scripts.empty());  // off unless asked for
}

TEST(InSitu, WithoutScriptsTheAdaptorDoesNothing) {
  const auto a = make_insitu_adaptor(load_scene(kScene), "insitu_null");
  EXPECT_EQ(a->name(), "none");
  for (std::int64_t step : {0, 1, 10, 1000}) EXPECT_FALSE(a->due(step));
  EXPECT_FALSE(std::filesystem::exists("insitu_null/catalyst"));
}

TEST(InSitu, ScriptsWithoutCatalystAreRefused) {
  if (catalyst_compiled()) GTEST_SKIP() << "this build has Catalyst (tests/catalyst covers it)";
  const Scene s = load_scene(kScene, {"insitu={scripts: [catalyst/runup.py]}"});
  try {
    make_insitu_adaptor(s, "insitu_refused");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              kScene +
                  ": insitu: this sphdem was built without Catalyst; rebuild with "
                  "-DSPHDEM_ENABLE_CATALYST=ON (ParaView 5.11: paraview-dev python3-paraview), or "
                  "remove the insitu section");
  }
}

}  // namespace
}  // namespace sphdem
