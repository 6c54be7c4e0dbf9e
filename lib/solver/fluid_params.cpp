#include "solver/fluid_params.hpp"

#include <cmath>

#include "scene/build.hpp"
#include "scene/scene.hpp"

namespace sphdem {

StepParams make_step_params(const Scene& scene, Real c0) {
  StepParams p;
  p.dim = scene.dim;
  p.dp = scene.sph.dp;
  p.h = scene.h();
  p.kernel = make_kernel(scene.dim, p.h);
  p.eos = make_eos(scene.fluid.rho0, c0, scene.fluid.gamma, scene.fluid.p_min);
  p.radius2 = Real(4) * p.h * p.h;
  p.eta2 = Real(0.01) * p.h * p.h;
  p.gravity = scene.gravity;
  p.g_mag = norm(scene.gravity);
  p.g_hat = p.g_mag > 0 ? scene.gravity / p.g_mag : Vec3();
  p.laminar = scene.fluid.viscosity == ViscosityModel::kLaminar;
  p.nu = scene.fluid.nu;
  p.alpha = scene.fluid.alpha;
  p.diffusion = scene.fluid.diffusion != DiffusionModel::kNone && scene.fluid.delta > 0;
  p.diffusion_hydrostatic = scene.fluid.diffusion == DiffusionModel::kFourtakas;
  p.delta_h_c0 = scene.fluid.delta * p.h * c0;
  p.mdbc = scene.sph.boundary == BoundaryMethod::kMdbc;
  p.free_slip = scene.sph.slip == SlipCondition::kFreeSlip;
  p.no_penetration = p.mdbc && scene.sph.no_penetration;
  p.mdbc_limit = p.mdbc && scene.sph.mdbc_limiter;
  p.pairwise = scene.sph.pairwise;
  const RheologyParams& rh = scene.fluid.rheology;
  p.hbp = rh.model == RheologyModel::kHbp;
  p.hbp_params.k = rh.k;
  p.hbp_params.n = rh.n;
  p.hbp_params.m = rh.m;
  p.hbp_params.cohesion = rh.cohesion;
  p.hbp_params.tan_phi = std::tan(rh.friction_deg * kPi / Real(180));
  p.hbp_params.mu_max = rh.mu_max;
  p.hbp_params.yield = rh.yield;
  p.sps = scene.fluid.sps.enabled;
  p.sps_cs = scene.fluid.sps.cs;
  p.sps_ci = scene.fluid.sps.ci;
  p.domain_lo = scene.domain_lo;
  p.domain_hi = scene.domain_hi;
  p.sym = scene.symmetry;
  // The grid covers the domain plus the boundary depth, so wall particles outside the fluid
  // domain still have cells. A 10% skin keeps the symplectic half step inside neighbour cells.
  const Real skin = scene.time.integrator == Integrator::kSymplectic ? Real(1.1) : Real(1.0);
  const Real depth = boundary_depth(scene);
  Vec3 lo = scene.domain_lo, hi = scene.domain_hi;
  for (int k = 0; k < 3; ++k) {
    if (scene.periodic[k]) continue;
    lo[k] -= depth;
    hi[k] += depth;
  }
  // Cells of edge h (half the support), scanned two on each side: fewer candidates per particle
  // than 2h cells scanned one on each side (docs/BENCHMARKS.md).
  constexpr int kReach = 2;
  p.grid = make_cell_grid(scene.dim, lo, hi, Real(2) * p.h * skin / kReach, scene.periodic, kReach);
  return p;
}

}  // namespace sphdem
