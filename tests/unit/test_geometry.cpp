// Tests of the geometry library: analytic SDFs, CSG, transforms, the tank, grid SDFs, mesh
// loading (STL ascii/binary, OBJ) and mesh SDFs, and the quaternion helpers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "core/quat.hpp"
#include "geometry/grid_sdf.hpp"
#include "geometry/sdf.hpp"

namespace {

using sphdem::InputError;
using sphdem::kPi;
using sphdem::Real;
using sphdem::Vec3;
namespace geom = sphdem::geom;

// Tolerances: t in double builds; a float-sized one (for values of order 1) with
// SPHDEM_PRECISION=float.
constexpr bool kDouble = std::is_same_v<Real, double>;
Real tol(double t) {
  return kDouble ? Real(t) : std::max(Real(t), Real(5e-5));
}
const Real kTol = tol(tol(1e-12));

void expect_vec_near(const Vec3& a, const Vec3& b, Real tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// Checks |grad| = 1 and that phi grows by ~eps along grad, at random points of a box.
void check_gradients(const geom::Sdf& s, Vec3 lo, Vec3 hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(0, 1);
  const Real eps = kDouble ? 1e-6 : 1e-3;
  for (int n = 0; n < 200; ++n) {
    const Vec3 x(lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
                 lo.z + (hi.z - lo.z) * u(rng));
    const Vec3 g = s.grad(x);
    EXPECT_NEAR(norm(g), 1.0, tol(1e-9));
    EXPECT_NEAR((s.phi(x + eps * g) - s.phi(x - eps * g)) / (2 * eps), 1.0, kDouble ? 1e-5 : 1e-2)
        << "at (" << x.x << ", " << x.y << ", " << x.z << ")";
  }
}

// ---- primitives --------------------------------------------------------------------------------

TEST(GeometryBox, PhiAtInsideOutsideEdgeCorner) {
  const auto b = geom::make_box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  EXPECT_NEAR(b->phi(Vec3(0.5, 1, 1.5)), -0.5, kTol);          // centre: nearest face x
  EXPECT_NEAR(b->phi(Vec3(0.5, 0.1, 1.5)), -0.1, kTol);        // near the y = 0 face
  EXPECT_NEAR(b->phi(Vec3(1, 1, 1.5)), 0.0, kTol);             // on a face
  EXPECT_NEAR(b->phi(Vec3(2, 1, 1.5)), 1.0, kTol);             // outside a face
  EXPECT_NEAR(b->phi(Vec3(2, 3, 1.5)), std::sqrt(2.0), kTol);  // outside an edge
  EXPECT_NEAR(b->phi(Vec3(2, 3, 4)), std::sqrt(3.0), kTol);    // outside a corner
  EXPECT_NEAR(b->phi(Vec3(-1, -2, -3)), std::sqrt(14.0), kTol);
  const geom::Aabb bb = b->bounds();
  expect_vec_near(bb.lo, Vec3(0, 0, 0), 0);
  expect_vec_near(bb.hi, Vec3(1, 2, 3), 0);
}

TEST(GeometryBox, GradientDirections) {
  const auto b = geom::make_box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  expect_vec_near(b->grad(Vec3(2, 1, 1.5)), Vec3(1, 0, 0), kTol);
  expect_vec_near(b->grad(Vec3(2, 3, 4)), Vec3(1, 1, 1) / std::sqrt(3.0), kTol);
  expect_vec_near(b->grad(Vec3(0.5, 0.1, 1.5)), Vec3(0, -1, 0), kTol);
  expect_vec_near(b->grad(Vec3(0.5, 1, 2.9)), Vec3(0, 0, 1), kTol);
  check_gradients(*b, Vec3(-1, -1, -1), Vec3(2, 3, 4), 1);
}

TEST(GeometryBox, RejectsInvertedBox) {
  EXPECT_THROW(geom::make_box(Vec3(1, 0, 0), Vec3(0, 1, 1)), InputError);
}

TEST(GeometrySphere, PhiAndGradient) {
  const auto s = geom::make_sphere(Vec3(1, 2, 3), 0.5);
  EXPECT_NEAR(s->phi(Vec3(1, 2, 3)), -0.5, kTol);
  EXPECT_NEAR(s->phi(Vec3(1, 2, 4)), 0.5, kTol);
  EXPECT_NEAR(s->phi(Vec3(1, 2.3, 3)), -0.2, kTol);
  expect_vec_near(s->grad(Vec3(1, 2, 4)), Vec3(0, 0, 1), kTol);
  expect_vec_near(s->grad(Vec3(2, 3, 3)), Vec3(1, 1, 0) / std::sqrt(2.0), kTol);
  check_gradients(*s, Vec3(0, 1, 2), Vec3(2, 3, 4), 2);
  const geom::Aabb bb = s->bounds();
  expect_vec_near(bb.lo, Vec3(0.5, 1.5, 2.5), kTol);
  expect_vec_near(bb.hi, Vec3(1.5, 2.5, 3.5), kTol);
}

TEST(GeometryCylinder, PhiInsideOutsideRimAndCaps) {
  const auto c = geom::make_cylinder(Vec3(0, 0, 0), Vec3(0, 0, 2), 1.0);
  EXPECT_NEAR(c->phi(Vec3(0, 0, 1)), -1.0, kTol);
  EXPECT_NEAR(c->phi(Vec3(0.5, 0, 1)), -0.5, kTol);
  EXPECT_NEAR(c->phi(Vec3(0, 0, 1.8)), -0.2, kTol);  // near the top cap
  EXPECT_NEAR(c->phi(Vec3(0, 0, 0.1)), -0.1, kTol);  // near the bottom cap
  EXPECT_NEAR(c->phi(Vec3(1.5, 0, 1)), 0.5, kTol);   // outside the side
  EXPECT_NEAR(c->phi(Vec3(0, 0, 3)), 1.0, kTol);     // above the cap
  EXPECT_NEAR(c->phi(Vec3(0.5, 0, 3)), 1.0, kTol);
  EXPECT_NEAR(c->phi(Vec3(0, 2, 3)), std::sqrt(2.0), kTol);  // outside the rim
  EXPECT_NEAR(c->phi(Vec3(0, -2, -1)), std::sqrt(2.0), kTol);
  expect_vec_near(c->grad(Vec3(0, 2, 3)), Vec3(0, 1, 1) / std::sqrt(2.0), kTol);
  expect_vec_near(c->grad(Vec3(0, 0, 1.8)), Vec3(0, 0, 1), kTol);
  expect_vec_near(c->grad(Vec3(0, -0.9, 1)), Vec3(0, -1, 0), kTol);
  check_gradients(*c, Vec3(-2, -2, -1), Vec3(2, 2, 3), 3);
}

TEST(GeometryCylinder, SlantedAxisAndBounds) {
  // Axis from (0,0,0) to (2,2,0), radius 1.
  const auto c = geom::make_cylinder(Vec3(0, 0, 0), Vec3(2, 2, 0), 1.0);
  const Vec3 side = Vec3(1, -1, 0) / std::sqrt(2.0);
  EXPECT_NEAR(c->phi(Vec3(1, 1, 0) + 3 * side), 2.0, kTol);
  EXPECT_NEAR(c->phi(Vec3(1, 1, 0) + 0.25 * side), -0.75, kTol);
  EXPECT_NEAR(c->phi(Vec3(3, 3, 0)), std::sqrt(2.0), kTol);  // beyond the b cap
  const geom::Aabb bb = c->bounds();
  const Real e = std::sqrt(0.5);
  expect_vec_near(bb.lo, Vec3(-e, -e, -1), kTol);
  expect_vec_near(bb.hi, Vec3(2 + e, 2 + e, 1), kTol);
  check_gradients(*c, Vec3(-2, -2, -2), Vec3(4, 4, 2), 4);
}

TEST(GeometryPlane, HalfSpaceAndSlab) {
  const auto p = geom::make_plane(Vec3(0, 0, 1), Vec3(0, 0, 2));
  EXPECT_NEAR(p->phi(Vec3(5, 5, 3)), 2.0, kTol);
  EXPECT_NEAR(p->phi(Vec3(0, 0, 0)), -1.0, kTol);
  expect_vec_near(p->grad(Vec3(1, 2, 3)), Vec3(0, 0, 1), kTol);
  EXPECT_LE(p->bounds().lo.x, -1e29);
  EXPECT_GE(p->bounds().hi.z, 1e29);

  const auto tilted = geom::make_plane(Vec3(1, 0, 0), Vec3(1, 1, 0));
  EXPECT_NEAR(tilted->phi(Vec3(2, 1, 7)), std::sqrt(2.0), kTol);

  const auto s = geom::make_slab(Vec3(0, 0, 0), Vec3(1, 0, 0), 0.2);
  EXPECT_NEAR(s->phi(Vec3(0.05, 3, 4)), -0.05, kTol);
  EXPECT_NEAR(s->phi(Vec3(-0.3, 3, 4)), 0.2, kTol);
  expect_vec_near(s->grad(Vec3(-0.3, 0, 0)), Vec3(-1, 0, 0), kTol);
  expect_vec_near(s->grad(Vec3(0.02, 0, 0)), Vec3(1, 0, 0), kTol);
  EXPECT_NEAR(s->bounds().lo.x, -0.1, kTol);
  EXPECT_NEAR(s->bounds().hi.x, 0.1, kTol);
  EXPECT_GE(s->bounds().hi.y, 1e29);
  EXPECT_THROW(geom::make_plane(Vec3(0, 0, 0), Vec3(0, 0, 0)), InputError);
}

// An SDF with only phi: exercises the central-difference Sdf::grad.
class PhiOnlySphere : public geom::Sdf {
 public:
  Real phi(const Vec3& x) const override { return norm(x - Vec3(0.1, 0.2, 0.3)) - 0.4; }
  geom::Aabb bounds() const override { return {Vec3(-1, -1, -1), Vec3(1, 1, 1)}; }
};

TEST(GeometryGrad, DefaultCentralDifferences) {
  const PhiOnlySphere s;
  const Vec3 x(0.9, -0.4, 0.7);
  const Vec3 expect = (x - Vec3(0.1, 0.2, 0.3)) / norm(x - Vec3(0.1, 0.2, 0.3));
  expect_vec_near(s.grad(x), expect, kDouble ? 1e-8 : 2e-4);
  EXPECT_NEAR(norm(s.grad(Vec3(50, 60, -70))), 1.0, tol(1e-12));
}

// ---- combinations ------------------------------------------------------------------------------

TEST(GeometryCsg, UnionAndDifference) {
  const auto a = geom::make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const auto b = geom::make_box(Vec3(2, 0, 0), Vec3(3, 1, 1));
  const auto u = geom::make_union({a, b});
  EXPECT_NEAR(u->phi(Vec3(1.5, 0.5, 0.5)), 0.5, kTol);  // in the gap
  EXPECT_NEAR(u->phi(Vec3(1.2, 0.5, 0.5)), 0.2, kTol);
  EXPECT_NEAR(u->phi(Vec3(2.9, 0.5, 0.5)), -0.1, kTol);  // inside b
  expect_vec_near(u->grad(Vec3(1.2, 0.5, 0.5)), Vec3(1, 0, 0), kTol);
  expect_vec_near(u->grad(Vec3(1.8, 0.5, 0.5)), Vec3(-1, 0, 0), kTol);
  expect_vec_near(u->bounds().lo, Vec3(0, 0, 0), 0);
  expect_vec_near(u->bounds().hi, Vec3(3, 1, 1), 0);

  // A box with a spherical hole at its centre.
  const auto d = geom::make_difference(geom::make_box(Vec3(-1, -1, -1), Vec3(1, 1, 1)),
                                       geom::make_sphere(Vec3(0, 0, 0), 0.5));
  EXPECT_NEAR(d->phi(Vec3(0, 0, 0)), 0.5, kTol);  // in the hole
  EXPECT_NEAR(d->phi(Vec3(0.3, 0, 0)), 0.2, kTol);
  EXPECT_NEAR(d->phi(Vec3(0.7, 0, 0)), -0.2, kTol);                 // in the material
  EXPECT_NEAR(d->phi(Vec3(0.95, 0, 0)), -0.05, kTol);               // near the outer face
  EXPECT_NEAR(d->phi(Vec3(1.5, 0, 0)), 0.5, kTol);                  // outside
  expect_vec_near(d->grad(Vec3(0.3, 0, 0)), Vec3(-1, 0, 0), kTol);  // points into the hole
  expect_vec_near(d->grad(Vec3(0.95, 0, 0)), Vec3(1, 0, 0), kTol);
  EXPECT_THROW(geom::make_union({}), InputError);
}

TEST(GeometryTransform, RotatedBox) {
  // Body: box [0,2]x[0,1]x[0,1]; rotated 90 degrees about z, then moved by (10, 0, 0).
  // The body x axis maps to world y, body y to world -x: world box [9,10]x[0,2]x[0,1].
  const auto t = geom::make_transform(geom::make_box(Vec3(0, 0, 0), Vec3(2, 1, 1)), Vec3(0, 0, 3),
                                      kPi / 2, Vec3(10, 0, 0));
  EXPECT_NEAR(t->phi(Vec3(9.5, 1.5, 0.5)), -0.5, kTol);
  EXPECT_NEAR(t->phi(Vec3(9.8, 1.0, 0.5)), -0.2, kTol);
  EXPECT_NEAR(t->phi(Vec3(9.5, 2.5, 0.5)), 0.5, kTol);  // beyond the body's +x end
  EXPECT_NEAR(t->phi(Vec3(11.5, 0.5, 0.5)), 1.5, kTol);
  EXPECT_NEAR(t->phi(Vec3(8.0, 0.5, 0.5)), 1.0, kTol);
  expect_vec_near(t->grad(Vec3(9.5, 2.5, 0.5)), Vec3(0, 1, 0), kTol);
  expect_vec_near(t->grad(Vec3(11.5, 0.5, 0.5)), Vec3(1, 0, 0), kTol);
  const geom::Aabb bb = t->bounds();
  expect_vec_near(bb.lo, Vec3(9, 0, 0), tol(1e-12));
  expect_vec_near(bb.hi, Vec3(10, 2, 1), tol(1e-12));
  check_gradients(*t, Vec3(8, -1, -1), Vec3(11, 3, 2), 5);
}

TEST(GeometryTank, OpenTopWallsFluidAndRim) {
  const auto tank = geom::make_tank(Vec3(0, 0, 0), Vec3(1, 1, 1), 0.1, false);
  EXPECT_NEAR(tank->phi(Vec3(-0.05, 0.5, 0.5)), -0.05, kTol);    // side wall
  EXPECT_NEAR(tank->phi(Vec3(0.5, 1.03, 0.5)), -0.03, kTol);     // side wall
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, -0.05)), -0.05, kTol);    // floor
  EXPECT_NEAR(tank->phi(Vec3(-0.05, -0.05, 0.5)), -0.05, kTol);  // vertical corner
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, 0.5)), 0.5, kTol);        // fluid region
  EXPECT_NEAR(tank->phi(Vec3(0.2, 0.5, 0.9)), 0.2, kTol);        // near the open top
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, 0.05)), 0.05, kTol);      // just above the floor
  EXPECT_GT(tank->phi(Vec3(0.5, 0.5, 1.5)), 0.0);                // above the open top
  EXPECT_GT(tank->phi(Vec3(0.5, 0.5, 1.0 + 1e-3)), 0.0);
  EXPECT_NEAR(tank->phi(Vec3(-0.05, 0.5, 1.2)), 0.2, kTol);     // above the rim
  EXPECT_NEAR(tank->phi(Vec3(-0.05, 0.5, 0.98)), -0.02, kTol);  // in the wall below the rim
  EXPECT_NEAR(tank->phi(Vec3(-0.5, 0.5, 0.5)), 0.4, kTol);      // outside
  expect_vec_near(tank->grad(Vec3(0.2, 0.5, 0.5)), Vec3(1, 0, 0), kTol);
  expect_vec_near(tank->grad(Vec3(0.5, 0.5, 0.1)), Vec3(0, 0, 1), kTol);
  const geom::Aabb bb = tank->bounds();
  expect_vec_near(bb.lo, Vec3(-0.1, -0.1, -0.1), kTol);
  expect_vec_near(bb.hi, Vec3(1.1, 1.1, 1.0), kTol);
}

