// Grain packs given by solid volume fraction, and packs scattered at random through a box (the
// flume's boulders): the count follows from the fraction and the template volume, the grains lie
// inside the box without overlapping and spread through it, and impossible input is named.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"
#include "scene/build_dem.hpp"

namespace sphdem {
namespace {

// The flume's debris block (0.2 x 0.4 x 0.04327 m) with 16 mm glass beads.
std::string scene_text(const std::string& pack) {
  return R"(name: packs
dimension: 3
domain: {lo: [-0.3, -0.1, -0.1], hi: [0.2, 0.5, 0.3]}
time: {end: 0.1}
dem:
  grain_grain: {kn: 1e4, restitution: 0.5, friction: 0.3}
  grain_wall: {kn: 1e4, restitution: 0.5, friction: 0.3}
  shapes:
    - {name: bead, type: sphere, diameter: 0.016}
  packs:
    - )" +
         pack + "\n";
}

DemBuild build(const std::string& pack) {
  const Scene s = parse_scene(scene_text(pack), "packs.yaml");
  std::ostringstream log;
  return build_dem(s, log);
}

const char* kBox = "lo: [-0.2, 0, 0], hi: [0, 0.4, 0.04327]";

TEST(GrainPacks, FractionSetsTheCountFromTheTemplateVolume) {
  const double v_box = 0.2 * 0.4 * 0.04327;
  const double v_bead = M_PI / 6 * 0.016 * 0.016 * 0.016;
  // The seed's sweep read as boulder volume over debris volume: 2.7, 5.4, 13.3, 19.0 beads.
  const double fractions[] = {0.00167, 0.00334, 0.00822, 0.01176};
  const int expected[] = {3, 5, 13, 19};
  for (int k = 0; k < 4; ++k) {
    const DemBuild b = build("{shape: bead, fraction: " + std::to_string(fractions[k]) +
                             ", placement: random, density: 2500, " + kBox + "}");
    const auto& bodies = b.system->bodies();
    EXPECT_EQ(int(bodies.size()), expected[k]) << fractions[k];
    // The template's volume (integrated from its level set) is the sphere's to 1 %.
    EXPECT_NEAR(b.system->shape(0).volume(), v_bead, 0.01 * v_bead);
    EXPECT_EQ(int(bodies.size()),
              int(std::lround(fractions[k] * v_box / b.system->shape(0).volume())));
  }
}

TEST(GrainPacks, RandomPlacementFillsTheBoxWithoutOverlap) {
  const DemBuild b =
      build(std::string("{shape: bead, count: 60, placement: random, seed: 4, ") + kBox + "}");
  const auto& bodies = b.system->bodies();
  ASSERT_EQ(bodies.size(), 60u);
  const double r = b.system->shape(0).bounding_radius();
  double xmin = 1, xmax = -1, ymin = 1, ymax = -1;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Vec3 c = bodies[i].x;
    EXPECT_GE(c.x - r, -0.2 - 1e-12);
    EXPECT_LE(c.x + r, 1e-12);
    EXPECT_GE(c.y - r, -1e-12);
    EXPECT_LE(c.y + r, 0.4 + 1e-12);
    EXPECT_GE(c.z - r, -1e-12);
    EXPECT_LE(c.z + r, 0.04327 + 1e-12);
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT(norm(c - bodies[j].x), 2 * r);
    xmin = std::min(xmin, double(c.x));
    xmax = std::max(xmax, double(c.x));
    ymin = std::min(ymin, double(c.y));
    ymax = std::max(ymax, double(c.y));
  }
  // Spread through the box, not stacked from one corner as the shelf packing does.
  EXPECT_GT(xmax - xmin, 0.12);
  EXPECT_GT(ymax - ymin, 0.25);
  const DemBuild shelf = build(std::string("{shape: bead, count: 60, seed: 4, ") + kBox + "}");
  double shelf_ymax = -1;
  for (const auto& g : shelf.system->bodies()) shelf_ymax = std::max(shelf_ymax, double(g.x.y));
  EXPECT_LT(shelf_ymax, 0.1);
  // The same seed places the same grains.
  const DemBuild again =
      build(std::string("{shape: bead, count: 60, placement: random, seed: 4, ") + kBox + "}");
  for (std::size_t i = 0; i < bodies.size(); ++i)
    EXPECT_EQ(norm(again.system->bodies()[i].x - bodies[i].x), 0.0);
}

TEST(GrainPacks, ImpossiblePacksAreNamed) {
  auto message = [](const std::string& pack) {
    try {
      build(pack);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Far more beads than a 4 cm deep block holds at random.
  std::string m =
      message(std::string("{shape: bead, count: 2000, placement: random, ") + kBox + "}");
  EXPECT_NE(m.find("packs.yaml: dem.packs[0]"), std::string::npos) << m;
  EXPECT_NE(m.find("no room"), std::string::npos) << m;
  m = message(std::string("{shape: bead, count: 3, fraction: 0.01, ") + kBox + "}");
  EXPECT_NE(m.find("fraction"), std::string::npos) << m;
  EXPECT_NE(m.find("not both"), std::string::npos) << m;
  m = message(std::string("{shape: bead, fraction: 0.5, ") + kBox + "}");
  EXPECT_NE(m.find("fraction"), std::string::npos) << m;
  m = message(std::string("{shape: bead, fraction: 0.0001, ") + kBox + "}");
  EXPECT_NE(m.find("dem.packs[0]: fraction"), std::string::npos) << m;
  EXPECT_NE(m.find("less than half a grain"), std::string::npos) << m;
  m = message(std::string("{shape: bead, count: 3, placement: poisson, ") + kBox + "}");
  EXPECT_NE(m.find("placement"), std::string::npos) << m;
  EXPECT_NE(m.find("poisson"), std::string::npos) << m;
}

}  // namespace
}  // namespace sphdem
