// Level-set contact (DemSystem narrow phase, seed Eq. 19 with Kawamoto's master-slave test in both
// orders): symmetry between two identical non-spherical grains, the force of a face-to-face
// overlap, walls given as SDFs, the time step, and the contact history keyed by body ids.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "dem/dem_system.hpp"
#include "precision.hpp"

namespace sphdem::dem {
namespace {

using test::kFloatEps;
using test::tol;

DemParams static_params(Real kn) {
  DemParams p;
  p.gravity = Vec3(0, 0, 0);
  p.grain_grain.kn = kn;
  p.grain_grain.restitution = 0.5;
  p.grain_grain.mu = 0.4;
  p.grain_wall = p.grain_grain;
  return p;
}

Quat random_quat(std::mt19937& rng) {
  std::normal_distribution<Real> n(0, 1);
  return normalize(Quat{n(rng), n(rng), n(rng), n(rng)});
}

TEST(DemLevelSet, IdenticalGrainsGetEqualAndOppositeForces) {
  const GrainTemplate shape = GrainTemplate::trigonal_pyramid(0.02, 0.1, 3, 0.016);
  std::mt19937 rng(11);
  int checked = 0;
  for (int trial = 0; trial < 40 && checked < 10; ++trial) {
    const Quat qa = random_quat(rng), qb = random_quat(rng);
    const Vec3 xa(0, 0, 0), xb(0.009, 0.002, -0.001);
    // Order A, B and order B, A: the pair force must not depend on which body comes first.
    DemSystem ab(static_params(1e5)), ba(static_params(1e5));
    const int sa = ab.add_template(shape), sb = ba.add_template(shape);
    ab.add_body(sa, 2500, xa, qa);
    ab.add_body(sa, 2500, xb, qb);
    ba.add_body(sb, 2500, xb, qb);
    ba.add_body(sb, 2500, xa, qa);
    ab.compute_forces(1e-6);
    ba.compute_forces(1e-6);
    const Vec3 fa = ab.force(0), fb = ab.force(1);
    if (norm(fa) == 0) continue;
    ++checked;
    const Real scale = norm(fa);
    // Float: a body's force and torque are sums over the pair's n (~400) node contacts, taken in
    // another order when the bodies are swapped. A sum of n terms carries up to (n - 1) u
    // sum |f_i| of round-off (u = eps/2), and the node forces of one contact lie close to one
    // normal (sum |f_i| ~ |F|): two orders differ by up to n eps |F|, the torques (lever arms up
    // to the bounding radius R) by n eps |F| R, and the balance (which adds x_B x F, |x_B| < 0.01
    // m) by n eps |F| (R + 0.01 m).
    const double n_eps = double(ab.contact_count()) * kFloatEps;
    const double arm = shape.bounding_radius();
    EXPECT_LT(norm(fa + fb), 1e-12 * scale);
    // Angular momentum balance about the origin: T_A + T_B + x_A x F_A + x_B x F_B = 0.
    const Vec3 l = ab.torque(0) + ab.torque(1) + cross(xa, fa) + cross(xb, fb);
    EXPECT_LT(norm(l), tol(1e-10 * scale * 0.01, n_eps * scale * (arm + 0.01)));
    // Repulsive: A is pushed away from B.
    EXPECT_GT(dot(fa, xa - xb), 0);
    // Swapped order: the same force and torque on the same physical body.
    EXPECT_LT(norm(ba.force(1) - fa), tol(1e-12 * scale, n_eps * scale));
    EXPECT_LT(norm(ba.torque(1) - ab.torque(0)), tol(1e-12 * scale * 0.01, n_eps * scale * arm));
    EXPECT_LT(norm(ba.force(0) - fb), tol(1e-12 * scale, n_eps * scale));
  }
  EXPECT_GE(checked, 5) << "too few overlapping configurations";
}

TEST(DemLevelSet, FaceToFaceOverlapGivesKnTimesDepthPerNode) {
  // Two 2 cm cubes, node spacing 2.5 mm (9 x 9 nodes per face), B on top of A overlapping by
  // delta and shifted by 1.25 mm in x and y: 8 x 8 top nodes of A lie in B at depth delta, and
  // 8 x 8 bottom nodes of B in A. Each pass has weight 1/2: F = (64 + 64)/2 kn delta.
  // The phi grid (0.25 mm) is fine enough that the trilinear interpolant is exact (phi linear in
  // z) over every cell around the penetrating nodes, which sit >= 1.25 mm from the side faces.
  TemplateOptions opt;
  opt.node_spacing = 0.0025;
  opt.grid_spacing = 0.00025;
  opt.quad_sub = 1;
  const Real kn = 1e5, delta = 1e-4, s = 0.00125;
  DemSystem sys(static_params(kn));
  const int c = sys.add_template(GrainTemplate::box(Vec3(0.01, 0.01, 0.01), opt));
  const GrainTemplate& t = sys.shape(c);
  const Quat q = quat_from_matrix(t.source_rotation());
  sys.add_body(c, 2500, Vec3(0, 0, 0), q);
  sys.add_body(c, 2500, Vec3(s, s, 0.02 - delta), q);
  sys.compute_forces(1e-6);
  std::printf("face contact: F_z %.6f N, expected %.6f N, %zu contact points\n", sys.force(1).z,
              64 * kn * delta, sys.contact_count());
  // Float: each node's depth delta = 1e-4 m is read from positions and phi values of size up to
  // L = 0.02 m (B's centre at z = 0.0199), each rounded to u L (u = eps/2) in a few steps (body
  // pose, node transform, trilinear phi): the depth, and so each node force, carries a relative
  // error of up to ~4 eps L / delta = 1e-4. The normals come from phi differences over the
  // 0.25 mm grid cells (L / 0.25 mm = 80 < L / delta), so the x component stays below the same
  // bound, and summing the 128 forces adds only ~128 u.
  const double face_tol = tol(1e-9, 4 * kFloatEps * 0.02 / delta);
  EXPECT_NEAR(sys.force(1).z, 64 * kn * delta, face_tol * 64 * kn * delta);
  EXPECT_NEAR(sys.force(1).x, 0, face_tol * 64 * kn * delta);
  EXPECT_EQ(sys.contact_count(), 128u);
}

TEST(DemLevelSet, SdfWallMatchesPlaneWall) {
  const GrainTemplate shape = GrainTemplate::random_polyhedron(0.016, 12, 5);
  std::mt19937 rng(3);
  const Quat q = random_quat(rng);
  DemSystem a(static_params(1e5)), b(static_params(1e5));
  const int sa = a.add_template(shape), sb = b.add_template(shape);
  a.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  b.add_sdf_wall(geom::make_plane(Vec3(0, 0, 0), Vec3(0, 0, 1)));
  // The lowest node 20 um below the plane, sliding along +x and sinking.
  Real zmin = 1;
  for (const Vec3& n : shape.nodes()) zmin = std::min(zmin, rotate(q, n).z);
  const Vec3 x0(0, 0, -zmin - 2e-5);
  a.add_body(sa, 2500, x0, q, Vec3(0.1, 0, -0.01));
  b.add_body(sb, 2500, x0, q, Vec3(0.1, 0, -0.01));
  for (int k = 0; k < 20; ++k) {
    a.step(1e-7);
    b.step(1e-7);
  }
  ASSERT_GT(norm(a.force(0)), 0);
  EXPECT_LT(norm(a.force(0) - b.force(0)), 1e-9 * norm(a.force(0)));
  EXPECT_GT(a.force(0).z, 0);
  EXPECT_LT(a.force(0).x, 0);  // friction opposes the sliding along +x
}

TEST(DemLevelSet, TimeStepIsContactTimeOverFifty) {
  DemSystem sys(static_params(2e5));
  const int s = sys.add_template(GrainTemplate::sphere(0.008));
  sys.add_body(s, 2500, Vec3(0, 0, 0));
  const Real m = sys.bodies()[0].mass;
  // Float: pi sqrt(m* / kn) / 50 takes ~5 roundings on each side (m* = m / 2, quotient, sqrt,
  // two products): 4 eps of the step.
  EXPECT_NEAR(sys.time_step(), kPi * std::sqrt(0.5 * m / 2e5) / 50,
              tol(1e-15, 4 * kFloatEps * sys.time_step()));
}

TEST(DemLevelSet, HistoryIsKeyedByBodyIdNotSlot) {
  // A sphere sliding on a plane keeps its tangential spring when other bodies are added before
  // the next step (ids, not array positions, find the spring again).
  DemParams p = static_params(1e6);
  p.gravity = Vec3(0, 0, -9.81);
  DemSystem sys(p);
  const int s = sys.add_template(GrainTemplate::sphere(0.01));
  sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  sys.add_body(s, 2500, Vec3(0, 0, 0.0099999), Quat{}, Vec3(1e-3, 0, 0));
  for (int k = 0; k < 20; ++k) sys.step(1e-5);
  ASSERT_EQ(sys.contact_count(), 1u);
  const Vec3 spring = sys.history_springs()[0];
  EXPECT_GT(norm(spring), 0);
  sys.add_body(s, 2500, Vec3(1, 1, 1));
  sys.add_body(s, 2500, Vec3(1, 1, 1.015));  // a second contact, between two new bodies
  sys.compute_forces(0);                     // dt = 0: springs carried over, not advanced
  ASSERT_EQ(sys.contact_count(), 2u);
  const auto& keys = sys.history_keys();
  for (std::size_t k = 0; k < keys.size(); ++k)
    if (keys[k].master == sys.bodies()[0].id) {
      EXPECT_LT(norm(sys.history_springs()[k] - spring), 1e-15);
    }
}

}  // namespace
}  // namespace sphdem::dem

