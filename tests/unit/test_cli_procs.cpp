// --procs: the process grid for runs on many ranks. Parsed strictly, and refused when it asks for
// more ranks than the run has.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "app/simulation.hpp"
#include "core/error.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

TEST(Procs, ParsesThreeCounts) {
  EXPECT_EQ(parse_procs("2x1x3"), (std::array<int, 3>{2, 1, 3}));
  EXPECT_EQ(parse_procs("0,0,4"), (std::array<int, 3>{0, 0, 4}));
  EXPECT_EQ(parse_procs(""), (std::array<int, 3>{0, 0, 0}));
  for (const char* bad : {"2x1", "2x1x1x1", "ax1x1", "-1x1x1", "2.5x1x1"})
    EXPECT_THROW(parse_procs(bad), InputError) << bad;
}

TEST(Procs, MoreRanksThanTheRunHasIsRefused) {
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml", {"sph.dp=0.0146"});
  std::ostringstream log;
  try {
    make_solver(scene, Backend::kHost, log, nullptr, nullptr, {0, 1, 2});
    FAIL() << "--procs 0x1x2 on one rank was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("asks for 2 ranks, but this run has 1"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(make_solver(scene, Backend::kHost, log, nullptr, nullptr, {1, 1, 1}));
}

}  // namespace
}  // namespace sphdem
