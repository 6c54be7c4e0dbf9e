// Solver<Space>: the fluid step on one execution space. Included by solver_host.cpp (Host) and
// cuda/solver_device.cu (Device, after cuda/exec_device.cuh). Host logic only: the physics is in
// fluid_drivers.hpp and lib/sph/.
#pragma once

#include <chrono>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "neighbor/cell_list.hpp"
#include "solver/fluid_drivers.hpp"
#include "solver/solver.hpp"

namespace sphdem {

// Copies a host field set into a space (a move on the host), and back. The Device overloads are
// in cuda/particles_device.hpp; calls are unqualified so they are found at instantiation.
inline void to_space(Host, ParticleSet<Host>&& src, ParticleSet<Host>& dst) {
  dst = std::move(src);
}
inline void to_host(Host, ParticleSet<Host>&, ParticleSet<Host>&) {}

template <class Space>
class Solver final : public SolverBase {
 public:
  Solver(const Scene& scene, ParticleSet<Host> particles, Real c0)
      : scene_(scene), p_(make_step_params(scene, c0)) {
    to_space(Space{}, std::move(particles), ps_);
    max_id_ = 0;
    host_valid_ = false;
    max_id_ = GlobalId(ps_.size());
    rate_.resize(std::size_t(ps_.size()));
    sort_boundary();
    verlet_count_ = 0;
  }

  const char* space_name() const override { return Space::name; }
  Real time() const override { return time_; }
  std::int64_t step_count() const override { return step_; }
  const StepParams& params() const override { return p_; }
  Index fluid_count() const override { return ps_.n_fluid; }
  Index removed_count() const override { return removed_; }
  Real removed_mass() const override { return removed_mass_; }
  const PhaseTimes& phase_times() const override { return times_; }

  const ParticleSet<Host>& host_particles() override {
    if constexpr (std::is_same_v<Space, Host>) {
      return ps_;
    } else {
      if (!host_valid_) {
        to_host(Space{}, ps_, host_);
        host_valid_ = true;
      }
      return host_;
    }
  }

  StepStats step() override {
    using clock = std::chrono::steady_clock;
    host_valid_ = false;
    StepStats st;
    auto t0 = clock::now();
    st.removed = remove_and_wrap();
    sort_fluid();
    auto t1 = clock::now();
    times_.cell_list += std::chrono::duration<double>(t1 - t0).count();

    const bool symplectic = scene_.time.integrator == Integrator::kSymplectic;
    evaluate_rates();
    st = limits(st);
    const Real dt = st.dt;
    auto t2 = clock::now();
    ParticleView v = view();
    const Index nf = ps_.n_fluid;
    if (symplectic) {
      symplectic_predict(Space{}, v, 0, nf, dt);
      evaluate_rates();
      symplectic_correct(Space{}, v, 0, nf, dt);
    } else {
      ++verlet_count_;
      const int every = scene_.time.verlet_euler_every;
      const bool euler = step_ == 0 || (every > 0 && verlet_count_ % every == 0);
      integrate_verlet(Space{}, v, 0, nf, dt, euler);
    }
    if (!p_.mdbc) {
      integrate_dbc_density(Space{}, v, ps_.wall_begin(), ps_.size(), dt, p_.eos);
    }
    times_.integrate += std::chrono::duration<double>(clock::now() - t2).count();
    time_ += dt;
    ++step_;
    return st;
  }

  // The particle view plus the solver's per-step scratch fields.
  ParticleView view() {
    const std::size_t n = std::size_t(ps_.size());
    if (visc_.size() < n) {
      visc_.resize(n);
      sps_d_.resize(n);
      sps_o_.resize(n);
    }
    ParticleView v = ps_.view();
    v.visc = visc_.data();
    v.sps_d = sps_d_.data();
    v.sps_o = sps_o_.data();
    return v;
  }

  SolverCounters counters() const override {
    return SolverCounters{time_, step_, verlet_count_, removed_, removed_mass_};
  }

