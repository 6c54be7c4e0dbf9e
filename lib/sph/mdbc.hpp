// Modified dynamic boundary condition (mDBC), English et al. (2022); seed Eqs. (21)-(22).
//
// Each boundary particle B has a ghost node G mirrored into the fluid across the solid surface,
// r_G = r_B - 2 phi(r_B) grad phi(r_B). At G, density and its gradient come from a first-order
// consistent SPH interpolation over fluid particles only. From the Taylor expansion
// rho_j = rho_G + (r_j - r_G) . grad rho_G, weighted by V_j W and by V_j grad W and summed:
//
//   [ sum V_j W          sum V_j (r_j - r_G) W        ] [ rho_G      ]   [ sum V_j rho_j W      ]
//   [ sum V_j gradW      sum V_j gradW (r_j - r_G)^T  ] [ grad rho_G ] = [ sum V_j rho_j gradW  ]
//
// with gradW = grad_G W(r_G - r_j). If the matrix is near-singular (few neighbours), fall back to
// a Shepard average with zero gradient. Then rho_B = rho_G + (r_B - r_G) . grad rho_G  (Eq. 21).
// The boundary velocity for the viscous term mirrors the Shepard velocity at G (Eq. 22):
// no-slip reverses it, free-slip reverses only its normal component.
#pragma once

#include <limits>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

// Accumulated sums at one ghost node. The 4x4 matrix of the system above is kept in its 20
// distinct entries: row 0 is (shepard, wd), column 0 below it is g, and the lower-right 3x3 block,
// sum V_j gradW (r_j - r_G)^T = -sum V_j F (r_j - r_G)(r_j - r_G)^T, is symmetric (gd). In 2D the
// y entries stay zero and are not used.
struct MdbcSums {
  Real shepard = 0;  // sum V_j W (the matrix's entry (0,0))
  Real wd[3] = {0};  // sum V_j W (r_j - r_G)
  Real g[3] = {0};   // sum V_j gradW
  Real gd[6] = {0};  // sum V_j gradW (r_j - r_G)^T: xx, xy, xz, yy, yz, zz
  Real b[4] = {0};   // right-hand side: sum V_j rho_j W, sum V_j rho_j gradW
  Vec3 vel;          // sum V_j v_j W
  // The range of the fluid densities seen (for mdbc_limit_density); empty while shepard is 0.
  Real rho_lo = Real(3e38), rho_hi = Real(-3e38);
  // Entry (r, c) of the 4x4 matrix (0: rho, 1-3: x, y, z).
  SPHDEM_HD Real a(int r, int c) const {
    if (r == 0) return c == 0 ? shepard : wd[c - 1];
    if (c == 0) return g[r - 1];
    const int i = r < c ? r - 1 : c - 1, j = r < c ? c - 1 : r - 1;  // i <= j
    return gd[i == 0 ? j : i + j + 1];  // (0,0..2) -> 0..2, (1,1) -> 3, (1,2) -> 4, (2,2) -> 5
  }
};

// Adds fluid particle j (volume v_j, at offset d = r_j - r_G; w = W and f = F at its distance)
// to the sums.
SPHDEM_HD inline void mdbc_accumulate(MdbcSums& s, Real v_j, Real rho_j, const Vec3& vel_j,
                                      const Vec3& d, Real w, Real f) {
  // gradW at G with respect to r_G: (r_G - r_j) F = -d F.
  const Real vw = v_j * w;
  const Real vf = -v_j * f;
  const Real gx = vf * d.x, gy = vf * d.y, gz = vf * d.z;
  s.shepard += vw;
  if (rho_j < s.rho_lo) s.rho_lo = rho_j;
  if (rho_j > s.rho_hi) s.rho_hi = rho_j;
  s.wd[0] += vw * d.x;
  s.wd[1] += vw * d.y;
  s.wd[2] += vw * d.z;
  s.g[0] += gx;
  s.g[1] += gy;
  s.g[2] += gz;
  s.gd[0] += gx * d.x;
  s.gd[1] += gx * d.y;
  s.gd[2] += gx * d.z;
  s.gd[3] += gy * d.y;
  s.gd[4] += gy * d.z;
  s.gd[5] += gz * d.z;
  s.b[0] += vw * rho_j;
  s.b[1] += gx * rho_j;
  s.b[2] += gy * rho_j;
  s.b[3] += gz * rho_j;
  s.vel += vel_j * vw;
}

