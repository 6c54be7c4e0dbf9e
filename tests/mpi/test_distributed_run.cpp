// The solver on many ranks against the same solver on one rank (issue #7): after 200 steps every
// particle, looked up by global id, has the same position, velocity and density to 1e-9 relative,
// and so do the front, the total energy and the fluid force on the tank. The halo plan is reused
// between rebuilds (parallel.skin), so both paths are exercised. Decompositions along x,
// y and z; Verlet with mDBC, symplectic with DBC, and the HBP rheology (halo mu_eff).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "decomposition/distributed.hpp"
#include "diagnostics/probes.hpp"
#include "io/scene_yaml.hpp"
#include "mpi/mpi_test_util.hpp"
#include "scene/build.hpp"

namespace sphdem {
namespace {

using mpitest::all_ranks;

constexpr int kSteps = 200;

Scene scene_for(const std::string& file, std::vector<std::string> sets) {
  return load_scene(std::string(SPHDEM_INPUTS) + "/" + file, sets);
}

// A gate (Solid::removed_at) that goes after this many steps, or never (-1).
struct Gate {
  int solid = -1, after_steps = -1;
};

// The one-rank run, on rank 0 only (the others wait at the comparison).
ParticleSet<Host> serial_run(const Scene& scene, Gate gate = {}) {
  BuildReport rep;
  ParticleSet<Host> ps = build_particles(scene, &rep);
  const Real c0 = resolve_sound_speed(scene, rep);
  auto solver = make_host_solver(scene, std::move(ps), c0);
  for (int i = 0; i < kSteps; ++i) {
    if (i == gate.after_steps) solver->remove_solid(gate.solid);
    solver->step();
  }
  return solver->host_particles();
}

// Compares the gathered distributed state with the serial one on rank 0; true on every rank iff
// everything agrees.
bool same_as_serial(const Scene& scene, const ParticleSet<Host>& serial, std::array<int, 3> procs,
                    std::string* why, Gate gate = {}, int* rebalances = nullptr) {
  std::ostringstream log;
  BuildReport rep;
  std::shared_ptr<MpiExchange> ex;
  auto solver = make_solver(scene, Backend::kHost, log, &rep, &ex, procs);
  if (!ex) {
    *why = "no decomposition was made";
    return all_ranks(false);
  }
  const int rebalanced_at_start = ex->rebalance_count();
  for (int i = 0; i < kSteps; ++i) {
    if (i == gate.after_steps) solver->remove_solid(gate.solid);
    solver->step();
  }
  if (rebalances) *rebalances = ex->rebalance_count() - rebalanced_at_start;
  // The halo plan must have been reused between rebuilds (skin), and rebuilt more than once.
  const std::int64_t rebuilds = solver->halo_rebuilds();
  const std::int64_t at_least = scene.parallel.skin < 0.05 ? 5 : 2;
  if (scene.parallel.skin > 0 && (rebuilds < at_least || rebuilds >= kSteps)) {
    *why =
        "halo rebuilt at " + std::to_string(rebuilds) + " of " + std::to_string(kSteps) + " steps";
    return all_ranks(false);
  }
  std::printf("[rank %d] halo rebuilt at %lld of %d steps\n", mpitest::rank(), (long long)rebuilds,
              kSteps);
  const ParticleSet<Host> all =
      gather_on_root(ex->comm(), solver->host_particles(), solver->wall_mine());
  bool ok = true;
  std::ostringstream os;
  if (mpitest::rank() == 0) {
    if (all.n_fluid != serial.n_fluid || all.n_wall != serial.n_wall + serial.n_grain) {
      os << "counts: fluid " << all.n_fluid << " vs " << serial.n_fluid << ", walls " << all.n_wall
         << " vs " << serial.n_wall;
      ok = false;
    } else {
      std::map<GlobalId, Index> at;
      for (Index i = 0; i < serial.n_fluid; ++i) at[serial.id[i]] = i;
      double worst = 0;
      Index worst_at = 0, worst_ref = 0;
      for (Index i = 0; i < all.n_fluid; ++i) {
        const auto it = at.find(all.id[i]);
        if (it == at.end()) {
          os << "id " << all.id[i] << " is not in the serial run";
          ok = false;
          break;
        }
        const Index j = it->second;
        const double d = std::max(
            {double(norm(all.pos[i] - serial.pos[j])) / 0.1,
             double(norm(all.vel[i] - serial.vel[j])) / std::max(1e-3, double(norm(serial.vel[j]))),
             std::abs(double(all.rho[i] - serial.rho[j])) / double(serial.rho[j])});
        if (d > worst) {
          worst = d;
          worst_at = i;
          worst_ref = j;
        }
      }
      if (worst > 1e-9) {
        const Vec3 x = serial.pos[worst_ref];
        os << "largest relative difference by id " << worst << " (id " << all.id[worst_at] << " at "
           << x.x << ", " << x.y << ", " << x.z << ")";
        ok = false;
      }
      const Vec3 dir(1, 0, 0);
      const Real f1 = probe_front(serial, Vec3(), dir), fn = probe_front(all, Vec3(), dir);
      const Energy e1 = probe_energy(serial, scene.gravity), en = probe_energy(all, scene.gravity);
      const Vec3 w1 = probe_solid_force(serial, 0), wn = probe_solid_force(all, 0);
      const double de =
          std::abs(double((en.kinetic + en.potential) - (e1.kinetic + e1.potential))) /
          double(e1.kinetic + e1.potential);
      const double dw = double(norm(wn - w1)) / std::max(1e-30, double(norm(w1)));
      if (std::abs(double(fn - f1)) > 1e-9 * std::abs(double(f1)) || de > 1e-9 || dw > 1e-9) {
        os << "front " << fn << " vs " << f1 << ", energy rel " << de << ", tank force rel " << dw;
        ok = false;
      }
    }
  }
  *why = os.str();
  return all_ranks(ok);
}

TEST(DistributedRun, DamBreak3DAlongEachAxisMatchesOneRank) {
  // A thin skin, so the plan is rebuilt by drift many times within the 200 steps.
  const Scene scene =
      scene_for("dam_break_3d.yaml", {"sph.dp=0.02", "parallel.skin=0.02", "time.cfl=0.2"});
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene);
  const int n = mpitest::size();
  for (const std::array<int, 3> procs :
       {std::array<int, 3>{n, 1, 1}, std::array<int, 3>{1, n, 1}, std::array<int, 3>{1, 1, n}}) {
    std::string why;
    EXPECT_TRUE(same_as_serial(scene, serial, procs, &why))
        << procs[0] << "x" << procs[1] << "x" << procs[2] << ": " << why;
  }
}

TEST(DistributedRun, SymplecticWithDbcMatchesOneRank) {
  const Scene scene = scene_for("dam_break_3d.yaml",
                                {"sph.dp=0.02", "time.integrator=symplectic", "sph.boundary=dbc"});
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene);
  std::string why;
  EXPECT_TRUE(same_as_serial(scene, serial, {0, 0, 0}, &why)) << why;
}