namespace sphdem::dem {
namespace {

using test::kFloatEps;
using test::tol;

// A jittered lattice of spheres and pyramids, overlapping their neighbours, on a floor: enough
// bodies (>= 64) that the pair search and the force loops run on OpenMP threads.
DemSystem packed_system() {
  DemParams p = static_params(200);
  p.gravity = Vec3(0, 0, -9.81);
  DemSystem sys(p);
  const int s = sys.add_template(GrainTemplate::sphere(0.005));
  const int r = sys.add_template(GrainTemplate::trigonal_pyramid(0.01, 0.1, 3, 0.0008));
  sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> j(-0.0002, 0.0002);
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 4; ++z)
        sys.add_body((x + y + z) % 5 == 0 ? r : s, 2500,
                     Vec3(0.0098 * x + j(rng), 0.0098 * y + j(rng), 0.0049 + 0.0098 * z + j(rng)),
                     random_quat(rng), Vec3(j(rng), j(rng), j(rng)));
  return sys;
}

// The contact forces do not depend on the OpenMP thread count (deterministic gathers), and the
// Verlet pair list (rebuilt only when a grain has moved half a skin) gives the same forces as a
// list rebuilt every step: a restored state forces a rebuild, so the two systems below differ
// only in when their lists were built.
TEST(DemSystemThreads, ForcesIndependentOfThreadsAndOfPairListAge) {
#ifdef _OPENMP
  const int threads_before = omp_get_max_threads();
#endif
  auto run = [](int threads, bool rebuild_every_step) {
#ifdef _OPENMP
    omp_set_num_threads(threads);
#else
    (void)threads;
#endif
    DemSystem sys = packed_system();
    for (int k = 0; k < 60; ++k) {
      if (rebuild_every_step) sys.restore(sys.state());
      sys.step(2e-5);
    }
    std::vector<Vec3> f;
    for (std::size_t i = 0; i < sys.bodies().size(); ++i) {
      f.push_back(sys.force(i));
      f.push_back(sys.torque(i));
      f.push_back(sys.bodies()[i].x);
    }
    return std::make_pair(f, sys.contact_count());
  };
  const auto one = run(1, false);
  const auto two = run(2, false);
  const auto fresh = run(2, true);
#ifdef _OPENMP
  omp_set_num_threads(threads_before);
#endif
  ASSERT_GT(one.second, 100u) << "the lattice should be in contact";
  ASSERT_EQ(one.first.size(), two.first.size());
  for (std::size_t i = 0; i < one.first.size(); ++i) {
    EXPECT_EQ(one.first[i].x, two.first[i].x) << i;
    EXPECT_EQ(one.first[i].y, two.first[i].y) << i;
    EXPECT_EQ(one.first[i].z, two.first[i].z) << i;
    EXPECT_EQ(one.first[i].x, fresh.first[i].x) << i;
    EXPECT_EQ(one.first[i].y, fresh.first[i].y) << i;
    EXPECT_EQ(one.first[i].z, fresh.first[i].z) << i;
  }
  EXPECT_EQ(one.second, two.second);
  EXPECT_EQ(one.second, fresh.second);
}

// The contact pass skips a grain's octants that face away from the other grain. Skipping must be
// conservative: a brute-force count over every node of every pair, with the same filters (the
// other grain's bounding sphere and padded node box), finds exactly the contact points the
// system reports, in a jittered, randomly oriented lattice of overlapping pyramids.
TEST(DemSystemPairs, OctantSkippingMissesNoContactNode) {
  DemSystem sys(static_params(200));
  const int r = sys.add_template(GrainTemplate::trigonal_pyramid(0.01, 0.15, 7));
  std::mt19937 rng(11);
  std::uniform_real_distribution<Real> j(-0.0015, 0.0015);
  for (int x = 0; x < 5; ++x)
    for (int y = 0; y < 5; ++y)
      for (int z = 0; z < 3; ++z)
        sys.add_body(r, 2500, Vec3(0.0065 * x + j(rng), 0.0065 * y + j(rng), 0.0065 * z + j(rng)),
                     random_quat(rng));
  sys.compute_forces(0);
  const GrainTemplate& t = sys.shape(r);
  const auto& b = sys.bodies();
  const Real pad = t.node_spacing(), rb = t.bounding_radius();
  std::vector<Vec3> lo(b.size()), hi(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) {
    lo[i] = hi[i] = b[i].x;
    for (const Vec3& y : t.nodes()) {
      const Vec3 x = b[i].x + rotate(b[i].q, y);
      for (int d = 0; d < 3; ++d) {
        lo[i][d] = std::min(lo[i][d], x[d]);
        hi[i][d] = std::max(hi[i][d], x[d]);
      }
    }
    lo[i] = lo[i] - Vec3(pad, pad, pad);
    hi[i] = hi[i] + Vec3(pad, pad, pad);
  }
  std::size_t brute = 0;
  for (std::size_t m = 0; m < b.size(); ++m)
    for (std::size_t s = 0; s < b.size(); ++s) {
      if (m == s || norm(b[m].x - b[s].x) > 2 * rb) continue;
      for (const Vec3& y : t.nodes()) {
        const Vec3 x = b[m].x + rotate(b[m].q, y);
        bool in_box = true;
        for (int d = 0; d < 3; ++d) in_box = in_box && x[d] >= lo[s][d] && x[d] <= hi[s][d];
        if (!in_box || norm2(x - b[s].x) > rb * rb) continue;
        const Vec3 yl = rotate(conjugate(b[s].q), x - b[s].x);
        if (geom::grid_phi(t.view(), yl) < 0 && norm2(geom::grid_normal(t.view(), yl)) > 0) ++brute;
      }
    }
  std::printf("octant skipping: %zu contact points by brute force\n", brute);
  ASSERT_GT(brute, 50u) << "the lattice should overlap";
  EXPECT_EQ(sys.contact_count(), brute);
  // The octants partition the nodes.
  std::vector<int> seen(t.nodes().size(), 0);
  for (const NodeGroup& g : t.node_groups())
    for (std::uint32_t i = g.begin; i < g.end; ++i) ++seen[t.node_order()[i]];
  for (int c : seen) EXPECT_EQ(c, 1);
}

// The node lists skip a node only if geom::grid_phi cannot fall below zero there before the list
// is remade. That rests on two bounds of the template: phi's Lipschitz constant and its least
// value on the grid box's boundary. Random point pairs in and around a pyramid's grid must obey
// both (brute force).
TEST(DemSystemPairs, PhiBoundsHoldOnRandomPoints) {
  const GrainTemplate t = GrainTemplate::trigonal_pyramid(0.01, 0.15, 7);
  const geom::GridSdfView v = t.view();
  const Real l = t.phi_lipschitz();
  // sqrt(L^2 + 1) with L about 1 for a distance field (the grid's differences per spacing).
  EXPECT_GT(l, std::sqrt(Real(2)) - 0.05);
  EXPECT_LT(l, 2);
  EXPECT_GT(t.phi_box_min(), 0) << "the grid is padded beyond the surface";
  const Vec3 lo = t.grid_lo(), hi = t.grid_hi();
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-0.3, 1.3), step(-0.002, 0.002);
  Real worst = 0;
  for (int k = 0; k < 20000; ++k) {
    Vec3 x;
    for (int d = 0; d < 3; ++d) x[d] = lo[d] + u(rng) * (hi[d] - lo[d]);
    const Vec3 y = x + Vec3(step(rng), step(rng), step(rng));
    const Real dphi = std::abs(geom::grid_phi(v, x) - geom::grid_phi(v, y));
    worst = std::max(worst, dphi / norm(x - y));
    Vec3 c;
    for (int d = 0; d < 3; ++d) c[d] = std::clamp(x[d], lo[d], hi[d]);
    if (norm(x - c) > 0) {
      EXPECT_GE(geom::grid_phi(v, x), t.phi_box_min() + norm(x - c) - 1e-15);
    }
  }
  std::printf("phi bounds: Lipschitz bound %.4f, steepest sampled %.4f, box minimum %.3g m\n", l,
              worst, t.phi_box_min());
  EXPECT_LE(worst, l);
  EXPECT_GT(worst, 1.0) << "the sample should reach the steep parts";
}