TEST(GeometryTank, ClosedTop) {
  const auto tank = geom::make_tank(Vec3(0, 0, 0), Vec3(1, 2, 1), 0.1, true);
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, 0.9)), 0.1, kTol);
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, 1.05)), -0.05, kTol);  // lid
  EXPECT_NEAR(tank->phi(Vec3(0.5, 0.5, 1.5)), 0.4, kTol);     // above the lid
  EXPECT_NEAR(tank->bounds().hi.z, 1.1, kTol);
}

// A tank's wet surface is its inner box: a point in the back half of a wall is measured from the
// inner face, not from the nearer outer face (whose mirror image holds no fluid), in a wall, a
// bottom edge and a bottom corner, and through a transform and a union.
TEST(GeometryTank, WetSurfaceIsTheInnerFace) {
  const auto tank = geom::make_tank(Vec3(0, 0, 0), Vec3(1, 1, 1), 0.1, false);
  const Vec3 floor_back(0.5, 0.5, -0.08);
  EXPECT_NEAR(tank->phi(floor_back), -0.02, kTol);  // nearest face: the dry underside
  EXPECT_NEAR(tank->wet_phi(floor_back), -0.08, kTol);
  expect_vec_near(tank->wet_grad(floor_back), Vec3(0, 0, 1), kTol);
  const Vec3 edge(1.07, 0.5, -0.07);
  EXPECT_NEAR(tank->wet_phi(edge), -0.07 * std::sqrt(2.0), kTol);
  expect_vec_near(tank->wet_grad(edge), Vec3(-1, 0, 1) / std::sqrt(2.0), kTol);
  const Vec3 corner(-0.06, -0.06, -0.06);
  EXPECT_NEAR(tank->wet_phi(corner), -0.06 * std::sqrt(3.0), kTol);
  expect_vec_near(tank->wet_grad(corner), Vec3(1, 1, 1) / std::sqrt(3.0), kTol);
  // Walls near the inner face: wet_phi is phi.
  EXPECT_NEAR(tank->wet_phi(Vec3(0.5, 0.5, -0.03)), tank->phi(Vec3(0.5, 0.5, -0.03)), kTol);
  // A plain box has every face wet.
  const auto box = geom::make_box(Vec3(0, 0, -0.1), Vec3(1, 1, 0));
  EXPECT_NEAR(box->wet_phi(Vec3(0.5, 0.5, -0.08)), -0.02, kTol);
  // Shifted by +10 in x and joined with a far box, the tank keeps its wet surface.
  const auto moved = geom::make_union({geom::make_transform(tank, Vec3(0, 0, 1), 0, Vec3(10, 0, 0)),
                                       geom::make_box(Vec3(-5, -5, -5), Vec3(-4, -4, -4))});
  EXPECT_NEAR(moved->wet_phi(floor_back + Vec3(10, 0, 0)), -0.08, kTol);
  expect_vec_near(moved->wet_grad(corner + Vec3(10, 0, 0)), Vec3(1, 1, 1) / std::sqrt(3.0), kTol);
}

