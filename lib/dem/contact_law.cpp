// Host helpers of the contact laws (contact_law.hpp): the damping constant of the Hertz law.
#include "dem/contact_law.hpp"

#include <cmath>
#include <map>
#include <mutex>
#include <string>

#include "core/error.hpp"

namespace sphdem::dem {

Real hertz_restitution(Real alpha) {
  // State (x, v); the force is -max(0, alpha x^{1/4} v + x^{3/2}) (no attraction, as
  // hertz_normal_force), with x clamped at 0 in the powers. Once the rebounding dashpot cancels
  // the spring the force stays zero and v is the exit speed.
  auto acc = [alpha](double x, double v) {
    const double xp = x > 0 ? x : 0.0;
    const double push = double(alpha) * std::sqrt(std::sqrt(xp)) * v + xp * std::sqrt(xp);
    return push > 0 ? -push : 0.0;
  };
  const double h = 2e-4;  // the undamped contact lasts t = 3.218 in these units
  double x = 0, v = 1;
  for (int step = 0; step < 200000; ++step) {
    const double k1x = v, k1v = acc(x, v);
    const double k2x = v + 0.5 * h * k1v, k2v = acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const double k3x = v + 0.5 * h * k2v, k3v = acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const double k4x = v + h * k3v, k4v = acc(x + h * k3x, v + h * k3v);
    const double xn = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    const double vn = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (step > 0 && xn <= 0) {
      // Linear interpolation of v at the zero crossing of x.
      const double f = x / (x - xn);
      return Real(-(v + f * (vn - v)));
    }
    x = xn;
    v = vn;
  }
  return Real(0);
}

Real hertz_damping_alpha(Real e) {
  if (!(e > Real(0)))
    throw InputError("Hertz damping: restitution coefficient must be > 0, got " +
                     std::to_string(e));
  if (e >= Real(1)) return Real(0);
  // Cached: a run uses one or two restitution coefficients.
  static std::mutex mutex;
  static std::map<Real, Real> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = cache.find(e);
    if (it != cache.end()) return it->second;
  }
  // e(alpha) decreases monotonically; bracket and bisect.
  Real lo = 0, hi = 1;
  while (hertz_restitution(hi) > e && hi < Real(1e3)) hi *= 2;
  for (int it = 0; it < 60 && hi - lo > Real(1e-10) * hi; ++it) {
    const Real mid = Real(0.5) * (lo + hi);
    if (hertz_restitution(mid) > e)
      lo = mid;
    else
      hi = mid;
  }
  const Real alpha = Real(0.5) * (lo + hi);
  std::lock_guard<std::mutex> lock(mutex);
  cache[e] = alpha;
  return alpha;
}

}  // namespace sphdem::dem
