#include "diagnostics/heap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace sphdem {

HeapShape measure_heap(const std::vector<Vec3>& points, const HeapOptions& opt) {
  HeapShape out;
  out.repose_deg = std::numeric_limits<Real>::quiet_NaN();
  if (points.empty()) return out;
  std::map<std::pair<long, long>, Real> top;  // (ix, iy) -> highest point above the floor
  std::map<long, Real> xtop;                  // ix -> highest point
  for (const Vec3& p : points) {
    const long ix = long(std::floor(p.x / opt.cell)), iy = long(std::floor(p.y / opt.cell));
    const Real z = p.z - opt.z_floor;
    auto [it, fresh] = top.emplace(std::make_pair(ix, iy), z);
    if (!fresh) it->second = std::max(it->second, z);
    auto [jt, fresh_x] = xtop.emplace(ix, z);
    if (!fresh_x) jt->second = std::max(jt->second, z);
  }
  long ix_high = xtop.begin()->first;
  for (const auto& [ix, z] : xtop) {
    if (z > out.height) {
      out.height = z;
      ix_high = ix;
    }
  }
  long ix_toe = ix_high;
  while (xtop.count(ix_toe + 1)) ++ix_toe;
  out.toe = Real(ix_toe + 1) * opt.cell;

  // Least squares z = a + b x + c y over the qualifying column tops (column centres).
  double s[4][4] = {}, r[4] = {};
  std::vector<Vec3> used;
  for (const auto& [key, z] : top) {
    const Real x = (Real(key.first) + Real(0.5)) * opt.cell;
    const Real y = (Real(key.second) + Real(0.5)) * opt.cell;
    if (z < opt.lo_frac * out.height || z > opt.hi_frac * out.height) continue;
    if (x < opt.x_min || x > opt.x_max || key.first > ix_toe) continue;
    used.emplace_back(x, y, z);
    const double v[3] = {1, x, y};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) s[i][j] += v[i] * v[j];
      r[i] += v[i] * z;
    }
  }
  out.columns = int(used.size());
  if (used.size() < 3) return out;
  // Solve the 3x3 normal equations (Cramer).
  auto det3 = [](double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  double m[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = s[i][j];
  const double d = det3(m);
  double coef[3] = {0, 0, 0};
  if (std::abs(d) > 1e-300) {
    for (int c = 0; c < 3; ++c) {
      double mc[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) mc[i][j] = j == c ? r[i] : s[i][j];
      coef[c] = det3(mc) / d;
    }
  } else {  // all columns in one row across y: fit z = a + b x
    const double n = s[0][0], sx = s[0][1], sxx = s[1][1];
    const double den = n * sxx - sx * sx;
    if (std::abs(den) < 1e-300) return out;
    coef[1] = (n * r[1] - sx * r[0]) / den;
    coef[0] = (r[0] - coef[1] * sx) / n;
  }
  out.repose_deg = Real(std::atan(std::hypot(coef[1], coef[2])) * 180 / M_PI);
  double rr = 0;
  const double g = std::sqrt(1 + coef[1] * coef[1] + coef[2] * coef[2]);
  for (const Vec3& u : used) {
    const double e = (u.z - (coef[0] + coef[1] * u.x + coef[2] * u.y)) / g;
    rr += e * e;
  }
  out.fit_rms = Real(std::sqrt(rr / double(used.size())));
  return out;
}

}  // namespace sphdem