// A system of the rock collapse's pyramids (79 nodes each) on a floor, for the node-list tests:
// lists on or off, the rock template's index in `rock`.
DemSystem rock_floor_system(bool lists, int& rock) {
  DemParams p = static_params(200);
  p.gravity = Vec3(0, 0, -9.81);
  DemSystem sys(p);
  sys.set_node_lists(lists);
  TemplateOptions opt;
  opt.grid_spacing = 0.0006;
  opt.node_spacing = 0.0018;
  rock = sys.add_template(GrainTemplate::trigonal_pyramid(0.01, 0.15, 7, 0.007, opt));
  sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  return sys;
}

// Pyramids thrown at each other and at a floor, spinning: the system with per-pair node lists
// (the default) steps exactly like one that scans every node every step, to the bit, while the
// lists are remade many times (the grains move and turn by many skins) and save most lookups.
TEST(DemSystemPairs, NodeListsGiveTheForcesOfAFullScan) {
  auto make = [](bool lists) {
    int r = 0;
    DemSystem sys = rock_floor_system(lists, r);
    std::mt19937 rng(17);
    // The rock collapse's rocks (79 nodes each), 5.5 mm apart: bounding spheres overlapping.
    const Real a = 0.0055;
    std::uniform_real_distribution<Real> j(-0.0005, 0.0005), v(-0.05, 0.05), w(-5, 5);
    for (int x = 0; x < 5; ++x)
      for (int y = 0; y < 4; ++y)
        for (int z = 0; z < 4; ++z)
          sys.add_body(r, 2500, Vec3(a * x + j(rng), a * y + j(rng), 0.004 + a * z + j(rng)),
                       random_quat(rng), Vec3(v(rng), v(rng), v(rng)),
                       Vec3(w(rng), w(rng), w(rng)));
    return sys;
  };
  DemSystem with = make(true), without = make(false);
  std::size_t lookups_with = 0, lookups_without = 0, contacts = 0;
  for (int k = 0; k < 400; ++k) {
    with.step(2e-5);
    without.step(2e-5);
    lookups_with += with.phi_lookups();
    lookups_without += without.phi_lookups();
    contacts += with.contact_count();
    ASSERT_EQ(with.contact_count(), without.contact_count()) << "step " << k;
  }
  for (std::size_t i = 0; i < with.bodies().size(); ++i) {
    const RigidBody &a = with.bodies()[i], &b = without.bodies()[i];
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(a.x[d], b.x[d]) << i;
      EXPECT_EQ(a.v[d], b.v[d]) << i;
      EXPECT_EQ(a.w[d], b.w[d]) << i;
    }
    EXPECT_EQ(a.q.w, b.q.w) << i;
    EXPECT_EQ(a.q.x, b.q.x) << i;
  }
  std::printf(
      "node lists: %zu contact point-steps; phi lookups %zu with lists, %zu without; "
      "%zu lists made, %zu pairs\n",
      contacts, lookups_with, lookups_without, with.node_list_builds(), with.pair_count());
  ASSERT_GT(contacts, 4000u) << "the grains should touch";
  EXPECT_GT(with.node_list_builds(), 4 * with.pair_count())
      << "lists must be remade as grains move";
  EXPECT_EQ(without.node_list_builds(), 0u);
  EXPECT_LT(lookups_with, lookups_without / 3);
}

