// DemSystem: broad phase, level-set narrow phase, contact history and stepping (dem_system.hpp).
#include "dem/dem_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "core/error.hpp"
#include "core/exec.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/cell_list.hpp"

namespace sphdem::dem {

namespace {

struct HistEntry {
  ContactKey key;
  Vec3 spring;
};

// Collects force on a body at point xc and its torque about the centroid x.
struct Load {
  Vec3 f, t;
  void add(const Vec3& force, const Vec3& xc, const Vec3& x) {
    f += force;
    t += cross(xc - x, force);
  }
};

// for_each on the host space, but a plain loop for short ranges: a parallel region costs more
// than a few bodies' work, and much more when the cores are shared.
constexpr Index kSerialBelow = 64;
// A pair's node lists stay valid while no node has moved by more than this many node spacings
// relative to the other grain (DemSystem::NodeList).
constexpr Real kNodeListSkin = Real(0.25);
// Dynamic schedule: contacts cluster (a pile's bottom grains, numbered first, have them all), so
// equal static chunks leave one thread idle. Each item writes only its own slot, so the result
// does not depend on the schedule. Chunks of n/(64 threads), at least 16: with chunks of 16 the
// threads wrote neighbouring slots of the same cache lines (a sphere pair's flag is one byte),
// and 2 threads stepped the 32k-sphere collapse no faster than one.
template <class F>
void run_each(Index n, const F& f) {
  if (n < kSerialBelow) {
    for (Index i = 0; i < n; ++i) f(i);
  } else {
    const Index chunk = std::max<Index>(16, n / (64 * Index(host_thread_count())));
#pragma omp parallel for schedule(dynamic, chunk)
    for (Index i = 0; i < n; ++i) f(i);
  }
}

Real wall_phi(const Wall& w, const Vec3& x) {
  return w.sdf ? w.sdf->phi(x - w.offset) : dot(x - w.point, w.normal);
}
Vec3 wall_normal(const Wall& w, const Vec3& x) {
  if (!w.sdf) return w.normal;
  const Vec3 g = w.sdf->grad(x - w.offset);
  const Real l = norm(g);
  return l > 0 ? g / l : Vec3(0, 0, 1);
}

}  // namespace

struct DemSystem::PairOut {
  Load a, b;
  Real max_d = 0;
  std::size_t lookups = 0, builds = 0;  // phi lookups and node lists remade
  std::vector<HistEntry> hist;
};

DemSystem::DemSystem(const DemParams& params) {
  set_params(params);
}

void DemSystem::set_params(const DemParams& p) {
  params_ = p;
  auto alpha = [](const ContactModel& m) {
    if (m.law != NormalLaw::kHertz) return Real(0);
    if (!(m.young > 0)) throw InputError("DEM: the Hertz law needs a positive Young's modulus");
    return hertz_damping_alpha(m.restitution);
  };
  for (const ContactModel* m : {&p.grain_grain, &p.grain_wall}) {
    if (!(m->restitution > 0 && m->restitution <= 1))
      throw InputError("DEM: restitution coefficient must be in (0, 1], got " +
                       std::to_string(m->restitution));
    if (!(m->mu >= 0)) throw InputError("DEM: friction coefficient must be >= 0");
    if (!(m->kn > 0) && !(m->young > 0))
      throw InputError("DEM: a contact model needs kn > 0 or a Young's modulus");
  }
  alpha_gg_ = alpha(p.grain_grain);
  alpha_gw_ = alpha(p.grain_wall);
  zeta_gg_ = damping_ratio_from_restitution(p.grain_grain.restitution);
  zeta_gw_ = damping_ratio_from_restitution(p.grain_wall.restitution);
}

int DemSystem::add_template(GrainTemplate t) {
  templates_.push_back(std::make_shared<const GrainTemplate>(std::move(t)));
  return int(templates_.size()) - 1;
}

std::size_t DemSystem::add_body(int shape, Real rho, Vec3 x, Quat q, Vec3 v, Vec3 w_world,
                                Motion motion) {
  if (shape < 0 || std::size_t(shape) >= templates_.size())
    throw InputError("DEM: unknown grain shape " + std::to_string(shape));
  if (!(rho > 0)) throw InputError("DEM: grain density must be positive");
  const GrainTemplate& t = *templates_[std::size_t(shape)];
  RigidBody b;
  b.x = x;
  b.q = normalize(q);
  b.v = v;
  b.w = rotate(conjugate(b.q), w_world);
  b.mass = rho * t.volume();
  b.inertia = rho * t.inertia_per_density();
  b.motion = motion;
  b.shape = shape;
  b.id = next_id_++;
  bodies_.push_back(b);
  force_.emplace_back();
  torque_.emplace_back();
  ext_force_.emplace_back();
  ext_torque_.emplace_back();
  acc_prev_.emplace_back();
  alpha_prev_.emplace_back();
  return bodies_.size() - 1;
}

int DemSystem::add_plane_wall(Vec3 point, Vec3 normal, Vec3 velocity) {
  const Real l = norm(normal);
  if (!(l > 0)) throw InputError("DEM: wall normal must be nonzero");
  Wall w;
  w.point = point;
  w.normal = normal / l;
  w.velocity = velocity;
  walls_.push_back(w);
  wall_force_.emplace_back();
  wall_impulse_.emplace_back();
  return int(walls_.size()) - 1;
}

int DemSystem::add_sdf_wall(geom::SdfPtr sdf, Vec3 velocity) {
  if (!sdf) throw InputError("DEM: null wall SDF");
  Wall w;
  w.sdf = std::move(sdf);
  w.velocity = velocity;
  walls_.push_back(w);
  wall_force_.emplace_back();
  wall_impulse_.emplace_back();
  return int(walls_.size()) - 1;
}

void DemSystem::set_wall_contact(int w, Real mu, Real restitution) {
  if (w < 0 || std::size_t(w) >= walls_.size())
    throw InputError("DEM: no wall " + std::to_string(w));
  if (!(mu < 0) && !(mu >= 0)) throw InputError("DEM: a wall's friction coefficient is NaN");
  if (restitution >= 0 && !(restitution > 0 && restitution <= 1))
    throw InputError("DEM: a wall's restitution coefficient must be in (0, 1], got " +
                     std::to_string(restitution));
  Wall& wall = walls_[std::size_t(w)];
  wall.mu = mu < 0 ? Real(-1) : mu;
  wall.restitution = restitution < 0 ? Real(-1) : restitution;
  if (wall.restitution > 0) {
    wall.zeta = damping_ratio_from_restitution(wall.restitution);
    wall.alpha = hertz_damping_alpha(wall.restitution);
  }
}

void DemSystem::set_external(std::size_t i, Vec3 f, Vec3 t) {
  ext_force_.at(i) = f;
  ext_torque_.at(i) = t;
}

Real DemSystem::kinetic_energy() const {
  Real e = 0;
  for (const RigidBody& b : bodies_)
    if (b.motion == Motion::kFree) e += dem::kinetic_energy(b);
  return e;
}

// The contact law of bodies a and b (b = a for a wall contact, wall = true).
PairLaw DemSystem::pair_law(const RigidBody& a, const RigidBody& b, bool wall) const {
  const ContactModel& m = wall ? params_.grain_wall : params_.grain_grain;
  const GrainTemplate& ta = *templates_[std::size_t(a.shape)];
  const GrainTemplate& tb = *templates_[std::size_t(b.shape)];
  PairLaw p;
  p.mu = m.mu;
  p.m_eff = wall ? contact_mass(a) : effective_mass(contact_mass(a), contact_mass(b));
  if (!(p.m_eff > 0)) p.m_eff = a.mass;
  const Real e_star =
      m.young > 0 ? (wall ? effective_young(m.young, m.poisson, m.wall_young, m.wall_poisson)
                          : effective_young(m.young, m.poisson, m.young, m.poisson))
                  : Real(0);
  const bool spheres = ta.is_sphere() && (wall || tb.is_sphere());
  const Real ra = ta.is_sphere() ? ta.radius() : Real(0.5) * ta.equivalent_diameter();
  const Real rb = tb.is_sphere() ? tb.radius() : Real(0.5) * tb.equivalent_diameter();
  p.r_star = wall ? ra : effective_radius(ra, rb);
  if (m.law == NormalLaw::kHertz && spheres) {
    p.law = NormalLaw::kHertz;
    p.k_hertz = hertz_constant(e_star, p.r_star);
    p.alpha = wall ? alpha_gw_ : alpha_gg_;
    p.g_star = wall ? effective_shear(m.young, m.poisson, m.wall_young, m.wall_poisson)
                    : effective_shear(m.young, m.poisson, m.young, m.poisson);
    p.tangential_damping = m.tangential_damping;
    return p;
  }
  p.law = NormalLaw::kLinear;
  p.kn = m.kn > 0 ? m.kn : linear_stiffness_from_young(e_star, p.r_star, m.stiffness_overlap);
  p.kt = m.kt > 0 ? m.kt : p.kn * 2 * (1 - m.poisson) / (2 - m.poisson);
  const Real zeta = wall ? zeta_gw_ : zeta_gg_;  // damping_ratio_from_restitution(m.restitution)
  p.cn = linear_damping_zeta(zeta, p.m_eff, p.kn);
  p.ct = m.tangential_damping ? linear_damping_zeta(zeta, p.m_eff, p.kt) : Real(0);
  return p;
}

PairLaw DemSystem::wall_law(const PairLaw& base, const Wall& w) const {
  PairLaw p = base;
  if (w.mu >= 0) p.mu = w.mu;
  if (w.restitution > 0) {
    if (p.law == NormalLaw::kHertz) {
      p.alpha = w.alpha;
    } else {
      p.cn = linear_damping_zeta(w.zeta, p.m_eff, p.kn);
      p.ct = params_.grain_wall.tangential_damping ? linear_damping_zeta(w.zeta, p.m_eff, p.kt)
                                                   : Real(0);
    }
  }
  return p;
}

const Vec3* DemSystem::find_spring(const ContactKey& k) const {
  const auto it = std::lower_bound(hist_keys_.begin(), hist_keys_.end(), k);
  if (it == hist_keys_.end() || !(*it == k)) return nullptr;
  return &hist_springs_[std::size_t(it - hist_keys_.begin())];
}

// A grain's bounding sphere does not change as it turns, so the pair list stays valid while no
// grain has moved more than half the skin: two grains then close the gap by at most one skin.
// The list leaves out pairs of two bodies that are not free, so a body whose motion flag changed
// (a fixed grain released, through bodies()) also makes it stale.
bool DemSystem::pairs_stale() const {
  if (pairs_built_at_.size() != bodies_.size()) return true;
  const Real lim2 = Real(0.25) * skin_ * skin_;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (!(norm2(bodies_[i].x - pairs_built_at_[i]) <= lim2)) return true;  // NaN: rebuild
    if (bodies_[i].motion != pairs_built_motion_[i]) return true;
  }
  return false;
}

