// Heap measurement (diagnostics/heap.hpp): repose angle and toe of synthetic heaps of known shape.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "diagnostics/heap.hpp"

namespace sphdem {
namespace {

// Points on the surface z = (L - x) tan(theta) for 0 <= x <= L, 0 <= y <= W, plus the floor
// beyond, with seeded jitter below the surface (the interior of a heap).
std::vector<Vec3> wedge(Real theta_deg, Real L, Real W, Real jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Vec3> pts;
  const Real t = std::tan(theta_deg * Real(M_PI / 180));
  for (int i = 0; i < 20000; ++i) {
    const Real x = L * u(rng), y = W * u(rng);
    const Real top = (L - x) * t;
    pts.emplace_back(x, y, top - jitter * u(rng) * (i % 4 == 0 ? 0 : 1));
  }
  return pts;
}

TEST(Heap, WedgeAngleAndToe) {
  for (Real theta : {20.0, 31.0, 45.0}) {
    HeapOptions o;
    o.cell = 0.005;
    const HeapShape h = measure_heap(wedge(theta, 0.2, 0.05, 0.01, 7), o);
    EXPECT_NEAR(h.repose_deg, theta, 1.0) << theta;
    EXPECT_NEAR(h.toe, 0.2, o.cell) << theta;
    EXPECT_NEAR(h.height, 0.2 * std::tan(theta * M_PI / 180), 0.004) << theta;
    EXPECT_GT(h.columns, 20);
  }
}

TEST(Heap, AngleAcrossTheWidthCounts) {
  // The same slope turned to face y: the fit uses both x and y.
  std::vector<Vec3> pts = wedge(30.0, 0.2, 0.2, 0.005, 3);
  for (Vec3& p : pts) std::swap(p.x, p.y);
  HeapOptions o;
  o.cell = 0.005;
  EXPECT_NEAR(measure_heap(pts, o).repose_deg, 30.0, 1.0);
}

TEST(Heap, ToeStopsAtAGapAndFitWindowApplies) {
  std::vector<Vec3> pts = wedge(30.0, 0.2, 0.05, 0.005, 5);
  pts.emplace_back(0.3, 0.02, 0.002);  // one stray grain far beyond the heap
  HeapOptions o;
  o.cell = 0.005;
  HeapShape h = measure_heap(pts, o);
  EXPECT_NEAR(h.toe, 0.2, o.cell);
  // A fit window on a flat-topped heap: only the slope's part gives the angle.
  for (Vec3& p : pts) p.z = std::min(p.z, Real(0.08));
  o.x_min = 0.07;
  h = measure_heap(pts, o);
  EXPECT_NEAR(h.repose_deg, 30.0, 1.5);
}

TEST(Heap, TooFewColumnsGiveNoAngle) {
  HeapOptions o;
  EXPECT_TRUE(std::isnan(measure_heap({Vec3(0, 0, 0.01)}, o).repose_deg));
  EXPECT_TRUE(std::isnan(measure_heap({}, o).repose_deg));
}

}  // namespace
}  // namespace sphdem
