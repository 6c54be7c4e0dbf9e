// The time loop's core: one fluid step on one execution space. The Simulation (app/) owns I/O,
// diagnostics and guards and talks to the solver through this interface, so it does not care
// whether particles live on the host or the device.
#pragma once

#include <functional>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/exec.hpp"
#include "coupling/grain_pose.hpp"
#include "scene/scene.hpp"
#include "solver/exchange.hpp"
#include "solver/fluid_params.hpp"
#include "solver/particles.hpp"
#include "sph/mdbc.hpp"

namespace sphdem {

struct StepStats {
  Real dt = 0;
  Real dt_force = 0, dt_acoustic = 0, dt_viscous = 0;  // the three limits of Eq. (23)
  Real max_speed = 0;
  Real rho_min = 0, rho_max = 0;
  Index removed = 0;  // fluid particles that left the domain in this step
};

// Wall time spent per phase, seconds (summed over steps).
struct PhaseTimes {
  double cell_list = 0, halo = 0, mdbc = 0, forces = 0, integrate = 0, other = 0;
};
// The phase times between two readings of the totals.
inline PhaseTimes operator-(const PhaseTimes& a, const PhaseTimes& b) {
  return {a.cell_list - b.cell_list, a.halo - b.halo,           a.mdbc - b.mdbc,
          a.forces - b.forces,       a.integrate - b.integrate, a.other - b.other};
}

// Everything beyond the particle fields that a bit-identical restart needs.
struct SolverCounters {
  Real time = 0;
  std::int64_t step = 0;
  std::int64_t verlet_count = 0;  // steps since the start, for the Euler step every N
  Index removed = 0;              // fluid particles removed at open ends so far
  Real removed_mass = 0;
};

class SolverBase {
 public:
  virtual ~SolverBase() = default;
  virtual const char* space_name() const = 0;
  // Advances one step; returns what it measured.
  virtual StepStats step() = 0;
  virtual Real time() const = 0;
  virtual std::int64_t step_count() const = 0;
  virtual const StepParams& params() const = 0;
  // A host copy of all particles (no copy on the host space).
  virtual const ParticleSet<Host>& host_particles() = 0;
  // Owned fluid particles now (no host copy needed).
  virtual Index fluid_count() const = 0;
  virtual Index removed_count() const = 0;
  virtual Real removed_mass() const = 0;
  virtual const PhaseTimes& phase_times() const = 0;
  // Number of neighbour pairs within 2h seen by the last force pass (for PIPS).
  virtual double last_pair_count() = 0;
  // What the mDBC limiter does to the walls' fits now, over all ranks (mDBC only; collective).
  // NaN before the first step and after restore(), when there are no cell lists to gather with.
  virtual MdbcLimiterStats mdbc_limiter_stats() = 0;
  // Many ranks: 1 for each wall slot of host_particles() this rank owns (empty on one rank).
  virtual std::vector<std::uint8_t> wall_mine() const = 0;
  // Many ranks: steps that rebuilt the halo plan (the others reused it); 0 on one rank.
  virtual std::int64_t halo_rebuilds() const = 0;
  // Restart support: the counters, and replacing the whole state (particles and counters).
  virtual SolverCounters counters() const = 0;
  virtual void restore(ParticleSet<Host> particles, const SolverCounters& c) = 0;
  // SPH-DEM coupling (lib/coupling): poses the grain boundary slots (positions, ghost nodes,
  // normals, velocities) from the bodies' state in the execution space (pose_grain_point), then
  // re-sorts the grain range. `table` is uploaded when a different one is passed; pass the
  // coupling's own each step.
  virtual void pose_grains(const GrainPointTable& table,
                           const std::vector<dem::RigidBody>& bodies) = 0;
  // The grain slots alone in host memory (every field; n_grain set), for the loads on the grains
  // (GrainCoupling::loads): on the device only the grain range is downloaded. grain_mine(): many
  // ranks, 1 for each of them this rank owns (empty on one rank).
  virtual const ParticleSet<Host>& grain_particles() = 0;
  virtual std::vector<std::uint8_t> grain_mine() const = 0;
  // Many ranks (DESIGN.md §5, "Grains"): no rank holds every grain boundary particle. At each
  // neighbour rebuild the solver takes from `source` the posed grain particles that may reach its
  // box [lo, hi] (GrainCoupling::generate), keeps those whose ghost node (DBC: position) it owns,
  // and receives copies of the other ranks' within the halo width. Between rebuilds pose_grains
  // poses the slots held. `total`: the grain particles of all ranks, which the owned
  // ones must add up to at every rebuild. Required on many ranks when there are grains.
  using GrainSource = std::function<ParticleSet<Host>(const Vec3& lo, const Vec3& hi)>;
  virtual void set_grain_source(GrainSource source, Index total) = 0;
  // The fluid's body acceleration (default: scene.gravity); a mean pressure gradient G makes it
  // gravity - G / rho0 (scene.hpp PressureGradient). Its direction also orients Fourtakas'
  // hydrostatic density correction, which follows the pressure gradient the fluid carries.
  virtual void set_body_acceleration(Vec3 a) = 0;
  // Removes the boundary particles of solid index `solid` (a gate that opens); returns how many
  // went.
  virtual Index remove_solid(std::int32_t solid) = 0;
};

// Builds a solver on the host (OpenMP) or the device (CUDA). `particles` come from
// build_particles(); c0 is the resolved speed of sound. On many ranks, `ex` is the decomposition
// and `particles` this rank's owned fluid plus every wall particle.
std::unique_ptr<SolverBase> make_host_solver(const Scene& scene, ParticleSet<Host> particles,
                                             Real c0, std::shared_ptr<Exchange> ex = nullptr);
std::unique_ptr<SolverBase> make_device_solver(const Scene& scene, ParticleSet<Host> particles,
                                               Real c0, std::shared_ptr<Exchange> ex = nullptr);

}  // namespace sphdem
