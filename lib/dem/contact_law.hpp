// DEM contact laws (seed §2.2, Eqs. 18-20; DESIGN.md §1 "Grains").
//
// All functions are SPHDEM_HD functions of plain values, shared by the CPU and CUDA backends.
// Sign conventions used throughout:
//   n      unit normal of the contact, pointing from the slave body (or wall) towards the master
//          body: the normal force on the master is +F_n n.
//   d      overlap (penetration depth) >= 0; for a level-set node d = -phi_slave(node).
//   v_rel  velocity of the master's material point minus the slave's, at the contact point.
//   v_n    = dot(v_rel, n): negative while the bodies approach, so d' = -v_n.
//
// ---- Linear spring-dashpot (seed Eq. 19 plus normal damping) ------------------------------------
//   F_n = k_n d + c_n d' = k_n d - c_n v_n                                             (Eq. 19)
// The paper lists a restitution coefficient e but never says how it enters. Here it sets the
// dashpot of the linear spring-dashpot oscillator m* d'' + c_n d' + k_n d = 0
// (validation FORMULAS.md §7):
//   zeta = -ln e / sqrt(pi^2 + ln^2 e),  c_n = 2 zeta sqrt(m* k_n),
//   t_c  = pi / (omega_0 sqrt(1 - zeta^2)),  omega_0 = sqrt(k_n / m*).
// For a level-set node m* is the mass the node sees (m_point, rotation included; see
// at_point_mass below): a node at a lever arm r from the centroid of a grain of radius of gyration
// k moves like a mass m / (1 + (r x n)^2 / k^2), up to 8x lighter than m at a pyramid's tip. A
// dashpot sized with the centroid mass then overdamps that point and the explicit step makes it
// unstable: a settled pile of 120 pyramids kept KE ~ 1e-5 J at dt = t_c/50, and came to rest
// (1e-22 J) only at t_c/100 (docs/VALIDATION.md, "Rock collapse").
// The contact ends when the OVERLAP returns to zero; the small tensile dashpot force at the end is
// kept (no clamp), so the restitution coefficient comes out exactly e (clamping F_n >= 0 would give
// a larger e, FORMULAS.md §7).
//
// ---- Time step (replaces the seed's Eq. 26, which is dimensionally wrong) ---------------------
//   t_c = pi sqrt(m* / k_n),  dt_DEM = t_c / 50.
//
// ---- Normal stiffness from Young's modulus and Poisson's ratio
// ----------------------------------- The paper's tables give E and nu but the linear law of Eq. 19
// needs a stiffness k_n [N/m]. We use the secant stiffness of the Hertz contact of two spheres of
// the grains' equivalent radius at a reference overlap delta_ref = eps R* (eps = 1e-2 by default,
// i.e. 1 % of R*):
//   E*  = [(1 - nu1^2)/E1 + (1 - nu2^2)/E2]^-1      (a rigid wall: second term 0)
//   R*  = (1/R1 + 1/R2)^-1
//   k_n = F_Hertz(delta_ref) / delta_ref = (4/3) E* sqrt(R* delta_ref) = (4/3) E* R* sqrt(eps).
// For Table 2 (E = 6e8 Pa, nu = 0.3, d_eq = 16 mm): E* = 3.30e8 Pa, R* = 4 mm, k_n = 1.76e5 N/m.
// In the level-set contact this k_n acts on every penetrating node (Eq. 19), so a face-to-face
// contact with M nodes is M times stiffer than a vertex contact, as in LS-DEM (Kawamoto 2016).
// The tangential stiffness follows the Mindlin ratio k_t / k_n = 2 (1 - nu) / (2 - nu) (equal
// materials).
//
// ---- Tangential spring with history, capped by Coulomb friction (seed Eq. 20) -----------------
//   s   <- s - (s.n) n, rescaled to its old length      (follow the rotating contact plane)
//   s   <- s + v_t dt                                   (v_t: tangential part of v_rel)
//   F_t  = -k_t s;  if |F_t| > mu F_n+:  F_t <- mu F_n+ F_t/|F_t|,  s <- -F_t / k_t   (Eq. 20)
// The capped spring is rescaled so the stored displacement matches the force at the cap.
// F_n+ = max(F_n, 0): the seed writes mu |F_n|, but the normal force is tensile only in the
// dashpot's pull at the end of a damped contact (kept for the restitution, above), and friction
// fed by that pull adds tangential impulse that no Coulomb contact has. Chung & Ooi tests 6 and 8
// (e = 0.5, gross sliding) caught it: with |F_n| the spin-driven impacts took 6-7 % more
// tangential impulse than mu (1 + e) m Vcn, the rigid-body value the reference curves follow.
//
// ---- Hertz normal law for sphere pairs (Hertz 1882; Chung & Ooi 2011 tests 1-3) -----------------
//   F_n = max(0, (4/3) E* sqrt(R*) d^{3/2} + c_H d^{1/4} d'),
//   c_H = alpha(e) sqrt(m* (4/3) E* sqrt(R*)).
// With a damping force proportional to d^{1/4} d' (Tsuji et al. 1992) the restitution
// coefficient does not depend on the impact speed. Unlike the linear law the Hertz force is
// clamped at zero (never attractive). alpha(e) is found by solving the dimensionless oscillator
// x'' = -max(0, alpha x^{1/4} x' + x^{3/2}) (hertz_damping_alpha in contact_law.cpp), so the
// restitution coefficient comes out exactly e; e = 1 gives alpha = 0 (elastic Hertz).
// Tangential (Mindlin 1949, no-slip form used by Chung & Ooi and Yade/EDEM "Hertz-Mindlin"):
//   k_t = 8 G* sqrt(R* d),  G* = [(2 - nu1)/G1 + (2 - nu2)/G2]^-1,  G = E / (2 (1 + nu)),
// with the same spring history and Coulomb cap as Eq. 20.
#pragma once

