// Solver<Space>: the fluid step on one execution space. Included by solver_host.cpp (Host) and
// cuda/solver_device.cu (Device, after cuda/exec_device.cuh). Host logic only: the physics is in
// fluid_drivers.hpp and lib/sph/.
#pragma once

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <type_traits>
#include <unordered_map>

#include "core/error.hpp"
#include "neighbor/cell_list.hpp"
#include "solver/exchange.hpp"
#include "solver/fluid_drivers.hpp"
#include "solver/pairwise_host.hpp"
#include "solver/solver.hpp"

namespace sphdem {

// Copies a host field set into a space (a move on the host), and back. The Device overloads are
// in cuda/particles_device.hpp; calls are unqualified so they are found at instantiation.
inline void to_space(Host, ParticleSet<Host>&& src, ParticleSet<Host>& dst) {
  dst = std::move(src);
}
inline void to_host(Host, ParticleSet<Host>&, ParticleSet<Host>&) {}

// Whether x lies outside the domain along a non-periodic axis (y does not count in 2D); NaN is
// outside.
SPHDEM_HD inline bool outside_domain(const StepParams& p, const Vec3& x) {
  for (int k = 0; k < 3; ++k) {
    if (p.grid.periodic[k] || (p.dim == 2 && k == 1)) continue;
    if (!(x[k] >= p.domain_lo[k] && x[k] <= p.domain_hi[k])) return true;
  }
  return false;
}

template <class Space>
class Solver final : public SolverBase {
 public:
  // `ex`: the decomposition on many ranks (particles: this rank's owned fluid and every wall
  // particle); null on one rank.
  Solver(const Scene& scene, ParticleSet<Host> particles, Real c0,
         std::shared_ptr<Exchange> ex = nullptr)
      : scene_(scene), p_(make_step_params(scene, c0)), ex_(std::move(ex)) {
    adopt(std::move(particles));
    verlet_count_ = 0;
  }

  const char* space_name() const override { return Space::name; }
  Real time() const override { return time_; }
  std::int64_t step_count() const override { return step_; }
  const StepParams& params() const override { return p_; }
  void set_body_acceleration(Vec3 a) override {
    p_.gravity = a;
    p_.g_mag = norm(a);
    p_.g_hat = p_.g_mag > 0 ? a / p_.g_mag : Vec3();
  }
  Index fluid_count() const override { return global_fluid_; }
  Index removed_count() const override { return removed_; }
  Real removed_mass() const override { return removed_mass_; }
  const PhaseTimes& phase_times() const override { return times_; }
  // Phase clock (PhaseClock in core/exec.hpp; CUDA events on the device): a mark at each phase
  // boundary, the times made final at the end of each step.
  typename PhaseClock<Space>::Mark tick() { return clock_.mark(); }

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
    host_valid_ = false;
    StepStats st;
    auto t0 = tick();
    if (!ex_) {
      st.removed = remove_and_wrap();
      sort_fluid();
      clock_.add(times_.cell_list, t0, tick());
    } else if (need_rebuild()) {
      // Neighbour rebuild: leavers move, boxes may be rebalanced, a new halo plan is built.
      drop_halo();
      st.removed = remove_and_wrap();
      bool rebalanced = false;
      const Index walls_were_at = ps_.wall_begin();
      on_host([&](ParticleSet<Host>& h) {
        ex_->migrate(h);
        const int every = scene_.parallel.rebalance_every;
        rebalanced = every > 0 && step_ > 0 && step_ % every == 0 && ex_->rebalance(h);
      });
      // Arrivals and departures moved the wall slots: the boundary list follows them.
      shift_boundary(ps_.wall_begin() - walls_were_at);
      if (rebalanced) reselect_walls();
      sort_fluid();
      auto t1 = tick();
      clock_.add(times_.cell_list, t0, t1);
      fill_halo();
      record_build();
      rebuild_grains();
      ++rebuilds_;
      clock_.add(times_.halo, t1, tick());
    } else {
      // Between rebuilds: owned particles stay owned, the halo copies are refreshed in place.
      st.removed = remove_and_wrap();  // none: need_rebuild() saw none outside
      sort_fluid();
      follow(root_at_, fluid_cells_);
      auto t1 = tick();
      clock_.add(times_.cell_list, t0, t1);
      refresh_halo(ps_.pos, true);
      refresh_halo(ps_.vel, false, HaloField::kVelocity);
      refresh_halo(ps_.rho);
      sort_range(ps_.n_fluid, ps_.n_halo, halo_cells_);
      follow(leaf_at_, halo_cells_);
      clock_.add(times_.halo, t1, tick());
    }
    lists_ready_ = true;

    const bool symplectic = scene_.time.integrator == Integrator::kSymplectic;
    evaluate_rates();
    st = limits(st);
    const Real dt = st.dt;
    auto t2 = tick();
    ParticleView v = view();
    const Index nf = ps_.n_fluid;
    if (symplectic) {
      symplectic_predict(Space{}, v, 0, nf, dt, p_.eos);
      refresh_halo(ps_.pos, true);
      refresh_halo(ps_.vel, false, HaloField::kVelocity);
      refresh_halo(ps_.rho);
      evaluate_rates();
      symplectic_correct(Space{}, v, 0, nf, dt, p_.eos);
    } else {
      ++verlet_count_;
      const int every = scene_.time.verlet_euler_every;
      const bool euler = step_ == 0 || (every > 0 && verlet_count_ % every == 0);
      integrate_verlet(Space{}, v, 0, nf, dt, euler, p_.eos);
    }
    if (!p_.mdbc) {
      integrate_dbc_density(Space{}, v, ps_.wall_begin(), ps_.size(), dt, p_.eos);
    }
    extremes(st);
    clock_.add(times_.integrate, t2, tick());
    clock_.settle();
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
    adopt(std::move(particles));
    time_ = c.time;
    step_ = c.step;
    verlet_count_ = c.verlet_count;
    removed_ = c.removed;
    removed_mass_ = c.removed_mass;
  }