// ---- grid SDF ----------------------------------------------------------------------------------

std::shared_ptr<geom::GridSdf> sample(Real (*f)(const Vec3&), Vec3 lo, Real h, int n) {
  std::vector<Real> v(std::size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v[i + n * (j + n * k)] = f(lo + h * Vec3(i, j, k));
  return std::make_shared<geom::GridSdf>(lo, h, n, n, n, std::move(v));
}

Real linear_field(const Vec3& x) {
  return 0.3 * x.x - 0.2 * x.y + 0.5 * x.z + 0.1;
}
Real sphere_field(const Vec3& x) {
  return norm(x - Vec3(0.05, -0.02, 0.01)) - 0.6;
}

TEST(GridSdf, TrilinearReproducesLinearField) {
  const auto g = sample(linear_field, Vec3(-1, -1, -1), 0.25, 9);
  const geom::GridSdfView v = g->view();
  std::mt19937 rng(7);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int n = 0; n < 500; ++n) {
    const Vec3 x(u(rng), u(rng), u(rng));
    EXPECT_NEAR(geom::grid_phi(v, x), linear_field(x), tol(1e-12));
    expect_vec_near(geom::grid_grad(v, x), Vec3(0.3, -0.2, 0.5), tol(1e-12));
  }
  // Exactly on nodes and on the grid's faces.
  EXPECT_NEAR(geom::grid_phi(v, Vec3(1, 1, 1)), linear_field(Vec3(1, 1, 1)), tol(1e-12));
  EXPECT_NEAR(geom::grid_phi(v, Vec3(-1, 0.25, 1)), linear_field(Vec3(-1, 0.25, 1)), tol(1e-12));
  // Outside: the value at the clamped point plus the distance to the grid box.
  EXPECT_NEAR(geom::grid_phi(v, Vec3(3, 0, 0)), linear_field(Vec3(1, 0, 0)) + 2, tol(1e-12));
  EXPECT_NEAR(geom::grid_phi(v, Vec3(4, 5, 0.5)),
              linear_field(Vec3(1, 1, 0.5)) + std::sqrt(9.0 + 16.0), tol(1e-12));
  expect_vec_near(geom::grid_grad(v, Vec3(3, 0, 0)), Vec3(1, -0.2, 0.5), tol(1e-12));
  expect_vec_near(geom::grid_grad(v, Vec3(4, 5, 0.5)), Vec3(0.6, 0.8, 0.5), tol(1e-12));
}

