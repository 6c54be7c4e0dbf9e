// Slit-type barrier layouts (seed §4.1, Fig. 17): wall placement, opening ratio, solids.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"
#include "diagnostics/probes.hpp"
#include "precision.hpp"
#include "scene/barrier.hpp"
#include "scene/build.hpp"
#include "solver/fluid_params.hpp"

namespace sphdem {
namespace {

using test::kFloatEps;
using test::tol;

// Water (1000 kg/m^3) at rest on the lattice (i + 1/2, j + 1/2, k + 1/2 + shift) dp, nx x ny x nz.
ParticleSet<Host> water_lattice(int nx, int ny, int nz, Real dp, Real shift = 0) {
  ParticleSet<Host> ps;
  ps.n_fluid = Index(nx) * ny * nz;
  ps.resize(ps.size());
  Index n = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k, ++n) {
        ps.pos[n] = Vec3((i + 0.5) * dp, (j + 0.5) * dp, (k + 0.5 + shift) * dp);
        ps.mass[n] = 1000 * dp * dp * dp;
        ps.rho[n] = 1000;
        ps.body[n] = -1;
      }
  return ps;
}

Barrier preset(const std::string& name) {
  Barrier b;
  b.enabled = true;
  EXPECT_TRUE(apply_barrier_preset(b, name)) << name;
  b.x = 0.6;
  return b;
}

// Seven 50 mm walls across 400 mm: P00 leaves 50 mm open. Turned walls cast a shadow
// w |cos a| + t |sin a| on the cross-channel axis; with 7 walls on a 400/7 mm pitch that gives the
// seed's V-type ratios 0.128 (30°) and 0.220 (45°) exactly. The seed's P30 and P45 (0.485,
// 0.613) are not reproduced by any turn of these walls (docs/STUDIES.md): projected, P30 = V30.
TEST(Barrier, OpeningRatiosOfThePresets) {
  const Real w = 0.05, t = 0.013, W = 0.4;
  auto projected = [&](Real deg) {
    const Real a = deg * kPi / 180;
    return 1 - 7 * (w * std::cos(a) + t * std::sin(a)) / W;
  };
  // Float: the ratio is 1 - covered / W, with covered a sum of 7 shadow lengths, each the
  // difference of two shadow ends of size <= W that carry a few roundings (pitch, centre, cos/sin,
  // half-extent); so covered / W, and the test's own projected(), carry <= ~16 eps.
  const double ratio_tol = tol(1e-12, 16 * kFloatEps);
  EXPECT_NEAR(barrier_opening_ratio(preset("P00")), 0.125, ratio_tol);
  EXPECT_NEAR(barrier_opening_ratio(preset("V30")), projected(30), ratio_tol);
  EXPECT_NEAR(barrier_opening_ratio(preset("V45")), projected(45), ratio_tol);
  EXPECT_NEAR(barrier_opening_ratio(preset("V30")), 0.128, 0.0005);  // the seed's values
  EXPECT_NEAR(barrier_opening_ratio(preset("V45")), 0.220, 0.0005);
  EXPECT_NEAR(barrier_opening_ratio(preset("P30")), projected(30), ratio_tol);
  EXPECT_NEAR(barrier_opening_ratio(preset("P45")), projected(45), ratio_tol);
}

// Overlapping shadows are counted once: walls wider than the pitch close the channel, not more.
TEST(Barrier, OverlappingWallsAreCountedOnce) {
  Barrier b = preset("P00");
  b.width = 0.08;  // 7 x 80 mm = 560 mm > 400 mm
  EXPECT_NEAR(barrier_opening_ratio(b), 0.0, 1e-12);
  b.walls = 1;
  b.width = 0.1;
  EXPECT_NEAR(barrier_opening_ratio(b), 0.75, 1e-12);
}

// The opening as the lattice resolves it, on the flume's P00 build. At dp = 5 mm no wall face is
// on a lattice row, so a column is blocked exactly when its centre lies inside a wall's y-range:
// counted here from the geometry alone, 10 columns per 50 mm wall, 10 of 80 open, and every gap
// (6 slits of 7.1 mm, two 3.6 mm side gaps) holds at least one. At 10 mm the middle wall's faces
// (0.175, 0.225 m) lie on rows and the build keeps both: 6 + 6 x 5 = 36 of 40 columns blocked, and
// the gaps beside the middle wall and both side gaps hold no free column.
TEST(Barrier, LatticeOpeningOfTheFlumeBuild) {
  const std::string flume = std::string(SPHDEM_SOURCE_DIR) + "/inputs/flume/flume.yaml";
  const auto opening = [&](const std::string& dp) {
    const Scene s = load_scene(flume, {"sph.dp=" + dp});
    const ParticleSet<Host> ps = build_particles(s);
    std::vector<bool> is_wall(s.solids.size());
    for (std::size_t k = 0; k < s.solids.size(); ++k)
      is_wall[k] = s.solids[k].name.rfind("barrier_", 0) == 0;
    return std::make_pair(s, barrier_lattice_opening(s.barrier, ps, is_wall, s.sph.dp));
  };
  const auto [s5, five] = opening("0.005");
  Index blocked = 0, columns = 0;
  for (Real y = 0.0025; y < 0.4; y += 0.005, ++columns)
    for (const BarrierWall& w : barrier_walls(s5.barrier))
      if (std::abs(y - w.center.y) < 0.5 * s5.barrier.width) {
        ++blocked;
        break;
      }
  EXPECT_EQ(columns, 80);
  EXPECT_EQ(five.columns, columns);
  EXPECT_EQ(five.open, columns - blocked);
  EXPECT_EQ(five.open, 10);
  EXPECT_NEAR(five.ratio(), 0.125, 1e-12);
  EXPECT_EQ(five.gaps, 8);
  EXPECT_EQ(five.closed_gaps, 0);

  const auto [s10, ten] = opening("0.01");
  EXPECT_EQ(ten.columns, 40);
  EXPECT_EQ(ten.open, 4);
  EXPECT_EQ(ten.gaps, 8);
  EXPECT_EQ(ten.closed_gaps, 4);
}

TEST(Barrier, WallPlacement) {
  // Float: coordinates are below 1 m (x ~ 0.6 to 0.7, y <= 0.4) and come from a few roundings
  // (the literals 0.6 and 0.4, pitch, (k + 1/2) pitch, |off| tan a, the box SDF's transform),
  // each at most eps/2 of 1 m: 4 eps of 1 m bounds them, and the SDF values phi computed from
  // them.
  const double pos_tol = tol(1e-12, 4 * kFloatEps);
  const Barrier p = preset("P30");
  const auto pw = barrier_walls(p);
  ASSERT_EQ(pw.size(), 7u);
  for (int k = 0; k < 7; ++k) {
    EXPECT_NEAR(pw[k].center.y, (k + 0.5) * 0.4 / 7, pos_tol);
    EXPECT_NEAR(pw[k].center.x, 0.6, pos_tol);  // a straight row
    EXPECT_NEAR(pw[k].angle, kPi / 6, 1e-12);
  }
  // V30, apex upstream: the centre wall at x, the others trail downstream along arms at 30°,
  // turned to lie along their arm (mirror images about the centre line).
  const auto vw = barrier_walls(preset("V30"));
  EXPECT_NEAR(vw[3].center.x, 0.6, pos_tol);
  for (int k = 0; k < 3; ++k) {
    const Real off = std::abs(vw[k].center.y - 0.2);
    EXPECT_NEAR(vw[k].center.x, 0.6 + off * std::tan(kPi / 6), pos_tol);
    EXPECT_NEAR(vw[6 - k].center.x, vw[k].center.x, 1e-12);
    EXPECT_NEAR(vw[k].angle, -vw[6 - k].angle, 1e-12);
  }
  // The solids: a point at each wall's centre, mid-height, is inside; one a wall thickness
  // upstream of the P00 walls' faces is outside.
  const auto solids = barrier_solids(preset("P00"));
  ASSERT_EQ(solids.size(), 7u);
  EXPECT_EQ(solids[0].name, "barrier_1");
  EXPECT_EQ(solids[6].name, "barrier_7");
  for (std::size_t k = 0; k < 7; ++k) {
    const Vec3 c = barrier_walls(preset("P00"))[k].center + Vec3(0, 0, 0.045);
    EXPECT_NEAR(solids[k].sdf->phi(c), -0.0065, pos_tol);  // half the thickness
    EXPECT_NEAR(solids[k].sdf->phi(c - Vec3(0.0065 + 0.013, 0, 0)), 0.013, pos_tol);
  }
}

TEST(Barrier, SceneKeysAndErrors) {
  const std::string base = R"(
name: b
dimension: 3
domain: {lo: [0, 0, 0], hi: [1, 0.4, 0.3]}
sph: {dp: 0.01}
time: {end: 0.1}
)";
  const Scene s = parse_scene(base + "barrier: {preset: V45, x: 0.5}\n", "b.yaml");
  ASSERT_TRUE(s.barrier.enabled);
  EXPECT_EQ(s.barrier.layout, 'V');
  EXPECT_EQ(s.barrier.angle_deg, 45);
  ASSERT_EQ(s.solids.size(), 7u);
  EXPECT_TRUE(s.find_solid("barrier_4"));
  auto message = [&](const std::string& extra) {
    try {
      parse_scene(base + extra, "b.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("barrier: {preset: P60}\n").find("barrier.preset"), std::string::npos);
  EXPECT_NE(message("barrier: {preset: P30, angle_deg: 10}\n").find("not both"), std::string::npos);
  EXPECT_NE(message("barrier: {walls: 0}\n").find("barrier.walls"), std::string::npos);
  EXPECT_NE(message("barrier: {y: [0.4, 0]}\n").find("must be above"), std::string::npos);
  EXPECT_NE(message("solids:\n  - {name: barrier_2, shape: {type: box, lo: [0, 0, 0], hi: "
                    "[1, 1, 1]}}\nbarrier: {preset: P00}\n")
                .find("already exists"),
            std::string::npos);
  EXPECT_NE(message("solids:\n  - {name: w, shape: {type: box, lo: [0, 0, 0], hi: [1, 1, 1]}, "
                    "boundary_regions: []}\n")
                .find("boundary_regions"),
            std::string::npos);
}

// A uniform layer D = 0.04 m deep (8 particles of dp = 5 mm) flowing at u = 1.5 m/s down a 15°
// channel: the gauge reads u exactly, the depth to within dp/4 and Fr = u / sqrt(g cos15 D); the
// trap counts all the fluid upstream of a row standing downstream of it.
TEST(Barrier, ChannelFlowGaugeAndTrap) {
  const Scene scene = parse_scene(R"(
name: layer
dimension: 3
domain: {lo: [0, 0, 0], hi: [0.2, 0.2, 0.2]}
gravity: [2.5390, 0, -9.4757]
sph: {dp: 0.005, h_factor: 1.0}
time: {end: 0.1}
barrier: {preset: P00, x: 0.3, y: [0, 0.2]}
)",
                                  "layer.yaml");
  const StepParams p = make_step_params(scene, 20);
  const Real dp = 0.005;
  ParticleSet<Host> ps = water_lattice(40, 40, 8, dp);
  for (Index i = 0; i < ps.n_fluid; ++i) ps.vel[i] = Vec3(1.5, 0, 0);
  const ChannelFlow c = probe_channel_flow(ps, p, scene.gravity, 0.1, 0.1);
  EXPECT_NEAR(c.u, 1.5, 1e-12);
  EXPECT_NEAR(c.depth, 0.04, 0.25 * dp);
  // Float: Fr = u / sqrt(g_n D) takes 3 roundings (product, sqrt, quotient) and g_n = 9.4757 is
  // rounded once: <= 2.5 eps relative; 4 eps of Fr.
  EXPECT_NEAR(c.froude, 1.5 / std::sqrt(9.4757 * c.depth), tol(1e-12, 4 * kFloatEps * c.froude));
  EXPECT_NEAR(c.froude, 1.5 / std::sqrt(9.4757 * 0.04), 0.05);
  // Off the layer: dry.
  const ChannelFlow dry = probe_channel_flow(ps, p, scene.gravity, 0.19, 0.5);
  EXPECT_EQ(dry.depth, 0);
  EXPECT_EQ(dry.froude, 0);
  const Trap t = barrier_trap(scene.barrier, ps);
  // Float: the trap adds n = 12800 equal masses m one by one. The k-th partial sum is k m (up to
  // the earlier errors), rounded by at most u k m (u = eps/2), so the total error is at most
  // u m n (n + 1) / 2 = (n + 1) eps M / 4 for M = n m; the reference n 1000 dp^3 and the masses
  // themselves are rounded differently, which adds a few eps of M.
  const Real fluid = ps.n_fluid * 1000 * dp * dp * dp;
  EXPECT_NEAR(t.fluid_upstream, fluid,
              tol(1e-9, ((double(ps.n_fluid) + 1) / 4 + 4) * kFloatEps * fluid));
  EXPECT_EQ(t.fluid_downstream, 0);
}

// The surface gauge on a still lattice filled to z = H (particle centres at (k + 1/2) dp) reads H
// to well under a tenth of dp, wherever the surface falls against the gauge's dp/8 scan
// (before the bisection it returned the scan sample below the crossing: up to dp/8 low), and next
// to a periodic side as well as in the middle (it ignored the periodic images before).
TEST(Probes, SurfaceHeightOfAFilledLatticeIsItsFillLevel) {
  for (const double h_factor : {1.0, 1.2}) {
    const Scene scene = parse_scene(
        // Periodic in x and y with a 0.12 m period: the gauge at (0.01, 0.02) needs the images.
        "name: tank\ndimension: 3\ndomain: {lo: [0, 0, 0], hi: [0.12, 0.12, 0.3], periodic: "
        "[true, true, false]}\nsph: {dp: 0.01, h_factor: " +
            std::to_string(h_factor) + "}\ntime: {end: 0.1}\n",
        "tank.yaml");
    const StepParams p = make_step_params(scene, 10);
    const Real dp = 0.01;
    for (const double shift : {0.0, 0.3, 0.55, 0.8}) {  // lattice raised by a fraction of dp
      const ParticleSet<Host> ps = water_lattice(12, 12, 12, dp, Real(shift));
      const double fill = (12 + shift) * dp;
      for (const Vec3 at : {Vec3(0.06, 0.06, 0), Vec3(0.01, 0.02, 0)}) {
        const Real z = probe_surface_height(ps, p, at.x, at.y);
        EXPECT_NEAR(z, fill, 0.05 * dp)
            << "h_factor " << h_factor << ", shift " << shift << ", gauge at " << at.x;
      }
    }
  }
}

// The velocity probe (profiles with quantity: velocity) interpolates with the Shepard-normalised
// kernel: a uniform field comes back exactly anywhere in the fluid, a linear one exactly at a
// lattice point (the weights are symmetric there), and a point with no fluid within 2h reads 0.
TEST(Probes, VelocityProbeInterpolatesTheFluidVelocity) {
  const Scene scene = parse_scene(
      "name: box\ndimension: 3\ndomain: {lo: [0, 0, 0], hi: [0.12, 0.12, 0.3], periodic: "
      "[true, true, false]}\nsph: {dp: 0.01, h_factor: 1.2}\ntime: {end: 0.1}\n",
      "box.yaml");
  const StepParams p = make_step_params(scene, 10);
  const Real dp = 0.01;
  ParticleSet<Host> ps = water_lattice(12, 12, 12, dp);
  for (Index i = 0; i < ps.n_fluid; ++i) ps.vel[i] = Vec3(0.3, -0.1, 0.2);
  // Float: Shepard's estimate is sum_j w_j v_j / sum_j w_j over the N ~ 58 lattice points within
  // 2h = 2.4 dp; each sum of N terms carries up to N u of relative round-off (u = eps/2), so
  // the quotient carries up to ~N eps (+ the literals' own rounding): 64 eps of the largest
  // velocity in the support (0.3 m/s for the uniform field, 2 z <= 0.16 m/s for the shear).
  const Vec3 u = probe_velocity(ps, p, Vec3(0.043, 0.071, 0.052));
  EXPECT_NEAR(u.x, 0.3, tol(1e-12, 64 * kFloatEps * 0.3));
  EXPECT_NEAR(u.y, -0.1, tol(1e-12, 64 * kFloatEps * 0.3));
  EXPECT_NEAR(u.z, 0.2, tol(1e-12, 64 * kFloatEps * 0.3));
  for (Index i = 0; i < ps.n_fluid; ++i) ps.vel[i] = Vec3(2 * ps.pos[i].z, 0, 0);  // shear
  EXPECT_NEAR(probe_velocity(ps, p, Vec3(0.055, 0.055, 0.055)).x, 0.11,
              tol(1e-12, 64 * kFloatEps * 0.16));
  // Near the top the kernel sees fluid only below: Shepard's estimate leans toward it.
  EXPECT_LT(probe_velocity(ps, p, Vec3(0.055, 0.055, 0.115)).x, 0.23);
  const Vec3 dry = probe_velocity(ps, p, Vec3(0.05, 0.05, 0.25));
  EXPECT_EQ(dry.x, 0);
  EXPECT_EQ(dry.z, 0);
}

}  // namespace
}  // namespace sphdem
