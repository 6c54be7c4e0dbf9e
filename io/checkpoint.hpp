// Parallel HDF5 checkpoints (DESIGN.md §6). One file per checkpoint, written collectively: each
// rank writes its hyperslab of every field, at offsets from MPI_Exscan. Contents:
//   /fluid/<field>, /boundary/<field>   every particle field (Vec3 fields as N x 3), by global id
//   /scene_yaml                         the resolved scene (text)
//   /dem/...                            grain states, integrator rates, moving walls, tangential
//                                       contact history (keys and springs), with its own checksum
//   attributes on /                     format_version, time, step, verlet_count, removed,
//                                       removed_mass, dim, dp, precision, next_output_time,
//                                       checksum (order-independent, verified on read)
// Files are written to "<name>.tmp" and renamed on success, so a crash mid-write leaves the
// previous checkpoint intact. The last `keep` checkpoints are kept.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dem/dem_system.hpp"
#include "scene/scene.hpp"
#include "solver/particles.hpp"
#include "solver/solver.hpp"

namespace sphdem {

constexpr int kCheckpointFormatVersion = 1;

struct CheckpointData {
  ParticleSet<Host> particles;  // this rank's share
  SolverCounters counters;
  Real next_output_time = 0;  // diagnostics schedule
  std::vector<std::int64_t> profile_next;
  // guards.csv's open span (diagnostics/guards.hpp GuardSpan): the steps since its last row and
  // their extremes, so a resumed run's rows equal the straight run's. guard_steps < 0: not in
  // the file (a checkpoint of an older sphdem), and the resumed run starts a fresh span.
  std::int64_t guard_steps = -1;
  double guard_max_speed = 0, guard_rho_min = 0, guard_rho_max = 0, guard_dt_min = 0;
  std::string scene_yaml;
  int dim = 0;
  Real dp = 0;
  Index total_fluid = 0, total_boundary = 0;
  // Rigid grains (replicated on every rank): written as /dem when there are bodies.
  dem::DemState dem;
};

// Makes sure MPI is initialised (sphdem's main does it through PETSc; tests may not).
void ensure_mpi();

// Writes the checkpoint collectively on MPI_COMM_WORLD. Returns the bytes written.
std::uint64_t write_checkpoint(const std::string& path, const CheckpointData& data);

// Reads a checkpoint; each rank gets a contiguous block of the particles. Throws InputError for a
// missing, truncated, corrupted (checksum) or incompatible file, naming the file and the cause.
CheckpointData read_checkpoint(const std::string& path);

// Refuses a checkpoint that does not belong to the scene (dimension, dp, boundary count).
void check_checkpoint_matches(const CheckpointData& cp, const Scene& scene,
                              Index scene_boundary_count, const std::string& path);

// "DIR/checkpoint_<step>.h5"; and the newest such file in DIR ("" if none).
std::string checkpoint_path(const std::string& dir, std::int64_t step);
std::string latest_checkpoint(const std::string& dir);
// Deletes all but the newest `keep` checkpoints in DIR.
void prune_checkpoints(const std::string& dir, int keep);

}  // namespace sphdem
