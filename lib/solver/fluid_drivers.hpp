// Fluid-step drivers, written once and templated on the execution space (DESIGN.md §3).
// Each is a gather loop: particle i writes only its own slots. Physics comes from lib/sph/.
#pragma once

#include "core/exec.hpp"
#include "neighbor/cell_grid.hpp"
#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"
#include "sph/continuity.hpp"
#include "sph/eos.hpp"
#include "sph/kernel.hpp"
#include "sph/mdbc.hpp"
#include "sph/momentum.hpp"
#include "sph/rheology.hpp"

namespace sphdem {

// The cell lists a driver needs: owned fluid, halo fluid (copies of other ranks' particles; empty
// on one rank), fixed walls, and grain boundary particles (sorted on their own each step, so the
// walls keep their slots while grains move).
struct NeighborLists {
  CellListView fluid;
  CellListView boundary;
  CellListView halo;
  bool has_halo = false;
  CellListView grain;
  bool has_grain = false;
};

// Calls f(j, r_ij, r2) for every boundary neighbour of x, walls then grains.
template <class F>
SPHDEM_HD inline void for_each_boundary_neighbor(const StepParams& p, const NeighborLists& nl,
                                                 const Vec3* pos, const Vec3& x, F&& f) {
  for_each_neighbor(p.grid, nl.boundary, pos, x, p.radius2, f);
  if (nl.has_grain) for_each_neighbor(p.grid, nl.grain, pos, x, p.radius2, f);
}

// Calls f(j, r_ij, r2) for every fluid neighbour of x, owned then halo.
template <class F>
SPHDEM_HD inline void for_each_fluid_neighbor(const StepParams& p, const NeighborLists& nl,
                                              const Vec3* pos, const Vec3& x, F&& f) {
  for_each_neighbor(p.grid, nl.fluid, pos, x, p.radius2, f);
  if (nl.has_halo) for_each_neighbor(p.grid, nl.halo, pos, x, p.radius2, f);
}

// p = Tait(rho) for slots [begin, end).
template <class Space>
void compute_pressure(Space s, ParticleView v, Index begin, Index end, EosParams eos) {
  for_each(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        v.press[i] = tait_pressure(eos, v.rho[i]);
      });
}

// The mDBC sums at ghost node rg over the fluid (and halo fluid) within 2h. Flattened: the
// neighbour loop and the accumulation inline into one function, so the sums stay local.
SPHDEM_HD SPHDEM_FLATTEN inline MdbcSums mdbc_gather(const StepParams& p, const NeighborLists& nl,
                                                     const ParticleView& v, const Vec3& rg) {
  MdbcSums sums;
  for_each_fluid_neighbor(p, nl, v.pos, rg, [&](Index j, const Vec3& r_gj, Real r2) {
    Real w, f;
    kernel_wf(p.kernel, std::sqrt(r2), w, f);
    mdbc_accumulate(sums, v.mass[j] / v.rho[j], v.rho[j], v.vel[j], -r_gj, w, f);  // r_j - r_G
  });
  return sums;
}

// The mDBC fit of boundary slot b: the sums at its ghost node, the normal it mirrors through, and
// the extrapolated density before the limiter and the rho0 floor. A thin solid (a barrier wall a
// few dp thick) has fluid on either face: the particle mirrors through the face whose ghost node
// sees more fluid.
struct MdbcFit {
  MdbcSums sums;
  Vec3 normal;
  Real rho = 0;
};
SPHDEM_HD inline MdbcFit mdbc_fit(const StepParams& p, const NeighborLists& nl,
                                  const ParticleView& v, Index b) {
  MdbcFit fit;
  Vec3 rg = v.ghost[b];
  fit.normal = v.normal[b];
  fit.sums = mdbc_gather(p, nl, v, rg);
  const Vec3 alt = v.ghost_alt[b];
  if (!(alt.x == rg.x && alt.y == rg.y && alt.z == rg.z)) {
    const MdbcSums other = mdbc_gather(p, nl, v, alt);
    if (other.shepard > fit.sums.shepard) {
      fit.sums = other;
      rg = alt;
      fit.normal = -fit.normal;
    }
  }
  const Vec3 rb_minus_rg = p.grid.separation(v.pos[b], rg);
  fit.rho =
      mdbc_boundary_density(fit.sums, p.dim, rb_minus_rg, p.eos.rho0, p.mdbc_det_min, p.kernel.h);
  return fit;
}

