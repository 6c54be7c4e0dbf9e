// Halo and migration timings for a dam_break_3d-sized fluid set (docs/SCALING.md). Disabled by
// default; run with
//   mpiexec --oversubscribe -n N mpi_tests --gtest_also_run_disabled_tests
//           --gtest_filter='*Bench*'
// SPHDEM_BENCH_REPS sets the number of timed halo exchanges (default 50).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "decomposition/domain_decomposition.hpp"
#include "decomposition/halo.hpp"
#include "decomposition/migration.hpp"
#include "mpi_test_util.hpp"

namespace sphdem {
namespace {

using namespace mpitest;

double max_ranks(double v) {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, comm());
  return v;
}

// Times f() over all ranks: barrier, run, slowest rank's wall time.
template <class F>
double timed(F&& f) {
  MPI_Barrier(comm());
  const double t0 = MPI_Wtime();
  f();
  return max_ranks(MPI_Wtime() - t0);
}

TEST(Bench, DISABLED_HaloDamBreak3D) {
  // inputs/dam_break_3d.yaml: dp = 0.002, h = 1.2 sqrt(3) dp, column 0.146 x 0.2 x 0.292 m in a
  // domain [-0.05, 0.65] x [-0.05, 0.25] x [-0.05, 0.6]. Cells and halo width 2h + 10% skin.
  const Real dp = Real(0.002), h = Real(1.2 * std::sqrt(3.0)) * dp;
  const Real width = Real(1.1) * 2 * h;
  const bool per[3] = {false, false, false};
  const CellGrid grid =
      make_cell_grid(3, Vec3(-0.05, -0.05, -0.05), Vec3(0.65, 0.25, 0.6), width, per);
  const int nx = 73, ny = 100, nz = 146;
  const std::int64_t n = std::int64_t(nx) * ny * nz;
  const char* reps_env = std::getenv("SPHDEM_BENCH_REPS");
  const int reps = reps_env ? std::max(1, std::atoi(reps_env)) : 50;

  // This rank's slice of ids, as a restart would read it.
  const std::int64_t first = n * rank() / size(), last = n * (rank() + 1) / size();
  ParticleSet<Host> ps;
  ps.n_fluid = Index(last - first);
  ps.resize(ps.size());
  for (std::int64_t id = first; id < last; ++id) {
    const std::size_t s = std::size_t(id - first);
    const std::int64_t i = id % nx, j = (id / nx) % ny, k = id / (std::int64_t(nx) * ny);
    ps.id[s] = GlobalId(id);
    ps.pos[s] =
        Vec3((Real(i) + Real(0.5)) * dp, (Real(j) + Real(0.5)) * dp, (Real(k) + Real(0.5)) * dp);
    ps.mass[s] = Real(1000) * dp * dp * dp;
    ps.rho[s] = 1000;
    ps.body[s] = -1;
  }

  DomainDecomposition dd(comm(), grid);
  const double t_dist = timed([&] { redistribute(dd, ps); });
  const auto rep = dd.rebalance(ps.pos.data(), ps.n_fluid, 1.1);
  const double t_redist = timed([&] { redistribute(dd, ps); });
  const double t_leavers = timed([&] { exchange_leavers(dd, ps); });
  HaloPlan plan(dd, ps, width);
  const double t_build = timed([&] { plan = HaloPlan(dd, ps, width); });
  const double t_fill = timed([&] { plan.fill(ps); });

  // One step's exchange: positions, velocities, densities and pressures of the halo.
  const Index no = ps.n_fluid;
  // The variants are interleaved within each repetition so that they see the same machine load.
  std::vector<double> step, vec3, real1, posn, red;
  for (int r = 0; r < reps; ++r) {
    step.push_back(timed([&] {
      plan.bcast_positions(ps.pos.data(), ps.pos.data() + no);
      plan.bcast(ps.vel.data(), ps.vel.data() + no);
      plan.bcast(ps.rho.data(), ps.rho.data() + no);
      plan.bcast(ps.press.data(), ps.press.data() + no);
    }));
    vec3.push_back(timed([&] { plan.bcast(ps.vel.data(), ps.vel.data() + no); }));
    real1.push_back(timed([&] { plan.bcast(ps.rho.data(), ps.rho.data() + no); }));
    posn.push_back(timed([&] { plan.bcast_positions(ps.pos.data(), ps.pos.data() + no); }));
    red.push_back(timed([&] { plan.reduce_sum(ps.acc.data() + no, ps.acc.data()); }));
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  auto fastest = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };

  // Then every particle moves by one lattice spacing dp along x, so that one layer crosses each
  // x boundary, and the leavers go to their neighbours.
  const Index n_halo_lattice = plan.n_halo();
  ps.n_halo = 0;
  ps.resize(ps.n_fluid);
  for (Index i = 0; i < ps.n_fluid; ++i) ps.pos[std::size_t(i)].x += dp;
  MigrationReport moved;
  const double t_moved = timed([&] { moved = exchange_leavers(dd, ps); });
  const std::int64_t n_moved = sum_ranks(moved.sent);

  const std::int64_t owned = sum_ranks(ps.n_fluid), halo = sum_ranks(n_halo_lattice);
  std::int64_t max_owned = ps.n_fluid, max_halo = n_halo_lattice;
  MPI_Allreduce(MPI_IN_PLACE, &max_owned, 1, MPI_INT64_T, MPI_MAX, comm());
  MPI_Allreduce(MPI_IN_PLACE, &max_halo, 1, MPI_INT64_T, MPI_MAX, comm());
  EXPECT_EQ(owned, n);
  if (rank() == 0) {
    const auto p = dd.procs();
    std::printf(
        "BENCH ranks %d layout %dx%dx%d cells %dx%dx%d owned %lld halo %lld "
        "halo/owned %.4f max_owned %lld max_halo %lld\n",
        size(), p[0], p[1], p[2], grid.n[0], grid.n[1], grid.n[2], (long long)owned,
        (long long)halo, double(halo) / double(owned), (long long)max_owned, (long long)max_halo);
    std::printf("BENCH imbalance %.3f -> %.3f (applied %d)\n", rep.before, rep.after,
                int(rep.applied));
    std::printf(
        "BENCH seconds: initial redistribute %.4f, redistribute after rebalance %.4f, "
        "leaver exchange (no leavers) %.4f, (%lld leavers after a dp move) %.4f, "
        "halo build %.4f, fill all 14 fields %.4f\n",
        t_dist, t_redist, t_leavers, (long long)n_moved, t_moved, t_build, t_fill);
    std::printf(
        "BENCH ms per call, median (fastest) of %d: step pos+vel+rho+press %.3f (%.3f), "
        "vel vec3 %.3f (%.3f), rho %.3f (%.3f), pos shifted %.3f (%.3f), "
        "reduce_sum vec3 %.3f (%.3f)\n",
        reps, 1e3 * median(step), 1e3 * fastest(step), 1e3 * median(vec3), 1e3 * fastest(vec3),
        1e3 * median(real1), 1e3 * fastest(real1), 1e3 * median(posn), 1e3 * fastest(posn),
        1e3 * median(red), 1e3 * fastest(red));
  }
}

}  // namespace
}  // namespace sphdem
