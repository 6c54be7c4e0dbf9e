// Diagnostics computed from a host copy of the particles (DESIGN.md §3 diagnostics/):
// pressure gauges, water height, front position, free-surface profiles, force on solids, energy.
// They are evaluated at output intervals, so they favour clarity over speed.
#pragma once

#include <vector>

#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"

namespace sphdem {

// Kernel-interpolated (Shepard-normalised) fluid pressure at a point; boundary particles are
// ignored. Returns 0 where no fluid is within 2h.
Real probe_pressure(const ParticleSet<Host>& ps, const StepParams& p, const Vec3& point);
// The same for the fluid velocity (zero where no fluid is within 2h).
Vec3 probe_velocity(const ParticleSet<Host>& ps, const StepParams& p, const Vec3& point);

// Free-surface elevation on the vertical (along -g) line through (x, y): the highest point where
// the fluid kernel sum sum_j V_j W(r - r_j) reaches 1/2. Returns NaN if no fluid is on the line.
Real probe_surface_height(const ParticleSet<Host>& ps, const StepParams& p, Real x, Real y);
// The same along a given unit `up` (the bed normal of an inclined channel).
Real probe_surface_height(const ParticleSet<Host>& ps, const StepParams& p, Real x, Real y,
                          const Vec3& up);

// Flow at a channel station (the channel along +x, bed z = 0): see VelocityGauge in
// scene/scene.hpp. depth is the bed-normal kernel-sum surface (0 if dry), u the mean x-velocity of
// the fluid within h of the line (0 if none), froude u / sqrt(g_n depth) (0 if dry).
struct ChannelFlow {
  Real u = 0, depth = 0, froude = 0;
};
ChannelFlow probe_channel_flow(const ParticleSet<Host>& ps, const StepParams& p,
                               const Vec3& gravity, Real x, Real y);

// Largest projection (x_j - origin) . dir over fluid particles (dir is normalised).
Real probe_front(const ParticleSet<Host>& ps, const Vec3& origin, const Vec3& dir);

// Force of the fluid on a solid: sum over the solid's boundary particles of m_B a_B, where a_B
// is the boundary particle's rate from fluid neighbours (pressure and viscous terms).
Vec3 probe_solid_force(const ParticleSet<Host>& ps, int solid_index);

struct Energy {
  Real kinetic = 0, potential = 0;
  Vec3 momentum;  // sum of m v
};
// Fluid kinetic energy, potential energy -m g.x (relative to the origin) and momentum.
Energy probe_energy(const ParticleSet<Host>& ps, const Vec3& gravity);

}  // namespace sphdem
