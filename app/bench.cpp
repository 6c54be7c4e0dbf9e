#include "bench.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <mpi.h>

#include "core/error.hpp"
#include "cuda/device.hpp"
#include "simulation.hpp"
#include "io/scene_yaml.hpp"

namespace sphdem {

void run_bench(const BenchOptions& opt, std::ostream& os_rank) {
  // Under mpirun every rank steps; rank 0 prints (phase times are rank 0's, counts global).
  std::ostringstream sink;
  std::ostream& os = world_rank() == 0 ? os_rank : sink;
  Scene scene = load_scene(opt.scene_path, opt.overrides);
  if (opt.target_particles < 0)
    throw InputError("--particles: " + std::to_string(opt.target_particles) +
                     " is negative; give a fluid particle count > 0");
  if (opt.target_particles > 0) {
    // Scale dp from the fluid count at the scene's dp: N ~ dp^-dim.
    BuildReport rep;
    build_particles(scene, &rep);
    const double ratio = double(rep.fluid) / double(opt.target_particles);
    std::vector<std::string> ov = opt.overrides;
    std::ostringstream dp;
    dp << std::setprecision(10) << scene.sph.dp * std::pow(ratio, 1.0 / scene.dim);
    ov.push_back("sph.dp=" + dp.str());
    scene = load_scene(opt.scene_path, ov);
  }
  std::ostringstream slog;
  BuildReport rep;
  auto solver = make_solver(scene, opt.backend, slog, &rep);
  for (int i = 0; i < opt.warmup; ++i) solver->step();
  if (std::string(solver->space_name()) == "device") cuda::synchronize();
  const PhaseTimes before = solver->phase_times();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < opt.steps; ++i) solver->step();
  if (std::string(solver->space_name()) == "device") cuda::synchronize();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PhaseTimes after = solver->phase_times();
  double pairs = solver->last_pair_count();
  if (world_size() > 1) MPI_Allreduce(MPI_IN_PLACE, &pairs, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  const double n = double(solver->fluid_count());
  struct Row {
    const char* name;
    double seconds;
    bool neighbour_pass;  // a pass over all pairs, so PIPS applies
  };
  // Phases not yet implemented (DEM contacts, coupling, I/O) are reported as 0.
  const Row rows[] = {
      {"cell_list", after.cell_list - before.cell_list, false},
      {"mdbc", after.mdbc - before.mdbc, false},
      {"fluid_forces", after.forces - before.forces, true},
      {"dem_contacts", 0, false},
      {"coupling", 0, false},
      {"integration", after.integrate - before.integrate, false},
      {"halo", after.halo - before.halo, false},
      {"io", 0, false},
  };
  const int steps = opt.steps;
  if (opt.json) {
    os << std::setprecision(6) << "{\n  \"scene\": \"" << scene.name << "\",\n  \"backend\": \""
       << solver->space_name() << "\",\n  \"threads\": " << host_thread_count()
       << ",\n  \"ranks\": " << world_size() << ",\n  \"precision\": \"" << SPHDEM_PRECISION_NAME
       << "\",\n  \"boundary\": \""
       << (scene.sph.boundary == BoundaryMethod::kMdbc ? "mdbc" : "dbc")
       << "\",\n  \"h_over_dp\": " << scene.sph.h_factor * std::sqrt(double(scene.dim))
       << ",\n  \"fluid_particles\": " << n
       << ",\n  \"boundary_particles\": " << rep.wall + rep.grain << ",\n  \"steps\": " << steps
       << ",\n  \"pairs_per_step\": " << pairs << ",\n  \"seconds_per_step\": " << wall / steps
       << ",\n  \"particle_steps_per_second\": " << n * steps / wall << ",\n  \"phases\": {";
    bool first = true;
    for (const Row& r : rows) {
      os << (first ? "\n" : ",\n") << "    \"" << r.name
         << "\": {\"seconds_per_step\": " << r.seconds / steps
         << ", \"pips\": " << (r.neighbour_pass && r.seconds > 0 ? pairs * steps / r.seconds : 0)
         << "}";
      first = false;
    }
    os << "\n  }\n}\n";
    return;
  }
  os << slog.str();
  os << "scene " << scene.name << ", " << n << " fluid + " << rep.wall + rep.grain
     << " boundary particles, " << SPHDEM_PRECISION_NAME << ", " << solver->space_name() << " ("
     << host_thread_count() << " threads x " << world_size() << " ranks), " << steps
     << " steps after " << opt.warmup << " warm-up\n";
  os << std::left << std::setw(14) << "phase" << std::right << std::setw(14) << "ms/step"
     << std::setw(18) << "particle-steps/s" << std::setw(14) << "PIPS"
     << "\n";
  for (const Row& r : rows) {
    const double ms = 1e3 * r.seconds / steps;
    os << std::left << std::setw(14) << r.name << std::right << std::setw(14)
       << std::setprecision(4) << ms << std::setw(18) << (r.seconds > 0 ? n * steps / r.seconds : 0)
       << std::setw(14) << (r.neighbour_pass && r.seconds > 0 ? pairs * steps / r.seconds : 0)
       << "\n";
  }
  os << std::left << std::setw(14) << "total" << std::right << std::setw(14) << 1e3 * wall / steps
     << std::setw(18) << n * steps / wall << std::setw(14) << pairs * steps / wall << "\n";
  os << "neighbour pairs within 2h per step: " << pairs << " (" << pairs / n
     << " per fluid particle)\n";
}

}  // namespace sphdem