std::size_t DemSystem::contact_count() const {
  std::size_t n = hist_keys_.size();
  for (std::uint8_t t : pair_touch_) n += t;
  return n;
}

void DemSystem::merged_history(std::vector<ContactKey>& keys, std::vector<Vec3>& springs) const {
  std::vector<HistEntry> all;
  all.reserve(hist_keys_.size());
  for (std::size_t k = 0; k < hist_keys_.size(); ++k)
    all.push_back({hist_keys_[k], hist_springs_[k]});
  const std::size_t n_hist = all.size();
  for (std::size_t pi = 0; pi < pair_touch_.size(); ++pi)
    if (pair_touch_[pi])
      all.push_back(
          {ContactKey{bodies_[pairs_[pi].first].id, bodies_[pairs_[pi].second].id, kCentreNode},
           pair_spring_[pi]});
  const auto by_key = [](const HistEntry& x, const HistEntry& y) { return x.key < y.key; };
  std::sort(all.begin() + std::ptrdiff_t(n_hist), all.end(), by_key);
  std::inplace_merge(all.begin(), all.begin() + std::ptrdiff_t(n_hist), all.end(), by_key);
  keys.resize(all.size());
  springs.resize(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    keys[k] = all[k].key;
    springs[k] = all[k].spring;
  }
}

