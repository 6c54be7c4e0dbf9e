// Fixed walls per box (issue #7, DESIGN.md §5): no rank holds the whole wall set. After a
// rebalance or a checkpoint read the walls are dealt to the ranks that keep them
// (MpiExchange::deal_walls). Checked against the brute-force selection: keep_walls applied to the
// whole wall set of the scene, rank by rank, with the same boxes.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "decomposition/distributed.hpp"
#include "io/scene_yaml.hpp"
#include "mpi/mpi_test_util.hpp"
#include "scene/build.hpp"
#include "solver/fluid_params.hpp"

namespace sphdem {
namespace {

using mpitest::all_ranks;

// The given slots of a set, as a set of wall slots.
ParticleSet<Host> slice_slots(const ParticleSet<Host>& ps, const std::vector<Index>& slots) {
  ParticleSet<Host> out;
  auto& src = const_cast<ParticleSet<Host>&>(ps);  // for_each_field is not const; read only
  std::vector<void*> from;
  src.for_each_field([&](const char*, auto& b) { from.push_back(&b); });
  std::size_t f = 0;
  out.for_each_field([&](const char*, auto& o) {
    const auto& b = *static_cast<std::decay_t<decltype(o)>*>(from[f++]);
    for (const Index i : slots) o.vec().push_back(b[std::size_t(i)]);
  });
  out.n_wall = Index(slots.size());
  return out;
}

bool same(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

struct WallScene {
  ParticleSet<Host> all;    // every particle of the scene, as every rank builds it
  ParticleSet<Host> walls;  // its wall slots only, sorted by id
  CellGrid grid;
  Real width = 0;
};

WallScene wall_scene(bool mdbc) {
  const Scene scene =
      load_scene(std::string(SPHDEM_INPUTS) + "/dam_break_3d.yaml",
                 {"sph.dp=0.02", std::string("sph.boundary=") + (mdbc ? "mdbc" : "dbc")});
  WallScene w;
  BuildReport rep;
  w.all = build_particles(scene, &rep);
  const StepParams p = make_step_params(scene, resolve_sound_speed(scene, rep));
  w.grid = p.grid;
  w.width = (Real(2.02) + scene.parallel.skin) * p.h;
  const Index wb = w.all.wall_begin(), n = w.all.size();
  std::vector<Index> slots(static_cast<std::size_t>(n - wb));
  std::iota(slots.begin(), slots.end(), wb);
  std::sort(slots.begin(), slots.end(),
            [&](Index a, Index b) { return w.all.id[std::size_t(a)] < w.all.id[std::size_t(b)]; });
  w.walls = slice_slots(w.all, slots);
  // A distinct density per wall (a built scene has rho0 on all), so the value check below would
  // see a wall that arrived with another wall's values.
  for (Index i = 0; i < w.walls.n_wall; ++i)
    w.walls.rho[std::size_t(i)] = Real(1000) + Real(i) * Real(1e-3);
  return w;
}

// The brute-force answer: the ids of the walls this rank keeps, out of the whole set.
std::vector<GlobalId> kept_ids(const MpiExchange& ex, const ParticleSet<Host>& walls, bool mdbc) {
  const auto keep = ex.keep_walls(walls.pos.data(), walls.ghost.data(), walls.ghost_alt.data(),
                                  walls.n_wall, mdbc);
  std::vector<GlobalId> ids;
  for (Index i = 0; i < walls.n_wall; ++i)
    if (keep[std::size_t(i)]) ids.push_back(walls.id[std::size_t(i)]);
  return ids;
}

// Rank r passes the walls with index i % size == r (a disjoint split, as after a read).
ParticleSet<Host> my_share(const ParticleSet<Host>& walls) {
  std::vector<Index> slots;
  for (Index i = mpitest::rank(); i < walls.n_wall; i += mpitest::size()) slots.push_back(i);
  return slice_slots(walls, slots);
}

// deal_walls gives each rank exactly the brute-force selection, with the values passed.
// per_box: no rank may hold every wall (true where the boxes are longer than the halo reach).
bool dealt_as_kept(const MpiExchange& ex, const WallScene& w, ParticleSet<Host> share, bool mdbc,
                   bool per_box, std::string* why) {
  const ParticleSet<Host> got = ex.deal_walls(share, mdbc);
  const std::vector<GlobalId> want = kept_ids(ex, w.walls, mdbc);
  std::vector<GlobalId> have(got.id.vec().begin(), got.id.vec().end());
  // Each rank checks its own share; every rank then reaches the same collectives below, whether
  // or not its checks failed (a rank that returned early would leave the others waiting).
  bool ok = true;
  if (have != want) {
    *why = "rank " + std::to_string(mpitest::rank()) + " holds " + std::to_string(have.size()) +
           " walls, the brute-force selection " + std::to_string(want.size());
    ok = false;
  }
  for (Index k = 0; ok && k < got.n_wall; ++k) {  // by id: the whole set is sorted by id
    const auto at =
        std::lower_bound(w.walls.id.vec().begin(), w.walls.id.vec().end(), got.id[std::size_t(k)]) -
        w.walls.id.vec().begin();
    if (!same(got.pos[std::size_t(k)], w.walls.pos[std::size_t(at)]) ||
        !same(got.ghost[std::size_t(k)], w.walls.ghost[std::size_t(at)]) ||
        got.rho[std::size_t(k)] != w.walls.rho[std::size_t(at)] ||
        got.body[std::size_t(k)] != w.walls.body[std::size_t(at)]) {
      *why = "wall id " + std::to_string(got.id[std::size_t(k)]) + " arrived with other values";
      ok = false;
    }
  }
  // Together the ranks hold each wall at least once; per box, no rank holds them all.
  const long long mine = got.n_wall;
  long long most = 0, sum = 0;
  MPI_Allreduce(&mine, &most, 1, MPI_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(&mine, &sum, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  std::printf("[rank %d] holds %lld of %lld walls (largest share %lld)\n", mpitest::rank(), mine,
              (long long)w.walls.n_wall, most);
  if ((per_box && most >= w.walls.n_wall) || sum < w.walls.n_wall) {
    *why = "largest share " + std::to_string(most) + ", sum " + std::to_string(sum) + " of " +
           std::to_string(w.walls.n_wall) + " walls";
    ok = false;
  }
  return all_ranks(ok);
}

TEST(WallsPerBox, DealGivesEachRankTheWallsNearItsBox) {
  for (const bool mdbc : {true, false}) {
    const WallScene w = wall_scene(mdbc);
    const int n = mpitest::size();
    for (const std::array<int, 3> procs :
         {std::array<int, 3>{n, 1, 1}, std::array<int, 3>{1, n, 1}, std::array<int, 3>{1, 1, n}}) {
      MpiExchange ex(MPI_COMM_WORLD, w.grid, procs, w.width, 1.2);
      std::string why;
      // Along x (0.584 m) each box is longer than the halo reach; across y (0.2 m) a middle
      // box's reach covers the tank.
      EXPECT_TRUE(dealt_as_kept(ex, w, my_share(w.walls), mdbc, procs[0] == n, &why))
          << (mdbc ? "mDBC " : "DBC ") << procs[0] << "x" << procs[1] << "x" << procs[2] << ": "
          << why;
    }
  }
}

// After a rebalance moved the boxes: the walls each rank owned under the old boxes, dealt again,
// are the selection under the new ones (what the solver does in reselect_walls).
TEST(WallsPerBox, OwnedWallsDealtAfterARebalance) {
  const WallScene w = wall_scene(true);
  MpiExchange ex(MPI_COMM_WORLD, w.grid, {mpitest::size(), 1, 1}, w.width, 1.0);
  ParticleSet<Host> fluid = w.all;
  keep_owned_fluid(ex, fluid);
  std::string why;
  ParticleSet<Host> share = my_share(w.walls);
  ParticleSet<Host> held = ex.deal_walls(share, true);
  const auto before = ex.decomposition().cell_starts(0);
  ASSERT_TRUE(all_ranks(ex.rebalance(fluid)));  // the column fills part of the tank only
  ASSERT_NE(before, ex.decomposition().cell_starts(0));
  // Each rank passes the walls it owned under the old boxes (the same split, made again).
  MpiExchange old(MPI_COMM_WORLD, w.grid, {mpitest::size(), 1, 1}, w.width, 1.2);
  std::vector<Index> slots;
  for (Index k = 0; k < held.n_wall; ++k)
    if (old.owns(held.ghost[std::size_t(k)])) slots.push_back(k);
  EXPECT_TRUE(dealt_as_kept(ex, w, slice_slots(held, slots), true, false, &why)) << why;
}

TEST(WallsPerBox, AWallPassedByTwoRanksIsAnError) {
  if (mpitest::size() < 2) GTEST_SKIP() << "needs two ranks";
  const WallScene w = wall_scene(true);
  MpiExchange ex(MPI_COMM_WORLD, w.grid, {mpitest::size(), 1, 1}, w.width, 1.2);
  ParticleSet<Host> every = w.walls;  // every rank passes every wall
  std::string msg;
  try {
    ex.deal_walls(every, true);
  } catch (const RuntimeFault& e) {
    msg = e.what();
  }
  EXPECT_TRUE(all_ranks(msg.find("was passed by more than one rank") != std::string::npos)) << msg;
}

TEST(WallsPerBox, AWallNoRankPassesIsNotMadeUp) {
  // Rank 0 keeps its share back: the others' shares still arrive where they belong, and the
  // missing walls are missing (the deal does not invent values).
  const WallScene w = wall_scene(true);
  MpiExchange ex(MPI_COMM_WORLD, w.grid, {mpitest::size(), 1, 1}, w.width, 1.2);
  ParticleSet<Host> share = my_share(w.walls);
  if (mpitest::rank() == 0) share = slice_slots(share, {});
  const ParticleSet<Host> got = ex.deal_walls(share, true);
  bool ok = true;
  for (Index k = 0; k < got.n_wall; ++k) {
    const auto at =
        std::lower_bound(w.walls.id.vec().begin(), w.walls.id.vec().end(), got.id[std::size_t(k)]) -
        w.walls.id.vec().begin();
    ok = ok && at % mpitest::size() != 0;
  }
  EXPECT_TRUE(all_ranks(ok));
}

}  // namespace
}  // namespace sphdem
