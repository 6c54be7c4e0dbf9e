// Halo through PetscSF: neighbour sums over owned + halo particles equal the single-process
// brute-force result by global id; the halo holds exactly the copies it should (edges, corners,
// periodic images); reduce_sum brings per-halo contributions back to the owners.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "decomposition/domain_decomposition.hpp"
#include "decomposition/halo.hpp"
#include "decomposition/migration.hpp"
#include "mpi_test_util.hpp"

namespace sphdem {
namespace {

using namespace mpitest;

constexpr Real kRadius = Real(0.1);

// A smooth pair weight with compact support: any symmetric function of distance will do.
Real weight(Real d) {
  const Real q = 1 - d / kRadius;
  return q * q * (1 + 2 * d / kRadius);
}

// Single-process reference: sum over j != i within the radius of f_j w(r_ij), minimum image on
// periodic axes (the axes hold at least 3 radii, so at most one image is in range).
std::vector<double> reference_sums(const GlobalSet& g, const CellGrid& grid) {
  const std::size_t n = g.size();
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      const Real d = norm(grid.separation(g.pos[i], g.pos[j]));
      if (d < kRadius) s[i] += double(g.f[j] * weight(d));
    }
  return s;
}

// The halo a rank should hold: every (id, shift) of another rank's particle, or a periodic
// image of any particle, within `width` of this rank's box (outer faces of non-periodic axes
// at infinity, as owner_of clamps).
std::vector<std::tuple<GlobalId, Real, Real, Real>> expected_halo(const DomainDecomposition& dd,
                                                                  const GlobalSet& g, Real width) {
  const CellGrid& grid = dd.grid();
  const auto p = dd.proc_coord(rank());
  const auto np = dd.procs();
  Vec3 lo = dd.owned_lo(), hi = dd.owned_hi();
  for (int k = 0; k < 3; ++k) {
    const bool open = !grid.periodic[k] || (grid.dim == 2 && k == 1);
    if (open && p[std::size_t(k)] == 0) lo[k] = -std::numeric_limits<Real>::infinity();
    if (open && p[std::size_t(k)] == np[std::size_t(k)] - 1)
      hi[k] = std::numeric_limits<Real>::infinity();
  }
  std::vector<std::tuple<GlobalId, Real, Real, Real>> v;
  const int t0 = grid.periodic[0] ? 1 : 0, t1 = grid.periodic[1] ? 1 : 0,
            t2 = grid.periodic[2] ? 1 : 0;
  for (std::size_t id = 0; id < g.size(); ++id)
    for (int a = -t0; a <= t0; ++a)
      for (int b = -t1; b <= t1; ++b)
        for (int c = -t2; c <= t2; ++c) {
          if (a == 0 && b == 0 && c == 0 && dd.owner_of(g.pos[id]) == rank()) continue;
          const Vec3 s(Real(a) * grid.period[0], Real(b) * grid.period[1],
                       Real(c) * grid.period[2]);
          const Vec3 x = g.pos[id] + s;
          Real d2 = 0;
          for (int k = 0; k < 3; ++k) {
            const Real d = std::max({Real(0), lo[k] - x[k], x[k] - hi[k]});
            d2 += d * d;
          }
          if (d2 <= width * width) v.emplace_back(GlobalId(id), s.x, s.y, s.z);
        }
  std::sort(v.begin(), v.end());
  return v;
}

struct Case {
  int dim;
  std::array<int, 3> procs;
  std::array<bool, 3> periodic;
  std::string name() const {
    std::string s = std::to_string(dim) + "D " + layout_name(procs);
    if (periodic[0] || periodic[1] || periodic[2]) {
      s += " periodic ";
      for (int k = 0; k < 3; ++k)
        if (periodic[std::size_t(k)]) s += "xyz"[k];
    }
    return s;
  }
};

std::vector<Case> halo_cases() {
  const int s = size();
  std::vector<Case> v = {
      {3, {s, 1, 1}, {false, false, false}},  // along x
      {3, {1, s, 1}, {false, false, false}},  // along y
      {3, {1, 1, s}, {false, false, false}},  // along z
      {3, {0, 0, 0}, {false, false, false}},  // PETSc's choice
      {3, {s, 1, 1}, {true, false, false}},   // across the periodic x boundary
      {3, {0, 0, 0}, {true, true, true}},     // periodic everywhere, incl. own images
      {2, {s, 1, 1}, {false, false, false}},  // 2D x-z
      {2, {1, 1, s}, {true, false, false}},   // 2D, split along z, periodic x on one process
  };
  if (s == 4) v.push_back({3, {2, 2, 1}, {false, false, false}});  // edges and corners
  return v;
}

void run_case(const Case& c) {
  SCOPED_TRACE(c.name());
  const CellGrid grid =
      make_cell_grid(c.dim, Vec3(0, 0, 0), Vec3(1, 1, 1), kRadius, c.periodic.data());
  DomainDecomposition dd(comm(), grid, c.procs);
  const std::size_t n = c.dim == 3 ? 3000 : 1500;
  const GlobalSet g = make_global(n, 21, c.dim, Vec3(0, 0, 0), Vec3(1, 1, 1));
  ParticleSet<Host> ps = make_slice(g, 2);
  redistribute(dd, ps);

  const Real width = kRadius;
  const HaloPlan plan(dd, ps, width);
  plan.fill(ps);
  // Collective, so that a mismatch on one rank stops every rank here (an ASSERT on one rank
  // alone would leave the others waiting in the reductions below).
  ASSERT_TRUE(all_ranks(ps.n_halo == plan.n_halo())) << "fill() stored a different halo count";

  // Exactly the expected copies, each with every field of its original (position shifted).
  std::vector<std::tuple<GlobalId, Real, Real, Real>> got;
  bool intact = true;
  for (Index j = 0; j < ps.n_halo; ++j) {
    const Index slot = ps.n_fluid + j;
    const Vec3 s = plan.shift()[std::size_t(j)];
    got.emplace_back(ps.id[std::size_t(slot)], s.x, s.y, s.z);
    intact = intact && particle_matches(ps, slot, g, s);
  }
  std::sort(got.begin(), got.end());
  EXPECT_TRUE(all_ranks(got == expected_halo(dd, g, width)))
      << "the halo differs from the copies within the width of the box";
  EXPECT_TRUE(all_ranks(intact)) << "a halo copy differs from its original";
  bool walls = ps.id[std::size_t(ps.fluid_end())] == GlobalId(1000000000) &&
               ps.body[std::size_t(ps.fluid_end() + 1)] == 0;
  EXPECT_TRUE(all_ranks(walls)) << "wall slots lost by fill()";
  EXPECT_EQ(sum_ranks(plan.n_copies_sent()), sum_ranks(plan.n_halo()));

  // Gather form: sums over owned + halo with plain distances, press holding f.
  const Index n_own = ps.n_fluid, n_all = ps.fluid_end();
  std::vector<double> sums(std::size_t(n_own), 0.0);
  for (Index i = 0; i < n_own; ++i)
    for (Index j = 0; j < n_all; ++j) {
      if (j == i) continue;
      const Real d = norm(ps.pos[std::size_t(i)] - ps.pos[std::size_t(j)]);
      if (d < kRadius) sums[std::size_t(i)] += double(ps.press[std::size_t(j)] * weight(d));
    }

  // Scatter form: each owned particle adds its contribution to every neighbour slot, owned or
  // halo; reduce_sum returns the halo parts to the owners.
  std::vector<Real> acc(std::size_t(n_all), 0);
  std::vector<Vec3> acc3(static_cast<std::size_t>(n_all));
  for (Index i = 0; i < n_own; ++i)
    for (Index j = 0; j < n_all; ++j) {
      if (j == i) continue;
      const Real d = norm(ps.pos[std::size_t(i)] - ps.pos[std::size_t(j)]);
      if (d < kRadius) {
        const Real v = ps.press[std::size_t(i)] * weight(d);
        acc[std::size_t(j)] += v;
        acc3[std::size_t(j)] += Vec3(1, 2, 3) * v;
      }
    }
  plan.reduce_sum(acc.data() + n_own, acc.data());
  plan.reduce_sum(acc3.data() + n_own, acc3.data());

  const std::vector<double> ref = rank() == 0 ? reference_sums(g, grid) : std::vector<double>();
  const auto gathered = gather_by_id(ps, sums);
  std::vector<double> red(static_cast<std::size_t>(n_own)), red3(static_cast<std::size_t>(n_own));
  for (Index i = 0; i < n_own; ++i) {
    red[std::size_t(i)] = double(acc[std::size_t(i)]);
    const Vec3 a = acc3[std::size_t(i)];
    red3[std::size_t(i)] = std::max({std::abs(double(a.x) - red[std::size_t(i)]),
                                     std::abs(double(a.y) - 2 * red[std::size_t(i)]),
                                     std::abs(double(a.z) - 3 * red[std::size_t(i)])});
  }
  const auto reduced = gather_by_id(ps, red);
  const auto reduced3 = gather_by_id(ps, red3);
  const std::int64_t total_halo = sum_ranks(plan.n_halo());
  bool ok = true;
  double worst = 0;
  if (rank() == 0) {
    ok = gathered.size() == n && reduced.size() == n;
    for (std::size_t i = 0; ok && i < n; ++i) {
      const double tol = 1e-12 * std::max(1.0, std::abs(ref[i]));
      const double e1 = std::abs(gathered[i].second - ref[i]);
      const double e2 = std::abs(reduced[i].second - ref[i]);
      worst = std::max({worst, e1, e2});
      ok = gathered[i].first == i && reduced[i].first == i && e1 <= tol && e2 <= tol &&
           reduced3[i].second <= 3 * tol;
    }
    std::printf("  %-28s halo/owned %.3f, worst |sum - reference| %.2e\n", c.name().c_str(),
                double(total_halo) / double(n), worst);
  }
  EXPECT_TRUE(all_ranks(ok)) << "neighbour sums differ from the single-process result";
}

TEST(Halo, NeighbourSumsMatchSingleProcess) {
  for (const Case& c : halo_cases()) run_case(c);
}

TEST(Halo, EmptyRanksAndBuildTwice) {
  // All particles in one corner: most ranks own none, and a plan can be rebuilt and moved.
  const CellGrid grid = unit_grid(3, kRadius);
  DomainDecomposition dd(comm(), grid, {size(), 1, 1});
  const GlobalSet g = make_global(200, 8, 3, Vec3(0, 0, 0), Vec3(Real(0.15), 1, 1));
  ParticleSet<Host> ps = make_slice(g);
  redistribute(dd, ps);
  HaloPlan plan(dd, ps, kRadius);
  plan = HaloPlan(dd, ps, kRadius);
  plan.fill(ps);
  bool intact = true;
  for (Index j = 0; j < ps.n_halo; ++j)
    intact = intact && particle_matches(ps, ps.n_fluid + j, g, plan.shift()[std::size_t(j)]);
  EXPECT_TRUE(all_ranks(intact));
  EXPECT_EQ(sum_ranks(ps.n_fluid), 200);
}

}  // namespace
}  // namespace sphdem
