// The CPU's pairwise fluid pass (solver/pairwise_host.hpp) against the gather that the GPU runs:
// the same rates to round-off on every kind of scene, and bit-identical results for any number
// of threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "app/simulation.hpp"
#include "io/scene_yaml.hpp"
#include "coupling/grain_boundary.hpp"
#include "scene/build.hpp"
#include "scene/build_dem.hpp"
#include "solver/pairwise_host.hpp"

namespace sphdem {
namespace {

std::string input(const std::string& name) {
  return std::string(SPHDEM_SOURCE_DIR) + "/inputs/" + name;
}

struct Rates {
  std::map<GlobalId, Vec3> acc, pos;
  std::map<GlobalId, Real> drho, rho;
  double acc_scale = 0, drho_scale = 0;
  double vmax = 0, rho0 = 0, dp = 0;
  Index grains = 0;                   // grain boundary slots
  std::map<GlobalId, Vec3> wall_acc;  // boundary slots: the fluid force per unit mass
  std::map<GlobalId, Real> wall_drho;
  double wall_acc_scale = 0, wall_drho_scale = 0;
};

Rates collect(const Scene& scene, SolverBase& solver) {
  const ParticleSet<Host>& ps = solver.host_particles();
  Rates r;
  r.rho0 = double(scene.fluid.rho0);
  r.grains = ps.n_grain;
  r.dp = double(scene.sph.dp);
  for (Index i = 0; i < ps.n_fluid; ++i) {
    r.vmax = std::max(r.vmax, double(norm(ps.vel[i])));
    r.acc[ps.id[i]] = ps.acc[i];
    r.drho[ps.id[i]] = ps.drho[i];
    r.pos[ps.id[i]] = ps.pos[i];
    r.rho[ps.id[i]] = ps.rho[i];
    r.acc_scale = std::max(r.acc_scale, double(norm(ps.acc[i])));
    r.drho_scale = std::max(r.drho_scale, double(std::abs(ps.drho[i])));
  }
  for (Index b = ps.wall_begin(); b < ps.size(); ++b) {
    r.wall_acc[ps.id[b]] = ps.acc[b];
    r.wall_drho[ps.id[b]] = ps.drho[b];
    r.wall_acc_scale = std::max(r.wall_acc_scale, double(norm(ps.acc[b])));
    r.wall_drho_scale = std::max(r.wall_drho_scale, double(std::abs(ps.drho[b])));
  }
  return r;
}

// A solver as `sphdem run` builds it: a scene with grains (dem) gets their boundary particles,
// placed from the grains' poses (the grains do not move here: no DEM step is taken).
struct Built {
  Scene scene;
  DemBuild dem;
  std::unique_ptr<GrainCoupling> coupling;
  std::unique_ptr<SolverBase> solver;
};

std::unique_ptr<Built> solver_for(const std::string& file, std::vector<std::string> sets,
                                  bool pairwise) {
  sets.push_back(std::string("sph.pairwise=") + (pairwise ? "true" : "false"));
  auto b = std::make_unique<Built>();
  b->scene = load_scene(input(file), sets);
  std::ostringstream log;
  std::function<void(ParticleSet<Host>&, BuildReport&)> prepare;
  if (b->scene.dem.enabled) {
    b->dem = build_dem(b->scene, log);
    b->coupling =
        std::make_unique<GrainCoupling>(*b->dem.system, b->scene.sph.dp, boundary_depth(b->scene),
                                        b->scene.fluid.rho0, b->scene.dim);
    Built* bp = b.get();
    prepare = [bp](ParticleSet<Host>& ps, BuildReport& br) {
      br.fluid -= bp->coupling->append(ps, *bp->dem.system);
      br.grain = bp->coupling->particle_count();
    };
  }
  b->solver = make_solver(b->scene, Backend::kHost, log, nullptr, nullptr, {0, 0, 0}, prepare);
  return b;
}

// Steps a solver and returns, by id, the rates of its last step and the state after it.
Rates run(const std::string& file, const std::vector<std::string>& sets, bool pairwise, int steps) {
  auto b = solver_for(file, sets, pairwise);
  for (int s = 0; s < steps; ++s) b->solver->step();
  return collect(b->scene, *b->solver);
}

// The rates of one step from the same state with both passes: the gather runs `steps` - 1 steps
// (a flow from rest needs a few to have rates worth comparing), the pairwise solver restores its
// state (as from a checkpoint, exactly), and both take one step.
std::pair<Rates, Rates> same_state(const std::string& file, const std::vector<std::string>& sets,
                                   int steps) {
  auto gather = solver_for(file, sets, false);
  auto pairwise = solver_for(file, sets, true);
  for (int s = 0; s + 1 < steps; ++s) gather->solver->step();
  pairwise->solver->restore(gather->solver->host_particles(), gather->solver->counters());
  gather->solver->step();
  pairwise->solver->step();
  return {collect(pairwise->scene, *pairwise->solver), collect(gather->scene, *gather->solver)};
}

struct Case {
  const char* file;
  std::vector<std::string> sets;
  bool pairwise;        // the grid allows the colouring; else the pass falls back to the gather
  int steps = 1;        // the rates of this step are compared (a flow from rest needs a few)
  int walls = 1;        // 0: the scene has no boundary particles
  bool grains = false;  // the scene has grain boundary particles (moving mDBC)
};

// Tolerances in units of the build's rounding: a wrong j-side term (sign, mass, diffusion
// direction) differs by the term itself, many orders above these.
class PairwiseMatchesGather : public ::testing::TestWithParam<Case> {};

TEST_P(PairwiseMatchesGather, RatesAndStateByIdToRoundOff) {
  const Case& c = GetParam();
  const double eps = double(std::numeric_limits<Real>::epsilon());
  const auto [a, b] = same_state(c.file, c.sets, c.steps);
  ASSERT_EQ(a.acc.size(), b.acc.size());
  ASSERT_GT(a.acc.size(), 100u);
  // The density rate can cancel to near zero everywhere (a shear flow along a period): its
  // scale is then the size of its terms, rho0 |v| / dp.
  const double drho_scale = std::max(a.drho_scale, a.rho0 * a.vmax / a.dp);
  double worst_acc = 0, worst_drho = 0;
  for (const auto& [id, acc] : a.acc) {
    worst_acc = std::max(worst_acc, double(norm(acc - b.acc.at(id))) / a.acc_scale);
    worst_drho = std::max(
        worst_drho, std::abs(double(a.drho.at(id) - b.drho.at(id))) / std::max(drho_scale, 1e-30));
  }
  std::printf(
      "%s: rates of step %d, pairwise vs gather: max |da|/max|a| %.3g, "
      "max |drho'|/max|drho'| %.3g\n",
      c.file, c.steps, worst_acc, worst_drho);
  EXPECT_LE(worst_acc, 1e3 * eps);
  EXPECT_LE(worst_drho, 1e3 * eps);
  EXPECT_GT(a.acc_scale, 0);
  // The boundary particles' side of each fluid-wall pair: the fluid force on the solids (and,
  // with DBC, their density rate).
  ASSERT_EQ(a.wall_acc.size(), b.wall_acc.size());
  ASSERT_EQ(a.wall_acc.empty(), c.walls == 0) << "boundary particles touched by fluid";
  ASSERT_EQ(a.grains > 0, c.grains) << "grain boundary particles";
  if (c.walls) {
    ASSERT_GT(a.wall_acc_scale, 0);
  }
  const double wall_drho_scale = std::max(a.wall_drho_scale, a.rho0 * a.vmax / a.dp);
  double worst_wall_acc = 0, worst_wall_drho = 0;
  for (const auto& [id, acc] : a.wall_acc) {
    worst_wall_acc =
        std::max(worst_wall_acc, double(norm(acc - b.wall_acc.at(id))) / a.wall_acc_scale);
    worst_wall_drho =
        std::max(worst_wall_drho, std::abs(double(a.wall_drho.at(id) - b.wall_drho.at(id))) /
                                      std::max(wall_drho_scale, 1e-30));
  }
  std::printf("  boundary: max |da|/max|a| %.3g, max |drho'|/max|drho'| %.3g\n", worst_wall_acc,
              worst_wall_drho);
  EXPECT_LE(worst_wall_acc, 1e3 * eps);
  EXPECT_LE(worst_wall_drho, 1e3 * eps);
  if (c.pairwise) {  // the pass ran: its sums come in another order, so some last bits differ
    EXPECT_GT(worst_acc + worst_drho, 0);
  } else {  // it fell back to the gather itself
    EXPECT_EQ(worst_acc + worst_drho, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, PairwiseMatchesGather,
    ::testing::Values(
        // 2D, artificial viscosity, Fourtakas diffusion, mDBC.
        Case{"dam_break_2d.yaml", {"sph.dp=0.0146"}, true, 20},
        // 3D, the same physics, the seed's kernel ratio.
        Case{"dam_break_3d.yaml", {"sph.dp=0.02", "sph.h_factor=1.0"}, true, 20},
        // 3D with SPS stress and laminar viscosity, DBC walls.
        Case{"dam_break_3d.yaml",
             {"sph.dp=0.02", "fluid.sps.enabled=true", "fluid.viscosity.model=laminar",
              "fluid.viscosity.nu=1e-6", "sph.boundary=dbc"},
             true,
             20},
        // The penetration control: the fluid's continuity velocity differs from the wall's.
        Case{"dam_break_2d.yaml",
             {"sph.dp=0.0146", "sph.no_penetration=true", "fluid.p_min=0"},
             true,
             20},
        // A floating grain (moving mDBC boundary particles), 3D, periodic along x and y:
        // h = 1.1 sqrt(3) dp gives 6 cells (3 tiles) along each period.
        Case{"floating_box.yaml", {"sph.dp=0.02", "sph.h_factor=1.1"}, true, 10, 1, true},
        // The shipped h: 5 cells, not a whole number of tiles (the gather runs).
        Case{"floating_box.yaml", {"sph.dp=0.02"}, false, 10, 1, true},
        // 2D, periodic along x, HBP viscosity, Molteni diffusion: h = 0.93 sqrt(2) dp gives 12
        // cells (of edge 1.1 h, symplectic) along the period: 6 tiles, a multiple of 3 colours.
        Case{"bingham_poiseuille_2d.yaml", {"sph.h_factor=0.93"}, true, 20},
        // The shipped h: 10 cells, 5 tiles, which two tiles of a colour would meet across.
        Case{"bingham_poiseuille_2d.yaml", {}, false, 20},
        // 3D, periodic on all axes, a grain (shipped h: 15 cells, 8 tiles; the gather runs).
        Case{"sphere_settling.yaml", {}, false, 2, 1, true}),
    [](const ::testing::TestParamInfo<Case>& info) {
      std::string n = info.param.file;
      n = n.substr(0, n.find('.')) + "_" + std::to_string(info.index);
      return n;
    });

// After 400 steps of the 2D dam break (the column is collapsing) the two passes still agree
// to round-off growth: the trajectories are the same.
TEST(PairwiseFluidPass, DamBreakTrajectoryMatchesTheGather) {
  const Rates a = run("dam_break_2d.yaml", {"sph.dp=0.0146"}, true, 400);
  const Rates b = run("dam_break_2d.yaml", {"sph.dp=0.0146"}, false, 400);
  double worst_pos = 0, worst_rho = 0;
  for (const auto& [id, x] : a.pos) {
    worst_pos = std::max(worst_pos, double(norm(x - b.pos.at(id))) / 0.0146);
    worst_rho = std::max(worst_rho, std::abs(double(a.rho.at(id) - b.rho.at(id))) / 1000.0);
  }
  std::printf("after 400 steps: max |dx|/dp %.3g, max |drho|/rho0 %.3g\n", worst_pos, worst_rho);
  const double eps = double(std::numeric_limits<Real>::epsilon());
  EXPECT_LE(worst_pos, 1e4 * eps);
  EXPECT_LE(worst_rho, 1e4 * eps);
}

TEST(PairwiseFluidPass, BitIdenticalForAnyThreadCount) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const int before = omp_get_max_threads();
  auto state = [](int threads) {
    omp_set_num_threads(threads);
    return run("dam_break_3d.yaml", {"sph.dp=0.02", "sph.h_factor=1.0"}, true, 10);
  };
  const Rates one = state(1), two = state(2), three = state(3);
  omp_set_num_threads(before);
  ASSERT_EQ(one.pos.size(), two.pos.size());
  std::size_t differ2 = 0, differ3 = 0;
  for (const auto& [id, x] : one.pos) {
    const auto same = [&](const Rates& o) {
      const Vec3 y = o.pos.at(id), a = one.acc.at(id), b = o.acc.at(id);
      return std::memcmp(&x, &y, sizeof x) == 0 && std::memcmp(&a, &b, sizeof a) == 0 &&
             one.rho.at(id) == o.rho.at(id);
    };
    differ2 += same(two) ? 0 : 1;
    differ3 += same(three) ? 0 : 1;
  }
  EXPECT_EQ(differ2, 0u) << "of " << one.pos.size() << " particles";
  EXPECT_EQ(differ3, 0u) << "of " << one.pos.size() << " particles";
#endif
}

TEST(PairwiseFluidPass, TilingRefusesPeriodicAxesThatWouldCollide) {
  const bool open[3] = {false, false, false};
  const bool px[3] = {true, false, false};
  const bool pz[3] = {false, false, true};
  // Open axes: always.
  EXPECT_TRUE(
      pairwise_tiling_ok(make_cell_grid(3, Vec3{0, 0, 0}, Vec3{1, 0.7, 0.3}, 0.05, open, 2)));
  // Periodic x with 12 cells of reach 2: 6 tiles, a multiple of 3 colours.
  const CellGrid g12 = make_cell_grid(3, Vec3{0, 0, 0}, Vec3{1.5, 0.5, 0.5}, 0.125, px, 2);
  ASSERT_EQ(g12.n[0], 12);
  EXPECT_TRUE(pairwise_tiling_ok(g12));
  // Periodic x with 8 cells: 4 tiles, tiles 0 and 3 share a colour and meet across the wrap.
  const CellGrid g8 = make_cell_grid(3, Vec3{0, 0, 0}, Vec3{1.0, 0.5, 0.5}, 0.125, px, 2);
  ASSERT_EQ(g8.n[0], 8);
  EXPECT_FALSE(pairwise_tiling_ok(g8));
  // Periodic z takes 3 colours (later slots lie on both sides across the wrap): 4 tiles fail.
  const CellGrid z8 = make_cell_grid(3, Vec3{0, 0, 0}, Vec3{0.5, 0.5, 1.0}, 0.125, pz, 2);
  ASSERT_EQ(z8.n[2], 8);
  EXPECT_FALSE(pairwise_tiling_ok(z8));
}

// pose_grains poses the grain slots in the solver's execution space with the same
// pose_grain_point as GrainCoupling::place on the host: for grains moved, turned and spinning,
// every slot's position, ghost nodes, normal and velocity agree exactly (same function, same
// inputs), and the poses did move (the comparison is not between two unmoved sets).
TEST(GrainPosing, SolverPoseMatchesTheCouplingOnTheHost) {
  auto b = solver_for("beads_settling.yaml", {}, true);
  const ParticleSet<Host> before = b->solver->grain_particles();
  ASSERT_GT(before.n_grain, 0);
  std::vector<dem::RigidBody>& bodies = b->dem.system->bodies();
  ASSERT_GE(bodies.size(), 2u);
  for (std::size_t g = 0; g < bodies.size(); ++g) {
    const Real s = Real(g + 1);
    bodies[g].x += Vec3(Real(0.002) * s, Real(-0.001), Real(0.003));
    bodies[g].q = normalize(
        multiply(from_axis_angle(Vec3(1, 2, 3) / std::sqrt(Real(14)), Real(0.3) * s), bodies[g].q));
    bodies[g].v = Vec3(Real(0.1), Real(-0.2) * s, Real(0.05));
    bodies[g].w = Vec3(Real(3) * s, Real(-1), Real(2));
  }
  b->solver->pose_grains(b->coupling->table(), bodies);
  const ParticleSet<Host> posed = b->solver->grain_particles();
  ParticleSet<Host> ref = posed;
  b->coupling->place(ref, *b->dem.system);  // every grain slot, on the host
  ASSERT_EQ(posed.n_grain, before.n_grain);
  Real moved = 0;
  std::map<GlobalId, Vec3> start;
  for (Index i = 0; i < before.n_grain; ++i) start[before.id[i]] = before.pos[i];
  for (Index i = 0; i < posed.n_grain; ++i) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(posed.pos[i][a], ref.pos[i][a]) << "slot " << i;
      EXPECT_EQ(posed.ghost[i][a], ref.ghost[i][a]) << "slot " << i;
      EXPECT_EQ(posed.ghost_alt[i][a], ref.ghost_alt[i][a]) << "slot " << i;
      EXPECT_EQ(posed.normal[i][a], ref.normal[i][a]) << "slot " << i;
      EXPECT_EQ(posed.vel[i][a], ref.vel[i][a]) << "slot " << i;
    }
    moved = std::max(moved, norm(posed.pos[i] - start.at(posed.id[i])));
  }
  EXPECT_GT(moved, Real(0.002));  // every grain moved by at least 2 mm and turned
}

}  // namespace
}  // namespace sphdem
