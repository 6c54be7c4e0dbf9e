// Per-wall contact materials (DemSystem::set_wall_contact, dem.walls[i].friction/restitution):
// two floors side by side, one with its own restitution, each with a sphere dropped on it at
// 1 m/s without gravity. Each sphere must rebound with its own floor's coefficient (the linear
// dashpot and the Hertz damping both come from it), to 2 % (Chung & Ooi test 3's tolerance).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"
#include "dem/dem_system.hpp"
#include "geometry/sdf.hpp"
#include "io/scene_yaml.hpp"
#include "scene/build_dem.hpp"

namespace sphdem::dem {
namespace {

struct Rebound {
  double e_plain = 0, e_own = 0;
};

// Floor A (x < 0) keeps grain_wall's restitution e_model; floor B (x > 0.5) has its own e_wall.
Rebound drop_on_two_floors(bool hertz, Real e_model, Real e_wall) {
  DemParams p;
  p.gravity = Vec3(0, 0, 0);
  p.grain_wall.restitution = e_model;
  p.grain_wall.mu = 0.3;
  if (hertz) {
    p.grain_wall.law = NormalLaw::kHertz;
    p.grain_wall.young = 7e10;
    p.grain_wall.poisson = 0.3;
    p.reference_speed = 1;
  } else {
    p.grain_wall.kn = 1e4;
  }
  p.grain_grain = p.grain_wall;
  DemSystem sys(p);
  sys.add_sdf_wall(geom::make_box(Vec3(-1, -1, -1), Vec3(0, 1, 0)));
  const int own = sys.add_sdf_wall(geom::make_box(Vec3(0.5, -1, -1), Vec3(1.5, 1, 0)));
  sys.set_wall_contact(own, -1, e_wall);
  const Real r = 0.01;
  const int s = sys.add_template(GrainTemplate::sphere(r));
  sys.add_body(s, 2500, Vec3(-0.5, 0, r + 1e-3), Quat(), Vec3(0, 0, -1));
  sys.add_body(s, 2500, Vec3(1.0, 0, r + 1e-3), Quat(), Vec3(0, 0, -1));
  const Real dt = sys.time_step() / 4;  // t_c / 200
  while (sys.time() < 0.02) sys.step(dt);
  Rebound out;
  out.e_plain = sys.bodies()[0].v.z;
  out.e_own = sys.bodies()[1].v.z;
  return out;
}

TEST(DemWalls, EachFloorReboundsWithItsOwnRestitution) {
  for (bool hertz : {false, true}) {
    const Rebound b = drop_on_two_floors(hertz, 0.3, 0.8);
    std::printf("%s: rebound %.4f on grain_wall's e = 0.3, %.4f on the wall's own 0.8\n",
                hertz ? "hertz" : "linear", b.e_plain, b.e_own);
    EXPECT_NEAR(b.e_plain, 0.3, 0.02 * 0.3) << (hertz ? "hertz" : "linear");
    EXPECT_NEAR(b.e_own, 0.8, 0.02 * 0.8) << (hertz ? "hertz" : "linear");
  }
}

TEST(DemWalls, BadWallMaterialIsRefused) {
  DemParams p;
  p.grain_wall.kn = p.grain_grain.kn = 1e4;
  DemSystem sys(p);
  const int w = sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  EXPECT_THROW(sys.set_wall_contact(w, 0.3, 1.5), InputError);
  EXPECT_THROW(sys.set_wall_contact(w, std::nan(""), -1), InputError);
  EXPECT_THROW(sys.set_wall_contact(w + 1, 0.3, 0.5), InputError);
  sys.set_wall_contact(w, 0.3, 0.5);
  EXPECT_DOUBLE_EQ(sys.walls()[std::size_t(w)].mu, Real(0.3));
  sys.set_wall_contact(w, -1, -1);  // back to grain_wall's
  EXPECT_LT(sys.walls()[std::size_t(w)].mu, 0);
  EXPECT_LT(sys.walls()[std::size_t(w)].restitution, 0);
}

// The scene keys reach the right walls: the floor keeps grain_wall's, the lid gets its own.
TEST(DemWalls, SceneKeysSetEachWallsMaterial) {
  const char* text = R"(name: walls
dimension: 3
domain: {lo: [-0.1, -0.1, -0.1], hi: [0.2, 0.2, 0.3]}
time: {end: 0.1}
solids:
  - {name: floor, shape: {type: box, lo: [-0.05, -0.05, -0.05], hi: [0.15, 0.15, 0]}}
  - {name: lid, shape: {type: box, lo: [-0.05, -0.05, 0.2], hi: [0.15, 0.15, 0.25]}}
dem:
  grain_grain: {kn: 1e4, restitution: 0.5, friction: 0.3}
  grain_wall: {kn: 1e4, restitution: 0.5, friction: 0.3}
  shapes:
    - {name: bead, type: sphere, diameter: 0.016}
  bodies:
    - {shape: bead, position: [0.05, 0.05, 0.1]}
  walls:
    - {solid: floor}
    - {solid: lid, friction: 0.9, restitution: 0.2}
)";
  const Scene s = parse_scene(text, "walls.yaml");
  ASSERT_EQ(s.dem.walls.size(), 2u);
  std::ostringstream log;
  const DemBuild d = build_dem(s, log);
  const Wall& floor = d.system->walls()[std::size_t(d.wall_index[0])];
  const Wall& lid = d.system->walls()[std::size_t(d.wall_index[1])];
  EXPECT_LT(floor.mu, 0);
  EXPECT_LT(floor.restitution, 0);
  EXPECT_DOUBLE_EQ(lid.mu, Real(0.9));  // the scene's values, stored as read
  EXPECT_DOUBLE_EQ(lid.restitution, Real(0.2));
  EXPECT_DOUBLE_EQ(lid.zeta, damping_ratio_from_restitution(0.2));
}

}  // namespace
}  // namespace sphdem::dem