#include <cmath>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem::dem {

// ---- effective properties -------------------------------------------------------------------

// m* = m1 m2 / (m1 + m2); a non-positive or infinite m2 (a wall, a fixed body) gives m1.
SPHDEM_HD inline Real effective_mass(Real m1, Real m2) {
  if (!(m2 > Real(0)) || std::isinf(m2)) return m1;
  if (!(m1 > Real(0)) || std::isinf(m1)) return m2;
  return m1 * m2 / (m1 + m2);
}

// R* = (1/R1 + 1/R2)^-1; R2 <= 0 means a plane (R* = R1).
SPHDEM_HD inline Real effective_radius(Real r1, Real r2) {
  if (!(r2 > Real(0))) return r1;
  return r1 * r2 / (r1 + r2);
}

// E* = [(1 - nu1^2)/E1 + (1 - nu2^2)/E2]^-1; E2 <= 0 means a rigid wall.
SPHDEM_HD inline Real effective_young(Real e1, Real nu1, Real e2, Real nu2) {
  Real s = (Real(1) - nu1 * nu1) / e1;
  if (e2 > Real(0)) s += (Real(1) - nu2 * nu2) / e2;
  return Real(1) / s;
}

// G* = [(2 - nu1)/G1 + (2 - nu2)/G2]^-1 with G = E / (2 (1 + nu)); E2 <= 0 means a rigid wall.
SPHDEM_HD inline Real effective_shear(Real e1, Real nu1, Real e2, Real nu2) {
  Real s = (Real(2) - nu1) * Real(2) * (Real(1) + nu1) / e1;
  if (e2 > Real(0)) s += (Real(2) - nu2) * Real(2) * (Real(1) + nu2) / e2;
  return Real(1) / s;
}

// Linear normal stiffness from elastic constants: the Hertz secant stiffness at the reference
// overlap eps R*, k_n = (4/3) E* R* sqrt(eps) (see the header comment).
SPHDEM_HD inline Real linear_stiffness_from_young(Real e_star, Real r_star, Real eps) {
  return Real(4) / Real(3) * e_star * r_star * std::sqrt(eps);
}

// ---- linear spring-dashpot (Eq. 19 + damping, FORMULAS.md §7) ------------------------------

// Damping ratio zeta of the linear oscillator that rebounds with restitution e in (0, 1]:
// zeta = -ln e / sqrt(pi^2 + ln^2 e). e <= 0 gives critical damping (zeta = 1).
SPHDEM_HD inline Real damping_ratio_from_restitution(Real e) {
  if (!(e > Real(0))) return Real(1);
  if (e >= Real(1)) return Real(0);
  const Real l = std::log(e);
  return -l / std::sqrt(kPi * kPi + l * l);
}