  void restore(ParticleSet<Host> particles, const SolverCounters& c) override {
    host_valid_ = false;
    to_space(Space{}, std::move(particles), ps_);
    GlobalId max_id = 0;
    const auto& h = host_particles();
    for (Index i = 0; i < h.size(); ++i) max_id = std::max(max_id, h.id[i]);
    max_id_ = std::max(max_id_, max_id + 1);
    rate_.resize(std::size_t(ps_.size()));
    time_ = c.time;
    step_ = c.step;
    verlet_count_ = c.verlet_count;
    removed_ = c.removed;
    removed_mass_ = c.removed_mass;
    sort_boundary();
  }

  double last_pair_count() override {
    ParticleView v = view();
    const NeighborLists nl{fluid_cells_.view(), boundary_cells_.view()};
    const StepParams p = p_;
    return reduce<SumOp, double>(
        Space{}, ps_.n_fluid, SPHDEM_LAMBDA(Index i) {
          double c = 0;
          auto count = [&](Index, const Vec3&, Real r2) { c += r2 > 0 ? 1 : 0; };
          for_each_neighbor(p.grid, nl.fluid, v.pos, v.pos[i], p.radius2, count);
          for_each_neighbor(p.grid, nl.boundary, v.pos, v.pos[i], p.radius2, count);
          return c;
        });
  }

  // The steps below are public only because nvcc forbids extended lambdas in private members.
  // Pressure, mDBC, and the rates of fluid and boundary particles at the current state.
  void evaluate_rates() {
    using clock = std::chrono::steady_clock;
    ParticleView v = view();
    const NeighborLists nl{fluid_cells_.view(), boundary_cells_.view()};
    auto t0 = clock::now();
    compute_pressure(Space{}, v, 0, ps_.n_fluid, p_.eos);
    if (p_.mdbc) update_mdbc(Space{}, v, nl, p_, ps_.wall_begin(), ps_.size());
    if (p_.hbp || p_.sps) compute_viscous_state(Space{}, v, nl, p_, ps_.n_fluid);
    auto t1 = clock::now();
    compute_rates(Space{}, v, nl, p_, 0, ps_.n_fluid, true, rate_.data());
    compute_rates(Space{}, v, nl, p_, ps_.wall_begin(), ps_.size(), false, rate_.data());
    auto t2 = clock::now();
    times_.mdbc += std::chrono::duration<double>(t1 - t0).count();
    times_.forces += std::chrono::duration<double>(t2 - t1).count();
  }

