#include "coupling/grain_boundary.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "geometry/grid_sdf.hpp"

namespace sphdem {

GrainBoundaryShape make_grain_boundary(const dem::GrainTemplate& t, Real dp, Real depth) {
  GrainBoundaryShape out;
  const geom::GridSdfView g = t.view();
  Vec3 hi;
  for (int a = 0; a < 3; ++a) hi[a] = g.lo[a] + g.spacing * Real(g.n[a] - 1);
  long i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    i0[a] = long(std::ceil(g.lo[a] / dp - Real(0.5)));
    i1[a] = long(std::floor(hi[a] / dp - Real(0.5)));
  }
  for (long k = i0[2]; k <= i1[2]; ++k)
    for (long j = i0[1]; j <= i1[1]; ++j)
      for (long i = i0[0]; i <= i1[0]; ++i) {
        const Vec3 x((Real(i) + Real(0.5)) * dp, (Real(j) + Real(0.5)) * dp,
                     (Real(k) + Real(0.5)) * dp);
        const Real phi = geom::grid_phi(g, x);
        if (!(phi < 0 && phi > -depth)) continue;
        const Vec3 n = geom::grid_normal(g, x);
        out.pos.push_back(x);
        out.ghost.push_back(x - n * (Real(2) * phi));
        out.normal.push_back(n);
      }
  return out;
}

GrainCoupling::GrainCoupling(const dem::DemSystem& sys, Real dp, Real depth, Real rho0, int dim)
    : mass_(rho0 * std::pow(dp, Real(dim))), rho0_(rho0) {
  if (dim != 3) throw InputError("grains in a fluid need dimension: 3");
  int nt = 0;
  for (const dem::RigidBody& b : sys.bodies()) nt = std::max(nt, b.shape + 1);
  for (int t = 0; t < nt; ++t) {
    shapes_.push_back(make_grain_boundary(sys.shape(t), dp, depth));
    Real r2 = 0;
    for (std::size_t k = 0; k < shapes_.back().pos.size(); ++k)
      r2 = std::max({r2, norm2(shapes_.back().pos[k]), norm2(shapes_.back().ghost[k])});
    reach_.push_back(std::sqrt(r2));
  }
  first_point_.push_back(0);
  for (const dem::RigidBody& b : sys.bodies())
    first_point_.push_back(first_point_.back() + Index(shapes_[std::size_t(b.shape)].pos.size()));
  for (const GrainBoundaryShape& s : shapes_) {
    table_.template_first.push_back(std::uint32_t(table_.pos.size()));
    table_.pos.insert(table_.pos.end(), s.pos.begin(), s.pos.end());
    table_.ghost.insert(table_.ghost.end(), s.ghost.begin(), s.ghost.end());
    table_.normal.insert(table_.normal.end(), s.normal.begin(), s.normal.end());
  }
  for (std::size_t g = 0; g + 1 < first_point_.size(); ++g)
    table_.grain_first.push_back(std::uint32_t(first_point_[g]));
}

void GrainCoupling::locate(std::size_t k, std::size_t& grain, std::size_t& point) const {
  const auto it = std::upper_bound(first_point_.begin(), first_point_.end(), Index(k));
  grain = std::size_t(it - first_point_.begin()) - 1;
  point = k - std::size_t(first_point_[grain]);
}

void GrainCoupling::pose(ParticleSet<Host>& ps, std::size_t i, const dem::RigidBody& body,
                         std::size_t p) const {
  const GrainBoundaryShape& s = shapes_[std::size_t(body.shape)];
  pose_grain_point(body, s.pos[p], s.ghost[p], s.normal[p], ps.pos[i], ps.ghost[i], ps.normal[i],
                   ps.vel[i]);
  ps.ghost_alt[i] = ps.ghost[i];
}

Index GrainCoupling::append(ParticleSet<Host>& ps, const dem::DemSystem& sys) {
  GlobalId max_id = 0;
  for (Index i = 0; i < ps.size(); ++i) max_id = std::max(max_id, ps.id[std::size_t(i)]);
  return append(ps, sys, max_id + 1);
}

