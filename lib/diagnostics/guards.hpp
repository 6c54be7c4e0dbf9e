// Stability guards (DESIGN.md §7). Each check names the cause, the particle (by global id) or
// the quantity, and the time, and throws StabilityError. The caller writes an emergency
// checkpoint and exits non-zero.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>

#include "scene/build.hpp"
#include "scene/scene.hpp"
#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"
#include "solver/solver.hpp"

namespace sphdem {

// Which fluid particle a guard names: the fastest (the Mach guard), or the densest or the
// lightest (the density guard, by the side of its bounds that was left).
enum class Extreme { fastest, densest, lightest };

// Cheap checks from the step's reductions: dt floor, Mach number, density range, NaN in them.
// `locate`, when given, is called only when the Mach or the density guard fires, and names the
// particle that guard judged (fluid_particle_text of extreme_fluid); on many ranks every rank
// calls it (the reductions agree), so it may be collective.
void check_step_guards(const Scene& scene, const StepParams& p, const StepStats& st, Real time,
                       std::int64_t step, const std::function<std::string(Extreme)>& locate = {});

// One fluid particle of a host copy, with `key` the value it is extreme in (speed, density, or
// minus the density); key is -inf when the copy holds no fluid.
struct ExtremeFluid {
  double key = -std::numeric_limits<double>::infinity();
  GlobalId id = 0;
  Vec3 pos, vel;
  Real rho = 0;
  bool found() const { return key > -std::numeric_limits<double>::infinity(); }
};
// The fastest, the densest or the lightest fluid particle (the first in slot order on ties).
ExtremeFluid extreme_fluid(const ParticleSet<Host>& ps, Extreme e);

// "fluid particle id N at (x, y, z), speed S m/s, velocity (u, v, w), density rho kg/m^3".
std::string fluid_particle_text(const ExtremeFluid& f);

// The guards' quantities over the steps between two rows of guards.csv: the largest fluid speed,
// the fluid density range and the shortest step, each the extreme over every step of the span,
// so a row shows how near the run came to guards.mach_max and the density bounds, a spike
// between two diagnostic times included. A NaN in a step's reductions stays in the span.
struct GuardSpan {
  std::int64_t steps = 0;
  Real max_speed = 0;
  Real rho_min = std::numeric_limits<Real>::infinity();
  Real rho_max = -std::numeric_limits<Real>::infinity();
  Real dt_min = std::numeric_limits<Real>::infinity();
  void add(const StepStats& st);
};

// Where x stands against the nearest solid whose surface lies within `reach` (removed solids
// skipped): "; it is 5.5 mm inside solid 'barrier_2'" or "...from the surface of solid ..."
// (saying so when that is nearer than dp/2, where the first fluid layer sits), and, when that
// solid is one of `thin` (thinner than the boundary depth), its thickness and, for a particle
// inside it or within dp of its surface, that it can leak.
// Empty when no solid is that near. The Mach and density guards append it to the particle they
// name: a particle squeezed into a thin wall is the usual cause of a lone fast or dense particle.
std::string near_solid_text(const Scene& scene, Real time, const Vec3& x, Real reach,
                            const std::vector<ThinSolid>& thin, Real boundary_depth);

// Per-particle checks on a host copy: NaN/Inf in position, velocity, density; density bounds;
// fluid inside a solid (deeper than dp/2 below its surface).
void check_particle_guards(const Scene& scene, const StepParams& p, const ParticleSet<Host>& ps,
                           Real time, std::int64_t step);

}  // namespace sphdem