std::vector<ContactKey> DemSystem::history_keys() const {
  std::vector<ContactKey> k;
  std::vector<Vec3> s;
  merged_history(k, s);
  return k;
}

std::vector<Vec3> DemSystem::history_springs() const {
  std::vector<ContactKey> k;
  std::vector<Vec3> s;
  merged_history(k, s);
  return s;
}

void DemSystem::find_pairs() {
  // The sphere pairs' springs leave the old list for the history, and come back into the new
  // list by key (the rest of the history is found by key every step).
  merged_history(hist_keys_, hist_springs_);
  const auto old_pairs = std::move(pairs_);
  auto old_lists = std::move(node_lists_);
  build_pair_list();
  // A pair that stays in the list keeps its node lists (both lists are in (i, j) order).
  node_lists_.clear();
  node_lists_.resize(pairs_.size());
  if (old_lists.size() == old_pairs.size()) {
    std::size_t o = 0;
    for (std::size_t pi = 0; pi < pairs_.size(); ++pi) {
      while (o < old_pairs.size() && old_pairs[o] < pairs_[pi]) ++o;
      if (o < old_pairs.size() && old_pairs[o] == pairs_[pi])
        node_lists_[pi] = std::move(old_lists[o]);
    }
  }
  pair_spring_.assign(pairs_.size(), Vec3());
  pair_touch_.assign(pairs_.size(), 0);
  for (std::size_t pi = 0; pi < pairs_.size(); ++pi) {
    const RigidBody& a = bodies_[pairs_[pi].first];
    const RigidBody& b = bodies_[pairs_[pi].second];
    if (!templates_[std::size_t(a.shape)]->is_sphere() ||
        !templates_[std::size_t(b.shape)]->is_sphere())
      continue;
    if (const Vec3* old = find_spring(ContactKey{a.id, b.id, kCentreNode})) {
      pair_spring_[pi] = *old;
      pair_touch_[pi] = 1;
    }
  }
  const std::size_t n = bodies_.size();
  by_body_off_.assign(n + 1, 0);
  for (const auto& [i, j] : pairs_) {
    ++by_body_off_[i + 1];
    ++by_body_off_[j + 1];
  }
  for (std::size_t i = 0; i < n; ++i) by_body_off_[i + 1] += by_body_off_[i];
  by_body_.resize(2 * pairs_.size());
  std::vector<std::uint32_t> fill(by_body_off_.begin(), by_body_off_.end() - 1);
  for (std::size_t pi = 0; pi < pairs_.size(); ++pi) {
    by_body_[fill[pairs_[pi].first]++] = std::uint32_t(2 * pi);
    by_body_[fill[pairs_[pi].second]++] = std::uint32_t(2 * pi + 1);
  }
}

