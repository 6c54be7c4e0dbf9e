// Migration: DMSwarm redistribution (any distance) and the neighbour leaver exchange; count and
// mass are conserved exactly, particles end on the rank whose box holds them, and a jump of more
// than one rank is an error, never a loss.
#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "decomposition/domain_decomposition.hpp"
#include "decomposition/migration.hpp"
#include "mpi_test_util.hpp"

namespace sphdem {
namespace {

using namespace mpitest;

constexpr Index kWalls = 3;

// Everything a migration must guarantee, checked against the global set g.
void check_after_migration(const DomainDecomposition& dd, const ParticleSet<Host>& ps,
                           const GlobalSet& g, const char* what) {
  SCOPED_TRACE(what);
  // Each owned particle sits in this rank's box and carries all its fields intact.
  bool placed = true, intact = true;
  const Vec3 lo = dd.owned_lo(), hi = dd.owned_hi();
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const Vec3& x = ps.pos[std::size_t(i)];
    placed = placed && dd.owner_of(x) == rank();
    for (int k = 0; k < 3; ++k) placed = placed && x[k] >= lo[k] && x[k] < hi[k];
    intact = intact && particle_matches(ps, i, g);
  }
  EXPECT_TRUE(all_ranks(placed)) << "a particle is not on the rank whose box holds it";
  EXPECT_TRUE(all_ranks(intact)) << "a particle's fields changed in transit";
  // Halo dropped, walls kept after the owned range.
  bool walls = ps.n_halo == 0 && ps.n_wall == kWalls && Index(ps.id.size()) == ps.size();
  for (Index w = 0; walls && w < kWalls; ++w)
    walls = ps.id[std::size_t(ps.n_fluid + w)] == GlobalId(1000000000) + GlobalId(w) &&
            ps.body[std::size_t(ps.n_fluid + w)] == 0;
  EXPECT_TRUE(all_ranks(walls)) << "wall slots were not preserved";
  // Count exact; every id exactly once, with its exact mass.
  EXPECT_EQ(sum_ranks(ps.n_fluid), std::int64_t(g.size()));
  const auto all = gather_by_id(ps, ps.mass.vec());
  bool exact = true;
  if (rank() == 0) {
    exact = all.size() == g.size();
    for (std::size_t i = 0; exact && i < all.size(); ++i)
      exact = all[i].first == GlobalId(i) && all[i].second == g.mass[i];
  }
  EXPECT_TRUE(all_ranks(exact)) << "the set of (id, mass) pairs changed";
}

struct Case {
  std::array<int, 3> procs;
  bool periodic;
};

std::vector<Case> cases() {
  std::vector<Case> v;
  for (const auto& l : line_layouts(3)) v.push_back({l, false});
  if (size() == 4) v.push_back({{2, 2, 1}, false});
  v.push_back({{size(), 1, 1}, true});
  v.push_back({{0, 0, 0}, true});
  return v;
}

std::string case_name(const Case& c) {
  return layout_name(c.procs) + (c.periodic ? " periodic" : "");
}

TEST(Migration, RedistributeFromSlicesConservesAndPlaces) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(case_name(c));
    const CellGrid grid = unit_grid(3, Real(0.1), c.periodic, c.periodic, c.periodic);
    DomainDecomposition dd(comm(), grid, c.procs);
    const GlobalSet g = make_global(3000, 1, 3, Vec3(0, 0, 0), Vec3(1, 1, 1));
    ParticleSet<Host> ps = make_slice(g, kWalls);
    const ParticleTotals before = particle_totals(comm(), ps);
    const MigrationReport rep = redistribute(dd, ps);
    const ParticleTotals after = particle_totals(comm(), ps, &before);
    EXPECT_TRUE(before == after);
    EXPECT_EQ(rep.global_count, std::int64_t(g.size()));
    EXPECT_EQ(sum_ranks(rep.sent), sum_ranks(rep.received));
    check_after_migration(dd, ps, g, "redistribute from slices");
  }
}

TEST(Migration, InitialDistributionFromRankZero) {
  // Everything starts on rank 0, so most particles jump several ranks: DMSwarm's explicit-rank
  // push must deliver them all.
  const CellGrid grid = unit_grid(3, Real(0.1));
  DomainDecomposition dd(comm(), grid, {1, 1, size()});
  const GlobalSet g = make_global(2000, 2, 3, Vec3(0, 0, 0), Vec3(1, 1, 1));
  ParticleSet<Host> ps = rank() == 0 ? make_set(g, 0, g.size(), kWalls) : make_set(g, 0, 0, kWalls);
  redistribute(dd, ps);
  check_after_migration(dd, ps, g, "initial distribution from rank 0");
}

