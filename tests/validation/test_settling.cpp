// A dense sphere settling through a viscous fluid (issue #6, coupling validation):
// inputs/sphere_settling.yaml, one cell of a simple cubic array of spheres (periodic box, the
// weight carried by a mean pressure gradient), d/dp = 10. The terminal slip velocity is compared
// with Stokes' drag corrected for the array (Hasimoto 1959; Sangani & Acrivos 1982):
//   F = 6 pi mu a U K,   1/K = 1 - 1.7601 c^(1/3) + c - 1.5593 c^2,
// with F = (rho_s - rho_mix) g V the weight the fluid's flow must carry, and U the superficial
// slip velocity (1 - c) (v_sphere - mean fluid velocity). docs/VALIDATION.md has the resolution
// study (jobs/settling_study.py).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "app/simulation.hpp"
#include "core/error.hpp"
#include "io/scene_yaml.hpp"
#include "validation/run_files.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/sphere_settling.yaml";

struct Settling {
  bool unstable = false;
  std::string failure;
  double u_ref = 0;           // Stokes with Hasimoto's array correction [m/s]
  double u_last = 0;          // superficial slip, mean over the last 10 ms
  double u_before = 0;        // the same over the 10 ms before
  double momentum_max = 0;    // largest |total momentum| of fluid and sphere [kg m/s]
  double momentum_scale = 0;  // sphere mass times u_ref
  double reynolds = 0;
};

const Settling& settling() {
  static const Settling s = [] {
    Settling out;
    const std::string dir = "settling_sphere";
    const Scene scene = load_scene(kScene);
    const RunResult r = runfiles::run_host(scene, dir);
    out.unstable = r.unstable;
    out.failure = r.failure;
    if (r.unstable) return out;

    const double rho0 = scene.fluid.rho0, nu = scene.fluid.nu, g = -scene.gravity.z;
    const double d = 0.01, rho_s = 2000, pi = std::acos(-1.0);
    const double box = (scene.domain_hi.x - scene.domain_lo.x) *
                       (scene.domain_hi.y - scene.domain_lo.y) *
                       (scene.domain_hi.z - scene.domain_lo.z);
    const double vs = pi * d * d * d / 6, ms = rho_s * vs, c = vs / box;
    const double mf = double(r.fluid) * rho0 * std::pow(double(scene.sph.dp), 3);
    const double rho_mix = (mf + ms) / (mf / rho0 + vs);
    const double force = (rho_s - rho_mix) * g * vs;
    const double inv_k = 1 - 1.7601 * std::cbrt(c) + c - 1.5593 * c * c;
    out.u_ref = force * inv_k / (6 * pi * rho0 * nu * (d / 2));
    out.reynolds = out.u_ref * d / nu;
    out.momentum_scale = ms * out.u_ref;

    const auto body = runfiles::read_numeric_csv(dir + "/bodies.csv");  // t,id,x,y,z,vx,vy,vz,...
    const auto energy =
        runfiles::read_numeric_csv(dir + "/energy.csv");  // t,kinetic,potential,total,px,py,pz
    const std::size_t n = std::min(body.size(), energy.size());
    if (n < 20) {
      out.unstable = true;
      out.failure = "only " + std::to_string(n) + " diagnostic rows in " + dir;
      return out;
    }
    const double end = body[n - 1][0];
    double sum_last = 0, sum_before = 0;
    int n_last = 0, n_before = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = body[i][0];
      EXPECT_NEAR(energy[i][0], t, 1e-9);
      const double p[3] = {ms * body[i][5] + energy[i][4], ms * body[i][6] + energy[i][5],
                           ms * body[i][7] + energy[i][6]};
      out.momentum_max =
          std::max(out.momentum_max, std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
      const double slip = (1 - c) * (energy[i][6] / mf - body[i][7]);  // downward slip > 0
      if (t > end - 0.01 + 1e-9) {
        sum_last += slip;
        ++n_last;
      } else if (t > end - 0.02 + 1e-9) {
        sum_before += slip;
        ++n_before;
      }
    }
    out.u_last = sum_last / std::max(n_last, 1);
    out.u_before = sum_before / std::max(n_before, 1);
    std::printf(
        "c = %.4f, Re = %.3f: U = %.5f m/s (last 10 ms), %.5f (the 10 ms before); Stokes x "
        "Hasimoto %.5f m/s, error %+.2f %%; largest |momentum| %.3g of m_s U\n",
        c, out.reynolds, out.u_last, out.u_before, out.u_ref, 100 * (out.u_last / out.u_ref - 1),
        out.momentum_max / out.momentum_scale);
    return out;
  }();
  return s;
}

// One test (ctest runs each test in a process of its own, and this one's run takes minutes):
// - the criterion: within 10 % of Stokes' law (here with the array correction,
//   1/K = 0.546) at d/dp >= 10, in the Stokes regime;
// - the sphere has reached its terminal velocity: the last two 10 ms means differ by under 2 %;
// - pressure_gradient: weight makes the forces on the periodic box sum to zero, so the momentum
//   of fluid plus sphere stays at its initial zero (a wrong G would accelerate the whole box).
TEST(Settling, TerminalVelocityWithin10PercentOfStokesAtTenParticlesAcross) {
  const Settling& s = settling();
  ASSERT_FALSE(s.unstable) << s.failure;
  ASSERT_GT(s.u_ref, 0) << "no diagnostics were read";
  EXPECT_LT(s.reynolds, 0.1);  // Stokes' law holds to about 1 %
  EXPECT_NEAR(s.u_last / s.u_ref, 1.0, 0.10);
  EXPECT_GT(s.u_before, 0);
  EXPECT_NEAR(s.u_last / s.u_before, 1.0, 0.02);
  const double tol = std::is_same<Real, float>::value ? 1e-3 : 1e-6;  // round-off: ~1e-9
  EXPECT_LT(s.momentum_max, tol * s.momentum_scale);
}

}  // namespace
}  // namespace sphdem
