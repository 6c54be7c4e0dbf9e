// Non-Newtonian rheology and turbulence closure, seed Eqs. (10)-(15), with DESIGN.md §1.
//
// Velocity gradient (SPH, first order): G_i = sum_j V_j (v_j - v_i) (x) grad_i W_ij, with
// G[a][b] = d v_a / d x_b. Strain rate (Eq. 13): eps = (G + G^T)/2.
//
// Shear rate. The seed's Eq. (14), gamma = sqrt(eps:eps / 2), is half the shear rate du/dy of a
// simple shear; its Eq. (11) then writes the yield part as tau_y (1 - exp(-2 m gamma)) / (2 gamma),
// which equals tau_y (1 - exp(-m g)) / g with the standard shear rate g = sqrt(2 eps:eps) (=
// |du/dy| in simple shear). We use g throughout, so that
//   mu_eff = K g^(n-1) + tau_y (1 - exp(-m g)) / g                  (Eq. 11, Papanastasiou)
// reproduces the Herschel-Bulkley law |tau| = tau_y + K |du/dy|^n of FORMULAS.md §4 as m -> inf.
// For n = 1 (Bingham) this is exactly the seed's model; for n != 1 the seed's printed form would
// scale K by 2^(1-n), which we do not follow.
// Eq. (15): (1 - exp(-m g)) / g -> m as g -> 0, evaluated with expm1 to avoid 0/0.
// Yield stress, Mohr-Coulomb (Eq. 12): tau_y = c + max(p, 0) tan(phi).
// mu_eff is a DYNAMIC viscosity (Pa s), capped at mu_max so the viscous time step stays finite.
//
// SPS (Eq. 10 is garbled in the seed; Dalrymple & Rogers 2006):
//   tau/rho = 2 nu_t (S - tr(S)/3 I) - (2/3) C_I dl^2 |S|^2 I,  nu_t = (C_S dl)^2 |S|,
//   |S| = sqrt(2 S:S), dl = dp.
#pragma once

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

// A symmetric 3x3 tensor: diagonal (xx, yy, zz) and off-diagonal (xy, xz, yz).
struct SymTensor {
  Vec3 d, o;
};

struct Mat3g {  // velocity gradient, g[a][b] = d v_a / d x_b
  Real g[3][3] = {{0}};
};

// Adds the pair contribution V_j (v_j - v_i) (x) grad_i W_ij; grad_i W_ij = r_ij F.
SPHDEM_HD inline void velocity_gradient_add(Mat3g& G, Real v_j, const Vec3& v_ji, const Vec3& r_ij,
                                            Real f) {
  const Real s = v_j * f;
  for (int a = 0; a < 3; ++a) {
    const Real va = v_ji[a] * s;
    G.g[a][0] += va * r_ij.x;
    G.g[a][1] += va * r_ij.y;
    G.g[a][2] += va * r_ij.z;
  }
}

// Strain-rate tensor eps = (G + G^T)/2.
SPHDEM_HD inline SymTensor strain_rate(const Mat3g& G) {
  SymTensor e;
  e.d = Vec3(G.g[0][0], G.g[1][1], G.g[2][2]);
  e.o = Vec3(Real(0.5) * (G.g[0][1] + G.g[1][0]), Real(0.5) * (G.g[0][2] + G.g[2][0]),
             Real(0.5) * (G.g[1][2] + G.g[2][1]));
  return e;
}

// eps:eps (the off-diagonal terms count twice).
SPHDEM_HD inline Real double_dot(const SymTensor& e) {
  return dot(e.d, e.d) + Real(2) * dot(e.o, e.o);
}

// Standard shear rate g = sqrt(2 eps:eps).
SPHDEM_HD inline Real shear_rate(const SymTensor& e) {
  return std::sqrt(Real(2) * double_dot(e));
}

struct HbpParams {
  Real k = 0;         // consistency K, Pa s^n
  Real n = 1;         // flow index
  Real m = 0;         // Papanastasiou exponent, s
  Real cohesion = 0;  // c, Pa
  Real tan_phi = 0;   // tan of the friction angle
  Real mu_max = 0;    // cap on mu_eff, Pa s
  bool yield = true;  // false removes the yield term (used by a test to show it matters)
};

// Mohr-Coulomb yield stress, Eq. (12), with p clamped at 0.
SPHDEM_HD inline Real yield_stress(const HbpParams& q, Real p) {
  return q.cohesion + (p > Real(0) ? p : Real(0)) * q.tan_phi;
}

// Effective dynamic viscosity, Eqs. (11) and (15), capped at mu_max.
SPHDEM_HD inline Real hbp_viscosity(const HbpParams& q, Real shear, Real tau_y) {
  Real mu = 0;
  // Power-law part: K g^(n-1); for n < 1 it diverges at g -> 0 and the cap takes over.
  if (q.n == Real(1)) {
    mu = q.k;
  } else if (shear > Real(0)) {
    mu = q.k * std::pow(shear, q.n - Real(1));
  } else {
    mu = q.n < Real(1) ? q.mu_max : Real(0);
  }
  if (q.yield && tau_y > Real(0)) {
    const Real x = q.m * shear;
    // (1 - exp(-m g)) / g = m (-expm1(-x) / x), -> m as x -> 0.
    const Real frac = x > Real(1e-8) ? -std::expm1(-x) / x : Real(1) - Real(0.5) * x;
    mu += tau_y * q.m * frac;
  }
  return mu < q.mu_max ? mu : q.mu_max;
}

// Dalrymple & Rogers SPS stress tau/rho for strain rate S and filter width dl.
SPHDEM_HD inline SymTensor sps_stress_over_rho(const SymTensor& S, Real cs, Real ci, Real dl) {
  const Real s_mag = std::sqrt(Real(2) * double_dot(S));
  const Real nu_t = (cs * dl) * (cs * dl) * s_mag;
  const Real tr3 = (S.d.x + S.d.y + S.d.z) / Real(3);
  const Real iso = Real(2) / Real(3) * ci * dl * dl * s_mag * s_mag;
  SymTensor t;
  t.d = Vec3(Real(2) * nu_t * (S.d.x - tr3) - iso, Real(2) * nu_t * (S.d.y - tr3) - iso,
             Real(2) * nu_t * (S.d.z - tr3) - iso);
  t.o = S.o * (Real(2) * nu_t);
  return t;
}

// T . r for a symmetric tensor.
SPHDEM_HD inline Vec3 sym_apply(const SymTensor& t, const Vec3& r) {
  return Vec3(t.d.x * r.x + t.o.x * r.y + t.o.y * r.z, t.o.x * r.x + t.d.y * r.y + t.o.z * r.z,
              t.o.y * r.x + t.o.z * r.y + t.d.z * r.z);
}

// SPS momentum term, seed Eq. (9) third term with tau/rho stored per particle:
//   m_j (tau_i/rho_i^2 + tau_j/rho_j^2) . grad_i W_ij = m_j ((tau/rho)_i/rho_i + (tau/rho)_j/rho_j)
//   . r_ij F
SPHDEM_HD inline Vec3 sps_acc_ij(Real m_j, const SymTensor& tr_i, Real rho_i, const SymTensor& tr_j,
                                 Real rho_j, const Vec3& r_ij, Real f) {
  const Vec3 a = sym_apply(tr_i, r_ij) / rho_i + sym_apply(tr_j, r_ij) / rho_j;
  return a * (m_j * f);
}

}  // namespace sphdem
