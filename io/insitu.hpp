// In-situ analysis (DESIGN.md §6): an InSituAdaptor hands the live particles to an analysis
// library at an interval of steps. The default adaptor does nothing. With
// -DSPHDEM_ENABLE_CATALYST=ON, a ParaView 5.11 legacy Catalyst adaptor (io/catalyst_adaptor.cpp:
// vtkCPProcessor + vtkCPPythonScriptV2Pipeline) runs the scene's `insitu.scripts`. A Catalyst 2
// backend would be another implementation of this interface.
//
// What an adaptor is given, on each extract step (Catalyst channel names in quotes):
//   "fluid"  the fluid particles: points with vel, rho, press, id
//   "walls"  the boundary particles: points with force (mass * acc, N: the fluid's force on that
//            particle), body (index into the scene's solids), normal, press, id; field data
//            solid_names (one per solid, by body index) and grain_force (one 3-vector per solid,
//            by body index, N: the grains' DEM contact load on that solid, the mean over the
//            last fluid step as in impact_force.csv's grain columns; zero for a solid that is no
//            DEM wall, and everywhere in a run without grains)
//   both carry field data: time, step, dp, h, dim.
// On many ranks each rank passes its owned fluid and the wall particles it owns, so a sum over
// the points is that rank's share (the scripts in inputs/catalyst/ reduce over the ranks);
// grain_force is whole on every rank (the DEM is replicated).
// The adaptor owns its library state and releases it in its destructor, so it must be destroyed
// before MPI_Finalize (run_scene's adaptor is a local of run_scene).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "solver/particles.hpp"
#include "solver/solver.hpp"

namespace sphdem {

class InSituAdaptor {
 public:
  virtual ~InSituAdaptor() = default;
  // True when `step` is an extract step (the scene's insitu.every_steps; step 0 included).
  virtual bool due(std::int64_t step) const = 0;
  // Hands the particles at (time, step) to the analysis, with the grains' contact load on each
  // solid (`grain_force`, by body index: one per scene solid). Throws std::runtime_error when
  // the analysis fails (a broken script).
  virtual void execute(std::int64_t step, Real time, const ParticleSet<Host>& ps,
                       const StepParams& p, const std::vector<Vec3>& grain_force) = 0;
  // Extract steps so far and the wall seconds spent in execute() (building the VTK data and
  // running the scripts).
  virtual std::int64_t executed() const = 0;
  virtual double seconds() const = 0;
  virtual std::string name() const = 0;
};

// Does nothing: the adaptor of a scene without `insitu`.
class NullInSituAdaptor final : public InSituAdaptor {
 public:
  bool due(std::int64_t) const override { return false; }
  void execute(std::int64_t, Real, const ParticleSet<Host>&, const StepParams&,
               const std::vector<Vec3>&) override {}
  std::int64_t executed() const override { return 0; }
  double seconds() const override { return 0; }
  std::string name() const override { return "none"; }
};

// Whether this build has the Catalyst adaptor (SPHDEM_ENABLE_CATALYST).
bool catalyst_compiled();

// The adaptor for the scene: NullInSituAdaptor when it has no insitu.scripts; the Catalyst
// adaptor otherwise, writing its extracts under `out_dir`/catalyst. Throws InputError when the
// scene asks for scripts and this build has no Catalyst, or when a script fails to load.
std::unique_ptr<InSituAdaptor> make_insitu_adaptor(const Scene& scene, const std::string& out_dir);

}  // namespace sphdem
