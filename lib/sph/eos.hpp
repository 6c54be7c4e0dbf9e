// Tait equation of state, seed Eq. (6): p = B [(rho/rho0)^gamma - 1], B = rho0 c0^2 / gamma.
#pragma once

#include <cmath>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

struct EosParams {
  Real rho0 = 1000;
  Real c0 = 10;
  Real gamma = 7;
  Real b = 0;  // rho0 c0^2 / gamma
  // Lowest pressure the fluid carries (Pa, gauge). A liquid cannot hold much tension: a free
  // surface flow thinning to a film of one or two particles otherwise reaches large negative
  // pressures and clumps (tensile instability). Default: no limit.
  Real p_min = Real(-1e30);
  // The density at p_min (0 without a floor). A fluid particle's density is kept at or above it:
  // below, the pressure no longer resists expansion, and a spreading film's density would drift
  // without bound (to the density guard) while carrying no force.
  Real rho_floor = 0;
  // (1 + x)^(1/gamma) - 1 = sum_k series[k-1] x^k for k = 1..kSeriesTerms, the binomial series,
  // which the Fourtakas diffusion sums instead of a pow per pair (sph/continuity.hpp). For
  // |x| < kSeriesRange the first omitted term is below 1e-16 of the sum (gamma >= 1).
  static constexpr int kSeriesTerms = 9;
  static constexpr double kSeriesRange = 0.02;
  Real series[kSeriesTerms] = {};
  Real inv_b = 0;  // 1 / b
  // gamma as an integer when it is one (1..16; the usual 7), else 0: the pressure of every
  // particle at every step is then a few multiplications instead of a pow (3% of a flume step).
  int gamma_int = 0;
};

// x^n for n >= 0 by repeated squaring (n = 7: four multiplications).
SPHDEM_HD inline Real int_pow(Real x, int n) {
  Real r = 1;
  while (n > 0) {
    if (n & 1) r *= x;
    x *= x;
    n >>= 1;
  }
  return r;
}

inline EosParams make_eos(Real rho0, Real c0, Real gamma, Real p_min = Real(-1e30)) {
  EosParams e;
  e.rho0 = rho0;
  e.c0 = c0;
  e.gamma = gamma;
  e.b = rho0 * c0 * c0 / gamma;
  e.p_min = p_min;
  e.inv_b = Real(1) / e.b;
  if (gamma >= 1 && gamma <= 16 && gamma == std::floor(gamma)) e.gamma_int = int(gamma);
  if (p_min > -e.b) e.rho_floor = rho0 * std::pow(Real(1) + p_min / e.b, Real(1) / gamma);
  // binom(a, k) = binom(a, k - 1) (a - k + 1) / k with a = 1/gamma.
  const double a = 1.0 / double(gamma);
  double c = 1;
  for (int k = 1; k <= EosParams::kSeriesTerms; ++k) {
    c *= (a - (k - 1)) / k;
    e.series[k - 1] = Real(c);
  }
  return e;
}

SPHDEM_HD inline Real floor_density(const EosParams& e, Real rho) {
  return rho < e.rho_floor ? e.rho_floor : rho;
}

SPHDEM_HD inline Real tait_pressure(const EosParams& e, Real rho) {
  const Real x = rho / e.rho0;
  const Real p = e.b * ((e.gamma_int ? int_pow(x, e.gamma_int) : std::pow(x, e.gamma)) - Real(1));
  return p < e.p_min ? e.p_min : p;
}

// Inverse: the density that gives pressure p.
SPHDEM_HD inline Real tait_density(const EosParams& e, Real p) {
  return e.rho0 * std::pow(Real(1) + p / e.b, Real(1) / e.gamma);
}

// Speed of sound at density rho: c = c0 (rho/rho0)^((gamma-1)/2).
SPHDEM_HD inline Real tait_sound_speed(const EosParams& e, Real rho) {
  return e.c0 * std::pow(rho / e.rho0, (e.gamma - Real(1)) * Real(0.5));
}

}  // namespace sphdem