TEST(GridSdf, ApproximatesSphere) {
  const Real h = 0.05;
  const auto g = sample(sphere_field, Vec3(-1, -1, -1), h, 41);
  std::mt19937 rng(11);
  std::uniform_real_distribution<Real> u(-1, 1);
  Real worst = 0;
  for (int n = 0; n < 2000; ++n) {
    const Vec3 x(u(rng), u(rng), u(rng));
    worst = std::max(worst, std::abs(g->phi(x) - sphere_field(x)));
    if (std::abs(sphere_field(x)) < 0.3 && norm(x) > 0.2) {
      const Vec3 nrm = (x - Vec3(0.05, -0.02, 0.01)) / norm(x - Vec3(0.05, -0.02, 0.01));
      EXPECT_GT(dot(g->grad(x), nrm), 0.99);
      EXPECT_NEAR(norm(g->grad(x)), 1.0, tol(1e-12));
    }
  }
  EXPECT_LT(worst, h);
  EXPECT_LT(worst, 0.01);  // second order: ~h^2 / r
  // Far away phi keeps growing.
  EXPECT_NEAR(g->phi(Vec3(100, 0, 0)), sphere_field(Vec3(100, 0, 0)), 0.01);
  const geom::Aabb bb = g->bounds();
  EXPECT_LE(bb.lo.x, 0.05 - 0.6 + tol(1e-12));
  EXPECT_GE(bb.hi.x, 0.05 + 0.6 - tol(1e-12));
  EXPECT_GT(bb.lo.x, -0.7);
}