// Solves for rho_G and grad rho_G; returns rho_B extrapolated to offset rb_minus_rg = r_B - r_G.
// Uses Gaussian elimination with partial pivoting on the (dim+1) system. `det_min` is the
// relative threshold below which the Shepard fallback is used. Returns rho_fallback when no fluid
// is near the ghost node.
//
// The singularity test is made on the dimensionless system: the unknowns are rho_G and
// `length` grad rho_G (length = h), so the W rows and the gradW rows have entries of order one.
// Tested on the dimensional matrix, a ghost node with one-sided support (near a wall, and worse in
// a corner) has gradW rows of order 1/h and its determinant looked 1e-7 "singular": the corner
// boundary particles fell back to a Shepard average, read too low a pressure and let the corner
// fluid particle through the tank's corner.
SPHDEM_HD inline Real mdbc_boundary_density(const MdbcSums& s, int dim, const Vec3& rb_minus_rg,
                                            Real rho_fallback, Real det_min, Real length) {
  if (s.shepard <= Real(0)) return rho_fallback;
  // Indices of the unknowns used: rho, d/dx, (d/dy), d/dz.
  int idx[4] = {0, 1, 2, 3};
  int n = 4;
  if (dim == 2) {
    idx[2] = 3;
    n = 3;
  }
  Real m[4][5];
  for (int r = 0; r < n; ++r) {
    const Real row_scale = r > 0 ? length : Real(1);  // gradW rows times h
    for (int c = 0; c < n; ++c)
      m[r][c] = s.a(idx[r], idx[c]) * row_scale / (c > 0 ? length : Real(1));  // unknown h grad
    m[r][n] = s.b[idx[r]] * row_scale;
  }
  // Scale-aware singularity test: determinant relative to the product of row norms.
  Real det = 1;
  Real scale = 1;
  for (int r = 0; r < n; ++r) {
    Real rn = 0;
    for (int c = 0; c < n; ++c) rn += m[r][c] * m[r][c];
    scale *= std::sqrt(rn);
  }
  for (int c = 0; c < n; ++c) {
    int p = c;
    for (int r = c + 1; r < n; ++r)
      if ((m[r][c] < 0 ? -m[r][c] : m[r][c]) > (m[p][c] < 0 ? -m[p][c] : m[p][c])) p = r;
    if (p != c) {
      for (int k = 0; k <= n; ++k) {
        const Real t = m[c][k];
        m[c][k] = m[p][k];
        m[p][k] = t;
      }
      det = -det;
    }
    det *= m[c][c];
    if (m[c][c] == Real(0)) break;
    for (int r = c + 1; r < n; ++r) {
      const Real fct = m[r][c] / m[c][c];
      for (int k = c; k <= n; ++k) m[r][k] -= fct * m[c][k];
    }
  }
  const Real rel = scale > Real(0) ? (det < 0 ? -det : det) / scale : Real(0);
  if (!(rel > det_min)) return s.b[0] / s.shepard;  // Shepard fallback, zero gradient
  Real x[4] = {0, 0, 0, 0};
  for (int r = n - 1; r >= 0; --r) {
    Real acc = m[r][n];
    for (int c = r + 1; c < n; ++c) acc -= m[r][c] * x[c];
    x[r] = acc / m[r][r];
  }
  Vec3 grad;
  if (dim == 2) {
    grad = Vec3(x[1], 0, x[2]) / length;
  } else {
    grad = Vec3(x[1], x[2], x[3]) / length;
  }
  return x[0] + dot(rb_minus_rg, grad);
}

// Limiter for the extrapolated boundary density (sph.mdbc_limiter). The linear fit at a ghost
// node with sparse or one-sided support (a jet through a barrier's slit, a splash) can return a
// steep gradient, and r_B - r_G, up to twice the boundary depth (more where a thin wall mirrors
// through its far face), multiplies it: rho_B three times rho0 was seen at the end of a V30
// wall, whose pressure shot the fluid out of the slit at Mach 0.23. The limiter keeps rho_B
// within the fluid densities seen at G widened by their spread on either side,
// [lo - (hi - lo), hi + (hi - lo)]. A linear field whose support reaches at least as far along
// the gradient as the extrapolation goes past it (hydrostatic walls: the support spans the depth
// plus 2h, the extrapolation at most the depth plus dp/2) is never clipped.
SPHDEM_HD inline Real mdbc_limit_density(const MdbcSums& s, Real rho_b) {
  if (!(s.shepard > Real(0))) return rho_b;
  const Real spread = s.rho_hi - s.rho_lo;
  const Real lo = s.rho_lo - spread, hi = s.rho_hi + spread;
  return rho_b < lo ? lo : (rho_b > hi ? hi : rho_b);
}

