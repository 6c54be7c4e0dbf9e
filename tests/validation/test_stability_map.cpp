// Three points of the stability map (jobs/stability_map.py, docs/figures/stability_map.png),
// pinned: the 2D dam break at dp = L/20.
//  - CFL 0.3 with delta = 0.1 and Verlet: the density guard fires within 0.02 s. Leapfrog
//    (rho^{n+1} = rho^{n-1} + 2 dt D) amplifies the diffusion term's odd-even mode between the
//    Euler steps; the same point with the symplectic integrator, or with an Euler step every 5
//    steps, runs (the controls).
//  - CFL 0.5 without density diffusion: stable to t = 0.6 s (with the Mach guard at 0.25).
// And three points of the DEM map (jobs/stability_map.py --dem, docs/figures/dem_stability_map.png)
// on inputs/sphere_pile.yaml: at kn 2e4 N/m a step of t_c/5 completes and t_c/2.5 stops on the
// overlap guard; at kn 20 N/m the beads sink into each other at any step and the same guard says
// the contacts are too soft.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {
namespace {

// Runs inputs/<file> with the overrides on the host into `out`.
RunResult run_input(const std::string& file, const std::vector<std::string>& overrides,
                    const std::string& out) {
  const Scene scene = load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/" + file, overrides);
  RunOptions opt;
  opt.out_dir = out;
  opt.backend = Backend::kHost;
  opt.quiet = true;
  opt.handle_signals = false;
  return run_scene(scene, opt);
}

RunResult run_point(const std::string& out, std::vector<std::string> extra) {
  std::vector<std::string> ov = {"sph.dp=0.0073", "guards.rho_min_ratio=0.7",
                                 "guards.rho_max_ratio=1.3", "guards.mach_max=0.2",
                                 "guards.check_every=1"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return run_input("dam_break_2d.yaml", ov, out);
}

TEST(StabilityMap, VerletWithDiffusionAtCfl03TripsDensityGuard) {
  const RunResult r =
      run_point("map_verlet_cfl03", {"time.cfl=0.3", "fluid.diffusion.delta=0.1", "time.end=0.05"});
  ASSERT_TRUE(r.unstable) << "expected the density guard; the run completed";
  EXPECT_NE(r.failure.find("density out of bounds"), std::string::npos) << r.failure;
  EXPECT_LT(r.sim_time, 0.03);
}

TEST(StabilityMap, SamePointRunsWithSymplecticOrFrequentEuler) {
  const RunResult a = run_point(
      "map_symplectic_cfl03",
      {"time.cfl=0.3", "fluid.diffusion.delta=0.1", "time.end=0.05", "time.integrator=symplectic"});
  EXPECT_FALSE(a.unstable) << a.failure;
  EXPECT_NEAR(a.sim_time, 0.05, 1e-3);
  const RunResult b = run_point("map_euler5_cfl03", {"time.cfl=0.3", "fluid.diffusion.delta=0.1",
                                                     "time.end=0.05", "time.verlet_euler_every=5"});
  EXPECT_FALSE(b.unstable) << b.failure;
  EXPECT_NEAR(b.sim_time, 0.05, 1e-3);
}

// Since the mDBC corner fix (first-order ghost interpolation at corners, 2026-11-29), the jet
// thrown up the far wall at t = 0.29 s reaches 6.99 m/s = Mach 0.206: the Mach guard at 0.2
// stops the run there and says so; with the guard at 0.25 the same point runs to 0.6 s without a
// density or NaN fault (before the fix the corner ghosts fell back to a Shepard average and the
// jet stayed under Mach 0.2).
TEST(StabilityMap, NoDiffusionAtCfl05IsStable) {
  const RunResult r = run_point("map_nodiff_cfl05", {"time.cfl=0.5", "fluid.diffusion.model=none",
                                                     "time.end=0.6", "guards.mach_max=0.25"});
  EXPECT_FALSE(r.unstable) << r.failure;
  EXPECT_NEAR(r.sim_time, 0.6, 1e-3);
  const RunResult m = run_point("map_nodiff_cfl05_mach",
                                {"time.cfl=0.5", "fluid.diffusion.model=none", "time.end=0.6"});
  ASSERT_TRUE(m.unstable);
  EXPECT_NE(m.failure.find("Mach number too high"), std::string::npos) << m.failure;
  EXPECT_GT(m.sim_time, 0.25);  // at the far wall, not at the start
}

RunResult run_pile(const std::string& out, const std::string& kn, const std::string& dt_factor) {
  return run_input("sphere_pile.yaml",
                   {"dem.grain_grain.kn=" + kn, "dem.grain_wall.kn=" + kn,
                    "dem.dt_factor=" + dt_factor, "time.end=0.2"},
                   out);
}

TEST(StabilityMap, DemStepOfTcOver5RunsAndTcOver2p5TripsOverlapGuard) {
  const RunResult ok = run_pile("map_dem_f10", "2e4", "10");
  EXPECT_FALSE(ok.unstable) << ok.failure;
  EXPECT_NEAR(ok.sim_time, 0.2, 1e-3);
  const RunResult bad = run_pile("map_dem_f20", "2e4", "20");
  ASSERT_TRUE(bad.unstable) << "expected the DEM overlap guard; the run completed";
  EXPECT_NE(bad.failure.find("DEM overlap"), std::string::npos) << bad.failure;
  EXPECT_NE(bad.failure.find("dem.dt_factor"), std::string::npos) << bad.failure;
  EXPECT_FALSE(bad.last_checkpoint.empty()) << "an unstable run writes an emergency checkpoint";
}

TEST(StabilityMap, DemSoftContactsTripOverlapGuardAtAnyStep) {
  const RunResult r = run_pile("map_dem_soft", "20", "0.5");
  ASSERT_TRUE(r.unstable) << "expected the DEM overlap guard; the run completed";
  EXPECT_NE(r.failure.find("too soft"), std::string::npos) << r.failure;
  EXPECT_LT(r.sim_time, 0.05);
}

}  // namespace
}  // namespace sphdem