TEST(Migration, LeaversMoveToNeighbours) {
  if (size() == 1) GTEST_SKIP() << "one rank has no neighbours to send leavers to";
  for (const Case& c : cases()) {
    SCOPED_TRACE(case_name(c));
    const CellGrid grid = unit_grid(3, Real(0.1), c.periodic, c.periodic, c.periodic);
    DomainDecomposition dd(comm(), grid, c.procs);
    GlobalSet g = make_global(3000, 3, 3, Vec3(0, 0, 0), Vec3(1, 1, 1));
    ParticleSet<Host> ps = make_slice(g, kWalls);
    redistribute(dd, ps);
    // Move every particle by up to half a cell (the skin/2 bound between rebuilds) in the
    // global set and in place, then let the leavers go.
    std::mt19937_64 rng(77);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    for (auto& x : g.pos) {
      for (int k = 0; k < 3; ++k) {
        x[k] += Real(u(rng));
        if (c.periodic) {
          if (x[k] < 0) x[k] += 1;
          if (x[k] >= 1) x[k] -= 1;
        } else {
          x[k] = std::min(std::max(x[k], Real(0)), Real(0.999999));
        }
      }
    }
    for (Index i = 0; i < ps.n_fluid; ++i) ps.pos[std::size_t(i)] = g.pos[ps.id[std::size_t(i)]];
    const MigrationReport rep = exchange_leavers(dd, ps);
    EXPECT_GT(sum_ranks(rep.sent), 0);
    EXPECT_EQ(sum_ranks(rep.sent), sum_ranks(rep.received));
    // Stayers keep their order and arrivals follow: sort to compare with the global set.
    check_after_migration(dd, ps, g, "exchange_leavers");
  }
}

// (c) A particle moved from rank 0's box to the far end of a 1x1xN layout: the leaver exchange
// refuses with a RuntimeFault naming the loss and moves nothing; DMSwarm redistribution then
// delivers it.
TEST(Migration, FarJumpIsAnErrorNotALoss) {
  if (size() < 3)
    GTEST_SKIP() << "a jump of more than one rank needs at least 3 ranks along one axis (1x1x"
                 << size() << " has none)";
  const CellGrid grid = unit_grid(3, Real(0.1));
  DomainDecomposition dd(comm(), grid, {1, 1, size()});
  GlobalSet g = make_global(2000, 4, 3, Vec3(0, 0, 0), Vec3(1, 1, 1));
  ParticleSet<Host> ps = make_slice(g, kWalls);
  redistribute(dd, ps);
  ASSERT_TRUE(all_ranks(ps.n_fluid > 0));
  GlobalId moved = 0;
  if (rank() == 0) {
    moved = ps.id[0];
    ps.pos[0].z = Real(0.995);  // inside rank size-1's box
  }
  MPI_Bcast(&moved, 1, MPI_UINT64_T, 0, comm());
  g.pos[moved].z = Real(0.995);
  ASSERT_EQ(dd.owner_of(g.pos[moved]), size() - 1);
  const Index n_before = ps.n_fluid;
  const ParticleTotals before = particle_totals(comm(), ps);
  std::string message;
  try {
    exchange_leavers(dd, ps);
  } catch (const RuntimeFault& e) {
    message = e.what();
  }
  EXPECT_TRUE(all_ranks(!message.empty())) << "no RuntimeFault on some rank";
  EXPECT_NE(message.find("migration would lose 1 particles ("), std::string::npos) << message;
  EXPECT_NE(message.find("kg): a particle moved more than one rank away"), std::string::npos)
      << message;
  EXPECT_NE(message.find("particle id " + std::to_string(moved) + " from rank 0 to rank " +
                         std::to_string(size() - 1)),
            std::string::npos)
      << message;
  if (rank() == 0) std::printf("  expected error: %s\n", message.c_str());
  // Nothing moved, nothing lost.
  EXPECT_EQ(ps.n_fluid, n_before);
  EXPECT_TRUE(particle_totals(comm(), ps, &before) == before);
  // The DMSwarm path takes it all the way.
  redistribute(dd, ps);
  bool there = false;
  for (Index i = 0; i < ps.n_fluid; ++i) there = there || ps.id[std::size_t(i)] == moved;
  int where = there ? rank() : -1;
  MPI_Allreduce(MPI_IN_PLACE, &where, 1, MPI_INT, MPI_MAX, comm());
  EXPECT_EQ(where, size() - 1);
  check_after_migration(dd, ps, g, "redistribute after the far jump");
}

}  // namespace
}  // namespace sphdem
