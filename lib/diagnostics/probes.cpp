#include "diagnostics/probes.hpp"

#include <cmath>
#include <limits>

#include "sph/kernel.hpp"

namespace sphdem {

namespace {
// Shepard-normalised kernel interpolation at a point of the fluid field value(j).
template <class T, class F>
T shepard(const ParticleSet<Host>& ps, const StepParams& p, const Vec3& point, F&& value) {
  T num{};
  Real den = 0;
  for (Index j = 0; j < ps.n_fluid; ++j) {
    const Vec3 d = p.grid.separation(point, ps.pos[j]);
    const Real r2 = norm2(d);
    if (r2 >= p.radius2) continue;
    const Real w = kernel_w(p.kernel, std::sqrt(r2)) * ps.mass[j] / ps.rho[j];
    num += value(j) * w;
    den += w;
  }
  return den > 0 ? num / den : T{};
}
}  // namespace

Real probe_pressure(const ParticleSet<Host>& ps, const StepParams& p, const Vec3& point) {
  return shepard<Real>(ps, p, point, [&](Index j) { return ps.press[j]; });
}

Vec3 probe_velocity(const ParticleSet<Host>& ps, const StepParams& p, const Vec3& point) {
  return shepard<Vec3>(ps, p, point, [&](Index j) { return ps.vel[j]; });
}

Real probe_surface_height(const ParticleSet<Host>& ps, const StepParams& p, Real x, Real y) {
  return probe_surface_height(ps, p, x, y, p.g_mag > 0 ? -p.g_hat : Vec3(0, 0, 1));
}

ChannelFlow probe_channel_flow(const ParticleSet<Host>& ps, const StepParams& p,
                               const Vec3& gravity, Real x, Real y) {
  ChannelFlow c;
  const Real d = probe_surface_height(ps, p, x, y, Vec3(0, 0, 1));
  if (!std::isfinite(d) || d <= 0) return c;
  c.depth = d;
  Real sum = 0;
  int n = 0;
  for (Index j = 0; j < ps.n_fluid; ++j) {
    const Vec3 d = p.grid.separation(ps.pos[j], Vec3(x, y, ps.pos[j].z));  // periodic images
    if (d.x * d.x + d.y * d.y < p.h * p.h) {
      sum += ps.vel[j].x;
      ++n;
    }
  }
  if (n > 0) c.u = sum / Real(n);
  const Real g_n = std::abs(gravity.z);
  if (g_n > 0) c.froude = c.u / std::sqrt(g_n * c.depth);
  return c;
}

Real probe_surface_height(const ParticleSet<Host>& ps, const StepParams& p, Real x, Real y,
                          const Vec3& up) {
  const Vec3 base(x, p.dim == 2 ? Real(0) : y, 0);
  // Particles near the line, and the range of heights to scan.
  std::vector<Index> near;
  Real top = -std::numeric_limits<Real>::infinity(), bottom = -top;
  const Real reach = Real(2) * p.h;
  // Separations through the periodic images: a gauge within 2h of a periodic side sees the fluid
  // across it (it read low there before: the Shepard sum missed those neighbours).
  for (Index j = 0; j < ps.n_fluid; ++j) {
    const Vec3 d = p.grid.separation(ps.pos[j], base);
    const Vec3 lateral = d - up * dot(d, up);
    if (p.dim == 2 && std::abs(lateral.x) >= reach) continue;
    if (p.dim == 3 && norm(lateral) >= reach) continue;
    near.push_back(j);
    top = std::max(top, dot(d, up));
    bottom = std::min(bottom, dot(d, up));
  }
  if (near.empty()) return std::numeric_limits<Real>::quiet_NaN();
  // The surface is where the Shepard sum of the particle volumes falls to one half: scan down in
  // steps of dp/8 to the first sample at or above one half, then bisect between it and the sample
  // above (returning the sample itself left a bias of up to dp/8, always downwards).
  auto shepard = [&](Real s) {
    const Vec3 q = base + up * s;
    Real sum = 0;
    for (Index j : near) {
      const Real r2 = norm2(p.grid.separation(q, ps.pos[j]));
      if (r2 < p.radius2) sum += kernel_w(p.kernel, std::sqrt(r2)) * ps.mass[j] / ps.rho[j];
    }
    return sum;
  };
  const Real step = p.dp / 8;
  for (Real s = top + reach; s >= bottom - reach; s -= step) {
    if (shepard(s) < Real(0.5)) continue;
    Real lo = s, hi = s + step;  // shepard(lo) >= 1/2 > shepard(hi)
    for (int it = 0; it < 30 && hi - lo > p.dp * Real(1e-6); ++it) {
      const Real mid = Real(0.5) * (lo + hi);
      (shepard(mid) >= Real(0.5) ? lo : hi) = mid;
    }
    return Real(0.5) * (lo + hi);
  }
  return std::numeric_limits<Real>::quiet_NaN();
}

Real probe_front(const ParticleSet<Host>& ps, const Vec3& origin, const Vec3& dir) {
  const Real n = norm(dir);
  const Vec3 u = n > 0 ? dir / n : Vec3(1, 0, 0);
  Real best = -std::numeric_limits<Real>::infinity();
  for (Index j = 0; j < ps.n_fluid; ++j) best = std::max(best, dot(ps.pos[j] - origin, u));
  return best;
}

Vec3 probe_solid_force(const ParticleSet<Host>& ps, int solid_index) {
  Vec3 f;
  for (Index i = ps.wall_begin(); i < ps.size(); ++i)
    if (ps.body[i] == solid_index) f += ps.acc[i] * ps.mass[i];
  return f;
}

Energy probe_energy(const ParticleSet<Host>& ps, const Vec3& gravity) {
  Energy e;
  for (Index j = 0; j < ps.n_fluid; ++j) {
    e.kinetic += Real(0.5) * ps.mass[j] * norm2(ps.vel[j]);
    e.potential -= ps.mass[j] * dot(gravity, ps.pos[j]);
    e.momentum += ps.mass[j] * ps.vel[j];
  }
  return e;
}

}  // namespace sphdem
