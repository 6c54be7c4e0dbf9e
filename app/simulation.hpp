// A run: builds particles from a scene, picks the execution space, steps to the end time,
// writes diagnostics (CSV), the run log and summary.json, and stops cleanly on a guard.
#pragma once

#include <array>
#include <functional>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>

#include "scene/build.hpp"
#include "scene/scene.hpp"
#include "solver/solver.hpp"

namespace sphdem {

enum class Backend { kAuto, kHost, kDevice };
Backend parse_backend(const std::string& s);

struct RunOptions {
  std::string out_dir = "out";
  Backend backend = Backend::kAuto;
  std::int64_t max_steps = -1;        // stop after this many steps (bench, tests); -1 = to time.end
  bool quiet = false;                 // no progress lines
  double progress_every_s = 2.0;      // wall seconds between progress lines when not on a TTY
  std::string restart;                // checkpoint file, "latest" (newest in out_dir), or "" (none)
  bool handle_signals = true;         // SIGTERM/SIGUSR1 write a checkpoint (SIGTERM then stops)
  std::array<int, 3> procs{0, 0, 0};  // process grid on many ranks (0: PETSc chooses)
  std::int64_t time_after_steps = -1;  // >= 0 (bench): RunResult::timing covers the later steps
};

// Wall seconds spent by a run's loop outside the solver's own phases.
struct LoopTimes {
  double coupling = 0;  // grain poses to their boundary particles, fluid loads to the grains
  double dem = 0;       // DEM steps (contacts and rigid-body integration) and moving walls
  double io = 0;        // diagnostics CSVs, frames, in situ, checkpoints
  double guards = 0;    // stability guards
};

// The steps of a run after RunOptions::time_after_steps, timed per phase (`sphdem bench` on
// scenes with grains). Empty (steps = 0) unless asked for and reached.
struct RunTiming {
  std::int64_t steps = 0;
  double wall = 0;    // seconds over those steps
  PhaseTimes solver;  // the fluid solver's phases over those steps
  LoopTimes loop;
  double pairs = 0;  // neighbour pairs within 2h of the last fluid force pass (this rank)
  Index fluid = 0, boundary = 0, grains = 0;
  double contacts = 0;  // DEM contact points after the last step
};

struct RunResult {
  std::int64_t steps = 0;
  double sim_time = 0;
  double wall_seconds = 0;
  Index fluid = 0, wall = 0, grain = 0;
  Index removed = 0;
  double removed_mass = 0;
  double particle_steps_per_second = 0;
  bool unstable = false;
  bool interrupted = false;  // stopped by SIGTERM after writing a checkpoint
  bool at_rest = false;      // grain-only runs: ended early by dem.stop_at_rest
  int checkpoints = 0;       // checkpoints written (emergency included)
  std::string last_checkpoint;
  std::string failure;  // the guard's message when unstable
  std::string space;    // host or device
  RunTiming timing;
};

class MpiExchange;

// Creates the solver for the backend (auto: the device if a GPU is seen, else the host, and
// says so in `log`). Under mpirun with more than one rank, the domain is decomposed (procs: the
// process grid, 0 = PETSc chooses), this rank keeps the fluid it owns, and `exchange` receives the
// decomposition.
// `prepare` (coupled runs) edits the built particles before the solver takes them: it removes
// the fluid inside grains and appends their boundary particles.
std::unique_ptr<SolverBase> make_solver(
    const Scene& scene, Backend backend, std::ostream& log, BuildReport* report = nullptr,
    std::shared_ptr<MpiExchange>* exchange = nullptr, std::array<int, 3> procs = {0, 0, 0},
    const std::function<void(ParticleSet<Host>&, BuildReport&)>& prepare = {});

// "2x1x1" or "2,1,1" -> {2, 1, 1}; "" -> {0, 0, 0}. Throws InputError naming --procs.
std::array<int, 3> parse_procs(const std::string& s);
int world_rank();
int world_size();

// Runs the scene. Throws InputError for bad input; a stability guard does not throw: it is
// reported in RunResult (and the log), with an emergency state file written.
RunResult run_scene(const Scene& scene, const RunOptions& opt);

// `sphdem check`: counts, memory, dt estimate, steps and cost; prints to `os`.
void check_scene(const Scene& scene, std::ostream& os);

}  // namespace sphdem
