// HBP effective viscosity (seed Eqs. 11-15) and the SPS stress (Dalrymple & Rogers) against
// hand-computed values and limits.
#include <gtest/gtest.h>

#include <cmath>

#include "precision.hpp"
#include "sph/rheology.hpp"

namespace sphdem {
namespace {

using test::kFloatEps;
using test::tol;

HbpParams bingham(Real k, Real tau0, Real m) {
  HbpParams q;
  q.k = k;
  q.n = 1;
  q.m = m;
  q.cohesion = tau0;
  q.mu_max = 1e9;
  return q;
}

TEST(Rheology, PapanastasiouBinghamValues) {
  const HbpParams q = bingham(0.1, 2.0, 50);
  for (Real g : {0.01, 0.3, 2.0, 40.0}) {
    const Real expected = 0.1 + 2.0 * (1 - std::exp(-50 * g)) / g;
    // Float: K + tau m (-expm1(-m g)) / (m g) and the expected value each take ~6 roundings
    // (x = m g, exp, quotient, products, sum): <= ~8 eps relative between them.
    EXPECT_NEAR(hbp_viscosity(q, g, yield_stress(q, 0)), expected,
                tol(1e-12, 8 * kFloatEps) * expected)
        << g;
  }
  // Shear stress mu g approaches tau0 + K g once m g >> 1 (the Bingham law).
  const Real g = 5.0;
  EXPECT_NEAR(hbp_viscosity(q, g, 2.0) * g, 2.0 + 0.1 * g, 1e-9);
}

TEST(Rheology, ZeroShearLimitIsFinite) {
  // Eq. (15): (1 - exp(-m g))/g -> m, so mu -> K + m tau_y with no division by zero.
  const HbpParams q = bingham(0.1, 2.0, 50);
  EXPECT_REAL_EQ(hbp_viscosity(q, 0, 2.0), 0.1 + 50 * 2.0);
  // Float: K + m tau (frac = 1 - x/2 = 1 at x = 5e-11) takes 3 roundings of ~100 (u 100 each,
  // u = eps/2) and K = 0.1 one: 4 eps of 100.1 covers them.
  EXPECT_NEAR(hbp_viscosity(q, 1e-12, 2.0), 0.1 + 50 * 2.0, tol(1e-6, 4 * kFloatEps * 100.1));
  EXPECT_TRUE(std::isfinite(hbp_viscosity(q, 1e-300, 2.0)));
}

TEST(Rheology, CapAndPowerLaw) {
  HbpParams q = bingham(0.2, 1.0, 1000);
  q.mu_max = 7;
  EXPECT_DOUBLE_EQ(hbp_viscosity(q, 1e-6, 1.0), 7);
  q.n = 0.5;
  q.cohesion = 0;
  q.mu_max = 1e9;
  // Float: K g^(n - 1): K = 0.2 rounded, pow (<= 1 ulp) and the product: <= 2 eps of 0.1.
  EXPECT_NEAR(hbp_viscosity(q, 4.0, 0), 0.2 * std::pow(4.0, -0.5), tol(1e-12, 2 * kFloatEps * 0.1));
  q.mu_max = 3;
  EXPECT_DOUBLE_EQ(hbp_viscosity(q, 0, 0), 3);  // n < 1 diverges at g = 0: the cap holds
}

TEST(Rheology, YieldTermCanBeRemoved) {
  HbpParams q = bingham(0.1, 2.0, 50);
  q.yield = false;
  EXPECT_DOUBLE_EQ(hbp_viscosity(q, 0.5, 2.0), Real(0.1));  // K alone, as given
}

TEST(Rheology, MohrCoulombYieldClampsPressure) {
  HbpParams q;
  q.cohesion = 10;
  q.tan_phi = std::tan(30 * kPi / 180);
  EXPECT_NEAR(yield_stress(q, 1000), 10 + 1000 * std::tan(30 * kPi / 180), 1e-9);
  EXPECT_DOUBLE_EQ(yield_stress(q, -500), 10);  // tension does not lower the yield stress
}

TEST(Rheology, ShearRateOfSimpleShear) {
  // u = a z: G[0][2] = a; the standard shear rate sqrt(2 eps:eps) is |a|.
  Mat3g G;
  G.g[0][2] = 3.0;
  EXPECT_NEAR(shear_rate(strain_rate(G)), 3.0, 1e-14);
}

TEST(Rheology, SpsStressOfSimpleShear) {
  Mat3g G;
  G.g[0][2] = 2.0;  // S_xz = 1
  const SymTensor S = strain_rate(G);
  const Real dl = 0.01, cs = 0.12, ci = 0.0066;
  const SymTensor t = sps_stress_over_rho(S, cs, ci, dl);
  const Real smag = std::sqrt(2 * 2 * 1.0);  // sqrt(2 S:S), S:S = 2 S_xz^2
  const Real nut = cs * dl * cs * dl * smag;
  EXPECT_NEAR(t.o.y, 2 * nut * 1.0, 1e-15);  // xz component
  // Float: (2/3) C_I dl^2 |S|^2 takes ~6 roundings in the library (and |S|^2 two more): <= 4 eps
  // of the value.
  const double iso = -2.0 / 3 * ci * dl * dl * smag * smag;
  EXPECT_NEAR(t.d.x, iso, tol(1e-15, 4 * kFloatEps * std::abs(iso)));
  EXPECT_NEAR(t.o.x, 0, 1e-18);
}

}  // namespace
}  // namespace sphdem