void DemSystem::build_pair_list() {
  pairs_.clear();
  ++pair_builds_;
  pairs_built_at_.resize(bodies_.size());
  pairs_built_motion_.resize(bodies_.size());
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    pairs_built_at_[i] = bodies_[i].x;
    pairs_built_motion_[i] = bodies_[i].motion;
  }
  const Index n = Index(bodies_.size());
  // The skin: a quarter of the smallest bounding radius (LAMMPS-style Verlet list; the grains'
  // contact forces are unchanged, since a listed pair whose spheres do not touch adds nothing).
  Real rmin = std::numeric_limits<Real>::max();
  for (const RigidBody& b : bodies_)
    rmin = std::min(rmin, templates_[std::size_t(b.shape)]->bounding_radius());
  skin_ = n > 0 ? Real(0.25) * rmin : Real(0);
  if (n < 2) return;
  std::vector<Vec3> pos(static_cast<std::size_t>(n));
  std::vector<GlobalId> ids(static_cast<std::size_t>(n));
  std::vector<Real> rad(static_cast<std::size_t>(n));
  const Real inf = std::numeric_limits<Real>::max();
  Vec3 lo(inf, inf, inf), hi(-inf, -inf, -inf);
  Real rmax = 0;
  for (Index i = 0; i < n; ++i) {
    const RigidBody& b = bodies_[std::size_t(i)];
    if (!std::isfinite(b.x.x) || !std::isfinite(b.x.y) || !std::isfinite(b.x.z))
      throw StabilityError("DEM: grain " + std::to_string(b.id) +
                           " has a non-finite position at t = " + std::to_string(time_) +
                           " s (time step too large for the contact stiffness?)");
    pos[std::size_t(i)] = b.x;
    ids[std::size_t(i)] = GlobalId(i);
    rad[std::size_t(i)] = templates_[std::size_t(b.shape)]->bounding_radius();
    rmax = std::max(rmax, rad[std::size_t(i)]);
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], b.x[d]);
      hi[d] = std::max(hi[d], b.x[d]);
    }
  }
  if (n < kSerialBelow) {
    // Few bodies: all pairs, in (i, j) order like the cell-list path.
    for (Index i = 0; i < n; ++i)
      for (Index j = i + 1; j < n; ++j) {
        const RigidBody& a = bodies_[std::size_t(i)];
        const RigidBody& b = bodies_[std::size_t(j)];
        if (a.motion != Motion::kFree && b.motion != Motion::kFree) continue;
        const Real reach = rad[std::size_t(i)] + rad[std::size_t(j)] + skin_;
        if (norm2(a.x - b.x) < reach * reach)
          pairs_.emplace_back(std::uint32_t(i), std::uint32_t(j));
      }
    return;
  }
  Real cell = 2 * rmax + skin_;
  for (int d = 0; d < 3; ++d) {
    lo[d] -= cell;
    hi[d] += cell;
  }
  // Keep the cell count near the body count even when bodies are far apart.
  const Real vol = (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
  if (vol / (cell * cell * cell) > Real(8) * Real(n) + Real(64))
    cell = std::cbrt(vol / (Real(8) * Real(n) + Real(64)));
  const bool periodic[3] = {false, false, false};
  const CellGrid grid = make_cell_grid(3, lo, hi, cell, periodic);
  CellList<Host> cl;
  sort_cells(Host{}, grid, pos.data(), ids.data(), GlobalId(n), 0, n, cl);
  std::vector<Vec3> spos(static_cast<std::size_t>(n));
  std::vector<std::uint32_t> sidx(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    sidx[std::size_t(i)] = cl.order[std::size_t(i)];
    spos[std::size_t(i)] = pos[cl.order[std::size_t(i)]];
  }
  mark_cells(Host{}, grid, cl);
  const CellListView view = cl.view();
  std::vector<std::vector<std::uint32_t>> nb(static_cast<std::size_t>(n));
  const Real r2 = cell * cell;
  for_each(Host{}, n, [&](Index i) {
    const RigidBody& a = bodies_[std::size_t(i)];
    auto& out = nb[std::size_t(i)];
    for_each_neighbor(grid, view, spos.data(), a.x, r2, [&](Index j, const Vec3& rij, Real rr) {
      const std::uint32_t bj = sidx[std::size_t(j)];
      if (Index(bj) <= i) return;
      const RigidBody& b = bodies_[bj];
      if (a.motion != Motion::kFree && b.motion != Motion::kFree) return;
      const Real reach = rad[std::size_t(i)] + rad[bj] + skin_;
      if (rr < reach * reach) out.push_back(bj);
      (void)rij;
    });
    std::sort(out.begin(), out.end());
  });
  for (Index i = 0; i < n; ++i)
    for (std::uint32_t j : nb[std::size_t(i)]) pairs_.emplace_back(std::uint32_t(i), j);
}