// mDBC: boundary density from the ghost-node interpolation over fluid, and the boundary velocity
// for the viscous term. Boundary slots [begin, end); v.vel holds the solid's own velocity.
// With `mine` (one flag per slot of the range), slots whose flag is 0 are zeroed instead: another
// rank owns their ghost node, and the ranks' results are summed.
template <class Space>
void update_mdbc(Space s, ParticleView v, NeighborLists nl, StepParams p, Index begin, Index end,
                 const std::uint8_t* mine = nullptr) {
  for_each_uneven(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index b = begin + k;
        if (mine && !mine[k]) {
          v.rho[b] = 0;
          v.press[b] = 0;
          v.vel_bc[b] = Vec3();
          return;
        }
        const MdbcFit fit = mdbc_fit(p, nl, v, b);
        Real rho_b = fit.rho;
        if (p.mdbc_limit) rho_b = mdbc_limit_density(fit.sums, rho_b);
        // Walls push, never pull: a boundary below rho0 would attract the free surface.
        if (rho_b < p.eos.rho0) rho_b = p.eos.rho0;
        v.rho[b] = rho_b;
        v.press[b] = tait_pressure(p.eos, rho_b);
        v.vel_bc[b] = mdbc_boundary_velocity(fit.sums, v.vel[b], fit.normal, p.free_slip);
      });
}

// The fitted density and the limiter's cut (mdbc_limiter_cut) of each boundary slot of
// [begin, end), into fit[k] and cut[k] for slot begin + k: 0 and 0 where `mine` (as in
// update_mdbc) is 0. The walls' state is not changed. Diagnostic only: it repeats the ghost-node
// gathers once.
template <class Space>
void mdbc_limiter_cuts(Space s, ParticleView v, NeighborLists nl, StepParams p, Index begin,
                       Index end, Real* fit, Real* cut, const std::uint8_t* mine = nullptr) {
  for_each_uneven(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        if (mine && !mine[k]) {
          fit[k] = 0;
          cut[k] = 0;
          return;
        }
        const MdbcFit f = mdbc_fit(p, nl, v, begin + k);
        fit[k] = f.rho;
        cut[k] = mdbc_limiter_cut(f.sums, f.rho, p.eos.rho0);
      });
}

// This rank's MdbcLimiterStats (sph/mdbc.hpp) of n boundary slots from `begin`, from
// mdbc_limiter_cuts' fit and cut. Only a clip that changes the wall's pressure counts (a cut
// past round-off, mdbc_cut_is_clip: the rho0 floor hides one below it). Without a clip here the
// x range is (+max, lowest), which the ranks' min and max pass over. cut_at stays NaN:
// mdbc_cut_position finds it once the ranks agree on the largest cut.
template <class Space>
MdbcLimiterStats mdbc_limiter_reduce(Space s, const Vec3* pos, Index begin, Index n,
                                     const Real* fit, const Real* cut, Real rho0) {
  MdbcLimiterStats st;
  st.clipped = reduce<SumOp, double>(
      s, n, SPHDEM_LAMBDA(Index k) { return mdbc_cut_is_clip(cut[k], rho0) ? 1.0 : 0.0; });
  st.rho_fit_max = reduce<MaxOp, Real>(
      s, n, SPHDEM_LAMBDA(Index k) { return fit[k]; });
  st.rho_cut_max = reduce<MaxOp, Real>(
      s, n, SPHDEM_LAMBDA(Index k) { return cut[k]; });
  st.clip_x_lo = reduce<MinOp, Real>(
      s, n, SPHDEM_LAMBDA(Index k) {
        return mdbc_cut_is_clip(cut[k], rho0) ? pos[begin + k].x : MinOp::identity<Real>();
      });
  st.clip_x_hi = reduce<MaxOp, Real>(
      s, n, SPHDEM_LAMBDA(Index k) {
        return mdbc_cut_is_clip(cut[k], rho0) ? pos[begin + k].x : MaxOp::identity<Real>();
      });
  return st;
}

// Where the cut equals cut_max (> 0): the position of the first such slot of this rank, or
// (lowest, lowest, lowest) if this rank has none, so that a maximum over the ranks picks it.
template <class Space>
Vec3 mdbc_cut_position(Space s, const Vec3* pos, Index begin, Index n, const Real* cut,
                       Real cut_max) {
  const Real none = MaxOp::identity<Real>();
  const double first = reduce<MinOp, double>(
      s, n,
      SPHDEM_LAMBDA(Index k) { return cut[k] == cut_max ? double(k) : MinOp::identity<double>(); });
  if (!(cut_max > Real(0)) || first == MinOp::identity<double>()) return Vec3(none, none, none);
  const Index at = Index(first);
  Vec3 r;
  for (int c = 0; c < 3; ++c)
    r[c] = reduce<MaxOp, Real>(
        s, 1, SPHDEM_LAMBDA(Index) { return pos[begin + at][c]; });
  return r;
}