// Node lists are carried across pair-list rebuilds by the pair's two body indices. A caller may
// reorder the bodies (bodies() is writable), and then an index pair names other grains. Here the
// reordered pair (0, 1) holds a box and a rock in exactly the relative pose that a rock and a box
// had there before, so only the list's record of the bodies (ids and shapes) tells the old list
// from a valid one: reusing it would test the box's nodes by the rock's node numbers.
TEST(DemSystemPairs, NodeListsFollowBodiesThatAreReordered) {
  auto make = [](bool lists) {
    DemSystem sys(static_params(200));
    sys.set_node_lists(lists);
    TemplateOptions opt;
    opt.grid_spacing = 0.0006;
    opt.node_spacing = 0.0018;
    const int r = sys.add_template(GrainTemplate::trigonal_pyramid(0.01, 0.15, 7, 0.007, opt));
    const int b = sys.add_template(GrainTemplate::box(Vec3(0.003, 0.002, 0.0025), opt));
    const Quat qr = from_axis_angle(Vec3(1, 2, 3), 0.7), qb = from_axis_angle(Vec3(-2, 1, 1), 0.4);
    const Vec3 far(0.05, 0, 0), gap(0.0045, 0.0005, -0.0003);
    sys.add_body(r, 2500, Vec3(), qr);     // 0: rock
    sys.add_body(b, 2500, gap, qb);        // 1: box pressing into it
    sys.add_body(r, 2500, far + gap, qb);  // 2: rock where body 1 is, shifted
    sys.add_body(b, 2500, far, qr);        // 3: box where body 0 is, shifted
    return sys;
  };
  DemSystem with = make(true), without = make(false);
  with.compute_forces(1e-6);
  without.compute_forces(1e-6);
  ASSERT_GT(with.contact_count(), 0u) << "the box should press into the rock";
  ASSERT_EQ(with.contact_count(), without.contact_count());
  // Reversed, index pair (0, 1) is (box at far, rock at far + gap): the relative pose of the old
  // pair (0, 1), with the shapes swapped.
  std::reverse(with.bodies().begin(), with.bodies().end());
  std::reverse(without.bodies().begin(), without.bodies().end());
  with.compute_forces(1e-6);
  without.compute_forces(1e-6);
  ASSERT_GT(without.contact_count(), 0u);
  EXPECT_EQ(with.contact_count(), without.contact_count());
  for (std::size_t i = 0; i < with.bodies().size(); ++i) {
    ASSERT_GT(norm(without.force(i)), 0) << "every body touches one other";
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(with.force(i)[d], without.force(i)[d]) << "body index " << i;
      EXPECT_EQ(with.torque(i)[d], without.torque(i)[d]) << "body index " << i;
    }
  }
}

