// Grid signed-distance functions (DESIGN.md §2): phi sampled on a uniform grid of nodes and
// interpolated trilinearly. Grains use one in their body frame; triangle meshes are turned into
// one. GridSdfView is a plain view (pointer + sizes) whose lookups are SPHDEM_HD, so the same
// code runs on the host and in CUDA kernels. GridSdf is the host-side owner.
//
// Layout: node (i, j, k) sits at lo + spacing * (i, j, k) and its value is
// phi[i + n[0] * (j + n[1] * k)], 0 <= i < n[0], 0 <= j < n[1], 0 <= k < n[2].
#pragma once

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem::geom {

// A non-owning view of a grid SDF. Valid while the owner's storage lives.
struct GridSdfView {
  Vec3 lo;           // position of node (0, 0, 0)
  Real spacing;      // node spacing, equal along x, y and z
  int n[3];          // number of nodes along x, y, z (each >= 1)
  const Real* phi;   // n[0] * n[1] * n[2] values, x fastest
  Real inv_spacing;  // 1 / spacing: the lookups multiply (docs/BENCHMARKS.md, level-set profile)
};

namespace detail {

// The value stored at node (i, j, k).
SPHDEM_HD inline Real grid_node(const GridSdfView& g, int i, int j, int k) {
  return g.phi[i + g.n[0] * (j + g.n[1] * k)];
}

// Locates the point xc (inside the grid box) in its cell: lower node index i0[d] and the
// fractional position t[d] in [0, 1] along each axis. Axes with a single node get i0 = 0, t = 0.
SPHDEM_HD inline void grid_locate(const GridSdfView& g, const Vec3& xc, int i0[3], Real t[3]) {
  for (int d = 0; d < 3; ++d) {
    if (g.n[d] < 2) {
      i0[d] = 0;
      t[d] = 0;
      continue;
    }
    const Real u = (xc[d] - g.lo[d]) * g.inv_spacing;
    // Truncation equals floor once clamped below at 0 (u in (-1, 0) truncates to 0, floors to -1).
    int i = static_cast<int>(u);
    i = i < 0 ? 0 : (i > g.n[d] - 2 ? g.n[d] - 2 : i);
    Real f = u - Real(i);
    f = f < Real(0) ? Real(0) : (f > Real(1) ? Real(1) : f);
    i0[d] = i;
    t[d] = f;
  }
}

// The point of the grid box [lo, lo + spacing * (n - 1)] nearest to x.
SPHDEM_HD inline Vec3 grid_clamp(const GridSdfView& g, const Vec3& x) {
  Vec3 c = x;
  for (int d = 0; d < 3; ++d) {
    const Real lo = g.lo[d];
    const Real hi = g.lo[d] + g.spacing * Real(g.n[d] - 1);
    c[d] = x[d] < lo ? lo : (x[d] > hi ? hi : x[d]);
  }
  return c;
}

// Trilinear value and, with kGradient, its exact gradient (d/dx of the interpolant) at a point
// xc inside the grid box. The gradient is the one-sided derivative of the cell that holds xc.
// The value is summed in the same order either way, so the two forms agree to the bit.
template <bool kGradient>
SPHDEM_HD inline Real grid_interpolate(const GridSdfView& g, const Vec3& xc, Vec3* gradient) {
  int i0[3];
  Real t[3];
  grid_locate(g, xc, i0, t);
  int i1[3];
  for (int d = 0; d < 3; ++d) i1[d] = i0[d] + 1 < g.n[d] ? i0[d] + 1 : i0[d];
  Real v = 0;
  Vec3 gr(0, 0, 0);
  for (int c = 0; c < 8; ++c) {
    const int b0 = c & 1, b1 = (c >> 1) & 1, b2 = (c >> 2) & 1;
    const Real f = grid_node(g, b0 ? i1[0] : i0[0], b1 ? i1[1] : i0[1], b2 ? i1[2] : i0[2]);
    const Real w0 = b0 ? t[0] : Real(1) - t[0];
    const Real w1 = b1 ? t[1] : Real(1) - t[1];
    const Real w2 = b2 ? t[2] : Real(1) - t[2];
    v += f * w0 * w1 * w2;
    if constexpr (kGradient) {
      gr.x += f * (b0 ? Real(1) : Real(-1)) * w1 * w2;
      gr.y += f * (b1 ? Real(1) : Real(-1)) * w0 * w2;
      gr.z += f * (b2 ? Real(1) : Real(-1)) * w0 * w1;
    }
  }
  if constexpr (kGradient) *gradient = gr * g.inv_spacing;
  return v;
}

SPHDEM_HD inline void grid_trilinear(const GridSdfView& g, const Vec3& xc, Real* value,
                                     Vec3* gradient) {
  *value = grid_interpolate<true>(g, xc, gradient);
}

// The distance from x to its clamped point c; zero, without a square root, inside the box.
SPHDEM_HD inline Real grid_outside(const Vec3& x, const Vec3& c) {
  return x.x == c.x && x.y == c.y && x.z == c.z ? Real(0) : norm(x - c);
}

}  // namespace detail

// phi at x: the trilinear interpolant inside the grid box. Outside it, the interpolant at the
// nearest point of the box plus the distance to the box, so phi keeps growing far away.
SPHDEM_HD inline Real grid_phi(const GridSdfView& g, const Vec3& x) {
  const Vec3 c = detail::grid_clamp(g, x);
  return detail::grid_interpolate<false>(g, c, nullptr) + detail::grid_outside(x, c);
}

// The gradient of grid_phi at x (not normalised): the derivative of the trilinear interpolant
// inside the grid box; outside it, along clamped axes the derivative of the distance to the box
// and along the others the derivative of the interpolant at the clamped point.
SPHDEM_HD inline Vec3 grid_grad(const GridSdfView& g, const Vec3& x) {
  const Vec3 c = detail::grid_clamp(g, x);
  Real v;
  Vec3 gr;
  detail::grid_trilinear(g, c, &v, &gr);
  const Vec3 out = x - c;
  const Real dist = norm(out);
  if (dist > Real(0)) {
    for (int d = 0; d < 3; ++d)
      if (out[d] != Real(0)) gr[d] = out[d] / dist;
  }
  return gr;
}

// grid_grad scaled to unit length; the zero vector where the gradient vanishes.
SPHDEM_HD inline Vec3 grid_normal(const GridSdfView& g, const Vec3& x) {
  const Vec3 gr = grid_grad(g, x);
  const Real len = norm(gr);
  return len > Real(0) ? gr / len : Vec3(0, 0, 0);
}

}  // namespace sphdem::geom