// Velocity gradient of fluid slots [0, n) (fluid and boundary neighbours; a boundary neighbour
// contributes its mDBC velocity), then mu_eff (HBP) and the SPS stress from the strain rate.
template <class Space>
void compute_viscous_state(Space s, ParticleView v, NeighborLists nl, StepParams p, Index n) {
  for_each(
      s, n, SPHDEM_LAMBDA(Index i) {
        const Vec3 ri = v.pos[i], vi = v.vel[i];
        Mat3g G;
        auto add = [&](Index j, const Vec3& r_ij, Real r2, bool fluid) {
          if (r2 <= Real(0)) return;
          const Real f = kernel_f(p.kernel, std::sqrt(r2));
          const Vec3 vj = fluid || !p.mdbc ? v.vel[j] : v.vel_bc[j];
          velocity_gradient_add(G, v.mass[j] / v.rho[j], vj - vi, r_ij, f);
        };
        for_each_fluid_neighbor(
            p, nl, v.pos, ri, [&](Index j, const Vec3& r_ij, Real r2) { add(j, r_ij, r2, true); });
        for_each_boundary_neighbor(
            p, nl, v.pos, ri, [&](Index j, const Vec3& r_ij, Real r2) { add(j, r_ij, r2, false); });
        const SymTensor eps = strain_rate(G);
        if (p.hbp) {
          const Real tau_y = yield_stress(p.hbp_params, v.press[i]);
          v.visc[i] = hbp_viscosity(p.hbp_params, shear_rate(eps), tau_y);
        }
        if (p.sps) {
          const SymTensor t = sps_stress_over_rho(eps, p.sps_cs, p.sps_ci, p.dp);
          v.sps_d[i] = t.d;
          v.sps_o[i] = t.o;
        }
      });
}

// The pair physics, shared by the fluid and boundary gathers and by the pairwise fluid pass
// (solver/pairwise_host.cpp), so it exists once. Every term of the momentum and continuity sums
// is the neighbour's mass times a factor of the pair; the factors are kept per unit mass so one
// evaluation serves both particles of a fluid pair:
//   a_i += m_j acc,  a_j -= m_i acc        (each momentum term is antisymmetric in i, j)
//   drho_i += m_j drho_i,  drho_j += m_i drho_j
// `j_fluid` selects density diffusion (fluid pairs only, as in DualSPHysics) and the velocity
// seen by the viscous term. drho_j is filled only with `both`: the Fourtakas hydrostatic
// difference is not odd in the height, and the penetration control changes the continuity
// velocity on the fluid's side of a fluid-wall pair only, so the j side is evaluated on its own.
struct PairCore {
  Vec3 acc;
  Real drho_i = 0, drho_j = 0;
  Real rate = 0;  // |h v_ij.r_ij/(r^2+eta^2)|, the same from both sides
};