// Dashpot coefficient c_n = 2 zeta sqrt(m* k_n), from the damping ratio (a system works it out
// once per contact model: the logarithm cost more than the rest of a sphere contact's law).
SPHDEM_HD inline Real linear_damping_zeta(Real zeta, Real m_eff, Real kn) {
  return Real(2) * zeta * std::sqrt(m_eff * kn);
}
// The same from the restitution coefficient.
SPHDEM_HD inline Real linear_damping(Real e, Real m_eff, Real kn) {
  return linear_damping_zeta(damping_ratio_from_restitution(e), m_eff, kn);
}

// Undamped contact time t_c = pi sqrt(m*/k_n).
SPHDEM_HD inline Real contact_time(Real m_eff, Real kn) {
  return kPi * std::sqrt(m_eff / kn);
}

// The DEM time step dt_DEM = t_c / 50 (replaces the seed's Eq. 26).
SPHDEM_HD inline Real dem_time_step(Real m_eff, Real kn) {
  return contact_time(m_eff, kn) / Real(50);
}

// Normal force magnitude of Eq. 19 with damping: k_n d - c_n v_n (v_n < 0 when approaching).
// Not clamped: the dashpot may pull slightly at the end of the contact (see header).
SPHDEM_HD inline Real linear_normal_force(Real kn, Real cn, Real d, Real vn) {
  return kn * d - cn * vn;
}

// ---- Hertz (sphere pairs) -----------------------------------------------------------------

// Hertz stiffness constant K = (4/3) E* sqrt(R*), so F = K d^{3/2}.
SPHDEM_HD inline Real hertz_constant(Real e_star, Real r_star) {
  return Real(4) / Real(3) * e_star * std::sqrt(r_star);
}

// Normal force magnitude max(0, K d^{3/2} - c_H d^{1/4} v_n) with c_H = alpha sqrt(m* K)
// (alpha = 0: elastic). Never attractive: at the end of a damped rebound the dashpot would pull,
// and friction would have nothing to act on; alpha (hertz_damping_alpha) is solved with the same
// clamp, so the restitution coefficient is still exactly e. In gross sliding the tangential
// impulse is then mu times the normal impulse, the rigid-body value of Chung & Ooi tests 4-6 and 8.
SPHDEM_HD inline Real hertz_normal_force(Real k_hertz, Real alpha, Real m_eff, Real d, Real vn) {
  if (!(d > Real(0))) return Real(0);
  const Real sd = std::sqrt(d);
  const Real elastic = k_hertz * d * sd;
  if (alpha == Real(0)) return elastic;
  const Real f = elastic - alpha * std::sqrt(m_eff * k_hertz) * std::sqrt(sd) * vn;
  return f > Real(0) ? f : Real(0);
}

// Tangential (Mindlin) stiffness k_t = 8 G* sqrt(R* d).
SPHDEM_HD inline Real mindlin_stiffness(Real g_star, Real r_star, Real d) {
  return d > Real(0) ? Real(8) * g_star * std::sqrt(r_star * d) : Real(0);
}

// Hertz maximum overlap, peak force and contact time of an elastic impact at approach speed v
// (FORMULAS.md §8); used by tests and for the time step of Hertz contacts.
SPHDEM_HD inline Real hertz_max_overlap(Real e_star, Real r_star, Real m_eff, Real v) {
  return std::pow(Real(15) * m_eff * v * v / (Real(16) * e_star * std::sqrt(r_star)), Real(0.4));
}
SPHDEM_HD inline Real hertz_contact_time(Real e_star, Real r_star, Real m_eff, Real v) {
  return Real(2.9432) * hertz_max_overlap(e_star, r_star, m_eff, v) / v;
}

// ---- tangential spring with history (Eq. 20) -------------------------------------------------

// Advances the tangential spring s (a displacement, stored between steps) of one contact by dt
// and returns the tangential force on the master body.
//   n: contact normal (unit), v_rel: relative velocity at the contact point, kt: tangential
//   stiffness, ct: tangential dashpot (0 for none; it acts only while sticking),
//   mu: friction coefficient, fn: normal force magnitude.
// The spring is first projected onto the current tangent plane keeping its length, then
// incremented by v_t dt. If the trial force exceeds mu max(F_n, 0), the force is capped and s is
// rescaled to -F_t/k_t so the stored displacement matches the cap (Eq. 20).
SPHDEM_HD inline Vec3 tangential_force(Vec3& s, const Vec3& n, const Vec3& v_rel, Real dt, Real kt,
                                       Real ct, Real mu, Real fn) {
  // Rotate the stored spring onto the current tangent plane.
  const Real s_len = norm(s);
  Vec3 sp = s - dot(s, n) * n;
  const Real sp_len = norm(sp);
  s = sp_len > Real(0) ? sp * (s_len / sp_len) : Vec3(0, 0, 0);
  const Vec3 vt = v_rel - dot(v_rel, n) * n;
  s += vt * dt;
  if (!(kt > Real(0))) {
    s = Vec3(0, 0, 0);
    return Vec3(0, 0, 0);
  }
  Vec3 ft = -kt * s - ct * vt;
  const Real ft_len = norm(ft);
  const Real cap = fn > Real(0) ? mu * fn : Real(0);  // no friction from a tensile dashpot
  if (ft_len > cap) {
    // Sliding (Eq. 20): force of magnitude mu F_n+ along the trial force; the dashpot is
    // dropped and the spring holds exactly the capped force.
    ft = ft_len > Real(0) ? ft * (cap / ft_len) : Vec3(0, 0, 0);
    s = -ft / kt;
  }
  return ft;
}

