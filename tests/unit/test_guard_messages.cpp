// What the Mach guard says about where its fastest particle is (near_solid_text): a particle
// squeezed into one of the flume's thin barrier walls is named as inside that wall, with the
// wall's thickness against the boundary depth and the leak it allows; one 2 dp off that wall
// gets the thickness without the leak; a particle near a thick wall gets its distance only; a
// particle away from every solid gets nothing.
#include <gtest/gtest.h>

#include <string>

#include "diagnostics/guards.hpp"
#include "io/scene_yaml.hpp"
#include "scene/build.hpp"

namespace sphdem {
namespace {

TEST(GuardMessages, NearSolidTextNamesTheThinWallAParticleIsIn) {
  const Scene scene = load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/flume/flume.yaml",
                                 {"sph.dp=0.00714285714", "barrier.preset=V30"});
  BuildReport rep;
  build_particles(scene, &rep);
  ASSERT_FALSE(rep.thin.empty());  // the 13 mm walls at dp = 7.14 mm (2h = 24.7 mm)
  const Real depth = rep.boundary_depth;
  ASSERT_NEAR(depth, 2 * std::sqrt(3.0) * 0.00714285714, 1e-9);

  const Solid* wall = scene.find_solid("barrier_4");
  ASSERT_NE(wall, nullptr);
  const geom::Aabb b = wall->sdf->bounds();
  const Vec3 centre = (b.lo + b.hi) * Real(0.5);  // the middle wall's centre: 6.5 mm deep
  const Real phi = wall->sdf->phi(centre);
  ASSERT_NEAR(phi, -0.0065, 1e-6);
  const std::string in = near_solid_text(scene, 0, centre, depth, rep.thin, depth);
  EXPECT_NE(in.find("; it is 6.5 mm inside solid 'barrier_4'"), std::string::npos) << in;
  EXPECT_NE(in.find("which is 13 mm thick, less than the boundary depth 24.7436 mm"),
            std::string::npos)
      << in;
  EXPECT_NE(in.find("lets fluid be pressed into it and shot out"), std::string::npos) << in;

  // Off the wall's upstream face: within dp of it the leak is named; 2 dp away the thickness is
  // stated but the particle is not one pressed into the wall.
  // (The wall stands across the inclined channel: the points are found along -x by bisection.)
  const Real dp = scene.sph.dp;
  const auto upstream_at = [&](Real target) {
    Real a = 0, b = Real(0.1);
    for (int it = 0; it < 60; ++it) {
      const Real m = Real(0.5) * (a + b);
      (wall->sdf->phi(centre - Vec3(m, 0, 0)) < target ? a : b) = m;
    }
    return centre - Vec3(Real(0.5) * (a + b), 0, 0);
  };
  const Vec3 near_face = upstream_at(Real(0.75) * dp);
  ASSERT_NEAR(wall->sdf->phi(near_face), 0.75 * dp, 1e-9);
  const std::string pressed_in = near_solid_text(scene, 0, near_face, depth, rep.thin, depth);
  EXPECT_NE(pressed_in.find("from the surface of solid 'barrier_4', which is 13 mm thick, less "
                            "than the boundary depth 24.7436 mm: its truncated boundary lets "
                            "fluid be pressed into it and shot out"),
            std::string::npos)
      << pressed_in;
  const Vec3 away = upstream_at(2 * dp);
  ASSERT_NEAR(wall->sdf->phi(away), 2 * dp, 1e-9);
  const std::string far = near_solid_text(scene, 0, away, depth, rep.thin, depth);
  EXPECT_EQ(far,
            "; it is 14.2857 mm from the surface of solid 'barrier_4', which is 13 mm thick, less "
            "than the boundary depth 24.7436 mm (the particle is 2 dp from it, farther than a "
            "particle pressed into it)")
      << far;

  // 10 mm above the channel's floor, upstream of the barrier: the channel (25 mm, not thin).
  const std::string floor = near_solid_text(scene, 0, Vec3(0.3, 0.2, 0.01), depth, rep.thin, depth);
  EXPECT_EQ(floor, "; it is 10 mm from the surface of solid 'channel'") << floor;

  // 1 mm above the floor: nearer than the first fluid layer's dp/2.
  const std::string pressed =
      near_solid_text(scene, 0, Vec3(0.3, 0.2, 0.001), depth, rep.thin, depth);
  EXPECT_EQ(pressed,
            "; it is 1 mm from the surface of solid 'channel' (nearer than dp/2 = 3.57143 mm, "
            "where the first fluid layer sits)")
      << pressed;

  // Mid-channel, 0.15 m from the floor and 0.2 m from either side wall: no solid within 2h.
  EXPECT_EQ(near_solid_text(scene, 0, Vec3(0.3, 0.2, 0.15), depth, rep.thin, depth), "");
}

}  // namespace
}  // namespace sphdem