// ---- host-side owner --------------------------------------------------------------------------
// Compiled by g++ and by nvcc (host code only): it uses the standard library and virtual calls.
#include <vector>

#include "geometry/sdf.hpp"

namespace sphdem::geom {

// A grid SDF that owns its node values. phi and grad use the GridSdfView lookups above.
class GridSdf : public Sdf {
 public:
  // Nodes n[0] x n[1] x n[2] (each >= 1) at lo + spacing * (i, j, k); values x fastest.
  // Throws sphdem::InputError if spacing <= 0, a count < 1 or values has the wrong size.
  GridSdf(Vec3 lo, Real spacing, int nx, int ny, int nz, std::vector<Real> values);

  Real phi(const Vec3& x) const override { return grid_phi(view(), x); }
  // The normalised gradient of the interpolant (grid_normal).
  Vec3 grad(const Vec3& x) const override { return grid_normal(view(), x); }
  // The union of the cells that hold a node with phi <= 0 (the trilinear solid lies inside it);
  // an empty box at lo if no node is inside.
  Aabb bounds() const override { return bounds_; }

  // A view for lookups (host or device memory holding the same layout may be substituted).
  GridSdfView view() const {
    return GridSdfView{lo_, spacing_, {n_[0], n_[1], n_[2]}, values_.data(), Real(1) / spacing_};
  }
  const std::vector<Real>& values() const { return values_; }
  Vec3 lo() const { return lo_; }
  Real spacing() const { return spacing_; }
  int count(int axis) const { return n_[axis]; }

 private:
  Vec3 lo_;
  Real spacing_;
  int n_[3];
  std::vector<Real> values_;
  Aabb bounds_;
};

}  // namespace sphdem::geom