// ---- one contact: normal law + tangential spring --------------------------------------------

enum class NormalLaw : int { kLinear = 0, kHertz = 1 };

// Everything one contact needs, resolved for the pair of bodies (see DemSystem).
struct PairLaw {
  NormalLaw law = NormalLaw::kLinear;
  Real kn = 0, cn = 0;              // linear: stiffness per node and dashpot (Eq. 19 + damping)
  Real kt = 0, ct = 0;              // linear: tangential stiffness and dashpot (ct = 0: none)
  Real mu = 0;                      // Coulomb friction coefficient (Eq. 20)
  Real k_hertz = 0;                 // Hertz: (4/3) E* sqrt(R*)
  Real alpha = 0;                   // Hertz: damping constant (0: elastic)
  Real g_star = 0, r_star = 0;      // Hertz-Mindlin tangential stiffness 8 G* sqrt(R* d)
  Real m_eff = 0;                   // effective mass m* of the pair
  bool tangential_damping = false;  // Hertz: tangential dashpot alpha sqrt(m* k_t)
};

// The law of one contact point whose effective mass (rotation included) is m_point, e.g.
// 1 / (inverse_point_mass(a) + inverse_point_mass(b)): the dashpots scale as sqrt(m*), so the
// point rebounds with the restitution coefficient e whatever its lever arm. m_point <= 0 or
// infinite keeps the law.
SPHDEM_HD inline PairLaw at_point_mass(PairLaw p, Real m_point) {
  if (!(m_point > Real(0)) || std::isinf(m_point) || !(p.m_eff > Real(0))) return p;
  const Real scale = std::sqrt(m_point / p.m_eff);
  p.cn *= scale;
  p.ct *= scale;
  p.m_eff = m_point;
  return p;
}

// Force on the master body of one contact of overlap d > 0, normal n (slave -> master) and relative
// velocity v_rel; advances the tangential spring s by dt. Writes the normal force magnitude.
SPHDEM_HD inline Vec3 contact_force(const PairLaw& p, Real d, const Vec3& n, const Vec3& v_rel,
                                    Real dt, Vec3& s, Real* fn_out) {
  const Real vn = dot(v_rel, n);
  Real fn, kt, ct;
  if (p.law == NormalLaw::kHertz) {
    fn = hertz_normal_force(p.k_hertz, p.alpha, p.m_eff, d, vn);
    kt = mindlin_stiffness(p.g_star, p.r_star, d);
    ct = p.tangential_damping ? p.alpha * std::sqrt(p.m_eff * kt) : Real(0);
  } else {
    fn = linear_normal_force(p.kn, p.cn, d, vn);
    kt = p.kt;
    ct = p.ct;
  }
  const Vec3 ft = tangential_force(s, n, v_rel, dt, kt, ct, p.mu, fn);
  if (fn_out) *fn_out = fn;
  return fn * n + ft;
}

// ---- host helpers (contact_law.cpp) ---------------------------------------------------------

// Restitution coefficient of the dimensionless damped Hertz oscillator
// x'' = -max(0, alpha x^{1/4} x' + x^{3/2}), x(0) = 0, x'(0) = 1: e = -x'(t_end) where
// x(t_end) = 0 (0 if the overlap never returns to zero). Integrated with RK4.
Real hertz_restitution(Real alpha);

// The inverse: alpha such that hertz_restitution(alpha) = e (bisection), e in (0, 1]; e >= 1
// gives 0. Throws sphdem::InputError for e <= 0.
Real hertz_damping_alpha(Real e);

}  // namespace sphdem::dem
