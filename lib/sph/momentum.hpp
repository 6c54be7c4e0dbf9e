// Momentum equation terms, seed Eq. (9). grad_i W_ij = r_ij F with F = (dW/dr)/r.
#pragma once

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

// Symmetric pressure term: -m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij (Monaghan 1992).
SPHDEM_HD inline Vec3 pressure_acc_ij(Real m_j, Real p_i, Real rho_i, Real p_j, Real rho_j,
                                      const Vec3& r_ij, Real f) {
  const Real s = -m_j * (p_i / (rho_i * rho_i) + p_j / (rho_j * rho_j)) * f;
  return r_ij * s;
}

// Laminar viscosity, Lo & Shao (2002), seed Eq. (9) second term:
//   m_j 4 nu_ij (r_ij . grad_i W_ij) / ((rho_i + rho_j)(r^2 + eta^2)) v_ij
// nu_ij is a KINEMATIC viscosity (m^2/s). For a variable dynamic viscosity mu (Pa s) pass
// nu_ij = (mu_i + mu_j) / (rho_i + rho_j). eta^2 = 0.01 h^2 keeps r -> 0 finite.
SPHDEM_HD inline Vec3 laminar_acc_ij(Real m_j, Real nu_ij, Real rho_i, Real rho_j, Real r2, Real f,
                                     Real eta2, const Vec3& v_ij) {
  const Real s = m_j * Real(4) * nu_ij * (r2 * f) / ((rho_i + rho_j) * (r2 + eta2));
  return v_ij * s;
}

// Artificial viscosity, Monaghan (1992): -m_j Pi_ij grad_i W_ij with
//   Pi_ij = -alpha c_mean mu_ij / rho_mean,  mu_ij = h v_ij.r_ij / (r^2 + eta^2), for v_ij.r_ij <
//   0.
SPHDEM_HD inline Vec3 artificial_acc_ij(Real m_j, Real alpha, Real c_mean, Real h, Real rho_i,
                                        Real rho_j, const Vec3& r_ij, Real r2, Real f, Real eta2,
                                        const Vec3& v_ij) {
  const Real vr = dot(v_ij, r_ij);
  if (vr >= Real(0)) return Vec3();
  const Real mu = h * vr / (r2 + eta2);
  const Real pi_ij = -alpha * c_mean * mu / (Real(0.5) * (rho_i + rho_j));
  return r_ij * (-m_j * pi_ij * f);
}

// The pair rate that limits the acoustic-viscous time step (Eq. 25 as in DualSPHysics; the seed
// prints it without h, which is not dimensionally a speed): |h v_ij . r_ij / (r^2 + eta^2)|.
SPHDEM_HD inline Real visc_dt_rate_ij(Real h, const Vec3& v_ij, const Vec3& r_ij, Real r2,
                                      Real eta2) {
  const Real m = h * dot(v_ij, r_ij) / (r2 + eta2);
  return m < 0 ? -m : m;
}

}  // namespace sphdem