  // Takes a new particle set (construction and restart): ids, scratch sizes, the wall list.
  void adopt(ParticleSet<Host> particles) {
    host_valid_ = false;
    lists_ready_ = false;
    GlobalId max_id = 0;
    for (Index i = 0; i < particles.size(); ++i) max_id = std::max(max_id, particles.id[i]);
    Real m = Real(max_id) + 1;
    if (ex_) ex_->max(&m, 1);
    // Never lower: on many ranks a later set may hold only some grain particles.
    max_id_ = std::max(max_id_, GlobalId(m));
    global_fluid_ = ex_ ? Index(ex_->sum(std::int64_t(particles.n_fluid))) : particles.n_fluid;
    grains_last(particles);
    if (ex_) {  // this rank keeps the walls it can use (the set may hold every wall particle)
      ParticleSet<Host> grains = take_grains(particles);
      ParticleSet<Host> walls = take_walls(particles);
      append_walls(particles, select_walls(walls));
      append_grains(particles, std::move(grains));
    }
    to_space(Space{}, std::move(particles), ps_);
    built_ = false;  // the next step rebuilds the halo (and, many ranks, the grain slots)
    grains_built_ = false;
    grain_at_.clear();
    rate_.resize(std::size_t(ps_.size()));
    sort_boundary();
    if (ex_) mark_wall_owners();
  }

  std::vector<std::uint8_t> wall_mine() const override { return mine_host_; }

  // Grains on many ranks (set_grain_source): each rank holds the grain particles it owns and
  // copies of others' near its box, and poses all of them from the replicated DEM state; the
  // owner computes a particle's mDBC state and the grain halo plan copies it out.
  void pose_grains(const GrainPointTable& t, const std::vector<dem::RigidBody>& bodies) override {
    if (ex_ && ps_.n_grain > 0 && !grain_source_)
      throw std::logic_error("Solver::pose_grains: grains on many ranks need set_grain_source");
    if (table_of_ != &t) {
      put_space(tpl_pos_, t.pos);
      put_space(tpl_ghost_, t.ghost);
      put_space(tpl_normal_, t.normal);
      put_space(tpl_first_, t.template_first);
      put_space(grain_first_, t.grain_first);
      table_of_ = &t;
    }
    put_space(bodies_, bodies);
    host_valid_ = false;
    ParticleView v = ps_.view();
    const Index gb = ps_.wall_begin() + ps_.n_wall, ng = ps_.n_grain;
    const GlobalId first_id = t.first_id;
    const Vec3* tp = tpl_pos_.data();
    const Vec3* tg = tpl_ghost_.data();
    const Vec3* tn = tpl_normal_.data();
    const std::uint32_t* tf = tpl_first_.data();
    const std::uint32_t* gf = grain_first_.data();
    const dem::RigidBody* b = bodies_.data();
    for_each(
        Space{}, ng, SPHDEM_LAMBDA(Index k) {
          const Index i = gb + k;
          const std::uint32_t g = std::uint32_t(kGrainBodyBase - v.body[i]);
          const dem::RigidBody& body = b[g];
          const std::uint32_t at = tf[body.shape] + std::uint32_t(v.id[i] - first_id) - gf[g];
          pose_grain_point(body, tp[at], tg[at], tn[at], v.pos[i], v.ghost[i], v.normal[i],
                           v.vel[i]);
          v.ghost_alt[i] = v.ghost[i];
        });
    sort_grains();
    mark_grain_owners();
  }

  const ParticleSet<Host>& grain_particles() override {
    const Index gb = ps_.wall_begin() + ps_.n_wall, ng = ps_.n_grain;
    std::vector<void*> dst;
    grain_host_.for_each_field([&](const char*, auto& b) { dst.push_back(&b); });
    std::size_t k = 0;
    ps_.for_each_field([&](const char*, auto& field) {
      using T = std::decay_t<decltype(field.data()[0])>;
      auto* d = static_cast<Buffer<T, Host>*>(dst[k++]);
      d->resize(std::size_t(ng));
      field.download_range(d->data(), std::size_t(gb), std::size_t(ng));
    });
    grain_host_.n_fluid = grain_host_.n_halo = grain_host_.n_wall = 0;
    grain_host_.n_grain = ng;
    return grain_host_;
  }
  std::vector<std::uint8_t> grain_mine() const override {
    if (mine_host_.size() < std::size_t(ps_.n_wall)) return {};
    return std::vector<std::uint8_t>(mine_host_.begin() + ps_.n_wall, mine_host_.end());
  }
  void set_grain_source(GrainSource source, Index total) override {
    grain_source_ = std::move(source);
    grain_total_ = total;
  }
  std::int64_t halo_rebuilds() const override { return rebuilds_; }

  double last_pair_count() override {
    ParticleView v = view();
    const NeighborLists nl = lists();
    const StepParams p = p_;
    return reduce<SumOp, double>(
        Space{}, ps_.n_fluid, SPHDEM_LAMBDA(Index i) {
          double c = 0;
          auto count = [&](Index, const Vec3&, Real r2) { c += r2 > 0 ? 1 : 0; };
          for_each_fluid_neighbor(p, nl, v.pos, v.pos[i], count);
          for_each_boundary_neighbor(p, nl, v.pos, v.pos[i], count);
          return c;
        });
  }

  MdbcLimiterStats mdbc_limiter_stats() override {
    if (!lists_ready_) {  // before the first step, or after a restore: no cell lists yet
      const double nan = std::numeric_limits<double>::quiet_NaN();
      MdbcLimiterStats st;
      st.clipped = nan;
      st.rho_fit_max = st.rho_cut_max = Real(nan);
      return st;
    }
    // The halo copies (other ranks' fluid, or the symmetry plane's mirror images) still hold the
    // state from before this step's update: refreshed as the next step would, the fits see what
    // one rank would.
    refresh_halo(ps_.pos, true);
    refresh_halo(ps_.vel, false, HaloField::kVelocity);
    refresh_halo(ps_.rho);
    const Index b = ps_.wall_begin(), n = ps_.size() - b;
    limiter_fit_.resize(std::size_t(n));
    limiter_cut_.resize(std::size_t(n));
    ParticleView v = view();
    mdbc_limiter_cuts(Space{}, v, lists(), p_, b, ps_.size(), limiter_fit_.data(),
                      limiter_cut_.data(), ex_ ? wall_mine_.data() : nullptr);
    MdbcLimiterStats st = mdbc_limiter_reduce(Space{}, v.pos, b, n, limiter_fit_.data(),
                                              limiter_cut_.data(), p_.eos.rho0);
    if (ex_) {  // a rank without walls gives 0 for each of the sum and the two maxima
      Real m[5] = {Real(st.clipped), st.rho_fit_max, st.rho_cut_max, st.clip_x_hi, -st.clip_x_lo};
      ex_->sum(&m[0], 1);
      ex_->max(&m[1], 4);
      st.clipped = double(m[0]);
      st.rho_fit_max = m[1];
      st.rho_cut_max = m[2];
      st.clip_x_hi = m[3];
      st.clip_x_lo = -m[4];
    }
    const Real nan = std::numeric_limits<Real>::quiet_NaN();
    if (!(st.clipped > 0)) {
      st.clip_x_lo = st.clip_x_hi = nan;
      return st;
    }
    // The largest cut is on one rank (an exact tie between two ranks would mix their positions).
    Vec3 at = mdbc_cut_position(Space{}, v.pos, b, n, limiter_cut_.data(), st.rho_cut_max);
    if (ex_) {
      Real m[3] = {at.x, at.y, at.z};
      ex_->max(m, 3);
      at = Vec3(m[0], m[1], m[2]);
    }
    st.cut_at = at;
    return st;
  }