TEST(GridSdf, RejectsWrongValueCount) {
  EXPECT_THROW(geom::GridSdf(Vec3(0, 0, 0), 0.1, 2, 2, 2, std::vector<Real>(7)), InputError);
  EXPECT_THROW(geom::GridSdf(Vec3(0, 0, 0), 0.0, 2, 2, 2, std::vector<Real>(8)), InputError);
}

// ---- meshes ------------------------------------------------------------------------------------

// The unit cube [0,1]^3: vertex i at (i & 1, (i >> 1) & 1, (i >> 2) & 1); quads wound
// counter-clockwise seen from outside.
std::vector<Vec3> cube_vertices() {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.push_back(Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  return v;
}
const int kCubeQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

std::vector<std::array<int, 3>> cube_triangles() {
  std::vector<std::array<int, 3>> t;
  for (const auto& q : kCubeQuads) {
    t.push_back({q[0], q[1], q[2]});
    t.push_back({q[0], q[2], q[3]});
  }
  return t;
}

class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("sphdem_geom_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
    return path(name);
  }

  std::string write_ascii_stl(const std::string& name,
                              const std::vector<std::array<int, 3>>& tris) const {
    const auto v = cube_vertices();
    std::ostringstream s;
    s << "solid cube\n";
    for (const auto& t : tris) {
      s << "  facet normal 0 0 0\n    outer loop\n";
      for (int k : t) s << "      vertex " << v[k].x << " " << v[k].y << " " << v[k].z << "\n";
      s << "    endloop\n  endfacet\n";
    }
    s << "endsolid cube\n";
    return write(name, s.str());
  }

  std::string write_binary_stl(const std::string& name) const {
    const auto v = cube_vertices();
    const auto tris = cube_triangles();
    std::string data(80, ' ');
    data.replace(0, 11, "solid cube ");  // a header that starts like ascii
    const std::uint32_t n = static_cast<std::uint32_t>(tris.size());
    data.append(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : tris) {
      float rec[12] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        rec[3 + 3 * k] = float(v[t[k]].x);
        rec[4 + 3 * k] = float(v[t[k]].y);
        rec[5 + 3 * k] = float(v[t[k]].z);
      }
      data.append(reinterpret_cast<const char*>(rec), sizeof rec);
      data.append(2, '\0');
    }
    return write(name, data);
  }

  // Quads with the v, v/vt, v//vn, v/vt/vn forms, and the last face with negative indices.
  std::string write_obj(const std::string& name) const {
    std::ostringstream s;
    s << "# unit cube\no cube\n";
    for (const Vec3& p : cube_vertices()) s << "v " << p.x << " " << p.y << " " << p.z << "\n";
    s << "vt 0 0\nvn 0 0 1\n";
    for (int f = 0; f < 5; ++f) {
      const int* q = kCubeQuads[f];
      s << "f " << q[0] + 1 << " " << q[1] + 1 << "/1 " << q[2] + 1 << "//1 " << q[3] + 1
        << "/1/1\n";
    }
    const int* q = kCubeQuads[5];
    s << "f";
    for (int k = 0; k < 4; ++k) s << " " << q[k] - 8;
    s << "\n";
    return write(name, s.str());
  }

  std::filesystem::path dir_;
};