// A gate holding the column goes after 100 steps (the flume's generating box): every rank drops
// the gate's wall particles from its store, DBC walls keep their integrated densities across the
// re-selection, and the run goes on as the one-rank run does.
TEST(DistributedRun, GateRemovedMidRunMatchesOneRank) {
  const Scene scene = scene_for(
      "dam_break_3d.yaml",
      {"sph.dp=0.02", "sph.boundary=dbc", "parallel.skin=0.05",
       "solids=[{name: tank, shape: {type: tank, inner_lo: [0, 0, 0], inner_hi: [0.584, 0.2, "
       "0.35], thickness: 0.01, closed_top: false}}, {name: gate, shape: {type: box, lo: [0.146, "
       "0, 0], hi: [0.19, 0.2, 0.34]}, removed_at: 1}]"});
  const Gate gate{1, 100};
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene, gate);
  std::string why;
  EXPECT_TRUE(same_as_serial(scene, serial, {0, 0, 0}, &why, gate)) << why;
  if (mpitest::rank() == 0) {  // the comparison can fail: the gate went and the column moved
    BuildReport rep;
    build_particles(scene, &rep);
    EXPECT_EQ(serial.n_wall, rep.wall - rep.wall_by_solid[1]);
    // Against the gate kept shut: once open, the column's face flows toward the open side
    // (x-momentum +0.032 kg m/s of the 8.5 kg column after 100 steps; the whole column is
    // still settling on its DBC floor, which dominates its momentum).
    const ParticleSet<Host> shut = serial_run(scene);
    const double px_open = double(probe_energy(serial, scene.gravity).momentum.x);
    const double px_shut = double(probe_energy(shut, scene.gravity).momentum.x);
    std::printf("fluid x-momentum: gate opened at step 100 %.4f, kept shut %.4f kg m/s\n", px_open,
                px_shut);
    EXPECT_GT(px_open - px_shut, 0.01);
  }
}

// Boxes rebalanced during the run: the column is thrown along x at 2 m/s, so the owned fluid per
// rank drifts off balance and the boxes follow it (checked every 20 steps, above 5%). Each rank's
// walls are dealt anew from their old owners (deal_walls), DBC walls with their integrated
// densities, and the run goes on as on one rank.
TEST(DistributedRun, RebalancedDuringTheRunWithDbcMatchesOneRank) {
  const Scene scene =
      scene_for("dam_break_3d.yaml",
                {"sph.dp=0.02", "sph.boundary=dbc", "parallel.skin=0.05", "time.cfl=0.2",
                 "parallel.rebalance_every=20", "parallel.imbalance=1.05",
                 "fluid_blocks=[{lo: [0, 0, 0], hi: [0.146, 0.2, 0.292], velocity: [2, 0, 0]}]"});
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene);
  std::string why;
  int rebalances = 0;
  EXPECT_TRUE(same_as_serial(scene, serial, {mpitest::size(), 1, 1}, &why, {}, &rebalances)) << why;
  std::printf("rebalanced %d times in %d steps\n", rebalances, kSteps);
  EXPECT_GE(rebalances, 2);
}

