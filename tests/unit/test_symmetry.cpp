// Symmetry planes (scene key `symmetry`, core/symmetry.hpp): the mirror halo of
// solver/mirror_exchange.hpp, the mirrored full scene of diagnostics/mirror.hpp, the scene
// checks, and the build's trimming. The run-level comparison with a full run is in
// tests/validation/test_symmetry.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "diagnostics/mirror.hpp"
#include "diagnostics/probes.hpp"
#include "io/scene_yaml.hpp"
#include "precision.hpp"
#include "scene/build.hpp"
#include "solver/fluid_params.hpp"
#include "solver/mirror_exchange.hpp"

namespace sphdem {
namespace {

const std::string kPillar = std::string(SPHDEM_TEST_DATA) + "/pillar_3d.yaml";
const std::string kHalf = "symmetry={axis: y, at: 0.1}";

std::string input_error(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

SymmetryPlane plane_y(Real at, int keep) {
  SymmetryPlane s;
  s.axis = 1;
  s.at = at;
  s.keep = keep;
  return s;
}

TEST(SymmetryPlane, ReflectsPointsVectorsAndTensors) {
  const SymmetryPlane s = plane_y(0.1, -1);
  EXPECT_REAL_EQ(s.side(Vec3(0, 0.05, 0)), 0.05);  // keep = -1: y < 0.1 is the modelled side
  const Vec3 p = s.reflect_point(Vec3(1, 0.07, 2));
  EXPECT_REAL_EQ(p.y, 0.13);
  EXPECT_DOUBLE_EQ(p.x, 1);
  const Vec3 v = s.reflect_vector(Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(v.y, -2);
  EXPECT_DOUBLE_EQ(v.z, 3);
  // (xy, xz, yz): the y-plane flips xy and yz, keeps xz.
  const Vec3 o = s.reflect_off_diagonal(Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(o.x, -1);
  EXPECT_DOUBLE_EQ(o.y, 2);
  EXPECT_DOUBLE_EQ(o.z, -3);
}

// The halo is exactly the owned fluid within the width, reflected, and refreshes follow the
// owners with the right transform per field kind.
TEST(MirrorExchange, HaloIsTheReflectedFluidNearThePlane) {
  const SymmetryPlane s = plane_y(0, 1);
  MirrorExchange ex(s, 0.3, 0.2);
  ParticleSet<Host> ps;
  ps.n_fluid = 4;
  ps.n_wall = 1;
  ps.resize(ps.size());
  const Real ys[4] = {0.05, 0.25, 0.35, 0.1};
  for (Index i = 0; i < 4; ++i) {
    ps.id[i] = GlobalId(i);
    ps.pos[i] = Vec3(Real(i), ys[i], 0);
    ps.vel[i] = Vec3(1, 2, 3);
    ps.rho[i] = 1000 + Real(i);
    ps.body[i] = -1;
  }
  ps.id[4] = 9;
  ps.pos[4] = Vec3(0, -0.01, -0.05);
  ps.ghost[4] = Vec3(0, -0.01, 0.05);
  ps.body[4] = 0;
  EXPECT_EQ(ex.keep_walls(ps.pos.data() + 4, ps.ghost.data() + 4, ps.ghost.data() + 4, 1, true),
            std::vector<std::uint8_t>{1});
  ex.build_halo(ps);
  ASSERT_EQ(ps.n_halo, 3);  // 0.35 is beyond the width 0.3
  EXPECT_EQ(ex.halo_count(), 3);
  EXPECT_EQ(ps.n_wall, 1);
  EXPECT_EQ(ps.id[ps.wall_begin()], 9u);  // the wall moved behind the halo
  const Index h0 = ps.n_fluid;
  // A plane at 0 negates y exactly: the images are the owners' values (as Real) negated.
  EXPECT_DOUBLE_EQ(ps.pos[h0].y, Real(-0.05));
  EXPECT_DOUBLE_EQ(ps.pos[h0 + 1].y, Real(-0.25));
  EXPECT_DOUBLE_EQ(ps.pos[h0 + 2].y, Real(-0.1));
  EXPECT_DOUBLE_EQ(ps.vel[h0].y, -2);
  EXPECT_DOUBLE_EQ(ps.vel[h0].x, 1);
  EXPECT_DOUBLE_EQ(ps.rho[h0 + 2], 1003);
  EXPECT_EQ(ps.id[h0 + 1], 1u);
  // Refreshes: owned values at the build's slots to the copies.
  std::vector<Vec3> owned = {Vec3(0, 0.01, 0), Vec3(0, 0.02, 0), Vec3(0, 0.03, 0),
                             Vec3(0, 0.04, 0)};
  std::vector<Vec3> halo(3);
  ex.bcast_positions(owned.data(), halo.data());
  EXPECT_DOUBLE_EQ(halo[2].y, Real(-0.04));
  ex.bcast_field(owned.data(), halo.data(), HaloField::kVelocity);
  EXPECT_DOUBLE_EQ(halo[1].y, Real(-0.02));
  ex.bcast_field(owned.data(), halo.data(), HaloField::kValue);
  EXPECT_DOUBLE_EQ(halo[1].y, Real(0.02));
  std::vector<Vec3> off = {Vec3(1, 2, 3), Vec3(), Vec3(), Vec3()};
  ex.bcast_field(off.data(), halo.data(), HaloField::kOffDiagonal);
  EXPECT_DOUBLE_EQ(halo[0].x, -1);
  EXPECT_DOUBLE_EQ(halo[0].y, 2);
  EXPECT_DOUBLE_EQ(halo[0].z, -3);
  std::vector<Real> r = {1, 2, 3, 4}, rh(3);
  ex.bcast(r.data(), rh.data());
  EXPECT_DOUBLE_EQ(rh[2], 4);
}

// A wall's ghost node across the plane widens the halo to 2h (the support) plus half the skin
// past it: the first ghost node, and the second (a thin solid's other face), whose gather needs
// the mirror fluid around it as much. Without mDBC (by_ghost false) only the wall itself counts.
TEST(MirrorExchange, HaloReachesPastTheDeepestGhostNode) {
  MirrorExchange ex(plane_y(0, 1), 0.3, 0.2);  // 2h = 0.2, skin 0.1
  EXPECT_DOUBLE_EQ(ex.width(), Real(0.3));     // the width as given
  const Vec3 near(0, -0.01, 0);
  ex.keep_walls(&near, &near, &near, 1, true);
  EXPECT_DOUBLE_EQ(ex.width(), Real(0.3));  // 0.01 + 0.2 + 0.05 is inside the width
  const Vec3 pos(0, -0.05, 0), ghost(0, -0.15, 0);
  ex.keep_walls(&pos, &ghost, &ghost, 1, true);
  EXPECT_REAL_EQ(ex.width(), 0.4);  // 0.15 + 0.2 + 0.05
  const Vec3 alt(0, -0.17, 0);
  ex.keep_walls(&pos, &ghost, &alt, 1, true);
  EXPECT_REAL_EQ(ex.width(), 0.42);  // the second ghost node is the deeper
  const Vec3 far(0, -0.25, 0);
  ex.keep_walls(&far, &ghost, &alt, 1, false);
  EXPECT_REAL_EQ(ex.width(), 0.5);  // DBC: the wall at 0.25
}

// The full scene's walls must be symmetric everywhere, not only near the plane. The flume's P00
// barrier is, at dp = 10 mm. At dp = 400/56 mm every wall's side faces fall on lattice rows and
// dp given as 0.00714285714 (3e-12 m short) puts each row just below its face, so the row at the
// +y face is kept and the one at the -y face dropped: the full build is the
// barrier shifted by dp/2, the half build the modelled side mirrored. The build says so, naming
// the barrier row; near the plane (within 2h) every wall has its image, so a check there alone
// found nothing.
TEST(SymmetryBuild, FindsWallsWithoutAMirrorImageFarFromThePlane) {
  const std::string flume = std::string(SPHDEM_SOURCE_DIR) + "/inputs/flume/flume.yaml";
  const std::string plane = "symmetry={axis: y, at: 0.2}";
  BuildReport coarse, fine;
  build_particles(load_scene(flume, {plane, "sph.dp=0.01"}), &coarse);
  EXPECT_EQ(coarse.symmetry_unmatched, 0);
  const Scene s = load_scene(flume, {plane, "sph.dp=0.00714285714"});
  const ParticleSet<Host> ps = build_particles(s, &fine);
  ASSERT_GT(fine.symmetry_unmatched, 0);
  // The barrier row: its 13 mm walls stand at x = 0.6 (two lattice columns), on the modelled
  // side from the middle wall's +y face (y = 0.225) on.
  EXPECT_NEAR(fine.symmetry_unmatched_lo.x, 0.6 - 0.5 * s.sph.dp, 1e-9);
  EXPECT_NEAR(fine.symmetry_unmatched_hi.x, 0.6 + 0.5 * s.sph.dp, 1e-9);
  EXPECT_NEAR(fine.symmetry_unmatched_lo.y, 0.225, 1e-9);
  EXPECT_GT(fine.symmetry_unmatched_hi.y, 0.39);
  // Brute force over the half build's walls near the barrier (every unmatched one is there, by
  // the box above): those on the modelled side whose image is no wall of the full build.
  const ParticleSet<Host> full = build_particles(load_scene(flume, {"sph.dp=0.00714285714"}));
  const auto near_barrier = [](const Vec3& x) { return std::abs(x.x - 0.6) < 0.05; };
  std::vector<Vec3> full_near;
  for (Index j = full.wall_begin(); j < full.size(); ++j)
    if (near_barrier(full.pos[j])) full_near.push_back(full.pos[j]);
  Index brute = 0;
  const Real q = Real(1e-3) * s.sph.dp;
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    if (!(ps.pos[i].y > 0.2) || !near_barrier(ps.pos[i])) continue;
    const Vec3 m(ps.pos[i].x, Real(0.4) - ps.pos[i].y, ps.pos[i].z);
    bool found = false;
    for (std::size_t j = 0; j < full_near.size() && !found; ++j) found = norm(full_near[j] - m) < q;
    if (!found) ++brute;
  }
  EXPECT_EQ(fine.symmetry_unmatched, brute);
  std::ostringstream os;
  describe_symmetry_mismatch(fine, os);
  EXPECT_EQ(os.str().rfind("warning: symmetry: " + std::to_string(brute) +
                               " wall particles of the modelled side, between (",
                           0),
            0u)
      << os.str();
  std::ostringstream none;
  describe_symmetry_mismatch(coarse, none);
  EXPECT_EQ(none.str(), "");
}

// The build models one side: half the fluid of the symmetric pillar scene, the walls beyond 2h
// across the plane dropped, every wall near the plane with its mirror image.
TEST(SymmetryBuild, HalvesTheFluidAndTrimsTheWalls) {
  BuildReport full, half;
  const ParticleSet<Host> pf = build_particles(load_scene(kPillar), &full);
  const Scene s = load_scene(kPillar, {kHalf});
  const ParticleSet<Host> ph = build_particles(s, &half);
  EXPECT_EQ(2 * half.fluid, full.fluid);
  EXPECT_EQ(half.symmetry_fluid_dropped, half.fluid);
  EXPECT_EQ(half.symmetry_unmatched, 0);
  EXPECT_LT(half.wall, full.wall);
  EXPECT_GT(half.wall, full.wall / 2);  // the walls within 2h across the plane stay
  const Real h = s.h();
  for (Index i = 0; i < ph.n_fluid; ++i) EXPECT_GT(ph.pos[i].y, 0.1);
  for (Index i = ph.wall_begin(); i < ph.size(); ++i) EXPECT_GT(ph.pos[i].y, 0.1 - 2.02 * h);
  // A plane on a lattice row is refused; so is a plane outside the domain or on a 2D scene.
  EXPECT_EQ(
      input_error([&] { build_particles(load_scene(kPillar, {"symmetry={axis: y, at: 0.105}"})); }),
      kPillar +
          ": symmetry.at: 0.105 lies on a row of fluid particles (y = 0.105); put the "
          "plane halfway between two rows (move it by dp/2 = 0.005 m)");
  EXPECT_EQ(input_error([&] { load_scene(kPillar, {"symmetry={axis: y, at: 0.3}"}); }),
            "--set symmetry={axis: y, at: 0.3}: symmetry.at: value 0.3 is not strictly inside the "
            "domain along y (-0.05, 0.25)");
  EXPECT_EQ(input_error([&] {
              load_scene(kPillar, {"symmetry={axis: w, at: 0.1}"});
            }).rfind("--set symmetry={axis: w, at: 0.1}: symmetry.axis: ", 0),
            0u);
  const std::string dam2d = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";
  EXPECT_EQ(input_error([&] { load_scene(dam2d, {"symmetry={axis: x, at: 0.1}"}); }),
            "--set symmetry={axis: x, at: 0.1}: symmetry: a symmetry plane needs dimension 3");
  EXPECT_EQ(input_error([&] {
              load_scene(kPillar, {kHalf, "sph.boundary=dbc"});
            }),
            "--set symmetry={axis: y, at: 0.1}: symmetry: a symmetry plane needs sph.boundary: "
            "mdbc (a DBC wall's density sums the fluid on both sides of the plane, and the mirror "
            "copies are not summed into walls)");
  const std::string beads = std::string(SPHDEM_SOURCE_DIR) + "/inputs/beads_settling.yaml";
  const std::string with_grains =
      input_error([&] { load_scene(beads, {"symmetry={axis: x, at: 0.0}"}); });
  EXPECT_NE(with_grains.find("a symmetry plane needs a scene without grains (dem)"),
            std::string::npos)
      << with_grains;
}

// mirror_full rebuilds the full scene: the fluid doubled, and every wall particle with its image
// (forces reflected, barrier walls paired with their mirror walls), so a solid's force is the
// modelled fluid's force on it plus the image of that on its mirror solid.
TEST(SymmetryDiagnostics, MirrorFullDoublesTheFluidAndPairsTheForces) {
  const SymmetryPlane s = plane_y(0.1, 1);
  ParticleSet<Host> ps;
  ps.n_fluid = 1;
  ps.n_wall = 3;
  ps.resize(ps.size());
  ps.pos[0] = Vec3(0, 0.12, 0.5);
  ps.vel[0] = Vec3(1, 1, 0);
  ps.mass[0] = 2;
  ps.body[0] = -1;
  // Solid 0 (its own mirror) on the modelled side, solid 1 across the plane, solid 2 (solid 1's
  // mirror) on the modelled side.
  ps.pos[1] = Vec3(0, 0.15, 0);
  ps.body[1] = 0;
  ps.acc[1] = Vec3(1, 2, 3);
  ps.pos[2] = Vec3(0, 0.05, 0);
  ps.body[2] = 1;
  ps.acc[2] = Vec3(0, 1, 0);
  ps.pos[3] = Vec3(0, 0.16, 0);
  ps.body[3] = 2;
  ps.acc[3] = Vec3(0, 0, 1);
  for (Index i = 1; i < 4; ++i) ps.mass[i] = 2;
  const ParticleSet<Host> f = mirror_full(ps, s, {0, 2, 1});
  EXPECT_EQ(f.n_fluid, 2);
  EXPECT_EQ(f.n_wall, 6);
  EXPECT_REAL_EQ(f.pos[1].y, 0.08);  // 2 (0.1) - 0.12
  const Energy e = probe_energy(f, Vec3(0, 0, -10));
  EXPECT_DOUBLE_EQ(e.kinetic, 2 * 0.5 * 2 * 2);
  EXPECT_DOUBLE_EQ(e.momentum.y, 0);
  EXPECT_DOUBLE_EQ(e.momentum.x, 4);
  const Vec3 f0 = probe_solid_force(f, 0), f1 = probe_solid_force(f, 1),
             f2 = probe_solid_force(f, 2);
  EXPECT_DOUBLE_EQ(f0.x, 4);  // itself plus its image
  EXPECT_DOUBLE_EQ(f0.y, 0);
  EXPECT_DOUBLE_EQ(f0.z, 12);
  EXPECT_DOUBLE_EQ(f1.y, 2);  // its own, plus the image of solid 2's
  EXPECT_DOUBLE_EQ(f1.z, 2);
  EXPECT_DOUBLE_EQ(f2.y, -2);
  EXPECT_DOUBLE_EQ(f2.z, 2);
}

// P00's walls pair with their mirror walls about the channel's centre line; the V layouts as
// built turn the middle wall one way, so it has no mirror image and is reported.
TEST(SymmetryDiagnostics, BarrierWallsPairAcrossTheCentreLine) {
  const std::string flume = std::string(SPHDEM_SOURCE_DIR) + "/inputs/flume/flume.yaml";
  const Scene p00 = load_scene(flume, {"symmetry={axis: y, at: 0.2}"});
  std::vector<std::string> unpaired;
  const std::vector<std::int32_t> m = mirror_solids(p00, &unpaired);
  EXPECT_TRUE(unpaired.empty());
  auto solid = [&](const Scene& sc, const std::string& name) {
    for (std::size_t k = 0; k < sc.solids.size(); ++k)
      if (sc.solids[k].name == name) return std::int32_t(k);
    return std::int32_t(-1);
  };
  EXPECT_EQ(m[std::size_t(solid(p00, "barrier_1"))], solid(p00, "barrier_7"));
  EXPECT_EQ(m[std::size_t(solid(p00, "barrier_3"))], solid(p00, "barrier_5"));
  EXPECT_EQ(m[std::size_t(solid(p00, "barrier_4"))], solid(p00, "barrier_4"));
  EXPECT_EQ(m[std::size_t(solid(p00, "channel"))], solid(p00, "channel"));
  const Scene v30 = load_scene(flume, {"symmetry={axis: y, at: 0.2}", "barrier.preset=V30"});
  unpaired.clear();
  const std::vector<std::int32_t> mv = mirror_solids(v30, &unpaired);
  EXPECT_EQ(unpaired, std::vector<std::string>{"barrier_4"});
  EXPECT_EQ(mv[std::size_t(solid(v30, "barrier_2"))], solid(v30, "barrier_6"));
}

}  // namespace
}  // namespace sphdem