SPHDEM_HD SPHDEM_INLINE PairCore pair_core(const StepParams& p, const ParticleView& v, Index i,
                                           Index j, const Vec3& r_ij, Real r2, bool i_fluid,
                                           bool j_fluid, bool both) {
  PairCore c;
  const Real r = std::sqrt(r2);
  const Real f = kernel_f(p.kernel, r);
  const Real rho_i = v.rho[i], rho_j = v.rho[j];
  // Continuity uses the solid's own velocity for boundary particles.
  const Vec3 v_ij = v.vel[i] - v.vel[j];
  Real p_i = v.press[i], p_j = v.press[j];
  // Both sides of a pair share one continuity term, except where the penetration control gives
  // the fluid's side of a fluid-wall pair its own velocity.
  const Real cont = continuity_ij(Real(1), v_ij, r_ij, f);
  c.drho_i = cont;
  c.drho_j = both ? cont : Real(0);
  if (p.no_penetration && i_fluid != j_fluid) {  // a fluid-wall pair (sph/mdbc.hpp)
    if (i_fluid) {
      c.drho_i = continuity_ij(Real(1), wall_continuity_velocity(v_ij, r_ij, v.normal[j]), r_ij, f);
      p_i = wall_pair_pressure(p_i);
    } else {  // the same pair seen from the wall: its force
      p_j = wall_pair_pressure(p_j);
    }
  }
  if (p.diffusion && i_fluid && j_fluid) {
    const Real height_ij = -dot(r_ij, p.g_hat);
    const Real d =
        diffusion_drho_ij(p.eos, rho_i, rho_j, p.diffusion_hydrostatic, p.g_mag, height_ij);
    c.drho_i += diffusion_ij(p.delta_h_c0, d, f, Real(1), rho_j);
    if (both) {
      const Real d_ji =
          diffusion_drho_ij(p.eos, rho_j, rho_i, p.diffusion_hydrostatic, p.g_mag, -height_ij);
      c.drho_j += diffusion_ij(p.delta_h_c0, d_ji, f, Real(1), rho_i);
    }
  }
  c.acc = pressure_acc_ij(Real(1), p_i, rho_i, p_j, rho_j, r_ij, f);
  // Viscous term: a boundary neighbour contributes through its mDBC velocity.
  const Vec3 vi = i_fluid || !p.mdbc ? v.vel[i] : v.vel_bc[i];
  const Vec3 vj = j_fluid || !p.mdbc ? v.vel[j] : v.vel_bc[j];
  const Vec3 vv_ij = vi - vj;
  if (p.hbp) {
    // Variable viscosity mu_eff (dynamic, Pa s). The pair viscosity is the harmonic mean
    // 2 mu_i mu_j / (mu_i + mu_j), which keeps the shear stress continuous across a jump in mu
    // (plug edge: mu jumps by mu_max/K); the arithmetic mean would let the plug's viscosity leak
    // into the yielded layer. nu_ij = mu_ij / rho_mean. A boundary slot takes the fluid's mu.
    const Real mu_i = i_fluid ? v.visc[i] : v.visc[j];
    const Real mu_j = j_fluid ? v.visc[j] : mu_i;
    const Real mu_ij = Real(2) * mu_i * mu_j / (mu_i + mu_j);
    c.acc += laminar_acc_ij(Real(1), Real(2) * mu_ij / (rho_i + rho_j), rho_i, rho_j, r2, f, p.eta2,
                            vv_ij);
  } else if (p.laminar) {
    c.acc += laminar_acc_ij(Real(1), p.nu, rho_i, rho_j, r2, f, p.eta2, vv_ij);
  } else {
    const Real c_mean = p.eos.c0;
    c.acc +=
        artificial_acc_ij(Real(1), p.alpha, c_mean, p.h, rho_i, rho_j, r_ij, r2, f, p.eta2, vv_ij);
  }
  if (p.sps && i_fluid && j_fluid) {
    const SymTensor ti{v.sps_d[i], v.sps_o[i]}, tj{v.sps_d[j], v.sps_o[j]};
    c.acc += sps_acc_ij(Real(1), ti, rho_i, tj, rho_j, r_ij, f);
  }
  c.rate = visc_dt_rate_ij(p.h, vv_ij, r_ij, r2, p.eta2);
  return c;
}

// Accumulates, for particle i at r_i, the interaction with neighbour j (a gather: i's side only).
struct PairSums {
  Vec3 acc;
  Real drho = 0;
  Real visc_rate = 0;  // max_j |h v_ij.r_ij/(r^2+eta^2)|
};

SPHDEM_HD SPHDEM_INLINE void accumulate_pair(const StepParams& p, const ParticleView& v, Index i,
                                             Index j, const Vec3& r_ij, Real r2, bool i_fluid,
                                             bool j_fluid, PairSums& out) {
  if (r2 <= Real(0)) return;  // self
  const PairCore c = pair_core(p, v, i, j, r_ij, r2, i_fluid, j_fluid, false);
  const Real m_j = v.mass[j];
  out.acc += c.acc * m_j;
  out.drho += c.drho_i * m_j;
  if (c.rate > out.visc_rate) out.visc_rate = c.rate;
}

// Rates of change for slots [begin, end): acceleration (with gravity for fluid), drho/dt, and
// the per-particle viscous dt rate into `rate`. Fluid slots see fluid and boundary neighbours;
// boundary slots see owned fluid only (their acc, times their mass, is the fluid force on the
// solid; on many ranks each rank holds its share, and the shares add up).
template <class Space>
void compute_rates(Space s, ParticleView v, NeighborLists nl, StepParams p, Index begin, Index end,
                   bool fluid_range, Real* rate) {
  for_each_uneven(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        const Vec3 ri = v.pos[i];
        PairSums sums;
        for_each_neighbor(p.grid, nl.fluid, v.pos, ri, p.radius2,
                          [&](Index j, const Vec3& r_ij, Real r2) {
                            accumulate_pair(p, v, i, j, r_ij, r2, fluid_range, true, sums);
                          });
        if (fluid_range) {
          if (nl.has_halo)
            for_each_neighbor(p.grid, nl.halo, v.pos, ri, p.radius2,
                              [&](Index j, const Vec3& r_ij, Real r2) {
                                accumulate_pair(p, v, i, j, r_ij, r2, true, true, sums);
                              });
          for_each_boundary_neighbor(p, nl, v.pos, ri, [&](Index j, const Vec3& r_ij, Real r2) {
            accumulate_pair(p, v, i, j, r_ij, r2, true, false, sums);
          });
          v.acc[i] = sums.acc + p.gravity;
        } else {
          v.acc[i] = sums.acc;
        }
        v.drho[i] = sums.drho;
        rate[i] = sums.visc_rate;
      });
}