TEST(DistributedRun, HbpColumnCollapse2DMatchesOneRank) {
  const Scene scene = scene_for("column_collapse_2d.yaml", {"sph.dp=0.01", "parallel.skin=0.05"});
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene);
  std::string why;
  EXPECT_TRUE(same_as_serial(scene, serial, {0, 1, 0}, &why)) << why;
}

// mdbc_limiter.csv on many ranks: a debris block thrown at 3 m/s hits the barrier row (x = 0.6 m),
// which the rank boundaries cut across the channel (along y), so walls on several ranks are
// clipped. Walls whose fit passes the bound by round-off only are not counted (mdbc_cut_is_clip):
// counted, there were 46 of them on one rank and 49 and 52 on 2 and 3. The count, the
// x range and the position of the largest cut equal the one-rank values exactly, the maxima to
// 1e-9. The halo copies are refreshed first: read as the step left them (a step old), the largest
// fit differed by 2.9 kg/m^3 on 4 ranks.
// The same thrown block on the V30 barrier, whose thin walls have a ghost node on either face:
// the rank owning a wall's first ghost node gathers at the second one too, which lies up to twice
// the wall's thickness away. A halo reaching only the kernel's support past the box truncated that
// gather, and 2 ranks differed from one by 2e-5 within 8 steps; the halo now reaches that far
// farther (BuildReport::ghost_spread).
TEST(DistributedRun, ThinBarrierWallsAcrossRanksMatchOneRank) {
  const Scene scene =
      scene_for("flume/flume.yaml",
                {"sph.dp=0.02", "barrier.preset=V30",
                 "fluid_blocks[0]={lo: [0.40, 0, 0], hi: [0.58, 0.4, 0.16], velocity: [3, 0, 0]}"});
  ParticleSet<Host> serial;
  if (mpitest::rank() == 0) serial = serial_run(scene);
  std::string why;
  EXPECT_TRUE(same_as_serial(scene, serial, {1, mpitest::size(), 1}, &why)) << why;
}

TEST(DistributedRun, MdbcLimiterStatsOfTheFlumeMatchOneRank) {
  const Scene scene =
      scene_for("flume/flume.yaml",
                {"sph.dp=0.02", "barrier.preset=V30",
                 "fluid_blocks[0]={lo: [0.40, 0, 0], hi: [0.58, 0.4, 0.16], velocity: [3, 0, 0]}"});
  constexpr int kLimiterSteps = 80;
  BuildReport rep;
  ParticleSet<Host> ps = build_particles(scene, &rep);
  auto serial = make_host_solver(scene, std::move(ps), resolve_sound_speed(scene, rep));
  std::ostringstream log;
  BuildReport rep_n;
  std::shared_ptr<MpiExchange> ex;
  auto solver = make_solver(scene, Backend::kHost, log, &rep_n, &ex, {1, mpitest::size(), 1});
  ASSERT_TRUE(all_ranks(ex != nullptr));
  for (int i = 0; i < kLimiterSteps; ++i) {
    serial->step();
    solver->step();
  }
  const MdbcLimiterStats want = serial->mdbc_limiter_stats();
  const MdbcLimiterStats got = solver->mdbc_limiter_stats();
  if (mpitest::rank() == 0)
    std::printf(
        "limiter: %g clipped over x in [%g, %g], largest cut %.12g (one rank %.12g) at "
        "(%g, %g, %g), largest fit %.12g (one rank %.12g)\n",
        got.clipped, double(got.clip_x_lo), double(got.clip_x_hi), double(got.rho_cut_max),
        double(want.rho_cut_max), double(got.cut_at.x), double(got.cut_at.y), double(got.cut_at.z),
        double(got.rho_fit_max), double(want.rho_fit_max));
  EXPECT_GT(want.clipped, 1);  // else this checks nothing
  EXPECT_EQ(got.clipped, want.clipped);
  EXPECT_EQ(got.clip_x_lo, want.clip_x_lo);
  EXPECT_EQ(got.clip_x_hi, want.clip_x_hi);
  EXPECT_EQ(got.cut_at.x, want.cut_at.x);
  EXPECT_EQ(got.cut_at.y, want.cut_at.y);
  EXPECT_EQ(got.cut_at.z, want.cut_at.z);
  EXPECT_NEAR(double(got.rho_fit_max), double(want.rho_fit_max), 1e-9 * double(want.rho_fit_max));
  EXPECT_NEAR(double(got.rho_cut_max), double(want.rho_cut_max), 1e-9 * double(want.rho_fit_max));
}

}  // namespace
}  // namespace sphdem