Index GrainCoupling::append(ParticleSet<Host>& ps, const dem::DemSystem& sys, GlobalId first_id) {
  // Fluid inside a grain goes.
  std::vector<char> keep(std::size_t(ps.size()), 1);
  Index removed = 0;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    for (const dem::RigidBody& b : sys.bodies()) {
      const dem::GrainTemplate& t = sys.shape(b.shape);
      const Vec3 r = ps.pos[std::size_t(i)] - b.x;
      if (norm2(r) > t.bounding_radius() * t.bounding_radius() * Real(1.5)) continue;
      if (geom::grid_phi(t.view(), rotate(conjugate(b.q), r)) < 0) {
        keep[std::size_t(i)] = 0;
        ++removed;
        break;
      }
    }
  }
  first_id_ = first_id;
  table_.first_id = first_id_;
  // Compact in place (fluid first, so every later slot moves down by the fluid removed).
  const Index n_old = ps.size() - removed;
  ps.for_each_field([&](const char*, auto& f) {
    Index to = 0;
    for (Index i = 0; i < ps.size(); ++i)
      if (keep[std::size_t(i)]) f[std::size_t(to++)] = f[std::size_t(i)];
  });
  ps.n_fluid -= removed;
  ps.resize(n_old + particle_count());
  ps.n_grain += particle_count();
  const Index at = n_old;
  for (std::size_t g = 0; g + 1 < first_point_.size(); ++g)
    for (Index k = first_point_[g]; k < first_point_[g + 1]; ++k) {
      const std::size_t i = std::size_t(at + k);
      ps.id[i] = first_id_ + GlobalId(k);
      ps.mass[i] = mass_;
      ps.rho[i] = ps.rho_prev[i] = rho0_;
      ps.press[i] = 0;
      ps.body[i] = kGrainBodyBase - std::int32_t(g);
    }
  place(ps, sys);
  return removed;
}

ParticleSet<Host> GrainCoupling::generate(const dem::DemSystem& sys, const Vec3& lo,
                                          const Vec3& hi) const {
  ParticleSet<Host> out;
  for (std::size_t g = 0; g < sys.bodies().size(); ++g) {
    const dem::RigidBody& b = sys.bodies()[g];
    Real d2 = 0;  // the box's distance from the centroid
    for (int a = 0; a < 3; ++a) {
      const Real d = b.x[a] < lo[a] ? lo[a] - b.x[a] : (b.x[a] > hi[a] ? b.x[a] - hi[a] : 0);
      d2 += d * d;
    }
    const Real r = reach_[std::size_t(b.shape)];
    if (d2 > r * r) continue;
    const Index n0 = out.n_grain, np = first_point_[g + 1] - first_point_[g];
    out.n_grain += np;
    out.resize(out.n_grain);
    for (Index k = 0; k < np; ++k) {
      const std::size_t i = std::size_t(n0 + k);
      out.id[i] = first_id_ + GlobalId(first_point_[g] + k);
      out.mass[i] = mass_;
      out.rho[i] = out.rho_prev[i] = rho0_;
      out.press[i] = 0;
      out.body[i] = kGrainBodyBase - std::int32_t(g);
      pose(out, i, b, std::size_t(k));
    }
  }
  return out;
}

void GrainCoupling::place(ParticleSet<Host>& ps, const dem::DemSystem& sys, bool every) const {
  // The solver sorts the grain range by cell: grain slots are those whose body field marks a
  // grain.
  Index seen = 0;
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    if (!is_grain_body(ps.body[std::size_t(i)])) continue;
    const std::size_t k = std::size_t(ps.id[std::size_t(i)] - first_id_);
    if (ps.id[std::size_t(i)] < first_id_ || k >= std::size_t(particle_count()))
      throw std::logic_error("GrainCoupling::place: slot " + std::to_string(i) + " has id " +
                             std::to_string(ps.id[std::size_t(i)]) + ", first grain id " +
                             std::to_string(first_id_));
    ++seen;
    std::size_t g = 0, p = 0;
    locate(k, g, p);
    pose(ps, std::size_t(i), sys.bodies()[g], p);
  }
  if (every && seen != particle_count())
    throw std::logic_error("GrainCoupling::place: " + std::to_string(seen) + " grain slots for " +
                           std::to_string(particle_count()) + " particles");
}

void GrainCoupling::loads(const ParticleSet<Host>& ps, const dem::DemSystem& sys,
                          std::vector<Vec3>& force, std::vector<Vec3>& torque,
                          const std::uint8_t* mine) const {
  force.assign(sys.bodies().size(), Vec3());
  torque.assign(sys.bodies().size(), Vec3());
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    if (!is_grain_body(ps.body[std::size_t(i)])) continue;
    if (mine && !mine[i - ps.wall_begin()]) continue;
    const std::uint32_t g = std::uint32_t(kGrainBodyBase - ps.body[std::size_t(i)]);
    const Vec3 f = ps.acc[std::size_t(i)] * ps.mass[std::size_t(i)];
    force[g] += f;
    torque[g] += cross(ps.pos[std::size_t(i)] - sys.bodies()[g].x, f);
  }
}

}  // namespace sphdem
