// Runs of grains only (a scene with a `dem` section and no fluid): the DEM system of
// scene/build_dem.hpp stepped to time.end, with the same outputs as a fluid run: run.log,
// grains.csv (energy, contacts, overlap, front), frames of the grains' surface nodes, checkpoints
// and restart, guards with an emergency checkpoint, summary.json, and heap.json (repose angle and
// run-out, diagnostics/heap.hpp) when the scene asks for it.
#pragma once

#include <ostream>

#include "dem/dem_system.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"

namespace sphdem {

bool is_granular(const Scene& scene);  // grains and no fluid blocks

// Stops the run (StabilityError) when a grain overlap exceeds dem.overlap_max of the smallest
// grain diameter or a grain leaves the domain.
void check_grain_guards(const Scene& scene, const dem::DemSystem& sys, Real min_diameter);
RunResult run_granular(const Scene& scene, const RunOptions& opt);
void check_granular(const Scene& scene, std::ostream& os);

}  // namespace sphdem