// The mesh SDF of the cube against the exact box SDF: equal at grid nodes, and within the
// interpolation error elsewhere.
void check_cube_sdf(const geom::TriMesh& m) {
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 36u);
  const Real h = 0.05;
  const auto s = geom::make_mesh_sdf(m, h, 3);
  const auto* g = dynamic_cast<const geom::GridSdf*>(s.get());
  ASSERT_NE(g, nullptr);
  const auto box = geom::make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  EXPECT_EQ(g->count(0), 27);
  EXPECT_NEAR(g->lo().x, -0.15, tol(1e-12));
  Real worst_node = 0;
  for (int k = 0; k < g->count(2); ++k)
    for (int j = 0; j < g->count(1); ++j)
      for (int i = 0; i < g->count(0); ++i) {
        const Vec3 x = g->lo() + h * Vec3(i, j, k);
        const Real v = g->values()[i + g->count(0) * (j + g->count(1) * k)];
        worst_node = std::max(worst_node, std::abs(v - box->phi(x)));
      }
  EXPECT_LT(worst_node, tol(1e-9));
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-0.3, 1.3);
  Real worst = 0;
  for (int n = 0; n < 3000; ++n) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const Real e = box->phi(x);
    worst = std::max(worst, std::abs(s->phi(x) - e));
    if (std::abs(e) > h) {
      EXPECT_EQ(s->phi(x) < 0, e < 0);
    }
  }
  EXPECT_LT(worst, 1.5 * h);
  EXPECT_LT(worst, 0.75 * h);
}

TEST_F(MeshFiles, AsciiStlCube) {
  const auto m = geom::load_mesh(write_ascii_stl("cube.stl", cube_triangles()));
  EXPECT_EQ(m.source, path("cube.stl"));
  check_cube_sdf(m);
}

TEST_F(MeshFiles, BinaryStlCube) {
  check_cube_sdf(geom::load_mesh(write_binary_stl("cube.STL")));
}

TEST_F(MeshFiles, ObjCube) {
  check_cube_sdf(geom::load_mesh(write_obj("cube.obj")));
}