// Spheres keep no world nodes; against a level-set grain each pass places the sphere's nodes
// that it tests, from a per-thread buffer the other pairs share. With node lists that is only the
// listed nodes, so a listed node placed for another pair, or not at all, would show here: spheres
// among rocks stepped with and without lists must agree to the bit.
TEST(DemSystemPairs, NodeListsGiveTheForcesOfAFullScanWithSpheres) {
  auto make = [](bool lists) {
    int r = 0;
    DemSystem sys = rock_floor_system(lists, r);
    const int b = sys.add_template(GrainTemplate::sphere(0.0035));
    std::mt19937 rng(5);
    const Real a = 0.0055;
    std::uniform_real_distribution<Real> j(-0.0005, 0.0005), w(-3, 3);
    for (int x = 0; x < 4; ++x)
      for (int y = 0; y < 3; ++y)
        for (int z = 0; z < 2; ++z)
          sys.add_body((x + 2 * y + z) % 3 ? r : b, 2500,
                       Vec3(a * x + j(rng), a * y + j(rng), 0.004 + a * z + j(rng)),
                       random_quat(rng), Vec3(), Vec3(w(rng), w(rng), w(rng)));
    return sys;
  };
  DemSystem with = make(true), without = make(false);
  std::size_t contacts = 0;
  for (int k = 0; k < 300; ++k) {
    with.step(2e-5);
    without.step(2e-5);
    contacts += with.contact_count();
    ASSERT_EQ(with.contact_count(), without.contact_count()) << "step " << k;
  }
  ASSERT_GT(contacts, 3000u) << "the grains should touch";
  for (std::size_t i = 0; i < with.bodies().size(); ++i)
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(with.bodies()[i].x[d], without.bodies()[i].x[d]) << i;
      EXPECT_EQ(with.bodies()[i].w[d], without.bodies()[i].w[d]) << i;
    }
}

