// Neighbour search: the sort-based cell list must find exactly the pairs a brute-force N^2 search
// finds (2D, 3D, periodic, particles in boundary cells), and sums over neighbours must be
// bit-identical from run to run.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "neighbor/cell_list.hpp"
#include "solver/particles.hpp"

namespace sphdem {
namespace {

struct Cloud {
  std::vector<Vec3> pos;
  std::vector<GlobalId> id;
};

Cloud random_cloud(int dim, Index n, Vec3 lo, Vec3 hi, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  for (Index i = 0; i < n; ++i) {
    Vec3 x(lo.x + (hi.x - lo.x) * u(rng), dim == 3 ? lo.y + (hi.y - lo.y) * u(rng) : 0,
           lo.z + (hi.z - lo.z) * u(rng));
    c.pos.push_back(x);
    c.id.push_back(GlobalId(1000 + 7 * i));  // ids not equal to slots
  }
  // Shuffle so slot order differs from id order.
  std::vector<Index> perm(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) perm[std::size_t(i)] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  Cloud s;
  for (Index i : perm) {
    s.pos.push_back(c.pos[std::size_t(i)]);
    s.id.push_back(c.id[std::size_t(i)]);
  }
  return s;
}

using PairSet = std::set<std::pair<GlobalId, GlobalId>>;

PairSet brute_force(const CellGrid& g, const Cloud& c, Real radius) {
  PairSet out;
  for (std::size_t i = 0; i < c.pos.size(); ++i)
    for (std::size_t j = 0; j < c.pos.size(); ++j) {
      if (i == j) continue;
      if (norm2(g.separation(c.pos[i], c.pos[j])) < radius * radius) out.insert({c.id[i], c.id[j]});
    }
  return out;
}

// Sorts the cloud with the cell list and returns the pairs it finds.
PairSet cell_list_pairs(const CellGrid& g, Cloud c, Real radius, Index begin = 0) {
  const Index n = Index(c.pos.size());
  // Put the cloud at an offset `begin` in the arrays, as a boundary range would be.
  std::vector<Vec3> pos(std::size_t(begin), Vec3(1e9, 1e9, 1e9));
  std::vector<GlobalId> id(std::size_t(begin), 0);
  pos.insert(pos.end(), c.pos.begin(), c.pos.end());
  id.insert(id.end(), c.id.begin(), c.id.end());
  Buffer<Vec3, Host> bpos;
  bpos.vec() = pos;
  Buffer<GlobalId, Host> bid;
  bid.vec() = id;
  CellList<Host> cl;
  sort_cells(Host{}, g, bpos.data(), bid.data(), GlobalId(100000), begin, n, cl);
  Buffer<Vec3, Host> s1;
  Buffer<GlobalId, Host> s2;
  permute_range(Host{}, bpos, cl, s1);
  permute_range(Host{}, bid, cl, s2);
  mark_cells(Host{}, g, cl);
  // Sorted by (cell, id): within a cell ids ascend.
  for (Index i = begin + 1; i < begin + n; ++i) {
    const auto k0 = g.key_of(bpos[std::size_t(i - 1)]), k1 = g.key_of(bpos[std::size_t(i)]);
    EXPECT_LE(k0, k1);
    if (k0 == k1) {
      EXPECT_LT(bid[std::size_t(i - 1)], bid[std::size_t(i)]);
    }
  }
  PairSet out;
  const CellListView v = cl.view();
  for (Index i = begin; i < begin + n; ++i) {
    for_each_neighbor(g, v, bpos.data(), bpos[std::size_t(i)], radius * radius,
                      [&](Index j, const Vec3&, Real) {
                        if (j != i) out.insert({bid[std::size_t(i)], bid[std::size_t(j)]});
                      });
  }
  return out;
}

// Sorts a cloud with the cell list (positions and ids permuted, cells marked): a whole range at
// slot 0.
struct SortedCloud {
  Buffer<Vec3, Host> pos;
  Buffer<GlobalId, Host> id;
  CellList<Host> cl;
};
SortedCloud sort_cloud(const CellGrid& g, const Cloud& c) {
  SortedCloud sc;
  sc.pos.vec() = c.pos;
  sc.id.vec() = c.id;
  const Index n = Index(c.pos.size());
  sort_cells(Host{}, g, sc.pos.data(), sc.id.data(), GlobalId(100000), 0, n, sc.cl);
  Buffer<Vec3, Host> s1;
  Buffer<GlobalId, Host> s2;
  permute_range(Host{}, sc.pos, sc.cl, s1);
  permute_range(Host{}, sc.id, sc.cl, s2);
  mark_cells(Host{}, g, sc.cl);
  return sc;
}

TEST(Neighbors, MatchBruteForce3D) {
  const bool per[3] = {false, false, false};
  const Real radius = 0.1;
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(1, 0.5, 0.7), radius, per);
  const Cloud c = random_cloud(3, 1500, Vec3(0, 0, 0), Vec3(1, 0.5, 0.7), 1);
  const PairSet ref = brute_force(g, c, radius);
  ASSERT_GT(ref.size(), 1000u);
  EXPECT_EQ(cell_list_pairs(g, c, radius), ref);
}

TEST(Neighbors, MatchBruteForce2D) {
  const bool per[3] = {false, false, false};
  const Real radius = 0.05;
  const CellGrid g = make_cell_grid(2, Vec3(0, 0, 0), Vec3(1, 0, 0.6), radius, per);
  EXPECT_EQ(g.n[1], 1);
  const Cloud c = random_cloud(2, 2000, Vec3(0, 0, 0), Vec3(1, 0, 0.6), 2);
  const PairSet ref = brute_force(g, c, radius);
  ASSERT_GT(ref.size(), 1000u);
  EXPECT_EQ(cell_list_pairs(g, c, radius), ref);
}

TEST(Neighbors, PeriodicAxes) {
  const bool per[3] = {true, false, true};
  const Real radius = 0.09;
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(0.5, 0.4, 0.45), radius, per);
  const Cloud c = random_cloud(3, 1200, Vec3(0, 0, 0), Vec3(0.5, 0.4, 0.45), 3);
  const PairSet ref = brute_force(g, c, radius);
  // Pairs across the periodic faces exist and are found.
  std::size_t across = 0;
  for (std::size_t i = 0; i < c.pos.size(); ++i)
    for (std::size_t j = 0; j < c.pos.size(); ++j)
      if (i != j && std::abs(c.pos[i].x - c.pos[j].x) > 0.3 &&
          norm2(g.separation(c.pos[i], c.pos[j])) < radius * radius)
        ++across;
  EXPECT_GT(across, 10u);
  EXPECT_EQ(cell_list_pairs(g, c, radius), ref);
}

