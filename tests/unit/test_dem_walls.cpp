// Per-wall contact materials (DemSystem::set_wall_contact, dem.walls[i].friction/restitution):
// two floors side by side, one with its own restitution, each with a sphere dropped on it at
// 1 m/s without gravity. Each sphere must rebound with its own floor's coefficient (the linear
// dashpot and the Hertz damping both come from it), to 2 % (Chung & Ooi test 3's tolerance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "dem/dem_system.hpp"
#include "geometry/sdf.hpp"
#include "io/scene_yaml.hpp"
#include "scene/build_dem.hpp"
#include "precision.hpp"

namespace sphdem::dem {
namespace {

using test::tol;

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

// The load on each wall (DemSystem::wall_force, wall_mean_force: a barrier wall's load from
// boulders in impact_force.csv). A bead rolls down a floor under the flume's gravity (15° tilt)
// into a vertical wall; a polyhedral grain sits on the floor away from it. Checks:
//   - at every step the walls' loads are the grains' wall-contact forces reversed (no grain
//     touches another here, so these are all their contact forces);
//   - over any window of steps the walls' mean load is sum m g - sum m dv / T (momentum: the
//     leapfrog's velocity changes by dt (F/m + g)), to round-off;
//   - at rest that is the grains' weight, and the vertical wall takes a push along +x;
//   - state()/restore() keeps the mean (a restart reports what the run it continues would).
TEST(DemWalls, WallLoadIsTheGrainsContactForceReversed) {
  DemParams p;
  p.gravity = Vec3(2.5390, 0, -9.4757);
  p.grain_wall.kn = 1e4;
  p.grain_wall.restitution = 0.5;
  p.grain_wall.mu = 0.5;
  p.grain_wall.tangential_damping = true;
  p.grain_grain = p.grain_wall;
  p.nodes_per_contact = 20;
  DemSystem sys(p);
  const int floor = sys.add_sdf_wall(geom::make_box(Vec3(-1, -1, -1), Vec3(1, 1, 0)));
  const int side = sys.add_sdf_wall(geom::make_box(Vec3(0.1, -1, -1), Vec3(1, 1, 1)));
  const int lid = sys.add_plane_wall(Vec3(0, 0, 0.5), Vec3(0, 0, -1));  // never touched
  const Real r = 0.008;
  const int bead = sys.add_template(GrainTemplate::sphere(r));
  const int rock = sys.add_template(GrainTemplate::random_polyhedron(0.016, 12, 5));
  sys.add_body(bead, 2500, Vec3(0.05, 0, r));
  Real zmin = 1;
  for (const Vec3& n : sys.shape(rock).nodes()) zmin = std::min(zmin, n.z);
  sys.add_body(rock, 2500, Vec3(-0.1, 0, -zmin + 1e-4));
  double mass = 0;
  for (const RigidBody& b : sys.bodies()) mass += double(b.mass);
  const Real dt = sys.time_step();
  auto walls_sum = [&](bool mean) {
    Vec3 f;
    for (int w : {floor, side, lid}) f += mean ? sys.wall_mean_force(w) : sys.wall_force(w);
    return f;
  };
  // Before any step the mean is zero, not a division by zero.
  EXPECT_EQ(norm(sys.wall_mean_force(floor)), 0);
  auto momentum = [&]() {
    Vec3 m;
    for (const RigidBody& b : sys.bodies()) m += b.mass * b.v;
    return m;
  };
  // The first 0.05 s: the bead rolls off and gains speed, so the mean load is not the weight.
  {
    const Vec3 m0 = momentum();
    const Real t0 = sys.time();
    while (sys.time() < 0.05) sys.step(dt);
    const Real T = sys.time() - t0;
    const Vec3 expect = Real(mass) * p.gravity - (momentum() - m0) / T;
    EXPECT_LT(norm(walls_sum(true) - expect), tol(1e-9, 1e-4) * mass * 9.81);
    EXPECT_GT(norm(walls_sum(true) - Real(mass) * p.gravity), 0.02 * mass * 9.81);
  }
  double worst_balance = 0;
  while (sys.time() < 0.6) {
    sys.step(dt);
    const Vec3 grains = sys.force(0) + sys.force(1);
    worst_balance = std::max(worst_balance, double(norm(walls_sum(false) + grains)));
  }
  // Round-off of summing a few node forces of size m g.
  EXPECT_LT(worst_balance, tol(1e-12, 1e-5) * mass * 9.81);
  EXPECT_EQ(norm(sys.wall_force(lid)), 0);
  // A window of 200 steps at rest, from a reset.
  const Vec3 m0 = momentum();
  sys.reset_wall_impulse();
  const Real t0 = sys.time();
  for (int k = 0; k < 200; ++k) sys.step(dt);
  const Vec3 expect = Real(mass) * p.gravity - (momentum() - m0) / (sys.time() - t0);
  const Vec3 mean = walls_sum(true);
  std::printf(
      "walls' mean load at rest (%.4f, %.4f, %.4f) N; weight (%.4f, %.4f, %.4f) N; "
      "vertical wall (%.4f, %.4f, %.4f) N; bead at x = %.5f m\n",
      double(mean.x), double(mean.y), double(mean.z), mass * p.gravity.x, 0.0, mass * p.gravity.z,
      double(sys.wall_mean_force(side).x), double(sys.wall_mean_force(side).y),
      double(sys.wall_mean_force(side).z), double(sys.bodies()[0].x.x));
  EXPECT_LT(norm(mean - expect), tol(1e-9, 1e-4) * mass * 9.81);
  EXPECT_LT(norm(mean - Real(mass) * p.gravity), 0.005 * mass * 9.81);  // at rest
  EXPECT_NEAR(sys.bodies()[0].x.x, 0.1 - r, 1e-4);  // the bead leans on the vertical wall
  EXPECT_GT(sys.wall_mean_force(side).x, 0.5 * sys.bodies()[0].mass * p.gravity.x);
  // Restore into a twin built the same way: the same mean, then the same loads on.
  DemSystem twin(p);
  twin.add_sdf_wall(geom::make_box(Vec3(-1, -1, -1), Vec3(1, 1, 0)));
  twin.add_sdf_wall(geom::make_box(Vec3(0.1, -1, -1), Vec3(1, 1, 1)));
  twin.add_plane_wall(Vec3(0, 0, 0.5), Vec3(0, 0, -1));
  twin.add_template(GrainTemplate::sphere(r));
  twin.add_template(GrainTemplate::random_polyhedron(0.016, 12, 5));
  twin.add_body(bead, 2500, Vec3(0, 0, 1));
  twin.add_body(rock, 2500, Vec3(0, 0, 2));
  twin.restore(sys.state());
  for (int w : {floor, side, lid})
    EXPECT_EQ(norm(twin.wall_mean_force(w) - sys.wall_mean_force(w)), 0) << w;
  // A state with a wrong number of wall impulses is refused.
  DemState bad = sys.state();
  bad.wall_impulse.pop_back();
  EXPECT_THROW(twin.restore(bad), InputError);
}

}  // namespace
}  // namespace sphdem::dem