// A sphere against a level-set grain runs the level-set passes in both orders, so the sphere's
// own surface nodes test the other grain's phi. The force on the pair must not depend on which
// bodies come after the sphere in the body list (each body's world nodes sit in one array).
TEST(DemLevelSet, SphereOnAGrainIsIndependentOfTheBodiesAfterIt) {
  std::size_t contacts = 0;
  auto force = [&contacts](bool sphere_first, bool more_after) {
    DemSystem sys(static_params(500));
    const int s = sys.add_template(GrainTemplate::sphere(0.004));
    const int c = sys.add_template(GrainTemplate::box(Vec3(0.005, 0.005, 0.005)));
    const Quat tilt = from_axis_angle(Vec3(1, 2, 0), 0.3);
    const Vec3 xs(0.0, 0.0, 0.0085), xc(0.0005, -0.0003, 0);
    std::size_t is = 0;
    if (sphere_first) {
      is = sys.add_body(s, 2500, xs);
      sys.add_body(c, 2500, xc, tilt);
    } else {
      sys.add_body(c, 2500, xc, tilt);
      is = sys.add_body(s, 2500, xs);
    }
    if (more_after) sys.add_body(c, 2500, Vec3(0.1, 0.1, 0.1));  // far away, after both
    sys.compute_forces(0);
    contacts = sys.contact_count();
    return sys.force(is);
  };
  const Vec3 ref = force(true, false);
  ASSERT_GT(norm(ref), 0.05) << "the sphere should press into the box's top face";
  // Float: the sphere's force sums its n (~200) node contacts, in another order when the body
  // list changes; two orders of a sum of n nearly parallel forces differ by up to n eps |F|
  // (as in IdenticalGrainsGetEqualAndOppositeForces).
  const double order_tol = tol(1e-9, double(contacts) * kFloatEps);
  for (const Vec3& f : {force(true, true), force(false, false), force(false, true)})
    EXPECT_LT(norm(f - ref), order_tol * norm(ref)) << f.x << " " << f.y << " " << f.z;
}