void DemSystem::compute_forces(Real dt) {
  const std::size_t n = bodies_.size();
  // Velocities predicted to the force time: the leapfrog carries v at half steps, so the dashpots
  // see v + a_prev dt/2 (second order for the damping; see DemSystem::step).
  eval_.resize(n);
  run_each(Index(n), [&](Index ii) {
    const std::size_t i = std::size_t(ii);
    eval_[i] = bodies_[i];
    if (eval_[i].motion == Motion::kFree) {
      eval_[i].v += Real(0.5) * dt * acc_prev_[i];
      eval_[i].w += Real(0.5) * dt * alpha_prev_[i];
    }
  });
  if (pairs_stale()) find_pairs();
  // World positions of every grain's surface nodes, once per step (a pair would otherwise rotate
  // the same nodes again for every neighbour).
  node_begin_.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const GrainTemplate& t = *templates_[std::size_t(eval_[i].shape)];
    node_begin_[i + 1] = node_begin_[i] + (t.is_sphere() ? 0 : t.nodes().size());
  }
  world_nodes_.resize(node_begin_[n]);
  box_lo_.resize(n);
  box_hi_.resize(n);
  run_each(Index(n), [&](Index ii) {
    const std::size_t i = std::size_t(ii);
    const RigidBody& b = eval_[i];
    const GrainTemplate& t = *templates_[std::size_t(b.shape)];
    if (t.is_sphere()) {
      const Real r = t.radius();
      box_lo_[i] = b.x - Vec3(r, r, r);
      box_hi_[i] = b.x + Vec3(r, r, r);
      return;
    }
    Vec3* w = world_nodes_.data() + node_begin_[i];
    const auto& nodes = t.nodes();
    Vec3 lo = b.x, hi = b.x;
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      w[k] = b.x + rotate(b.q, nodes[k]);
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], w[k][d]);
        hi[d] = std::max(hi[d], w[k][d]);
      }
    }
    // The nodes sample the surface; pad by one node spacing so the box holds the whole grain.
    const Real pad = t.node_spacing();
    box_lo_[i] = lo - Vec3(pad, pad, pad);
    box_hi_[i] = hi + Vec3(pad, pad, pad);
  });
  const Index np = Index(pairs_.size());
  // Per-step scratch kept between calls (its vectors keep their capacity): allocating one history
  // vector per pair and per body every step cost more than the sphere contacts themselves.
  // The lambdas below run on OpenMP worker threads, where the name of a thread_local would mean
  // that worker's own (empty) instance: bind the calling thread's instances to references first.
  static thread_local std::vector<PairOut> pout_tl;
  static thread_local std::vector<std::vector<HistEntry>> whist_tl;
  static thread_local std::vector<std::vector<std::pair<std::uint32_t, Vec3>>> wload_tl;
  static thread_local std::vector<HistEntry> all_tl;
  std::vector<PairOut>& pout = pout_tl;
  std::vector<std::vector<HistEntry>>& whist = whist_tl;
  // Per body: (wall, the force of that wall's contacts on the body), for the walls it touches.
  std::vector<std::vector<std::pair<std::uint32_t, Vec3>>>& wload = wload_tl;
  std::vector<HistEntry>& all = all_tl;
  pout.resize(static_cast<std::size_t>(np));

  // ---- pairs of grains (each pair writes only its own slot) ----
  run_each(np, [&](Index pi) {
    PairOut& out = pout[std::size_t(pi)];
    out.a = Load{};
    out.b = Load{};
    out.max_d = 0;
    out.lookups = 0;
    out.builds = 0;
    out.hist.clear();
    const RigidBody& a = eval_[pairs_[std::size_t(pi)].first];
    const RigidBody& b = eval_[pairs_[std::size_t(pi)].second];
    const GrainTemplate& ta = *templates_[std::size_t(a.shape)];
    const GrainTemplate& tb = *templates_[std::size_t(b.shape)];
    if (ta.is_sphere() && tb.is_sphere()) {
      // Fast path: one analytic contact point on the line of centres. The law (masses, damping)
      // is worked out only for pairs in contact: most listed pairs are not.
      const Vec3 ab = a.x - b.x;
      const Real dist = norm(ab);
      const Real d = ta.radius() + tb.radius() - dist;
      if (!(d > 0) || !(dist > 0)) {
        pair_touch_[std::size_t(pi)] = 0;
        return;
      }
      const PairLaw law = pair_law(a, b, false);
      const Vec3 nrm = ab / dist;
      const Vec3 xc = b.x + nrm * (tb.radius() - Real(0.5) * d);
      const Vec3 v_rel = point_velocity(a, xc) - point_velocity(b, xc);
      Vec3& s = pair_spring_[std::size_t(pi)];
      if (!pair_touch_[std::size_t(pi)]) s = Vec3();
      const Vec3 f = contact_force(law, d, nrm, v_rel, dt, s, nullptr);
      pair_touch_[std::size_t(pi)] = 1;
      out.a.add(f, xc, a.x);
      out.b.add(-f, xc, b.x);
      out.max_d = d;
      return;
    }
    // Bounding boxes of the surfaces apart: no node of one can be inside the other.
    {
      const std::size_t ia = pairs_[std::size_t(pi)].first, ib = pairs_[std::size_t(pi)].second;
      for (int d = 0; d < 3; ++d)
        if (box_lo_[ia][d] > box_hi_[ib][d] || box_lo_[ib][d] > box_hi_[ia][d]) return;
    }
    const PairLaw law = pair_law(a, b, false);
    // Level-set master-slave test in both orders, each with weight 1/2.
    auto pass = [&](const RigidBody& m, const GrainTemplate& tm, std::size_t mi, const RigidBody& s,
                    const GrainTemplate& ts, Load& load_m, Load& load_s, NodeList& nl) {
      const geom::GridSdfView phi_s = ts.view();
      const Quat qs_inv = conjugate(s.q);
      const Real reach2 = ts.bounding_radius() * ts.bounding_radius();
      // World nodes are kept for level-set grains only: a sphere (against a level-set grain
      // here) places its own template's nodes in this pass, only those it tests (`place`).
      const Vec3* wn = world_nodes_.data() + node_begin_[mi];
      static thread_local std::vector<Vec3> sphere_nodes;
      const bool sphere = tm.is_sphere();
      if (sphere) {
        sphere_nodes.resize(tm.nodes().size());
        wn = sphere_nodes.data();
      }
      auto place = [&](std::size_t k) {
        if (sphere) sphere_nodes[k] = m.x + rotate(m.q, tm.nodes()[k]);
      };
      const std::size_t si = mi == pairs_[std::size_t(pi)].first ? pairs_[std::size_t(pi)].second
                                                                 : pairs_[std::size_t(pi)].first;
      const Vec3 slo = box_lo_[si], shi = box_hi_[si];
      const Real rs = ts.bounding_radius();
      // One node (y: its position in s's frame) against s: the contact test and force of a full
      // scan. Returns phi at y; when the cheap tests (s's box and bounding sphere) rule the node
      // out, phi is looked up only if `need_phi`, and +inf returned otherwise.
      auto node = [&](std::size_t k, const Vec3& y, bool need_phi) {
        const Vec3& x = wn[k];
        const bool near = !(x.x < slo.x || x.x > shi.x || x.y < slo.y || x.y > shi.y ||
                            x.z < slo.z || x.z > shi.z || norm2(x - s.x) > reach2);
        if (!near && !need_phi) return std::numeric_limits<Real>::infinity();
        ++out.lookups;
        const Real ph = geom::grid_phi(phi_s, y);
        if (!near || !(ph < 0)) return ph;
        const Vec3 nb = geom::grid_normal(phi_s, y);
        if (norm2(nb) == 0) return ph;
        const Vec3 nrm = rotate(s.q, nb);
        const Real d = -ph;
        const Vec3 v_rel = point_velocity(m, x) - point_velocity(s, x);
        const ContactKey key{m.id, s.id, std::uint32_t(k)};
        const Vec3* old = find_spring(key);
        Vec3 spring = old ? *old : Vec3();
        const Real inv_m = inverse_point_mass(m, x, nrm) + inverse_point_mass(s, x, nrm);
        const Vec3 f = Real(0.5) * contact_force(at_point_mass(law, Real(1) / inv_m), d, nrm, v_rel,
                                                 dt, spring, nullptr);
        load_m.add(f, x, m.x);
        load_s.add(-f, x, s.x);
        out.max_d = std::max(out.max_d, d);
        out.hist.push_back({key, spring});
        return ph;
      };
      // The node list stays valid while no node of m has moved by more than `skin` in s's frame
      // since it was made: |dy| <= |dt_rel| + 2 sin(theta/2) |p| for a relative turn theta. A
      // node left out had phi >= band = L skin then (L: phi's Lipschitz bound), so phi >= 0 now
      // and it cannot touch: the list holds every node a full scan would find in contact.
      const Real skin = kNodeListSkin * tm.node_spacing();
      const Real band = ts.phi_lipschitz() * skin * Real(1.000001);  // margin for round-off
      const Quat qrel = multiply(qs_inv, m.q);
      const Vec3 trel = rotate(qs_inv, m.x - s.x);
      if (node_lists_on_ && nl.valid && nl.m_id == m.id && nl.s_id == s.id &&
          nl.m_shape == m.shape && nl.s_shape == s.shape) {
        const Quat dq = multiply(qrel, conjugate(nl.q0));
        const Real moved =
            norm(trel - nl.t0) +
            2 * std::sqrt(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z) * tm.bounding_radius();
        if (moved <= skin) {
          for (std::uint32_t k : nl.nodes) {
            place(k);
            node(k, rotate(qs_inv, wn[k] - s.x), false);
          }
          return;
        }
      }
      if (sphere)
        for (std::size_t k = 0; k < sphere_nodes.size(); ++k) place(k);
      // Full scan. With node lists it also makes the list: every node within `band` of s. Outside
      // s's grid box phi >= phi_box_min + the distance to the box, so a node (or an octant) that
      // far out is skipped; without lists the octants and nodes beyond s's bounding sphere or
      // box are skipped (they cannot touch now).
      const bool build = node_lists_on_;
      const Vec3 glo = ts.grid_lo(), ghi = ts.grid_hi();
      const Real box_reach = ts.phi_box_min() >= 0 ? band : std::numeric_limits<Real>::max();
      auto box_dist = [&](const Vec3& y) {
        const Vec3 c(std::clamp(y.x, glo.x, ghi.x), std::clamp(y.y, glo.y, ghi.y),
                     std::clamp(y.z, glo.z, ghi.z));
        return norm(y - c);
      };
      if (build) {
        nl.nodes.clear();
        nl.q0 = qrel;
        nl.t0 = trel;
        nl.valid = true;
        nl.m_id = m.id;
        nl.s_id = s.id;
        nl.m_shape = m.shape;
        nl.s_shape = s.shape;
        ++out.builds;
      }
      const std::uint32_t* order = tm.node_order().data();
      for (const NodeGroup& g : tm.node_groups()) {
        const Vec3 gc = m.x + rotate(m.q, g.centre);
        if (build) {
          if (box_dist(rotate(qs_inv, gc - s.x)) > g.radius + box_reach) continue;
        } else {
          // An octant whose nodes all lie beyond the other grain's bounding sphere or box is
          // skipped (most of a grain faces away from any one neighbour).
          const Real reach = g.radius + rs;
          if (norm2(gc - s.x) > reach * reach) continue;
          if (gc.x + g.radius < slo.x || gc.x - g.radius > shi.x || gc.y + g.radius < slo.y ||
              gc.y - g.radius > shi.y || gc.z + g.radius < slo.z || gc.z - g.radius > shi.z)
            continue;
        }
        for (std::uint32_t gi = g.begin; gi < g.end; ++gi) {
          const std::size_t k = order[gi];
          const Vec3& x = wn[k];
          if (!build && (x.x < slo.x || x.x > shi.x || x.y < slo.y || x.y > shi.y || x.z < slo.z ||
                         x.z > shi.z || norm2(x - s.x) > reach2))
            continue;
          const Vec3 y = rotate(qs_inv, x - s.x);
          if (build && box_dist(y) > box_reach) continue;
          const Real ph = node(k, y, build);
          if (build && ph < band) nl.nodes.push_back(std::uint32_t(k));
        }
      }
    };
    std::array<NodeList, 2>& lists = node_lists_[std::size_t(pi)];
    pass(a, ta, pairs_[std::size_t(pi)].first, b, tb, out.a, out.b, lists[0]);
    pass(b, tb, pairs_[std::size_t(pi)].second, a, ta, out.b, out.a, lists[1]);
  });

  // ---- per-body gather: walls, then the body's pairs in pair order ----
  whist.resize(n);
  wload.resize(n);
  std::vector<Real> wmax(n, Real(0));
  run_each(Index(n), [&](Index ii) {
    const std::size_t i = std::size_t(ii);
    const RigidBody& b = eval_[i];
    Load load;
    whist[i].clear();
    wload[i].clear();
    if (b.motion == Motion::kFree) {
      const GrainTemplate& t = *templates_[std::size_t(b.shape)];
      PairLaw base;
      bool have_law = false;  // worked out at the first wall within reach
      for (std::size_t w = 0; w < walls_.size(); ++w) {
        const Wall& wall = walls_[w];
        if (!wall.active) continue;  // an opened gate
        const Real phc = wall_phi(wall, b.x);
        if (phc > t.bounding_radius()) continue;
        if (!have_law) {
          base = pair_law(b, b, true);
          have_law = true;
        }
        const PairLaw law = wall_law(base, wall);
        const GlobalId wkey = kWallKeyBit | GlobalId(w);
        const Vec3 f_before = load.f;
        // Records this wall's share of the body's load (the reaction on the wall is its negative).
        auto note_wall = [&]() {
          const Vec3 d = load.f - f_before;
          if (d.x != 0 || d.y != 0 || d.z != 0) wload[i].push_back({std::uint32_t(w), d});
        };
        if (t.is_sphere()) {
          const Real d = t.radius() - phc;
          if (!(d > 0)) continue;
          const Vec3 nrm = wall_normal(wall, b.x);
          const Vec3 xc = b.x - nrm * (t.radius() - Real(0.5) * d);
          const Vec3 v_rel = point_velocity(b, xc) - wall.velocity;
          const ContactKey key{b.id, wkey, kCentreNode};
          const Vec3* old = find_spring(key);
          Vec3 s = old ? *old : Vec3();
          load.add(contact_force(law, d, nrm, v_rel, dt, s, nullptr), xc, b.x);
          wmax[i] = std::max(wmax[i], d);
          whist[i].push_back({key, s});
          note_wall();
          continue;
        }
        const std::size_t nn = t.nodes().size();
        const Vec3* wn = world_nodes_.data() + node_begin_[i];
        for (std::size_t k = 0; k < nn; ++k) {
          const Vec3& x = wn[k];
          const Real ph = wall_phi(wall, x);
          if (!(ph < 0)) continue;
          const Vec3 nrm = wall_normal(wall, x);
          const Vec3 v_rel = point_velocity(b, x) - wall.velocity;
          const ContactKey key{b.id, wkey, std::uint32_t(k)};
          const Vec3* old = find_spring(key);
          Vec3 s = old ? *old : Vec3();
          const PairLaw lp = at_point_mass(law, Real(1) / inverse_point_mass(b, x, nrm));
          load.add(contact_force(lp, -ph, nrm, v_rel, dt, s, nullptr), x, b.x);
          wmax[i] = std::max(wmax[i], -ph);
          whist[i].push_back({key, s});
        }
        note_wall();
      }
    }
    for (std::uint32_t e = by_body_off_[i]; e < by_body_off_[i + 1]; ++e) {
      const std::uint32_t code = by_body_[e];
      const Load& l = (code & 1u) == 0 ? pout[code >> 1].a : pout[code >> 1].b;
      load.f += l.f;
      load.t += l.t;
    }
    force_[i] = load.f;
    torque_[i] = load.t;
  });

  // ---- new contact history, sorted by key ----
  all.clear();
  max_overlap_ = 0;
  phi_lookups_ = 0;
  for (const PairOut& p : pout) {
    all.insert(all.end(), p.hist.begin(), p.hist.end());
    max_overlap_ = std::max(max_overlap_, p.max_d);
    phi_lookups_ += p.lookups;
    node_list_builds_ += p.builds;
  }
  for (Vec3& f : wall_force_) f = Vec3();
  for (std::size_t i = 0; i < n; ++i) {
    all.insert(all.end(), whist[i].begin(), whist[i].end());
    max_overlap_ = std::max(max_overlap_, wmax[i]);
    for (const auto& [w, f] : wload[i]) wall_force_[w] -= f;  // fixed order: bodies, then walls
  }
  std::sort(all.begin(), all.end(),
            [](const HistEntry& x, const HistEntry& y) { return x.key < y.key; });
  hist_keys_.resize(all.size());
  hist_springs_.resize(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    hist_keys_[k] = all[k].key;
    hist_springs_[k] = all[k].spring;
  }
}