  // The steps below are public only because nvcc forbids extended lambdas in private members.
  // Pressure, mDBC, and the rates of fluid and boundary particles at the current state.
  void evaluate_rates() {
    ParticleView v = view();
    const NeighborLists nl = lists();
    auto t0 = tick();
    compute_pressure(Space{}, v, 0, ps_.fluid_end(), p_.eos);  // halo copies too
    if (p_.mdbc) {
      update_mdbc(Space{}, v, nl, p_, ps_.wall_begin(), ps_.size(),
                  ex_ ? wall_mine_.data() : nullptr);
      if (ex_) {  // the owners' values to the other ranks' copies
        wall_sync(ps_.rho, false);
        wall_sync(ps_.press, false);
        wall_sync(ps_.vel_bc, false);
        grain_sync(ps_.rho, false);
        grain_sync(ps_.press, false);
        grain_sync(ps_.vel_bc, false);
      }
    }
    if (p_.hbp || p_.sps) {
      compute_viscous_state(Space{}, v, nl, p_, ps_.n_fluid);
      if (p_.hbp) refresh_halo(visc_);
      if (p_.sps) {
        refresh_halo(sps_d_);
        refresh_halo(sps_o_, false, HaloField::kOffDiagonal);
      }
    }
    auto t1 = tick();
    bool pairwise = false;  // the CPU evaluates each pair with an owned fluid particle once
    if constexpr (std::is_same_v<Space, Host>) {
      if (p_.pairwise)
        pairwise = compute_fluid_rates_pairwise(v, nl, p_, ps_.n_fluid, ps_.wall_begin(),
                                                ps_.size(), rate_.data());
    }
    if (!pairwise) {
      compute_rates(Space{}, v, nl, p_, 0, ps_.n_fluid, true, rate_.data());
      compute_rates(Space{}, v, nl, p_, ps_.wall_begin(), ps_.size(), false, rate_.data());
    }
    if (ex_) {
      wall_sync(ps_.acc, true);   // the owner holds the whole fluid force on its wall particles
      grain_sync(ps_.acc, true);  // and on its grain particles (summed per grain by the caller)
      if (!p_.mdbc) {             // DBC: the density rate is a sum over all ranks' fluid
        wall_sync(ps_.drho, true);
        wall_sync(ps_.drho, false);
        grain_sync(ps_.drho, true);
        grain_sync(ps_.drho, false);
      }
    }
    auto t2 = tick();
    clock_.add(times_.mdbc, t0, t1);
    clock_.add(times_.forces, t1, t2);
  }