// The pair list leaves out pairs of two non-free bodies. Releasing a fixed grain that touches
// another fixed one (no grain moves, so no displacement would trigger a rebuild) must bring the
// pair back: the released grain is pushed away at the next step.
TEST(DemSystemPairs, ReleasingAFixedGrainRebuildsThePairList) {
  DemParams p;
  p.gravity = Vec3(0, 0, 0);
  p.grain_grain.kn = p.grain_wall.kn = 1e4;
  p.grain_grain.restitution = p.grain_wall.restitution = 0.5;
  DemSystem sys(p);
  const int s = sys.add_template(GrainTemplate::sphere(0.01));
  // Overlapping by 1 mm, both fixed.
  sys.add_body(s, 2500, Vec3(0, 0, 0), Quat{}, {}, {}, Motion::kFixed);
  sys.add_body(s, 2500, Vec3(0.019, 0, 0), Quat{}, {}, {}, Motion::kFixed);
  sys.step(1e-5);
  EXPECT_EQ(sys.pair_count(), 0u);
  EXPECT_EQ(norm(sys.force(1)), 0);
  const std::size_t builds = sys.pair_builds();
  sys.bodies()[1].motion = Motion::kFree;
  sys.step(1e-5);
  EXPECT_EQ(sys.pair_builds(), builds + 1);
  EXPECT_EQ(sys.pair_count(), 1u);
  // k_n d = 1e4 N/m x 1 mm = 10 N along +x on the released grain (plus a small dashpot term).
  EXPECT_NEAR(sys.force(1).x, 10.0, 0.5);
  EXPECT_GT(sys.bodies()[1].v.x, 0);
}

}  // namespace
}  // namespace sphdem::dem