void DemSystem::step(Real dt) {
  compute_forces(dt);
  for (std::size_t w = 0; w < walls_.size(); ++w) wall_impulse_[w] += dt * wall_force_[w];
  wall_impulse_time_ += dt;
  const Vec3 g = params_.gravity;
  run_each(Index(bodies_.size()), [&](Index i) {
    const std::size_t k = std::size_t(i);
    RigidBody& b = bodies_[k];
    const Vec3 v0 = b.v, w0 = b.w;
    integrate_body(b, force_[k] + ext_force_[k], torque_[k] + ext_torque_[k], g, dt);
    acc_prev_[k] = (b.v - v0) / dt;
    alpha_prev_[k] = (b.w - w0) / dt;
  });
  for (Wall& w : walls_) {
    w.point += dt * w.velocity;
    w.offset += dt * w.velocity;
  }
  time_ += dt;
}

DemState DemSystem::state() const {
  DemState s;
  s.time = time_;
  s.bodies = bodies_;
  s.acc_prev = acc_prev_;
  s.alpha_prev = alpha_prev_;
  for (const Wall& w : walls_) {
    s.wall_point.push_back(w.point);
    s.wall_offset.push_back(w.offset);
  }
  merged_history(s.keys, s.springs);
  s.ext_force = ext_force_;
  s.ext_torque = ext_torque_;
  s.pairs_built_at = pairs_built_at_;
  for (Motion m : pairs_built_motion_) s.pairs_built_motion.push_back(std::int32_t(m));
  s.wall_impulse = wall_impulse_;
  s.wall_impulse_time = wall_impulse_time_;
  return s;
}