  // The fastest fluid speed and the density range of the state the step ends with: the state the
  // guards judge and the emergency dump holds (the rates, and so the limits, saw the state the
  // step began with).
  void extremes(StepStats& st) {
    ParticleView v = view();
    const Index nf = ps_.n_fluid;
    Real vmax2 = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return norm2(v.vel[i]); });
    st.rho_min = reduce<MinOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return v.rho[i]; });
    st.rho_max = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return v.rho[i]; });
    if (ex_) {  // the extremes over all ranks (a rank without fluid gives the identities)
      const Real lowest = -std::numeric_limits<Real>::max();
      Real m[3] = {nf ? vmax2 : lowest, nf ? -st.rho_min : lowest, nf ? st.rho_max : lowest};
      ex_->max(m, 3);
      vmax2 = m[0];
      st.rho_min = -m[1];
      st.rho_max = m[2];
    }
    if (global_fluid_ == 0) {  // every fluid particle has left through the open ends
      st.rho_min = st.rho_max = p_.eos.rho0;
    }
    st.max_speed = std::sqrt(std::max(vmax2, Real(0)));
  }

  // Time-step limits of Eq. (23) with the viscous limit; fills dt.
  StepStats limits(StepStats st) {
    ParticleView v = view();
    const Real* rate = rate_.data();
    const Index nf = ps_.n_fluid;
    Real amax2 = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return norm2(v.acc[i]); });
    Real rmax = reduce<MaxOp, Real>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return rate[i]; });
    Real nu_max = 0;
    if (p_.hbp) {
      // Explicit viscous limit with the largest mu_eff / rho (kinematic).
      const Real* visc = visc_.data();
      nu_max = reduce<MaxOp, Real>(
          Space{}, nf, SPHDEM_LAMBDA(Index i) { return visc[i] / v.rho[i]; });
    }
    if (ex_) {  // the extremes over all ranks (a rank without fluid gives the identities)
      const Real lowest = -std::numeric_limits<Real>::max();
      Real m[3] = {nf ? amax2 : lowest, nf ? rmax : lowest, nf ? nu_max : lowest};
      ex_->max(m, 3);
      amax2 = m[0];
      rmax = m[1];
      nu_max = m[2];
    }
    const Real h = p_.h;
    st.dt_force = amax2 > 0 ? std::sqrt(h / std::sqrt(amax2)) : Real(1e30);
    st.dt_acoustic = h / (p_.eos.c0 + std::max(rmax, Real(0)));
    st.dt_viscous = p_.laminar && p_.nu > 0 ? Real(0.125) * h * h / p_.nu : Real(1e30);
    if (p_.hbp) {
      st.dt_viscous = nu_max > 0 ? Real(0.125) * h * h / nu_max : Real(1e30);
    }
    Real dt = scene_.time.cfl * std::min(st.dt_force, st.dt_acoustic);
    dt = std::min(dt, st.dt_viscous);
    if (scene_.time.dt_max > 0) dt = std::min(dt, scene_.time.dt_max);
    if (scene_.time.dt_fixed > 0) dt = scene_.time.dt_fixed;
    st.dt = dt;
    return st;
  }

  // Sorts the boundary range once (fixed walls do not move).
  // Walls and grains are sorted as separate ranges: walls keep their slots (the wall plan on many
  // ranks refers to them) while grains move every step.
  void sort_boundary() {
    sort_range(ps_.wall_begin(), ps_.n_wall, boundary_cells_);
    sort_grains();
  }
  void sort_grains() {
    sort_range(ps_.wall_begin() + ps_.n_wall, ps_.n_grain, grain_cells_);
    if (grains_built_) follow(grain_at_, grain_cells_);
  }
  void sort_fluid() { sort_range(0, ps_.n_fluid, fluid_cells_); }

  void sort_range(Index begin, Index count, CellList<Space>& cl) {
    sort_cells(Space{}, p_.grid, ps_.pos.data(), ps_.id.data(), max_id_, begin, count, cl);
    ps_.for_each_field([&](const char*, auto& field) {
      using B = std::decay_t<decltype(field)>;
      B scratch;
      permute_range(Space{}, field, cl, scratch);
    });
    mark_cells(Space{}, p_.grid, cl);
    mark_blocks(Space{}, p_.grid, cl);
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
          // Fluid that crossed a symmetry plane comes back as its mirror image.
          if (p.sym.enabled() && p.sym.side(x) < 0) {
            x = p.sym.reflect_point(x);
            v.vel[i] = p.sym.reflect_vector(v.vel[i]);
            v.vel_prev[i] = p.sym.reflect_vector(v.vel_prev[i]);
          }
          v.pos[i] = x;
        });
    const Index out = reduce<SumOp, Index>(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { return Index(outside_domain(p, v.pos[i]) ? 1 : 0); });
    const Index out_all = ex_ ? Index(ex_->sum(std::int64_t(out))) : out;
    if (out_all == 0) return 0;
    Real mass_out = 0;
    if (out > 0) {
      ParticleSet<Host> h;
      if constexpr (std::is_same_v<Space, Host>) {
        h = std::move(ps_);
      } else {
        to_host(Space{}, ps_, h);
      }
      std::vector<char> keep(std::size_t(h.size()), 1);
      for (Index i = 0; i < h.n_fluid; ++i) {
        if (outside_domain(p, h.pos[i])) {
          keep[std::size_t(i)] = 0;
          mass_out += h.mass[i];
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
    }
    if (ex_) ex_->sum(&mass_out, 1);
    removed_ += out_all;
    removed_mass_ += mass_out;
    global_fluid_ -= out_all;
    // Boundary slots moved down: re-mark the boundary list.
    if (out > 0) sort_boundary();
    return out_all;
  }

  // The cell lists of the current layout.
  NeighborLists lists() const {
    return NeighborLists{fluid_cells_.view(), boundary_cells_.view(), halo_cells_.view(),
                         ps_.n_halo > 0,      grain_cells_.view(),    ps_.n_grain > 0};
  }

  // Removes the halo slots (their owners hold the particles); walls move down.
  void drop_halo() {
    if (ps_.n_halo == 0) return;
    const Index nf = ps_.n_fluid, nh = ps_.n_halo, n = ps_.size();
    ps_.for_each_field([&](const char*, auto& field) {
      using B = std::decay_t<decltype(field)>;
      B tail;
      tail.resize(std::size_t(n - nf - nh));
      copy_range(field, nf + nh, n, tail, 0);
      copy_range(tail, 0, n - nf - nh, field, nf);
      field.resize(std::size_t(n - nh));
    });
    ps_.n_halo = 0;
    shift_boundary(-nh);
  }

  // Copies src[b, e) to dst[at, ...) within one space.
  template <class B>
  static void copy_range(const B& src, Index b, Index e, B& dst, Index at) {
    const auto* s = src.data();
    auto* d = dst.data();
    for_each(
        Space{}, e - b, SPHDEM_LAMBDA(Index k) { d[at + k] = s[b + k]; });
  }

  // Boundary slots moved by `delta`: shift the boundary list's offsets (the walls keep their
  // order).
  void shift_boundary(Index delta) {
    if (delta == 0) return;
    std::uint32_t* st = boundary_cells_.start.data();
    const Index nc = Index(boundary_cells_.start.size());
    for_each(
        Space{}, nc, SPHDEM_LAMBDA(Index c) { st[c] = std::uint32_t(Index(st[c]) + delta); });
    boundary_cells_.begin += delta;
    std::uint32_t* gs = grain_cells_.start.data();
    const Index ng = Index(grain_cells_.start.size());
    for_each(
        Space{}, ng, SPHDEM_LAMBDA(Index c) { gs[c] = std::uint32_t(Index(gs[c]) + delta); });
    grain_cells_.begin += delta;
  }

  // Builds the halo (every field), sorts its range by (cell, id), and resizes the scratch.
  void fill_halo() {
    if (!ex_) return;
    on_host([&](ParticleSet<Host>& h) { ex_->build_halo(h); });
    shift_boundary(ps_.n_halo);
    sort_range(ps_.n_fluid, ps_.n_halo, halo_cells_);
    rate_.resize(std::size_t(ps_.size()));
  }

  // Runs f on the particles in host memory: in place on the host; on the device through a full
  // host copy and back (MPI here is not CUDA-aware; a first, unoptimised staging).
  template <class F>
  void on_host(F&& f) {
    host_valid_ = false;
    if constexpr (std::is_same_v<Space, Host>) {
      f(ps_);
    } else {
      ParticleSet<Host> h;
      to_host(Space{}, ps_, h);
      f(h);
      to_space(Space{}, std::move(h), ps_);
    }
  }

  // A host view of a buffer: the buffer's own storage on the host, a downloaded copy on the
  // device (put back with put_host).
  template <class T, class B>
  static T* get_host(B& b, std::vector<T>& tmp) {
    if constexpr (std::is_same_v<Space, Host>) {
      return b.data();
    } else {
      b.download(tmp);
      return tmp.data();
    }
  }
  template <class T, class B>
  static void put_host(B& b, const std::vector<T>& tmp) {
    if constexpr (!std::is_same_v<Space, Host>) b.upload(tmp);
  }

  // Sends the owned values of a field to the halo slots. The plan's roots and leaves are in the
  // order of the last rebuild; root_at_ and leaf_at_ map the current slots to them. Packing and
  // unpacking run in the execution space; on the device only the packed values travel, through
  // pinned host memory (HostStage).
  template <class T>
  void refresh_halo(Buffer<T, Space>& field, bool positions = false,
                    HaloField kind = HaloField::kValue) {
    if (!ex_) return;  // collective: every rank calls it, with or without halo slots
    host_valid_ = false;
    const Index nf = ps_.n_fluid, nh = ps_.n_halo;
    HaloScratch<T>& sc = scratch<T>();
    sc.send.resize(std::size_t(std::max<Index>(nf, 1)));
    T* f = field.data();
    T* send = sc.send.data();
    const std::uint32_t* ra = root_at_.data();
    for_each(
        Space{}, nf, SPHDEM_LAMBDA(Index i) { send[ra[i]] = f[i]; });
    T* roots = sc.send_host.read(sc.send, nf);
    T* leaves = sc.recv_host.space(sc.recv, nh);
    bcast_one(roots, leaves, positions, kind);
    sc.recv_host.write(sc.recv, nh);
    const T* recv = sc.recv.data();
    const std::uint32_t* la = leaf_at_.data();
    for_each(
        Space{}, nh, SPHDEM_LAMBDA(Index j) { f[nf + j] = recv[la[j]]; });
  }

  // After a sort of the range a cell list covers: slot i now holds what slot order[i] held.
  void follow(Buffer<std::uint32_t, Space>& at, CellList<Space>& cl) {
    const Index n = Index(at.size());
    if (n == 0) return;
    follow_scratch_.resize(at.size());
    const std::uint32_t* order = cl.order.data();
    const std::uint32_t* a = at.data();
    std::uint32_t* next = follow_scratch_.data();
    for_each(
        Space{}, n, SPHDEM_LAMBDA(Index i) { next[i] = a[order[i]]; });
    at.swap(follow_scratch_);
  }
  // The same for the grain tags, kept on the host.
  void follow(std::vector<std::uint32_t>& at, CellList<Space>& cl) {
    std::vector<std::uint32_t> otmp;
    const std::uint32_t* order = cl.count > 0 ? get_host<std::uint32_t>(cl.order, otmp) : nullptr;
    std::vector<std::uint32_t> next(at.size());
    for (std::size_t i = 0; i < at.size(); ++i) next[i] = at[order[i]];
    at.swap(next);
  }

  // At a rebuild: the plan's roots are the owned slots as sorted now, its leaves the halo slots
  // before their sort (halo_cells_.order), and the drift is measured from these positions.
  void record_build() {
    const Index nf = ps_.n_fluid, nh = ps_.n_halo;
    root_at_.resize(std::size_t(nf));
    leaf_at_.resize(std::size_t(nh));
    pos_at_build_.resize(std::size_t(nf));
    std::uint32_t* ra = root_at_.data();
    std::uint32_t* la = leaf_at_.data();
    Vec3* pb = pos_at_build_.data();
    const Vec3* pos = ps_.pos.data();
    for_each(
        Space{}, nf, SPHDEM_LAMBDA(Index i) {
          ra[i] = std::uint32_t(i);
          pb[i] = pos[i];
        });
    for_each(
        Space{}, nh, SPHDEM_LAMBDA(Index j) { la[j] = std::uint32_t(j); });
    follow(leaf_at_, halo_cells_);
    built_ = true;
  }

  // Whether this step needs a neighbour rebuild (collective): the first step, a rebalance check,
  // a particle leaving the domain, or an owned particle that moved more than skin/2 since the
  // last rebuild.
  bool need_rebuild() {
    const int every = scene_.parallel.rebalance_every;
    int local = !built_ || (every > 0 && step_ > 0 && step_ % every == 0) ? 1 : 0;
    const Index nf = ps_.n_fluid;
    Real drift2 = 0;
    if (!local && nf > 0) {  // in the execution space: no positions leave the device
      const Vec3* pos = ps_.pos.data();
      const Vec3* pb = pos_at_build_.data();
      const std::uint32_t* ra = root_at_.data();
      const StepParams p = p_;
      drift2 = reduce<MaxOp, Real>(
          Space{}, nf, SPHDEM_LAMBDA(Index i) { return norm2(pos[i] - pb[ra[i]]); });
      const Index out = reduce<SumOp, Index>(
          Space{}, nf, SPHDEM_LAMBDA(Index i) { return Index(outside_domain(p, pos[i]) ? 1 : 0); });
      if (out > 0) local = 1;
    }
    if (grain_source_ && !grains_built_) local = 1;
    if (grains_built_ && !local) {   // grain particles and their ghost nodes (rotation moves them
      std::vector<Vec3> ptmp, gtmp;  // further than the particles)
      const Vec3* pos = grain_range(ps_.pos, ptmp);
      const Vec3* ghost = grain_range(ps_.ghost, gtmp);
      for (Index k = 0; k < ps_.n_grain; ++k) {
        const std::size_t t = grain_at_[std::size_t(k)];
        drift2 = std::max({drift2, norm2(pos[k] - grain_pos_at_build_[t]),
                           norm2(ghost[k] - grain_ghost_at_build_[t])});
      }
    }
    const Real half = Real(0.5) * scene_.parallel.skin * p_.h;
    Real m[2] = {Real(local), drift2};
    ex_->max(m, 2);
    return m[0] > 0 || m[1] > half * half;
  }

  void bcast_one(Real* owned, Real* halo, bool, HaloField) { ex_->bcast(owned, halo); }
  void bcast_one(Vec3* owned, Vec3* halo, bool positions, HaloField kind) {
    if (positions) {
      ex_->bcast_positions(owned, halo);
    } else {
      ex_->bcast_field(owned, halo, kind);
    }
  }

  // Wall plan: reduce = add the copies' partial sums into the owners; otherwise copy the owners'
  // values to the copies. Packed and unpacked in the execution space (wall_roots_, wall_leaves_:
  // the plan's slots); on the device only the packed values are staged through pinned memory.
  template <class T>
  void wall_sync(Buffer<T, Space>& field, bool reduce) {
    host_valid_ = false;
    const Index nr = Index(wall_roots_.size()), nl = Index(wall_leaves_.size());
    HaloScratch<T>& sc = scratch<T>();
    sc.send.resize(std::size_t(std::max<Index>(nr, 1)));
    sc.recv.resize(std::size_t(std::max<Index>(nl, 1)));
    T* f = field.data() + ps_.wall_begin();
    T* rb = sc.send.data();
    T* lb = sc.recv.data();
    const std::uint32_t* wr = wall_roots_.data();
    const std::uint32_t* wl = wall_leaves_.data();
    for_each(
        Space{}, nr, SPHDEM_LAMBDA(Index k) { rb[k] = f[wr[k]]; });
    if (reduce) {
      for_each(
          Space{}, nl, SPHDEM_LAMBDA(Index j) { lb[j] = f[wl[j]]; });
      const T* leaves = sc.recv_host.read(sc.recv, nl);
      T* roots = sc.send_host.read(sc.send, nr);
      ex_->wall_reduce(leaves, roots);
      sc.send_host.write(sc.send, nr);
      for_each(
          Space{}, nr, SPHDEM_LAMBDA(Index k) { f[wr[k]] = rb[k]; });
    } else {
      const T* roots = sc.send_host.read(sc.send, nr);
      T* leaves = sc.recv_host.space(sc.recv, nl);
      ex_->wall_bcast(roots, leaves);
      sc.recv_host.write(sc.recv, nl);
      for_each(
          Space{}, nl, SPHDEM_LAMBDA(Index j) { f[wl[j]] = lb[j]; });
    }
  }

  // A host vector into a buffer of the execution space.
  template <class T>
  static void put_space(Buffer<T, Space>& b, const std::vector<T>& v) {
    if constexpr (std::is_same_v<Space, Host>) {
      b.vec() = v;
    } else {
      b.upload(v);
    }
  }

  // Moves the wall slots of a host set out into a set of their own, sorted by global id.
  static ParticleSet<Host> take_walls(ParticleSet<Host>& ps) {
    const Index wb = ps.wall_begin(), n = ps.size();
    std::vector<Index> perm(static_cast<std::size_t>(n - wb));
    std::iota(perm.begin(), perm.end(), wb);
    std::sort(perm.begin(), perm.end(),
              [&](Index a, Index b) { return ps.id[std::size_t(a)] < ps.id[std::size_t(b)]; });
    ParticleSet<Host> w = copy_slots(ps, perm);
    ps.for_each_field([&](const char*, auto& b) { b.vec().resize(std::size_t(wb)); });
    w.n_wall = n - wb;
    ps.n_wall = 0;
    ps.n_grain = 0;
    return w;
  }

  // The walls of `all` (wall slots only, sorted by id) this rank keeps (near its box, or whose
  // ghost node it owns).
  ParticleSet<Host> select_walls(ParticleSet<Host>& all) const {
    const Index n = all.n_wall;
    const std::vector<std::uint8_t> keep =
        ex_->keep_walls(all.pos.data(), all.ghost.data(), all.ghost_alt.data(), n, p_.mdbc);
    std::vector<Index> slots;
    for (Index i = 0; i < n; ++i)
      if (keep[std::size_t(i)]) slots.push_back(i);
    if (Index(slots.size()) == n) return std::move(all);
    ParticleSet<Host> w = copy_slots(all, slots);
    w.n_wall = Index(slots.size());
    return w;
  }

  // Calls f(a_field, b_field) for each pair of same-named fields of two host sets.
  template <class F>
  static void zip_fields(ParticleSet<Host>& a, ParticleSet<Host>& b, F&& f) {
    std::vector<void*> from;
    b.for_each_field([&](const char*, auto& field) { from.push_back(&field); });
    std::size_t k = 0;
    a.for_each_field([&](const char*, auto& field) {
      f(field, *static_cast<std::decay_t<decltype(field)>*>(from[k++]));
    });
  }

  // Appends every field of `src` to the end of `ps` (counts are the caller's).
  static void append_fields(ParticleSet<Host>& ps, ParticleSet<Host>& src) {
    zip_fields(ps, src, [](auto& d, auto& s) {
      d.vec().insert(d.vec().end(), s.vec().begin(), s.vec().end());
    });
  }

  // Appends walls after the fluid and halo of a host set that has none.
  static void append_walls(ParticleSet<Host>& ps, ParticleSet<Host>&& w) {
    append_fields(ps, w);
    ps.n_wall = w.n_wall;
  }

  // After a rebalance: the walls each rank owned under the old boxes are dealt to the ranks that
  // keep them under the new ones (Exchange::deal_walls). Owners hold a wall's current values (DBC:
  // its integrated density), so nothing is lost.
  void reselect_walls() {
    on_host([&](ParticleSet<Host>& h) {
      ParticleSet<Host> grains = take_grains(h);
      std::vector<std::uint8_t> owned(mine_host_.begin(), mine_host_.begin() + h.n_wall);
      ParticleSet<Host> walls = owned_walls(h, owned);
      append_walls(h, ex_->deal_walls(walls, p_.mdbc));
      append_grains(h, std::move(grains));
    });
    rate_.resize(std::size_t(ps_.size()));
    sort_boundary();
    mark_wall_owners();
  }

  // Moves the wall slots out of a host set without grains (as take_walls) and returns those
  // flagged in `owned` (one flag per wall slot, in slot order), sorted by id.
  static ParticleSet<Host> owned_walls(ParticleSet<Host>& h,
                                       const std::vector<std::uint8_t>& owned) {
    const Index wb = h.wall_begin();
    std::vector<std::pair<GlobalId, std::uint8_t>> flag;
    for (std::size_t k = 0; k < owned.size(); ++k) flag.emplace_back(h.id[wb + Index(k)], owned[k]);
    std::sort(flag.begin(), flag.end());
    ParticleSet<Host> all = take_walls(h);
    std::vector<Index> slots;
    for (Index i = 0; i < all.n_wall; ++i)
      if (flag[std::size_t(i)].second) slots.push_back(i);
    ParticleSet<Host> w = copy_slots(all, slots);
    w.n_wall = Index(slots.size());
    return w;
  }

  // A gate that opens (scene.hpp Solid::removed_at): the boundary particles of solid `solid`
  // leave the run. Halo copies are dropped and rebuilt by the next step. Returns how many
  // boundary particles went, over all ranks (each counted by its owner).
  Index remove_solid(std::int32_t solid) override {
    ParticleSet<Host> h;
    if constexpr (std::is_same_v<Space, Host>) {
      h = std::move(ps_);
    } else {
      to_host(Space{}, ps_, h);
    }
    std::int64_t removed = 0;
    for (Index k = 0; k < h.n_wall; ++k)
      if (h.body[std::size_t(h.wall_begin() + k)] == solid && (!ex_ || mine_host_[std::size_t(k)]))
        ++removed;
    ParticleSet<Host> grains = take_grains(h);
    ParticleSet<Host> walls = take_walls(h);
    h.for_each_field([&](const char*, auto& b) { b.vec().resize(std::size_t(h.n_fluid)); });
    h.n_halo = 0;
    std::vector<Index> slots;
    for (Index i = 0; i < walls.n_wall; ++i)
      if (walls.body[std::size_t(i)] != solid) slots.push_back(i);
    ParticleSet<Host> kept = copy_slots(walls, slots);
    kept.n_wall = Index(slots.size());
    append_walls(h, std::move(kept));
    append_grains(h, std::move(grains));
    adopt(std::move(h));
    return Index(ex_ ? ex_->sum(removed) : removed);
  }

  // Which wall and grain slots this rank computes: those whose mDBC ghost node (or, with DBC,
  // whose position) lies in its box. Walls are fixed, so their plan holds for the whole run;
  // grains are re-marked after every move (mark_grain_owners) and summed over all ranks instead.
  void mark_wall_owners() {
    const Index b = ps_.wall_begin(), n = ps_.n_wall + ps_.n_grain;
    const ParticleSet<Host>& h = host_particles();
    std::vector<std::uint8_t> mine(static_cast<std::size_t>(n));
    for (Index k = 0; k < n; ++k)
      mine[std::size_t(k)] = ex_->owns(p_.mdbc ? h.ghost[b + k] : h.pos[b + k]) ? 1 : 0;
    set_mine(std::move(mine));
    ex_->build_wall_plan(h.id.data() + b, mine_host_.data(), ps_.n_wall);
    std::vector<Index> roots, leaves;
    ex_->wall_slots(roots, leaves);
    put_space(wall_roots_, std::vector<std::uint32_t>(roots.begin(), roots.end()));
    put_space(wall_leaves_, std::vector<std::uint32_t>(leaves.begin(), leaves.end()));
    mark_grain_owners();  // grains: by the grain plan once it is built
  }

  // Grain slots owned: those whose tag is a root of the grain halo plan.
  void mark_grain_owners() {
    if (!grains_built_) return;
    std::vector<std::uint8_t> mine = mine_host_;
    mine.resize(std::size_t(ps_.n_wall + ps_.n_grain));
    for (Index k = 0; k < ps_.n_grain; ++k)
      mine[std::size_t(ps_.n_wall + k)] = grain_at_[std::size_t(k)] < n_grain_owned_ ? 1 : 0;
    set_mine(std::move(mine));
  }

  // Many ranks, at each neighbour rebuild: this rank's grain slots anew from the grain source.
  // It keeps the particles whose ghost node (DBC: position) its box owns, and the grain halo plan
  // brings copies of the other ranks' within the halo width. DBC particles carry their
  // integrated density: an owner takes it from the slot of the same id it held before (every one
  // did: a particle that moved into the box since the last rebuild was within the halo width of
  // it, or the rebuild would have come sooner). The owned particles of all ranks must add up to
  // every grain particle.
  void rebuild_grains() {
    if (!grain_source_) return;  // timed with the halo by step()
    Index owned = 0;
    on_host([&](ParticleSet<Host>& h) {
      ParticleSet<Host> old = take_grains(h);
      std::unordered_map<GlobalId, Index> was;
      for (Index i = 0; i < old.size(); ++i) was.emplace(old.id[std::size_t(i)], i);
      Vec3 lo, hi;
      ex_->owned_box(lo, hi);
      ParticleSet<Host> cand = grain_source_(lo, hi);
      std::vector<Index> keep;
      for (Index i = 0; i < cand.size(); ++i)
        if (ex_->owns(p_.mdbc ? cand.ghost[std::size_t(i)] : cand.pos[std::size_t(i)]))
          keep.push_back(i);
      ParticleSet<Host> g = copy_slots(cand, keep);
      g.n_fluid = Index(keep.size());  // laid out as fluid for the halo plan
      std::int64_t missing = 0;  // DBC particles this rank never held (collective check below)
      GlobalId missing_id = 0;
      if (!p_.mdbc)
        for (Index i = 0; i < g.size(); ++i) {
          const auto at = was.find(g.id[std::size_t(i)]);
          if (at == was.end()) {
            if (missing++ == 0) missing_id = g.id[std::size_t(i)];
            continue;
          }
          g.rho[std::size_t(i)] = old.rho[std::size_t(at->second)];
          g.rho_prev[std::size_t(i)] = old.rho_prev[std::size_t(at->second)];
          g.press[std::size_t(i)] = old.press[std::size_t(at->second)];
        }
      if (!p_.mdbc && ex_->sum(missing) > 0)  // every rank stops, not only the one that saw it
        throw RuntimeFault("grains across ranks: " + std::to_string(missing) +
                           " DBC grain boundary particles (first id " + std::to_string(missing_id) +
                           ") came into rank " + std::to_string(ex_->rank()) +
                           "'s box from beyond its halo between two rebuilds");
      ex_->build_grain_halo(g);
      owned = g.n_fluid;
      g.n_grain = g.n_fluid + g.n_halo;
      g.n_fluid = g.n_halo = 0;
      append_grains(h, std::move(g));
    });
    const std::int64_t all = ex_->sum(std::int64_t(owned));
    if (all != std::int64_t(grain_total_))
      throw RuntimeFault("grains across ranks: the ranks own " + std::to_string(all) +
                         " grain boundary particles, the grains have " +
                         std::to_string(grain_total_) +
                         " (a ghost node outside every box, or in two)");
    n_grain_owned_ = owned;
    grain_at_.resize(std::size_t(ps_.n_grain));
    std::iota(grain_at_.begin(), grain_at_.end(), std::uint32_t(0));
    grains_built_ = true;
    sort_grains();
    const ParticleSet<Host>& h = host_particles();
    const Index gb = h.wall_begin() + h.n_wall;
    grain_pos_at_build_.resize(std::size_t(h.n_grain));
    grain_ghost_at_build_.resize(std::size_t(h.n_grain));
    for (Index k = 0; k < h.n_grain; ++k) {
      const std::size_t t = grain_at_[std::size_t(k)];
      grain_pos_at_build_[t] = h.pos[std::size_t(gb + k)];
      grain_ghost_at_build_[t] = h.ghost[std::size_t(gb + k)];
    }
    mark_grain_owners();
    rate_.resize(std::size_t(ps_.size()));
  }

  // A new host set holding the given slots of src (every field), with no counts set.
  static ParticleSet<Host> copy_slots(ParticleSet<Host>& src, const std::vector<Index>& slots) {
    ParticleSet<Host> out;
    zip_fields(out, src, [&](auto& o, auto& b) {
      o.vec().resize(slots.size());
      for (std::size_t j = 0; j < slots.size(); ++j) o[j] = b[std::size_t(slots[j])];
    });
    return out;
  }

  void set_mine(std::vector<std::uint8_t> mine) {
    put_space(wall_mine_, mine);
    mine_host_ = std::move(mine);
  }

  // Grain plan: reduce = add the copies' partial sums into the owners; otherwise copy the owners'
  // values to the copies. The plan's roots and leaves are the tags of grain_at_.
  template <class T>
  void grain_sync(Buffer<T, Space>& field, bool reduce) {
    if (!grain_source_) return;
    host_valid_ = false;
    std::vector<T> tmp;
    T* f = grain_range(field, tmp);
    const Index ng = ps_.n_grain, no = n_grain_owned_;
    std::vector<T> roots(std::size_t(std::max<Index>(no, 1)), T());
    std::vector<T> leaves(std::size_t(std::max<Index>(ng - no, 1)), T());
    for (Index k = 0; k < ng; ++k) {
      const Index t = grain_at_[std::size_t(k)];
      if (t < no) {
        roots[std::size_t(t)] = f[k];
      } else {
        leaves[std::size_t(t - no)] = f[k];
      }
    }
    if (reduce) {
      ex_->grain_reduce(leaves.data(), roots.data());
    } else {
      ex_->grain_bcast(roots.data(), leaves.data());
    }
    for (Index k = 0; k < ng; ++k) {
      const Index t = grain_at_[std::size_t(k)];
      if (t < no) {
        if (reduce) f[k] = roots[std::size_t(t)];
      } else if (!reduce) {
        f[k] = leaves[std::size_t(t - no)];
      }
    }
    put_grain_range(field, tmp);
  }

  // The grain range of a field in host memory: the field itself on the host; on the device a
  // download of that range only, which put_grain_range uploads back.
  template <class T>
  T* grain_range(Buffer<T, Space>& field, std::vector<T>& tmp) {
    const Index gb = ps_.wall_begin() + ps_.n_wall, ng = ps_.n_grain;
    if constexpr (std::is_same_v<Space, Host>) {
      return field.data() + gb;
    } else {
      tmp.resize(std::size_t(ng));
      field.download_range(tmp.data(), std::size_t(gb), std::size_t(ng));
      return tmp.data();
    }
  }
  template <class T>
  void put_grain_range(Buffer<T, Space>& field, const std::vector<T>& tmp) {
    if constexpr (!std::is_same_v<Space, Host>)
      field.upload_range(tmp.data(), std::size_t(ps_.wall_begin() + ps_.n_wall), tmp.size());
  }

  // Splits the grain slots (the set's tail, after grains_last) off into a set of their own.
  static ParticleSet<Host> take_grains(ParticleSet<Host>& ps) {
    const Index gb = ps.wall_begin() + ps.n_wall, n = ps.size();
    ParticleSet<Host> g;
    zip_fields(g, ps, [&](auto& o, auto& b) {
      o.vec().assign(b.vec().begin() + gb, b.vec().begin() + n);
      b.vec().resize(std::size_t(gb));
    });
    g.n_grain = n - gb;
    ps.n_grain = 0;
    return g;
  }

  static void append_grains(ParticleSet<Host>& ps, ParticleSet<Host>&& g) {
    append_fields(ps, g);
    ps.n_grain = g.n_grain;
  }

 private:
  Scene scene_;
  StepParams p_;
  ParticleSet<Space> ps_;
  ParticleSet<Host> host_;
  bool host_valid_ = false;
  std::shared_ptr<Exchange> ex_;
  CellList<Space> fluid_cells_, boundary_cells_, halo_cells_, grain_cells_;
  Buffer<std::uint8_t, Space> wall_mine_;
  Buffer<Real, Space> limiter_fit_, limiter_cut_;  // mdbc_limiter_stats' scratch, one per wall
  bool lists_ready_ = false;  // the cell lists match the slots (set by step(), cleared by adopt())
  Buffer<std::uint32_t, Space> root_at_, leaf_at_;  // current owned/halo slot -> plan root/leaf
  Buffer<std::uint32_t, Space> follow_scratch_;
  Buffer<std::uint32_t, Space> wall_roots_, wall_leaves_;  // the wall plan's slots (from wall 0)
  // Grain posing (pose_grains): the coupling's point table as uploaded, and the bodies.
  const GrainPointTable* table_of_ = nullptr;
  Buffer<Vec3, Space> tpl_pos_, tpl_ghost_, tpl_normal_;
  Buffer<std::uint32_t, Space> tpl_first_, grain_first_;
  Buffer<dem::RigidBody, Space> bodies_;
  ParticleSet<Host> grain_host_;      // grain_particles()
  Buffer<Vec3, Space> pos_at_build_;  // owned positions at the last rebuild, by root
  // Packed halo values in the execution space and their host stages, per field type.
  template <class T>
  struct HaloScratch {
    Buffer<T, Space> send, recv;
    HostStage<T, Space> send_host, recv_host;
  };
  HaloScratch<Real> scratch_real_;
  HaloScratch<Vec3> scratch_vec3_;
  template <class T>
  HaloScratch<T>& scratch() {
    static_assert(std::is_same_v<T, Real> || std::is_same_v<T, Vec3>, "halo fields: Real, Vec3");
    if constexpr (std::is_same_v<T, Real>) {
      return scratch_real_;
    } else {
      return scratch_vec3_;
    }
  }
  // Many ranks, grains: the source, all ranks' grain particle count, the owned ones; per grain
  // slot its tag (< n_grain_owned_: a root of the grain plan, else leaf tag - n_grain_owned_);
  // per tag the position and ghost node at the rebuild.
  GrainSource grain_source_;
  Index grain_total_ = 0, n_grain_owned_ = 0;
  bool grains_built_ = false;
  std::vector<std::uint32_t> grain_at_;
  std::vector<Vec3> grain_pos_at_build_, grain_ghost_at_build_;
  bool built_ = false;
  std::int64_t rebuilds_ = 0;
  std::vector<std::uint8_t> mine_host_;  // wall slots this rank owns (many ranks only)
  Index global_fluid_ = 0;
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
  PhaseClock<Space> clock_;
};

}  // namespace sphdem
