// Unit tests of grain templates (lib/dem/grain_template.hpp): mass properties from SDF quadrature
// against analytic values, principal axes, surface nodes, and the shape generators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "dem/grain_template.hpp"
#include "geometry/grid_sdf.hpp"
#include "precision.hpp"

namespace sphdem::dem {
namespace {

using test::kFloatEps;
using test::tol;

double rel(double a, double b) {
  return std::fabs(a - b) / std::fabs(b);
}

// Mean and max of |phi(node)| in units of the grid spacing.
void expect_nodes_on_surface(const GrainTemplate& t, double mean_tol, double max_tol) {
  double sum = 0, mx = 0;
  for (const Vec3& n : t.nodes()) {
    const double a = std::fabs(geom::grid_phi(t.view(), n)) / t.grid_spacing();
    sum += a;
    mx = std::max(mx, a);
  }
  const double mean = sum / double(t.nodes().size());
  std::printf("nodes: mean |phi|/h %.3f, max %.3f\n", mean, mx);
  EXPECT_LT(mean, mean_tol);
  EXPECT_LT(mx, max_tol);
}

TEST(DemTemplate, BoxInertiaMatchesAnalytic) {
  // Box 2a x 2b x 2c = 0.02 x 0.04 x 0.06 m: I_x/rho = V (b^2 + c^2) / 3 etc. Grid h = L_max/30.
  const Vec3 h(0.01, 0.02, 0.03);
  const GrainTemplate t = GrainTemplate::box(h);
  const double v = 8 * h.x * h.y * h.z;
  const Vec3 i = t.inertia_per_density();
  const double ix = v * (h.y * h.y + h.z * h.z) / 3, iy = v * (h.x * h.x + h.z * h.z) / 3,
               iz = v * (h.x * h.x + h.y * h.y) / 3;
  std::printf("box: V err %.2e, I err %.2e %.2e %.2e; %s\n", rel(t.volume(), v), rel(i.x, iz),
              rel(i.y, iy), rel(i.z, ix), t.describe().c_str());
  EXPECT_LT(rel(t.volume(), v), 0.01);
  // Ascending order: the smallest moment is about the longest axis (z), i.e. I_z of the source.
  EXPECT_LT(rel(i.x, iz), 0.01);
  EXPECT_LT(rel(i.y, iy), 0.01);
  EXPECT_LT(rel(i.z, ix), 0.01);
  EXPECT_LT(norm(t.source_centroid()), 1e-3 * h.x);
  EXPECT_FALSE(t.is_sphere());
  // Nodes lie on the surface: phi(node) ~ 0, to a fraction of the grid spacing (the trilinear
  // interpolant rounds the sharp edges, so edge nodes read a little more).
  expect_nodes_on_surface(t, 0.02, 0.3);
}

TEST(DemTemplate, EllipsoidInertiaMatchesAnalytic) {
  // I_x = m (b^2 + c^2) / 5, V = 4/3 pi a b c.
  const Vec3 a(0.03, 0.02, 0.01);
  const GrainTemplate t = GrainTemplate::ellipsoid(a);
  const double v = 4.0 / 3.0 * kPi * a.x * a.y * a.z;
  const Vec3 i = t.inertia_per_density();
  // Ascending: the smallest moment about the longest semi-axis (x).
  const double i0 = v * (a.y * a.y + a.z * a.z) / 5, i1 = v * (a.x * a.x + a.z * a.z) / 5,
               i2 = v * (a.x * a.x + a.y * a.y) / 5;
  std::printf("ellipsoid: V err %.2e, I err %.2e %.2e %.2e; %s\n", rel(t.volume(), v), rel(i.x, i0),
              rel(i.y, i1), rel(i.z, i2), t.describe().c_str());
  EXPECT_LT(rel(t.volume(), v), 0.01);
  EXPECT_LT(rel(i.x, i0), 0.01);
  EXPECT_LT(rel(i.y, i1), 0.01);
  EXPECT_LT(rel(i.z, i2), 0.01);
}

TEST(DemTemplate, SphereIsExactAndFlagged) {
  const GrainTemplate t = GrainTemplate::sphere(0.01);
  EXPECT_TRUE(t.is_sphere());
  EXPECT_DOUBLE_EQ(t.radius(), Real(0.01));  // the radius as given
  // Float: V = 4/3 pi r^3 and I = 0.4 V r^2 take ~6 roundings and r = 0.01 is rounded once (3 u
  // in r^3, 2 u in r^2): <= ~4 eps relative. The nodes are unit Fibonacci directions (z, the
  // sqrt(1 - z^2), cos and sin, products: a few u) times r, and the check's norm adds ~4 u:
  // 4 eps of r.
  EXPECT_NEAR(t.volume(), 4.0 / 3.0 * kPi * 1e-6, tol(1e-15, 4 * kFloatEps * t.volume()));
  EXPECT_NEAR(t.inertia_per_density().x, 0.4 * t.volume() * 1e-4,
              tol(1e-18, 4 * kFloatEps * t.inertia_per_density().x));
  for (const Vec3& n : t.nodes()) EXPECT_NEAR(norm(n), 0.01, tol(1e-12, 4 * kFloatEps * 0.01));
  EXPECT_NEAR(geom::grid_phi(t.view(), Vec3(0.002, 0.001, -0.003)),
              norm(Vec3(0.002, 0.001, -0.003)) - 0.01, 0.1 * t.grid_spacing());
}

TEST(DemTemplate, RotatedBoxFindsItsPrincipalAxes) {
  // The box of BoxInertiaMatchesAnalytic, rotated and shifted: same moments, and the body axes
  // map onto the rotated box axes.
  const Quat q = from_axis_angle(Vec3(1, 2, 3), 0.8);
  const Vec3 c(0.1, -0.2, 0.05);
  const Vec3 h(0.01, 0.02, 0.03);
  std::vector<Vec3> n;
  std::vector<Real> d;
  for (int k = 0; k < 3; ++k)
    for (int s : {-1, 1}) {
      Vec3 e;
      e[k] = Real(s);
      const Vec3 nw = rotate(q, e);
      n.push_back(nw);
      d.push_back(dot(nw, c) + h[k]);
    }
  const GrainTemplate t = GrainTemplate::polyhedron(make_convex_polyhedron(n, d));
  const GrainTemplate ref = GrainTemplate::box(h);
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(rel(t.inertia_per_density()[k], ref.inertia_per_density()[k]), 0.01);
  EXPECT_LT(norm(t.source_centroid() - c), 1e-3 * h.x);
  // Body axis 0 (smallest moment) is the box's long axis z, rotated.
  const Mat3 r = t.source_rotation();
  const Vec3 axis0(r.m[0][0], r.m[1][0], r.m[2][0]);
  EXPECT_GT(std::fabs(dot(axis0, rotate(q, Vec3(0, 0, 1)))), 0.9999);
  // The full tensor in the source frame is R diag(I) R^T.
  const Mat3 j = t.source_inertia_tensor();
  Vec3 lam;
  Mat3 v;
  symmetric_eigen(j, &lam, &v);
  EXPECT_NEAR(lam.x, t.inertia_per_density().x, 1e-12 * lam.z);
}

TEST(DemTemplate, RandomPolyhedronHasItsEquivalentDiameter) {
  const GrainTemplate t = GrainTemplate::random_polyhedron(0.016, 14, 42);
  std::printf("polyhedron: d_eq %.5f (target 0.016); %s\n", t.equivalent_diameter(),
              t.describe().c_str());
  EXPECT_LT(rel(t.equivalent_diameter(), 0.016), 0.01);
  EXPECT_GT(t.nodes().size(), 100u);
  // Principal moments of a convex blob of this size lie near those of the sphere of equal volume.
  const double isph = 0.4 * t.volume() * 0.008 * 0.008;
  EXPECT_GT(t.inertia_per_density().x, 0.5 * isph);
  EXPECT_LT(t.inertia_per_density().z, 2.0 * isph);
  // Seeded: the same seed gives the same shape, another seed another one.
  const GrainTemplate same = GrainTemplate::random_polyhedron(0.016, 14, 42);
  const GrainTemplate other = GrainTemplate::random_polyhedron(0.016, 14, 43);
  EXPECT_EQ(same.nodes().size(), t.nodes().size());
  EXPECT_DOUBLE_EQ(same.inertia_per_density().x, t.inertia_per_density().x);
  EXPECT_NE(other.inertia_per_density().x, t.inertia_per_density().x);
}

TEST(DemTemplate, TrigonalPyramidVolumeAndSurface) {
  // Unperturbed: a regular-base pyramid of edge s and height s has V = (sqrt(3)/4 s^2) s / 3.
  const Real s = 0.02;
  const GrainTemplate t = GrainTemplate::trigonal_pyramid(s, 0, 1);
  EXPECT_LT(rel(t.volume(), std::sqrt(3.0) / 12 * s * s * s), 0.01);
  const GrainTemplate p = GrainTemplate::trigonal_pyramid(s, 0.1, 7, 0.016);
  EXPECT_LT(rel(p.equivalent_diameter(), 0.016), 0.01);
  // The tips are sharp: the trilinear phi rounds them by up to ~0.6 h.
  expect_nodes_on_surface(p, 0.1, 0.75);
  EXPECT_THROW(make_convex_polyhedron(
                   {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0)}, {1, 1, 1, 1}),
               InputError);  // an unbounded prism
}

TEST(DemTemplate, MeshTemplateMatchesBox) {
  // A closed OBJ box of 0.02 x 0.04 x 0.06 m.
  const std::string path =
      (std::filesystem::temp_directory_path() / "sphdem_dem_box_test.obj").string();
  {
    std::ofstream f(path);
    const double x[2] = {-0.01, 0.01}, y[2] = {-0.02, 0.02}, z[2] = {-0.03, 0.03};
    for (int k = 0; k < 8; ++k)
      f << "v " << x[k & 1] << " " << y[(k >> 1) & 1] << " " << z[k >> 2] << "\n";
    // Faces (1-based), outward.
    f << "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\n"
         "f 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";
  }
  const GrainTemplate t = GrainTemplate::mesh(geom::load_mesh(path));
  std::filesystem::remove(path);
  const GrainTemplate ref = GrainTemplate::box(Vec3(0.01, 0.02, 0.03));
  EXPECT_LT(rel(t.volume(), ref.volume()), 0.02);
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(rel(t.inertia_per_density()[k], ref.inertia_per_density()[k]), 0.02) << k;
}

}  // namespace
}  // namespace sphdem::dem