  // Time-step limits of Eq. (23) with the viscous limit; fills dt and the fluid extremes.
  StepStats limits(StepStats st) {
    ParticleView v = view();
    const Real* rate = rate_.data();
    const Index nf = ps_.n_fluid;
    const Real amax2 = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return norm2(v.acc[i]); });
    const Real rmax = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return rate[i]; });
    const Real vmax2 = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return norm2(v.vel[i]); });
    st.rho_min = reduce<MinOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return v.rho[i]; });
    st.rho_max = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return v.rho[i]; });
    if (nf == 0) {  // every fluid particle has left through the open ends
      st.rho_min = st.rho_max = p_.eos.rho0;
    }
    st.max_speed = std::sqrt(std::max(vmax2, Real(0)));
    const Real h = p_.h;
    st.dt_force = amax2 > 0 ? std::sqrt(h / std::sqrt(amax2)) : Real(1e30);
    st.dt_acoustic = h / (p_.eos.c0 + std::max(rmax, Real(0)));
    st.dt_viscous = p_.laminar && p_.nu > 0 ? Real(0.125) * h * h / p_.nu : Real(1e30);
    if (p_.hbp) {
      // Explicit viscous limit with the largest mu_eff / rho (kinematic).
      const Real* visc = visc_.data();
      const Real nu_max = reduce<MaxOp, Real>(
          Space{}, nf, SPHDEM_LAMBDA(Index i) { return visc[i] / v.rho[i]; });
      st.dt_viscous = nu_max > 0 ? Real(0.125) * h * h / nu_max : Real(1e30);
    }
    Real dt = scene_.time.cfl * std::min(st.dt_force, st.dt_acoustic);
    dt = std::min(dt, st.dt_viscous);
    if (scene_.time.dt_fixed > 0) dt = scene_.time.dt_fixed;
    st.dt = dt;
    return st;
  }

  // Sorts the boundary range once (fixed walls do not move).
  void sort_boundary() { sort_range(ps_.wall_begin(), ps_.n_wall + ps_.n_grain, boundary_cells_); }
  void sort_fluid() { sort_range(0, ps_.n_fluid, fluid_cells_); }

  void sort_range(Index begin, Index count, CellList<Space>& cl) {
    sort_cells(Space{}, p_.grid, ps_.pos.data(), ps_.id.data(), max_id_, begin, count, cl);
    ps_.for_each_field([&](const char*, auto& field) {
      using B = std::decay_t<decltype(field)>;
      B scratch;
      permute_range(Space{}, field, cl, scratch);
    });
    mark_cells(Space{}, p_.grid, cl);
  }

  // Wraps periodic axes and removes fluid that left the domain (open ends). Removal compacts on
  // the host: it is rare, and keeps the id order.
  Index remove_and_wrap() {
    ParticleView v = view();
    const StepParams p = p_;
    const Index nf = ps_.n_fluid;
    for_each(
        Space{}, nf, SPHDEM_LAMBDA(Index i) {
          Vec3 x = v.pos[i];
          for (int k = 0; k < 3; ++k) {
            if (!p.grid.periodic[k]) continue;
            const Real L = p.grid.period[k];
            const Real lo = p.grid.lo[k];
            while (x[k] < lo) x[k] += L;
            while (x[k] >= lo + L) x[k] -= L;
          }
          v.pos[i] = x;
        });
    const Index out = reduce<SumOp, Index>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) {
          const Vec3 x = v.pos[i];
          bool outside = false;
          for (int k = 0; k < 3; ++k) {
            if (p.grid.periodic[k] || (p.dim == 2 && k == 1)) continue;
            if (x[k] < p.domain_lo[k] || x[k] > p.domain_hi[k] || x[k] != x[k]) outside = true;
          }
          return Index(outside ? 1 : 0);
        });
    if (out == 0) return 0;
    ParticleSet<Host> h;
    if constexpr (std::is_same_v<Space, Host>) {
      h = std::move(ps_);
    } else {
      to_host(Space{}, ps_, h);
    }
    std::vector<char> keep(std::size_t(h.size()), 1);
    for (Index i = 0; i < h.n_fluid; ++i) {
      const Vec3 x = h.pos[i];
      for (int k = 0; k < 3; ++k) {
        if (p.grid.periodic[k] || (p.dim == 2 && k == 1)) continue;
        if (!(x[k] >= p.domain_lo[k] && x[k] <= p.domain_hi[k])) keep[std::size_t(i)] = 0;
      }
      if (!keep[std::size_t(i)]) {
        ++removed_;
        removed_mass_ += h.mass[i];
      }
    }
    Index w = 0;
    const Index n = h.size();
    for (Index i = 0; i < n; ++i) {
      if (!keep[std::size_t(i)]) continue;
      if (w != i) {
        h.for_each_field(
            [&](const char*, auto& field) { field[std::size_t(w)] = field[std::size_t(i)]; });
      }
      ++w;
    }
    h.n_fluid -= out;
    h.resize(h.size());
    if constexpr (std::is_same_v<Space, Host>) {
      ps_ = std::move(h);
    } else {
      to_space(Space{}, std::move(h), ps_);
    }
    // Boundary slots moved down: re-mark the boundary list.
    sort_boundary();
    return out;
  }

 private:
  Scene scene_;
  StepParams p_;
  ParticleSet<Space> ps_;
  ParticleSet<Host> host_;
  bool host_valid_ = false;
  CellList<Space> fluid_cells_, boundary_cells_;
  Buffer<Real, Space> rate_;
  Buffer<Real, Space> visc_;
  Buffer<Vec3, Space> sps_d_, sps_o_;
  GlobalId max_id_ = 0;
  Real time_ = 0;
  std::int64_t step_ = 0;
  std::int64_t verlet_count_ = 0;
  Index removed_ = 0;
  Real removed_mass_ = 0;
  PhaseTimes times_;
};

}  // namespace sphdem