// How far the limiter moves a fitted wall density `fit` once both sides take the rho0 floor
// (0 where it leaves the wall's pressure alone).
SPHDEM_HD inline Real mdbc_limiter_cut(const MdbcSums& s, Real fit, Real rho0) {
  const Real lim = mdbc_limit_density(s, fit);
  const Real a = fit < rho0 ? rho0 : fit, b = lim < rho0 ? rho0 : lim;
  return a > b ? a - b : b - a;
}

// Whether a cut counts as a clip in mdbc_limiter.csv: above a millionth of rho0. Where the fluid
// at the ghost node has one density (lo = hi), the bound is that density, and the fit's
// round-off passes it by 1e-13 to 1e-10 kg/m^3; such cuts are not clips, and their number
// differs with the rank count. A cut below 1e-6 rho0 moves the wall pressure by under
// 1e-6 rho0 c0^2 (1.2 Pa for the flume's debris at c0 = 30 m/s).
SPHDEM_HD inline bool mdbc_cut_is_clip(Real cut, Real rho0) {
  return cut > Real(1e-6) * rho0;
}

// What the limiter does at one instant (mdbc_limiter.csv): the number of boundary particles whose
// fit leaves the limiter's bound where it changes their pressure (above rho0, by more than
// round-off: mdbc_cut_is_clip), which are clipped when sph.mdbc_limiter is on and would be
// otherwise; the largest fitted density before the
// limiter and the rho0 floor; and the largest change the limiter makes (or would make) to a wall
// density, floors applied. Where it acts: the range along x of the clipped particles, and the
// position of the largest cut (NaN without a clip).
struct MdbcLimiterStats {
  double clipped = 0;
  Real rho_fit_max = 0;
  Real rho_cut_max = 0;
  Real clip_x_lo = std::numeric_limits<Real>::quiet_NaN();
  Real clip_x_hi = std::numeric_limits<Real>::quiet_NaN();
  Vec3 cut_at{std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::quiet_NaN(),
              std::numeric_limits<Real>::quiet_NaN()};
};

// Boundary velocity for the viscous term: mirror of the ghost node's Shepard velocity about the
// wall velocity. No-slip: v_B = 2 v_wall - v_G. Free-slip: only the normal part is mirrored.
SPHDEM_HD inline Vec3 mdbc_boundary_velocity(const MdbcSums& s, const Vec3& v_wall,
                                             const Vec3& normal, bool free_slip) {
  if (s.shepard <= Real(0)) return v_wall;
  const Vec3 vg = s.vel / s.shepard - v_wall;  // relative to the wall
  if (!free_slip) return v_wall - vg;
  const Vec3 vn = normal * dot(vg, normal);
  return v_wall + (vg - vn) - vn;
}

// Penetration control (sph.no_penetration), for a fluid particle f and a wall particle b.
//
// mDBC gives a wall particle the density extrapolated from the fluid near its ghost node, never
// below rho0. Where that fluid is a thin sheet at about zero pressure (the thinning tail of a
// release, a film on a slope), the wall then exerts no pressure at all, and two things carry the
// sheet into it: gravity, and the sheet's own tension (p < 0 in the pair term attracts the fluid
// particle to the wall particle). DualSPHysics 5.4 added a penetration control to mDBC for this.
// Ours has two parts:
//   - walls push, never pull: across a fluid-wall pair the fluid's pressure counts only if > 0;
//   - a fluid particle moving toward the wall, u = (v_f - v_b) . n < 0 with n the wall normal
//     turned toward f, sees in the continuity equation a wall that approaches it at the mirrored
//     speed (as a mirror particle would): the relative velocity's normal part is 2u. Its density
//     and pressure rise as it closes in, and the pair's pressure term pushes it back. Fluid at
//     rest or moving away is unaffected (hydrostatics unchanged).
// v_fb = v_f - v_b, r_fb = r_f - r_b, n_b: the wall particle's normal (either orientation).
SPHDEM_HD inline Vec3 wall_continuity_velocity(const Vec3& v_fb, const Vec3& r_fb,
                                               const Vec3& n_b) {
  const Vec3 n = dot(r_fb, n_b) < Real(0) ? -n_b : n_b;
  const Real u = dot(v_fb, n);
  return u < Real(0) ? v_fb + n * u : v_fb;
}

SPHDEM_HD inline Real wall_pair_pressure(Real p_fluid) {
  return p_fluid > Real(0) ? p_fluid : 0;
}

}  // namespace sphdem