TEST(Neighbors, ReachTwoMatchesBruteForceIn2DAnd3DAndPeriodic) {
  // Cells of half the radius scanned two on each side (what the solver uses).
  for (int dim : {2, 3}) {
    for (bool periodic : {false, true}) {
      const bool per[3] = {periodic, false, periodic};
      const Real radius = 0.1;
      const Vec3 hi(0.7, dim == 3 ? 0.5 : 0.0, 0.6);
      const CellGrid g = make_cell_grid(dim, Vec3(0, 0, 0), hi, radius / 2, per, 2);
      EXPECT_EQ(g.reach, 2);
      const Cloud c = random_cloud(dim, dim == 3 ? 1500 : 1200, Vec3(0, 0, 0), hi, 11 + dim);
      const PairSet ref = brute_force(g, c, radius);
      ASSERT_GT(ref.size(), 1000u);
      EXPECT_EQ(cell_list_pairs(g, c, radius), ref) << "dim " << dim << " periodic " << periodic;
    }
  }
}

TEST(Neighbors, ParticlesOutsideGridClampToBoundaryCells) {
  // Points slightly outside the grid (walls lie outside the fluid domain) land in edge cells and
  // are still found: the radius is smaller than the overhang.
  const bool per[3] = {false, false, false};
  const Real radius = 0.1;
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(1, 1, 1), radius, per);
  const Cloud c = random_cloud(3, 800, Vec3(-0.05, -0.05, -0.05), Vec3(1.05, 1.05, 1.05), 4);
  EXPECT_EQ(cell_list_pairs(g, c, radius), brute_force(g, c, radius));
}

TEST(Neighbors, RangeAtAnOffset) {
  const bool per[3] = {false, false, false};
  const Real radius = 0.1;
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(1, 1, 1), radius, per);
  const Cloud c = random_cloud(3, 700, Vec3(0, 0, 0), Vec3(1, 1, 1), 5);
  EXPECT_EQ(cell_list_pairs(g, c, radius, 123), brute_force(g, c, radius));
}

TEST(Neighbors, ComparatorDetectsAMissingPair) {
  // The brute-force comparison must be able to fail: shrink the search radius of the cell list.
  const bool per[3] = {false, false, false};
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(1, 1, 1), 0.1, per);
  const Cloud c = random_cloud(3, 500, Vec3(0, 0, 0), Vec3(1, 1, 1), 6);
  EXPECT_NE(cell_list_pairs(g, c, 0.099), brute_force(g, c, 0.1));
}

TEST(Neighbors, SumsAreBitIdenticalAcrossRuns) {
  const bool per[3] = {false, false, false};
  const Real radius = 0.08;
  const CellGrid g = make_cell_grid(3, Vec3(0, 0, 0), Vec3(1, 1, 1), radius, per);
  auto run = [&]() {
    const Cloud c = random_cloud(3, 3000, Vec3(0, 0, 0), Vec3(1, 1, 1), 7);
    SortedCloud sc = sort_cloud(g, c);
    Buffer<Vec3, Host>& pos = sc.pos;
    CellList<Host>& cl = sc.cl;
    const Index n = Index(c.pos.size());
    const Vec3* p = pos.data();
    const CellListView v = cl.view();
    std::vector<double> per_particle(static_cast<std::size_t>(n));
    double* out = per_particle.data();
    for_each(Host{}, n, [=](Index i) {
      double s = 0;
      for_each_neighbor(g, v, p, p[i], radius * radius,
                        [&](Index, const Vec3& r, Real r2) { s += std::sqrt(r2) * (1.0 + r.x); });
      out[i] = s;
    });
    const double total =
        reduce<SumOp, double>(Host{}, n, [=](Index i) { return out[i] * 1.000001; });
    return std::make_pair(per_particle, total);
  };
  const auto a = run();
  const auto b = run();
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);  // bitwise equal doubles
}

