// Stability guards (DESIGN.md §7). Each check names the cause, the particle (by global id) or
// the quantity, and the time, and throws StabilityError. The caller writes an emergency
// checkpoint and exits non-zero.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "scene/build.hpp"
#include "scene/scene.hpp"
#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"
#include "solver/solver.hpp"

namespace sphdem {

// Cheap checks from the step's reductions: dt floor, Mach number, density range, NaN in them.
// `locate`, when given, is called only when the Mach guard fires and names the fastest particle
// (fastest_fluid_text); on many ranks every rank calls it (the reductions agree), so it may be
// collective.
void check_step_guards(const Scene& scene, const StepParams& p, const StepStats& st, Real time,
                       std::int64_t step, const std::function<std::string()>& locate = {});

// The fastest fluid particle of a host copy (speed < 0 when it holds no fluid).
struct FastestFluid {
  double speed = -1;
  GlobalId id = 0;
  Vec3 pos, vel;
  Real rho = 0;
};
FastestFluid fastest_fluid(const ParticleSet<Host>& ps);

// "fluid particle id N at (x, y, z), speed S m/s, velocity (u, v, w), density rho kg/m^3".
std::string fastest_fluid_text(const FastestFluid& f);

// Where x stands against the nearest solid whose surface lies within `reach` (removed solids
// skipped): "; it is 5.5 mm inside solid 'barrier_2'" or "...from the surface of solid ..."
// (saying so when that is nearer than dp/2, where the first fluid layer sits), and, when that
// solid is one of `thin` (thinner than the boundary depth), that it can leak.
// Empty when no solid is that near. The Mach guard appends it to the fastest particle: a
// particle squeezed into a thin wall is the usual cause of a lone fast particle.
std::string near_solid_text(const Scene& scene, Real time, const Vec3& x, Real reach,
                            const std::vector<ThinSolid>& thin, Real boundary_depth);

// Per-particle checks on a host copy: NaN/Inf in position, velocity, density; density bounds;
// fluid inside a solid (deeper than dp/2 below its surface).
void check_particle_guards(const Scene& scene, const StepParams& p, const ParticleSet<Host>& ps,
                           Real time, std::int64_t step);

}  // namespace sphdem
