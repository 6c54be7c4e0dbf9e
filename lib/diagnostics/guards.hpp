// Stability guards (DESIGN.md §7). Each check names the cause, the particle (by global id) or
// the quantity, and the time, and throws StabilityError. The caller writes an emergency
// checkpoint and exits non-zero.
#pragma once

#include <cstdint>
#include <string>

#include "scene/scene.hpp"
#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"
#include "solver/solver.hpp"

namespace sphdem {

// Cheap checks from the step's reductions: dt floor, Mach number, density range, NaN in them.
void check_step_guards(const Scene& scene, const StepParams& p, const StepStats& st, Real time,
                       std::int64_t step);

// Per-particle checks on a host copy: NaN/Inf in position, velocity, density; density bounds;
// fluid inside a solid (deeper than dp/2 below its surface).
void check_particle_guards(const Scene& scene, const StepParams& p, const ParticleSet<Host>& ps,
                           Real time, std::int64_t step);

}  // namespace sphdem
