// Grain boundary particles (lib/coupling): placement in the body frame, posing with the grain,
// fluid loads from m a, and the fluid removed inside a grain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "coupling/grain_boundary.hpp"
#include "geometry/grid_sdf.hpp"
#include "precision.hpp"

namespace sphdem {
namespace {

using test::kFloatEps;
using test::tol;

dem::DemSystem one_box(Vec3 x, Quat q = {}, Vec3 v = {}, Vec3 w = {}) {
  dem::DemParams prm;
  prm.grain_grain.kn = prm.grain_wall.kn = 1e4;
  dem::DemSystem sys(prm);
  dem::TemplateOptions o;
  o.grid_spacing = 0.004;
  o.node_spacing = 0.01;
  sys.add_template(dem::GrainTemplate::box(Vec3(0.04, 0.04, 0.04), o));
  sys.add_body(0, 500, x, q, v, w);
  return sys;
}

TEST(GrainBoundary, LatticeInsideTheSurfaceWithMirroredGhosts) {
  dem::DemSystem sys = one_box(Vec3());
  const GrainBoundaryShape s = make_grain_boundary(sys.shape(0), 0.01, 0.042);
  // A 0.08 m cube on the dp = 0.01 lattice: 8 x 8 x 8 points, all within 2h of the surface.
  ASSERT_EQ(s.pos.size(), 512u);
  const geom::GridSdfView g = sys.shape(0).view();
  int faces = 0;
  for (std::size_t k = 0; k < s.pos.size(); ++k) {
    const Real phi = geom::grid_phi(g, s.pos[k]);
    EXPECT_LT(phi, 0);
    // Float: the normal is v / |v| and the check takes its norm again, about 16 roundings of
    // u = eps/2 each: 8 eps.
    EXPECT_NEAR(norm(s.normal[k]), 1, tol(1e-9, 8 * test::kFloatEps));
    // Near a face the ghost node is the mirror image through the surface: phi(ghost) = -phi.
    // Where two faces are equally near (edges, corners, the cube's diagonals) the gradient of phi
    // points between them and the mirror image falls short: it is only further out than the point.
    const Vec3 a(std::abs(s.pos[k].x), std::abs(s.pos[k].y), std::abs(s.pos[k].z));
    Real d[3] = {Real(0.04) - a.x, Real(0.04) - a.y, Real(0.04) - a.z};
    std::sort(d, d + 3);  // d[0]: the nearest face, d[1]: the second nearest
    const Real d1 = d[0], d2 = d[1];
    const Real ghost_phi = geom::grid_phi(g, s.ghost[k]);
    EXPECT_GT(ghost_phi, phi) << k;
    if (d2 - d1 > 0.015) {
      EXPECT_NEAR(ghost_phi, -phi, 5e-4) << k;
      ++faces;
    }
  }
  EXPECT_GT(faces, 100);
  // A shallower layer keeps only the outer shell: 8^3 - 6^3 points within one dp.
  EXPECT_EQ(make_grain_boundary(sys.shape(0), 0.01, 0.0101).pos.size(), 512u - 216u);
}

TEST(GrainBoundary, PosesFollowTheGrainAndLoadsSumMA) {
  const Quat q = from_axis_angle(Vec3(0, 0, 1), Real(M_PI / 2));
  const Vec3 x0(0.5, 0.5, 0.5), v0(0.1, 0, 0), w0(0, 0, 2);
  dem::DemSystem sys = one_box(x0, q, v0, w0);
  GrainCoupling c(sys, 0.01, 0.042, 1000, 3);
  // A fluid block around the grain: the fluid inside it goes.
  ParticleSet<Host> ps;
  const int n = 20;
  ps.resize(n * n * n);
  ps.n_fluid = n * n * n;
  for (int i = 0; i < n * n * n; ++i) {
    ps.pos[std::size_t(i)] =
        Vec3(0.405 + 0.01 * (i % n), 0.405 + 0.01 * ((i / n) % n), 0.405 + 0.01 * (i / (n * n)));
    ps.id[std::size_t(i)] = GlobalId(i);
    ps.body[std::size_t(i)] = -1;
  }
  const Index removed = c.append(ps, sys);
  EXPECT_EQ(removed, 512);  // the lattice points inside the cube
  EXPECT_EQ(ps.n_fluid, n * n * n - 512);
  EXPECT_EQ(ps.n_grain, 512);
  // Boundary velocities are the rigid motion v + w x r.
  const Vec3 w_world = dem::world_omega(sys.bodies()[0]);
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    const Vec3 r = ps.pos[std::size_t(i)] - x0;
    const Vec3 expect = v0 + cross(w_world, r);
    EXPECT_NEAR(norm(ps.vel[std::size_t(i)] - expect), 0, 1e-12);
    EXPECT_LT(std::abs(r.x), 0.04);
  }
  // Move and turn the grain: the particles follow (distances to the centroid are kept).
  sys.bodies()[0].x = Vec3(0.6, 0.5, 0.45);
  sys.bodies()[0].q = from_axis_angle(Vec3(1, 0, 0), Real(0.3));
  std::vector<Real> d0;
  for (Index i = ps.wall_begin(); i < ps.size(); ++i)
    d0.push_back(norm(ps.pos[std::size_t(i)] - x0));
  c.place(ps, sys);
  // Float: each pose rounds every coordinate (of size <= 0.7 m) to u 0.7 m (u = eps/2), and the
  // rotation of the <= 0.07 m body-frame point adds a few u of that: a distance moves by
  // <= sqrt(3) u 0.7 m per pose, two poses: < 4 eps 0.7 m.
  for (Index i = ps.wall_begin(); i < ps.size(); ++i)
    EXPECT_NEAR(norm(ps.pos[std::size_t(i)] - sys.bodies()[0].x),
                d0[std::size_t(i - ps.wall_begin())], tol(1e-12, 4 * kFloatEps * 0.7));
  // Loads: a uniform acceleration a on every grain slot gives F = N m a and no torque about the
  // (symmetric) centroid; a linear field gives the matching torque.
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) ps.acc[std::size_t(i)] = Vec3(0, 0, 3);
  std::vector<Vec3> f, t;
  c.loads(ps, sys, f, t);
  const Real mb = 1000 * 1e-6;
  // Float: F sums n equal forces mb a: the k-th partial sum is rounded by <= u (k/n) F, in all
  // (n + 1) eps F / 4, plus a few eps for mb a itself. The torque sums n terms r x mb a of size
  // <= R mb a (R = 0.07 m, the cube's half diagonal) that cancel in pairs: the sum's round-off is
  // <= n u (n R mb a), and the arms r = x_i - x (positions <= 0.7 m, rounded to u 0.7 m per
  // coordinate) add n sqrt(3) u 0.7 m mb a; 2x for the two nonzero components.
  const double n_grain = double(ps.n_grain);
  EXPECT_NEAR(f[0].z, 512 * mb * 3,
              tol(1e-9, ((n_grain + 1) / 4 + 4) * kFloatEps * n_grain * mb * 3));
  EXPECT_NEAR(
      norm(t[0]), 0,
      tol(1e-9, 2 * n_grain * 0.5 * kFloatEps * (n_grain * 0.07 + std::sqrt(3.0) * 0.7) * mb * 3));
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    const Vec3 r = ps.pos[std::size_t(i)] - sys.bodies()[0].x;
    ps.acc[std::size_t(i)] = Vec3(0, 0, r.x);
  }
  c.loads(ps, sys, f, t);
  Real ty = 0;
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    const Vec3 r = ps.pos[std::size_t(i)] - sys.bodies()[0].x;
    ty += -r.x * mb * r.x;  // (r x F)_y = z Fx - x Fz
  }
  // Float: the same n same-signed terms -x^2 mb, each product rounded in another order (2 u) and
  // summed (<= (n - 1) u |ty| each side): <= n eps |ty|.
  EXPECT_NEAR(t[0].y, ty, tol(1e-12, (n_grain + 4) * kFloatEps * std::abs(ty)));
}

}  // namespace
}  // namespace sphdem
