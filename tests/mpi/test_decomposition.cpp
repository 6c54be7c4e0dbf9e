// Ownership boxes from the DMDA, and rebalancing from the particle histogram.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "decomposition/domain_decomposition.hpp"
#include "mpi_test_util.hpp"

namespace sphdem {
namespace {

using namespace mpitest;

// The boxes tile the grid, owner_of agrees with the boxes, and neighbours are symmetric.
void check_layout(int dim, std::array<int, 3> procs, bool periodic) {
  SCOPED_TRACE("dim " + std::to_string(dim) + ", layout " + layout_name(procs) +
               (periodic ? ", periodic x and z" : ""));
  const CellGrid grid = unit_grid(dim, Real(0.1), periodic, false, periodic);
  DomainDecomposition dd(comm(), grid, procs);
  const auto p = dd.procs();
  EXPECT_EQ(p[0] * p[1] * p[2], size());
  for (int k = 0; k < 3; ++k)
    if (procs[std::size_t(k)] > 0) {
      EXPECT_EQ(p[std::size_t(k)], procs[std::size_t(k)]);
    }
  if (dim == 2) {
    EXPECT_EQ(p[1], 1);
  }

  // Volumes of all boxes add up to the grid's.
  double vol = 0, grid_vol = 1;
  for (int r = 0; r < size(); ++r) {
    const Vec3 lo = dd.box_lo(r), hi = dd.box_hi(r);
    double v = 1;
    for (int k = 0; k < 3; ++k) v *= double(hi[k] - lo[k]);
    vol += v;
  }
  for (int k = 0; k < 3; ++k) grid_vol *= double(grid.n[k]) * double(grid.cell[k]);
  EXPECT_NEAR(vol, grid_vol, 1e-12 * grid_vol);

  // owner_of(x) is the rank whose box holds x.
  const GlobalSet g = make_global(500, 11, dim, Vec3(0, 0, 0), Vec3(1, 1, 1));
  bool ok = true;
  for (const Vec3& x : g.pos) {
    const int o = dd.owner_of(x);
    const Vec3 lo = dd.box_lo(o), hi = dd.box_hi(o);
    for (int k = 0; k < 3; ++k) ok = ok && x[k] >= lo[k] && x[k] < hi[k];
  }
  EXPECT_TRUE(all_ranks(ok)) << "a point lies outside its owner's box";
  EXPECT_TRUE(all_ranks(dd.owns(Vec3(dd.owned_lo().x, dd.owned_lo().y, dd.owned_lo().z))));

  // Neighbour relation: symmetric, and exactly the ranks whose boxes touch (incl. the wrap).
  std::vector<int> adj(std::size_t(size() * size()), 0);
  for (int q : dd.neighbours()) adj[std::size_t(rank() * size() + q)] = 1;
  MPI_Allreduce(MPI_IN_PLACE, adj.data(), size() * size(), MPI_INT, MPI_SUM, comm());
  bool sym = true;
  for (int a = 0; a < size(); ++a)
    for (int b = 0; b < size(); ++b)
      sym = sym && adj[std::size_t(a * size() + b)] == adj[std::size_t(b * size() + a)];
  EXPECT_TRUE(sym);
  bool touch = true;
  for (int q = 0; q < size(); ++q) {
    if (q == rank()) continue;
    bool touching = true;
    for (int k = 0; k < 3; ++k) {
      if (dim == 2 && k == 1) continue;
      const Real a0 = dd.owned_lo()[k], a1 = dd.owned_hi()[k];
      const Real b0 = dd.box_lo(q)[k], b1 = dd.box_hi(q)[k];
      const Real L = grid.periodic[k] ? grid.period[k] : Real(0);
      const Real eps = Real(1e-9);
      bool t = a0 <= b1 + eps && b0 <= a1 + eps;
      if (L > 0)
        t = t || (std::abs(a0 - (b1 - L)) < eps) || (std::abs(b0 - (a1 - L)) < eps) ||
            (std::abs(a1 - (b0 + L)) < eps) || (std::abs(b1 - (a0 + L)) < eps);
      touching = touching && t;
    }
    touch = touch && (touching == dd.is_neighbour(q));
  }
  EXPECT_TRUE(all_ranks(touch)) << "neighbours() differs from the ranks whose boxes touch";
}

TEST(Ownership, BoxesTileTheGrid3D) {
  for (const auto& l : line_layouts(3)) check_layout(3, l, false);
  if (size() == 4) check_layout(3, {2, 2, 1}, false);
  check_layout(3, {size(), 1, 1}, true);
}

TEST(Ownership, BoxesTileTheGrid2D) {
  for (const auto& l : line_layouts(2)) check_layout(2, l, false);
  check_layout(2, {1, 1, size()}, true);
}

TEST(Ownership, ImpossibleLayoutIsAnInputError) {
  const CellGrid grid = unit_grid(3, Real(0.1));
  EXPECT_THROW(DomainDecomposition(comm(), grid, {size() + 1, 1, 1}), InputError);
  const CellGrid coarse = unit_grid(3, Real(0.5));  // 2 cells per axis
  if (size() > 2) {
    EXPECT_THROW(DomainDecomposition(comm(), coarse, {size(), 1, 1}), InputError);
  }
}

// A skewed set (density growing linearly along the split axes) is rebalanced below the
// threshold, the count is unchanged, and the DMDA is recreated with the new ranges.
void check_rebalance(std::array<int, 3> procs, std::array<bool, 3> skew) {
  SCOPED_TRACE("layout " + layout_name(procs));
  const double threshold = 1.2;
  const CellGrid grid = unit_grid(3, Real(1.0 / 64));
  DomainDecomposition dd(comm(), grid, procs);
  const GlobalSet g = make_global(20000, 5, 3, Vec3(0, 0, 0), Vec3(1, 1, 1), [&](double u, int k) {
    return skew[std::size_t(k)] ? std::sqrt(u) : u;
  });
  ParticleSet<Host> ps = make_slice(g);
  const auto before = dd.loads(ps.pos.data(), ps.n_fluid);
  const auto rep = dd.rebalance(ps.pos.data(), ps.n_fluid, threshold);
  EXPECT_GT(rep.before, threshold);
  EXPECT_TRUE(rep.applied);
  EXPECT_LT(rep.after, threshold);
  EXPECT_LT(rep.after, rep.before);
  // The new DMDA's boxes give the reported imbalance, and the particles fit in them.
  const auto after = dd.loads(ps.pos.data(), ps.n_fluid);
  std::int64_t nb = 0, na = 0, mx = 0;
  for (auto v : before) nb += v;
  for (auto v : after) {
    na += v;
    mx = std::max(mx, v);
  }
  EXPECT_EQ(nb, std::int64_t(g.size()));
  EXPECT_EQ(na, std::int64_t(g.size()));
  EXPECT_NEAR(double(mx) * size() / double(na), rep.after, 1e-12);
  if (rank() == 0)
    std::printf("  rebalance %s: max/mean %.3f -> %.3f (threshold %.2f)\n",
                layout_name(dd.procs()).c_str(), rep.before, rep.after, threshold);
}

TEST(Rebalance, SkewedAlongEachAxis) {
  if (size() == 1) GTEST_SKIP() << "one rank is always balanced";
  check_rebalance({size(), 1, 1}, {true, false, false});
  check_rebalance({1, size(), 1}, {false, true, false});
  check_rebalance({1, 1, size()}, {false, false, true});
  if (size() == 4) check_rebalance({2, 2, 1}, {true, true, false});
}

TEST(Rebalance, BalancedSetIsLeftAlone) {
  const CellGrid grid = unit_grid(3, Real(1.0 / 32));
  DomainDecomposition dd(comm(), grid, {size(), 1, 1});
  const GlobalSet g = make_global(4000, 9, 3, Vec3(0, 0, 0), Vec3(1, 1, 1));
  ParticleSet<Host> ps = make_slice(g);
  const auto starts = dd.cell_starts(0);
  const auto rep = dd.rebalance(ps.pos.data(), ps.n_fluid, 1.5);
  EXPECT_FALSE(rep.applied);
  EXPECT_LT(rep.before, 1.5);
  EXPECT_EQ(dd.cell_starts(0), starts);
}

}  // namespace
}  // namespace sphdem