// Verlet (seed §2; DualSPHysics): with a = a^n, D = drho^n,
//   r^{n+1} = r^n + dt v^n + dt^2/2 a
//   v^{n+1} = v^{n-1} + 2 dt a,  rho^{n+1} = rho^{n-1} + 2 dt D       (regular step)
//   v^{n+1} = v^n + dt a,        rho^{n+1} = rho^n + dt D             (Euler step, every N)
// vel_prev/rho_prev hold the n-1 values on entry and the n values on return.
SPHDEM_HD inline void verlet_update(Vec3& pos, Vec3& vel, Vec3& vel_prev, Real& rho, Real& rho_prev,
                                    const Vec3& a, Real d, Real dt, bool euler) {
  const Vec3 v_n = vel;
  const Real rho_n = rho;
  pos += v_n * dt + a * (Real(0.5) * dt * dt);
  if (euler) {
    vel = v_n + a * dt;
    rho = rho_n + d * dt;
  } else {
    vel = vel_prev + a * (Real(2) * dt);
    rho = rho_prev + d * (Real(2) * dt);
  }
  vel_prev = v_n;
  rho_prev = rho_n;
}

template <class Space>
void integrate_verlet(Space s, ParticleView v, Index begin, Index end, Real dt, bool euler,
                      EosParams eos) {
  for_each(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        verlet_update(v.pos[i], v.vel[i], v.vel_prev[i], v.rho[i], v.rho_prev[i], v.acc[i],
                      v.drho[i], dt, euler);
        v.rho[i] = floor_density(eos, v.rho[i]);
      });
}

// DBC density for boundary slots: rho^{n+1} = rho^n + dt D, never below rho0.
template <class Space>
void integrate_dbc_density(Space s, ParticleView v, Index begin, Index end, Real dt,
                           EosParams eos) {
  for_each(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        Real rho = v.rho[i] + v.drho[i] * dt;
        if (rho < eos.rho0) rho = eos.rho0;
        v.rho[i] = rho;
        v.press[i] = tait_pressure(eos, rho);
      });
}

// Symplectic position Verlet (DualSPHysics "symplectic"):
//   predictor: r^{n+1/2} = r^n + dt/2 v^n, v^{n+1/2} = v^n + dt/2 a^n, rho^{n+1/2} = rho^n + dt/2
//   D^n corrector: v^{n+1} = v^n + dt a^{n+1/2}, r^{n+1} = r^n + dt (v^n + v^{n+1})/2,
//              rho^{n+1} = rho^n (2 - eps)/(2 + eps), eps = -D^{n+1/2}/rho^{n+1/2} dt.
// The predictor keeps r^n in the fluid slot's `ghost` field (unused for fluid) and v^n, rho^n in
// vel_prev/rho_prev.
template <class Space>
void symplectic_predict(Space s, ParticleView v, Index begin, Index end, Real dt, EosParams eos) {
  for_each(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        v.ghost[i] = v.pos[i];
        v.vel_prev[i] = v.vel[i];
        v.rho_prev[i] = v.rho[i];
        v.pos[i] += v.vel[i] * (Real(0.5) * dt);
        v.vel[i] += v.acc[i] * (Real(0.5) * dt);
        v.rho[i] = floor_density(eos, v.rho[i] + v.drho[i] * (Real(0.5) * dt));
      });
}

template <class Space>
void symplectic_correct(Space s, ParticleView v, Index begin, Index end, Real dt, EosParams eos) {
  for_each(
      s, end - begin, SPHDEM_LAMBDA(Index k) {
        const Index i = begin + k;
        const Vec3 v_n = v.vel_prev[i];
        const Vec3 v_new = v_n + v.acc[i] * dt;
        v.pos[i] = v.ghost[i] + (v_n + v_new) * (Real(0.5) * dt);
        v.vel[i] = v_new;
        const Real eps = -v.drho[i] / v.rho[i] * dt;
        v.rho[i] = floor_density(eos, v.rho_prev[i] * (Real(2) - eps) / (Real(2) + eps));
      });
}

}  // namespace sphdem