Vec3 DemSystem::wall_mean_force(int w) const {
  const Vec3& j = wall_impulse_.at(std::size_t(w));
  return wall_impulse_time_ > 0 ? j / wall_impulse_time_ : Vec3();
}

void DemSystem::reset_wall_impulse() {
  for (Vec3& j : wall_impulse_) j = Vec3();
  wall_impulse_time_ = 0;
}

void DemSystem::restore(const DemState& s) {
  if (s.bodies.size() != bodies_.size() || s.wall_point.size() != walls_.size() ||
      s.acc_prev.size() != bodies_.size() || s.keys.size() != s.springs.size())
    throw InputError("DEM state: " + std::to_string(s.bodies.size()) + " bodies and " +
                     std::to_string(s.wall_point.size()) + " walls, the scene has " +
                     std::to_string(bodies_.size()) + " and " + std::to_string(walls_.size()));
  time_ = s.time;
  bodies_ = s.bodies;
  pairs_built_at_.clear();  // the pair list is rebuilt from the restored positions
  pairs_.clear();           // and its springs come from the restored history
  node_lists_.clear();
  pair_spring_.clear();
  pair_touch_.clear();
  acc_prev_ = s.acc_prev;
  alpha_prev_ = s.alpha_prev;
  for (std::size_t i = 0; i < walls_.size(); ++i) {
    walls_[i].point = s.wall_point[i];
    walls_[i].offset = s.wall_offset[i];
  }
  hist_keys_ = s.keys;
  hist_springs_ = s.springs;
  // The optional arrays are either absent (an older checkpoint) or one entry per body.
  for (std::size_t n : {s.ext_force.size(), s.ext_torque.size(), s.pairs_built_at.size(),
                        s.pairs_built_motion.size()})
    if (n != 0 && n != bodies_.size())
      throw InputError("DEM state: an array of " + std::to_string(n) + " entries for " +
                       std::to_string(bodies_.size()) + " bodies");
  if (!s.wall_impulse.empty() && s.wall_impulse.size() != walls_.size())
    throw InputError("DEM state: " + std::to_string(s.wall_impulse.size()) + " wall impulses for " +
                     std::to_string(walls_.size()) + " walls");
  wall_impulse_ = s.wall_impulse.empty() ? std::vector<Vec3>(walls_.size()) : s.wall_impulse;
  wall_impulse_time_ = s.wall_impulse.empty() ? Real(0) : s.wall_impulse_time;
  const bool kept = !s.ext_force.empty() && !s.ext_torque.empty();
  ext_force_ = kept ? s.ext_force : std::vector<Vec3>(bodies_.size());
  ext_torque_ = kept ? s.ext_torque : std::vector<Vec3>(bodies_.size());
  if (!s.pairs_built_at.empty() && !s.pairs_built_motion.empty()) {
    // The list as it was built: from the bodies where they were then, then back to now.
    std::vector<RigidBody> now = bodies_;
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      bodies_[i].x = s.pairs_built_at[i];
      bodies_[i].motion = Motion(s.pairs_built_motion[i]);
    }
    find_pairs();
    bodies_ = std::move(now);
  }
}

Real DemSystem::time_step() const {
  Real dt = std::numeric_limits<Real>::max();
  for (const RigidBody& b : bodies_) {
    if (b.motion != Motion::kFree) continue;
    for (int wall = 0; wall < 2; ++wall) {
      const PairLaw p = pair_law(b, b, wall == 1);
      // Grain-grain: two equal grains, m* = m/2; grain-wall: m* = m.
      const Real m_eff = wall ? b.mass : Real(0.5) * b.mass;
      Real tc;
      if (p.law == NormalLaw::kHertz) {
        const Real e_star = Real(0.75) * p.k_hertz / std::sqrt(p.r_star);
        tc = hertz_contact_time(e_star, p.r_star, m_eff, params_.reference_speed);
      } else {
        tc = contact_time(m_eff, p.kn * std::max(Real(1), params_.nodes_per_contact));
      }
      dt = std::min(dt, tc / Real(50));
    }
  }
  return dt;
}

}  // namespace sphdem::dem
