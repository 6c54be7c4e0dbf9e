#include "scene/barrier.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "geometry/sdf.hpp"

namespace sphdem {

bool apply_barrier_preset(Barrier& b, const std::string& preset) {
  if (preset.size() != 3 || (preset[0] != 'P' && preset[0] != 'V')) return false;
  if (preset.substr(1) != "00" && preset.substr(1) != "30" && preset.substr(1) != "45")
    return false;
  if (preset == "V00") return false;
  b.preset = preset;
  b.layout = preset[0];
  b.angle_deg = Real(std::stoi(preset.substr(1)));
  return true;
}

std::vector<BarrierWall> barrier_walls(const Barrier& b) {
  std::vector<BarrierWall> w;
  const int n = b.walls;
  const Real pitch = (b.y_hi - b.y_lo) / Real(n);
  const Real a = b.angle_deg * kPi / Real(180);
  const Real y_mid = Real(0.5) * (b.y_lo + b.y_hi);
  for (int k = 0; k < n; ++k) {
    BarrierWall wall;
    const Real y = b.y_lo + (Real(k) + Real(0.5)) * pitch;
    Real x = b.x;
    wall.angle = a;
    if (b.layout == 'V') {
      const Real off = y - y_mid;  // signed distance from the centre line
      const bool left = off < -Real(1e-12) * pitch;
      wall.angle = left ? a : -a;
      // The arms trail downstream of the apex (apex upstream) or lead it.
      x += (b.apex_upstream ? Real(1) : Real(-1)) * std::abs(off) * std::tan(a);
    }
    wall.center = Vec3(x, y, b.floor_z);
    w.push_back(wall);
  }
  return w;
}

std::vector<Solid> barrier_solids(const Barrier& b) {
  std::vector<Solid> out;
  const auto walls = barrier_walls(b);
  const Vec3 half(Real(0.5) * b.thickness, Real(0.5) * b.width, 0);
  for (std::size_t k = 0; k < walls.size(); ++k) {
    Solid s;
    s.name = "barrier_" + std::to_string(k + 1);
    auto box = geom::make_box(Vec3(-half.x, -half.y, 0), Vec3(half.x, half.y, b.height));
    s.sdf = geom::make_transform(box, Vec3(0, 0, 1), walls[k].angle, walls[k].center);
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

// The gaps between the walls' shadows on y within [y_lo, y_hi], in y order: each footprint's
// shadow has half-extent (w |cos a| + t |sin a|)/2 about its centre; overlapping shadows merge.
std::vector<std::pair<Real, Real>> shadow_gaps(const Barrier& b) {
  std::vector<std::pair<Real, Real>> shadow;
  for (const BarrierWall& w : barrier_walls(b)) {
    const Real e = Real(0.5) * (b.width * std::abs(std::cos(w.angle)) +
                                b.thickness * std::abs(std::sin(w.angle)));
    shadow.emplace_back(std::max(b.y_lo, w.center.y - e), std::min(b.y_hi, w.center.y + e));
  }
  std::sort(shadow.begin(), shadow.end());
  std::vector<std::pair<Real, Real>> gaps;
  Real end = b.y_lo;
  for (const auto& [lo, hi] : shadow) {
    if (lo > end) gaps.emplace_back(end, lo);
    end = std::max(end, hi);
  }
  if (b.y_hi > end) gaps.emplace_back(end, b.y_hi);
  return gaps;
}

}  // namespace

Real barrier_opening_ratio(const Barrier& b) {
  Real open = 0;
  for (const auto& [lo, hi] : shadow_gaps(b)) open += hi - lo;
  return open / (b.y_hi - b.y_lo);
}

LatticeOpening barrier_lattice_opening(const Barrier& b, const ParticleSet<Host>& ps,
                                       const std::vector<bool>& is_wall, Real dp) {
  // Columns j with (j + 1/2) dp inside (y_lo, y_hi).
  const long j0 = long(std::ceil(b.y_lo / dp - Real(0.5) + Real(1e-9)));
  const long j1 = long(std::floor(b.y_hi / dp - Real(0.5) - Real(1e-9)));
  LatticeOpening o;
  if (j1 < j0) return o;
  std::vector<std::uint8_t> blocked(std::size_t(j1 - j0 + 1), 0);
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    const std::int32_t body = ps.body[i];
    if (body < 0 || std::size_t(body) >= is_wall.size() || !is_wall[std::size_t(body)]) continue;
    const long j = std::lround(ps.pos[i].y / dp - Real(0.5));
    if (j >= j0 && j <= j1) blocked[std::size_t(j - j0)] = 1;
  }
  o.columns = Index(blocked.size());
  for (const std::uint8_t c : blocked) o.open += c ? 0 : 1;
  for (const auto& [lo, hi] : shadow_gaps(b)) {
    ++o.gaps;
    bool any = false;
    for (long j = j0; j <= j1 && !any; ++j) {
      const Real y = (Real(j) + Real(0.5)) * dp;
      any = !blocked[std::size_t(j - j0)] && y >= lo - Real(1e-6) * dp && y <= hi + Real(1e-6) * dp;
    }
    if (!any) ++o.closed_gaps;
  }
  return o;
}

namespace {

// The row's extent along x: every wall's footprint lies within [first, last].
void row_extent(const Barrier& b, Real& x_first, Real& x_last) {
  x_first = 1e30;
  x_last = -1e30;
  for (const BarrierWall& w : barrier_walls(b)) {
    const Real e = Real(0.5) * (b.thickness * std::abs(std::cos(w.angle)) +
                                b.width * std::abs(std::sin(w.angle)));
    x_first = std::min(x_first, w.center.x - e);
    x_last = std::max(x_last, w.center.x + e);
  }
}

}  // namespace

Trap barrier_trap(const Barrier& b, const ParticleSet<Host>& ps) {
  Real x_first, x_last;
  row_extent(b, x_first, x_last);
  Trap t;
  for (Index i = 0; i < ps.n_fluid; ++i)
    (ps.pos[i].x < x_first ? t.fluid_upstream : t.fluid_downstream) += ps.mass[i];
  std::map<std::int32_t, std::pair<Real, int>> grains;  // body -> (sum x, count)
  for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
    if (!is_grain_body(ps.body[i])) continue;
    auto& g = grains[ps.body[i]];
    g.first += ps.pos[i].x;
    ++g.second;
  }
  for (const auto& [body, g] : grains) {
    (void)body;
    if (g.first / Real(g.second) < x_first)
      ++t.grains_upstream;
    else
      ++t.grains_downstream;
  }
  return t;
}

Runup barrier_runup(const Barrier& b, const ParticleSet<Host>& ps, Real h2, Real dp) {
  Real x_first, x_last;
  row_extent(b, x_first, x_last);
  std::vector<Index> band;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const Vec3& x = ps.pos[i];
    if (x.x >= x_first - b.runup_band && x.x <= x_last && x.y >= b.y_lo && x.y <= b.y_hi)
      band.push_back(i);
  }
  // Highest first; the first with enough neighbours wins.
  std::sort(band.begin(), band.end(), [&](Index a, Index c) { return ps.pos[a].z > ps.pos[c].z; });
  Runup r;
  for (Index i : band) {
    int n = 0;
    for (Index j = 0; j < ps.n_fluid && n < 6; ++j)
      if (j != i && norm2(ps.pos[j] - ps.pos[i]) < h2) ++n;
    if (n >= 6) {
      r.height = ps.pos[i].z + Real(0.5) * dp - b.floor_z;
      r.where = ps.pos[i];
      return r;
    }
  }
  return r;
}

}  // namespace sphdem