// Block occupancy (mark_blocks): queries anywhere in the grid, most in empty blocks, against a
// cloud clustered in one corner must find exactly the brute-force neighbours, with and without
// periodic axes, reach 1 and 2, in 2D and 3D.
TEST(Neighbors, EmptyBlocksSkipOnlyQueriesWithNoNeighbours) {
  struct Case {
    int dim, reach;
    bool per[3];
  };
  const Case cases[] = {{3, 2, {false, false, false}},
                        {3, 1, {false, false, false}},
                        {3, 2, {true, false, true}},
                        {2, 2, {false, false, false}},
                        {2, 1, {true, false, false}}};
  for (const Case& k : cases) {
    const Real radius = 0.05;
    const Vec3 lo(0, 0, 0), hi(1, 0.6, 0.8);
    const CellGrid g = make_cell_grid(k.dim, lo, hi, radius / k.reach, k.per, k.reach);
    // The cloud fills a box in the middle (queries on every side of it) and a slab at x > 0.92
    // (touching the periodic x end, so queries near x = 0 must wrap to it).
    Cloud c = random_cloud(k.dim, 1200, Vec3(0.4, 0.2, 0.3), Vec3(0.6, 0.4, 0.5), 11);
    const Cloud c2 = random_cloud(k.dim, 600, Vec3(0.92, 0, 0), Vec3(1, 0.6, 0.2), 13);
    for (std::size_t a = 0; a < c2.pos.size(); ++a) {
      c.pos.push_back(c2.pos[a]);
      c.id.push_back(c2.id[a] + 50000);
    }
    SortedCloud sc = sort_cloud(g, c);
    Buffer<Vec3, Host>& pos = sc.pos;
    Buffer<GlobalId, Host>& id = sc.id;
    CellList<Host>& cl = sc.cl;
    mark_blocks(Host{}, g, cl);
    const auto empty = std::count(cl.occupied.vec().begin(), cl.occupied.vec().end(), 0);
    ASSERT_GT(empty, 0) << "dim " << k.dim << " reach " << k.reach;
    ASSERT_GT(std::count(cl.occupied.vec().begin(), cl.occupied.vec().end(), 1), 0);
    const Cloud q = random_cloud(k.dim, 4000, lo, hi, 12);
    Index skipped = 0, found = 0;
    for (std::size_t a = 0; a < q.pos.size(); ++a) {
      std::set<GlobalId> ref, got;
      for (std::size_t j = 0; j < c.pos.size(); ++j)
        if (norm2(g.separation(q.pos[a], c.pos[j])) < radius * radius) ref.insert(c.id[j]);
      for_each_neighbor(g, cl.view(), pos.data(), q.pos[a], radius * radius,
                        [&](Index j, const Vec3&, Real) { got.insert(id[std::size_t(j)]); });
      ASSERT_EQ(got, ref) << "dim " << k.dim << " reach " << k.reach << " query " << a;
      const int cx = g.coord(q.pos[a].x, 0), cy = k.dim == 2 ? 0 : g.coord(q.pos[a].y, 1);
      if (!window_occupied(g, cl.occupied.data(), cx, cy, g.coord(q.pos[a].z, 2))) ++skipped;
      if (!ref.empty()) ++found;
    }
    // Both branches are exercised: many queries return early, some find neighbours.
    EXPECT_GT(skipped, 1000) << "dim " << k.dim << " reach " << k.reach;
    EXPECT_GT(found, 100) << "dim " << k.dim << " reach " << k.reach;
  }
}

TEST(Neighbors, HostRadixSortIsStable) {
  std::vector<std::uint64_t> keys = {5, 3, 5, 1, 3, 5, 0, 1};
  std::vector<std::uint32_t> vals = {0, 1, 2, 3, 4, 5, 6, 7};
  sort_pairs_stable(Host{}, keys.data(), vals.data(), Index(keys.size()), 5);
  EXPECT_EQ(keys, (std::vector<std::uint64_t>{0, 1, 1, 3, 3, 5, 5, 5}));
  EXPECT_EQ(vals, (std::vector<std::uint32_t>{6, 3, 7, 1, 4, 0, 2, 5}));
}

TEST(Neighbors, PeriodicAxisTooShortIsAnError) {
  const bool per[3] = {true, false, false};
  EXPECT_THROW(make_cell_grid(3, Vec3(0, 0, 0), Vec3(0.25, 1, 1), 0.1, per), std::exception);
}

}  // namespace
}  // namespace sphdem
