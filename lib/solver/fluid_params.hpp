// Parameters of the fluid step, resolved from the scene once. Passed by value into kernels.
#pragma once

#include "core/symmetry.hpp"
#include "core/types.hpp"
#include "neighbor/cell_grid.hpp"
#include "sph/eos.hpp"
#include "sph/kernel.hpp"
#include "sph/rheology.hpp"

namespace sphdem {

struct FluidParams;
struct Scene;

struct StepParams {
  int dim = 3;
  KernelParams kernel;
  EosParams eos;
  CellGrid grid;
  Real dp = 0, h = 0, radius2 = 0;  // radius2 = (2h)^2
  Real eta2 = 0;                    // 0.01 h^2
  Vec3 gravity;
  Real g_mag = 0;
  Vec3 g_hat;           // unit vector along gravity (0 if none)
  bool laminar = true;  // Lo-Shao laminar; else Monaghan artificial viscosity
  Real nu = 0;          // kinematic viscosity (m^2/s)
  Real alpha = 0;       // artificial viscosity coefficient
  bool diffusion = true;
  bool diffusion_hydrostatic = true;  // Fourtakas correction
  Real delta_h_c0 = 0;                // delta * h * c0
  bool mdbc = true;                   // else plain DBC
  bool free_slip = false;
  bool no_penetration = false;  // mDBC only (see SphParams)
  bool mdbc_limit = false;      // mDBC only: sph.mdbc_limiter (sph/mdbc.hpp)
  bool pairwise = true;         // CPU: one evaluation per owned fluid pair (see SphParams)
  Real mdbc_det_min = Real(1e-3);
  bool hbp = false;  // per-particle mu_eff from the HBP model drives the laminar term
  HbpParams hbp_params;
  bool sps = false;  // Dalrymple & Rogers SPS stress
  Real sps_cs = 0, sps_ci = 0;
  Vec3 domain_lo, domain_hi;
  SymmetryPlane sym;  // fluid that crosses it is reflected back (core/symmetry.hpp)
};

// Resolves the step parameters from a scene and the derived speed of sound.
StepParams make_step_params(const Scene& scene, Real c0);

}  // namespace sphdem
