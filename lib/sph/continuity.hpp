// Continuity with density diffusion, seed Eqs. (7)-(8).
//
//   drho_i/dt = sum_j m_j (v_i - v_j) . grad_i W_ij  +  Phi_i
//
// Density diffusion (delta-SPH), Molteni & Colagrossi (2009):
//   Phi_i = 2 delta h c0 sum_j (rho_j - rho_i) (r_ji . grad_i W_ij) / |r_ij|^2 * m_j / rho_j
// Note the sign: the seed prints r_ij with r_ij = r_i - r_j, which would make the term
// anti-diffusive; with r_ji = r_j - r_i a denser neighbour raises rho_i, as diffusion must.
// Since grad_i W_ij = r_ij F(r), r_ji . grad_i W_ij = -r^2 F and the pair term is
//   -2 delta h c0 (rho_j - rho_i) F m_j / rho_j.
//
// Fourtakas et al. (2019) hydrostatic correction: replace (rho_j - rho_i) by
// (rho_j - rho_i) - (rho_j^H - rho_i^H), with the hydrostatic density difference
//   rho_j^H - rho_i^H = rho0 [(1 + rho0 g z_ij / B)^(1/gamma) - 1],  z_ij = height of i above j,
// so a still, hydrostatically stratified column is not diffused toward uniform density.
#pragma once

#include "core/hd.hpp"
#include "core/types.hpp"
#include "sph/eos.hpp"

namespace sphdem {

// m_j (v_i - v_j) . grad_i W_ij.
SPHDEM_HD inline Real continuity_ij(Real m_j, const Vec3& v_ij, const Vec3& r_ij, Real f) {
  return m_j * dot(v_ij, r_ij) * f;
}

// The density difference the diffusion acts on: rho_j - rho_i, minus its hydrostatic part when
// `hydrostatic` is set. height_ij = (r_i - r_j) . (-g_hat), the height of i above j.
SPHDEM_HD inline Real diffusion_drho_ij(const EosParams& e, Real rho_i, Real rho_j,
                                        bool hydrostatic, Real g_mag, Real height_ij) {
  Real d = rho_j - rho_i;
  if (hydrostatic) {
    // (1 + x)^(1/gamma) - 1 with x = rho0 g z_ij / B. Within a kernel support |x| is ~1e-4 to
    // 1e-2, where the binomial series (EosParams::series, Horner) is exact to round-off and
    // avoids a pow per pair.
    const Real x = e.rho0 * g_mag * height_ij * e.inv_b;
    Real frac;
    if (x > Real(-EosParams::kSeriesRange) && x < Real(EosParams::kSeriesRange)) {
      frac = e.series[EosParams::kSeriesTerms - 1];
      for (int k = EosParams::kSeriesTerms - 2; k >= 0; --k) frac = e.series[k] + x * frac;
      frac *= x;
    } else {
      const Real base = Real(1) + x;
      frac = std::pow(base > Real(0) ? base : Real(0), Real(1) / e.gamma) - Real(1);
    }
    d -= e.rho0 * frac;
  }
  return d;
}

// Phi_i pair term: -2 delta h c0 drho_ij F m_j / rho_j (F = (dW/dr)/r < 0).
SPHDEM_HD inline Real diffusion_ij(Real delta_h_c0, Real drho_ij, Real f, Real m_j, Real rho_j) {
  return Real(-2) * delta_h_c0 * drho_ij * f * m_j / rho_j;
}

}  // namespace sphdem