TEST_F(MeshFiles, ShiftedCubeOffGridAligned) {
  // A cube whose faces do not fall on grid nodes.
  geom::TriMesh m;
  for (const Vec3& p : cube_vertices()) m.vertices.push_back(0.37 * p + Vec3(0.013, -0.2, 0.31));
  for (const auto& t : cube_triangles()) m.triangles.insert(m.triangles.end(), t.begin(), t.end());
  const Real h = 0.02;
  const auto s = geom::make_mesh_sdf(m, h, 2);
  const auto box = geom::make_box(Vec3(0.013, -0.2, 0.31), Vec3(0.383, 0.17, 0.68));
  const auto* g = dynamic_cast<const geom::GridSdf*>(s.get());
  ASSERT_NE(g, nullptr);
  const Vec3 lo = g->lo();
  const Vec3 hi = lo + h * Vec3(g->count(0) - 1, g->count(1) - 1, g->count(2) - 1);
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> u(0, 1);
  for (int n = 0; n < 2000; ++n) {
    // Inside the grid box: within the interpolation error of the exact box SDF.
    const Vec3 x(lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
                 lo.z + (hi.z - lo.z) * u(rng));
    EXPECT_NEAR(s->phi(x), box->phi(x), 0.75 * h);
    // Beyond the grid: positive, and an upper bound of the distance.
    const Vec3 far = x + Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 2.0;
    if (box->phi(far) > 0.05) {
      EXPECT_GT(s->phi(far), 0.0);
      EXPECT_GE(s->phi(far), box->phi(far) - 0.75 * h);
    }
  }
}

// A torus (not convex, with a hole) built in memory: the mesh SDF follows the analytic torus
// SDF within interpolation plus faceting error, with the right sign, including in the hole.
TEST(MeshSdf, TorusMatchesAnalytic) {
  const int nu = 72, nv = 24;
  const Real big_r = 0.7, small_r = 0.25;
  geom::TriMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Real u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.push_back(Vec3((big_r + small_r * std::cos(v)) * std::cos(u),
                                (big_r + small_r * std::cos(v)) * std::sin(u),
                                small_r * std::sin(v)));
    }
  auto id = [&](int i, int j) { return (i % nu) * nv + (j % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.insert(m.triangles.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.insert(m.triangles.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  auto torus = [&](const Vec3& x) {
    const Real q = std::sqrt(x.x * x.x + x.y * x.y) - big_r;
    return std::sqrt(q * q + x.z * x.z) - small_r;
  };
  const Real h = 0.04;
  const auto s = geom::make_mesh_sdf(m, h, 3);
  // Faceting: the polygon sagittas of the tube and of the outer ring.
  const Real facet =
      small_r * (1 - std::cos(kPi / nv)) + (big_r + small_r) * (1 - std::cos(kPi / nu));
  std::mt19937 rng(9);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int n = 0; n < 3000; ++n) {
    const Vec3 x(1.05 * u(rng), 1.05 * u(rng), 0.35 * u(rng));
    const Real e = torus(x);
    EXPECT_NEAR(s->phi(x), e, 0.75 * h + facet) << x.x << " " << x.y << " " << x.z;
    if (std::abs(e) > h + facet) {
      EXPECT_EQ(s->phi(x) < 0, e < 0);
    }
  }
  EXPECT_NEAR(s->phi(Vec3(0, 0, 0)), big_r - small_r, 0.01);           // centre of the hole
  EXPECT_NEAR(s->phi(Vec3(big_r, 0, 0)), -small_r, 0.75 * h + facet);  // tube centre: a kink
}

TEST_F(MeshFiles, ObjBadIndexNamesFileAndLine) {
  std::ostringstream s;
  for (const Vec3& p : cube_vertices()) s << "v " << p.x << " " << p.y << " " << p.z << "\n";
  s << "f 1 2 3\n\nf 1 2 9\n";
  const std::string p = write("bad.obj", s.str());
  try {
    geom::load_mesh(p);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), p + ":11: face refers to vertex 9 but only 8 are defined");
  }
  const std::string q = write("neg.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n");
  try {
    geom::load_mesh(q);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), q + ":3: face refers to vertex -3 but only 2 are defined");
  }
}

TEST_F(MeshFiles, AsciiStlBadVertexNamesLine) {
  const std::string p = write("bad.stl",
                              "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                              "vertex 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n");
  try {
    geom::load_mesh(p);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), p + ":5: expected three numbers after 'vertex'");
  }
}

TEST_F(MeshFiles, OpenMeshIsRejected) {
  auto tris = cube_triangles();
  tris.pop_back();  // remove (1, 7, 5) from the x = 1 face
  const std::string p = write_ascii_stl("open.stl", tris);
  const auto m = geom::load_mesh(p);
  try {
    geom::make_mesh_sdf(m, 0.05);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "mesh file '" + p +
                  "' is not closed: 3 edges are not shared by exactly two triangles, e.g. the "
                  "edge (1, 0, 1)-(1, 1, 1) is used by 1 triangle");
  }
}

TEST_F(MeshFiles, MissingFileAndUnknownFormat) {
  const std::string p = path("nope.stl");
  try {
    geom::load_mesh(p);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot open mesh file '" + p + "'");
  }
  EXPECT_THROW(geom::load_mesh(write("cube.ply", "ply\n")), InputError);
  EXPECT_THROW(geom::load_mesh(write("junk.stl", "not an stl file at all")), InputError);
}

// ---- quaternions -------------------------------------------------------------------------------

sphdem::Quat random_quat(std::mt19937& rng) {
  std::normal_distribution<Real> n(0, 1);
  return sphdem::normalize(sphdem::Quat{n(rng), n(rng), n(rng), n(rng)});
}

TEST(QuatRotate, AxisAngle) {
  const auto q = sphdem::from_axis_angle(Vec3(0, 0, 2), kPi / 2);
  expect_vec_near(sphdem::rotate(q, Vec3(1, 0, 0)), Vec3(0, 1, 0), tol(1e-15));
  expect_vec_near(sphdem::rotate(q, Vec3(0, 1, 0)), Vec3(-1, 0, 0), tol(1e-15));
  expect_vec_near(sphdem::rotate(q, Vec3(0, 0, 1)), Vec3(0, 0, 1), tol(1e-15));
  const auto r = sphdem::from_axis_angle(Vec3(1, 1, 1), 2 * kPi / 3);  // cycles x -> y -> z
  expect_vec_near(sphdem::rotate(r, Vec3(1, 0, 0)), Vec3(0, 1, 0), tol(1e-15));
  expect_vec_near(sphdem::rotate(r, Vec3(0, 0, 1)), Vec3(1, 0, 0), tol(1e-15));
}

TEST(QuatRotate, MatchesRotationMatrix) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<Real> u(-2, 2);
  for (int n = 0; n < 100; ++n) {
    const auto q = random_quat(rng);
    const Vec3 v(u(rng), u(rng), u(rng));
    const sphdem::Mat3 r = sphdem::to_matrix(q);
    expect_vec_near(sphdem::rotate(q, v), sphdem::matvec(r, v), tol(1e-13));
    // R is orthogonal with R^T the inverse rotation.
    const sphdem::Mat3 i = sphdem::multiply(r, sphdem::transpose(r));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) EXPECT_NEAR(i.m[a][b], a == b ? 1.0 : 0.0, tol(1e-14));
    expect_vec_near(sphdem::rotate(sphdem::conjugate(q), sphdem::rotate(q, v)), v, tol(1e-13));
    EXPECT_NEAR(norm(sphdem::rotate(q, v)), norm(v), tol(1e-13));
  }
}

TEST(QuatCompose, ProductIsSuccessiveRotation) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<Real> u(-2, 2);
  for (int n = 0; n < 100; ++n) {
    const auto a = random_quat(rng), b = random_quat(rng);
    const Vec3 v(u(rng), u(rng), u(rng));
    const auto ab = sphdem::multiply(a, b);
    expect_vec_near(sphdem::rotate(ab, v), sphdem::rotate(a, sphdem::rotate(b, v)), tol(1e-13));
    const sphdem::Mat3 m = sphdem::multiply(sphdem::to_matrix(a), sphdem::to_matrix(b));
    const sphdem::Mat3 mab = sphdem::to_matrix(ab);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(mab.m[i][j], m.m[i][j], tol(1e-14));
  }
  // Two quarter turns about z make a half turn.
  const auto q = sphdem::from_axis_angle(Vec3(0, 0, 1), kPi / 2);
  expect_vec_near(sphdem::rotate(sphdem::multiply(q, q), Vec3(1, 2, 3)), Vec3(-1, -2, 3),
                  tol(1e-15));
}

TEST(QuatNormalize, UnitLengthAndIdentity) {
  const auto q = sphdem::normalize(sphdem::Quat{2, 0, 0, 0});
  EXPECT_DOUBLE_EQ(q.w, 1.0);
  EXPECT_DOUBLE_EQ(q.x, 0.0);
  const auto z = sphdem::normalize(sphdem::Quat{0, 0, 0, 0});
  EXPECT_DOUBLE_EQ(z.w, 1.0);
  const auto p = sphdem::normalize(sphdem::Quat{1, 2, -3, 4});
  EXPECT_NEAR(sphdem::norm(p), 1.0, tol(1e-15));
  EXPECT_NEAR(p.y / p.x, -1.5, tol(1e-15));
  // A drifted quaternion, renormalised, still rotates like the original rotation.
  const auto r = sphdem::from_axis_angle(Vec3(1, -2, 0.5), 0.7);
  const sphdem::Quat drift{r.w * Real(1.001), r.x * Real(1.001), r.y * Real(1.001),
                           r.z * Real(1.001)};
  expect_vec_near(sphdem::rotate(sphdem::normalize(drift), Vec3(1, 2, 3)),
                  sphdem::rotate(r, Vec3(1, 2, 3)), tol(1e-14));
  EXPECT_NEAR(sphdem::norm(sphdem::from_axis_angle(Vec3(3, 4, 0), 1.3)), 1.0, tol(1e-15));
  expect_vec_near(sphdem::rotate(sphdem::from_axis_angle(Vec3(0, 0, 0), 1.0), Vec3(1, 2, 3)),
                  Vec3(1, 2, 3), 0);
}

}  // namespace
