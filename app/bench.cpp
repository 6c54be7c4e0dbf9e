#include "bench.hpp"

#include <mpi.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "core/exec.hpp"
#include "cuda/device.hpp"
#include "io/scene_yaml.hpp"
#include "simulation.hpp"

namespace sphdem {

namespace {

// Bytes a phase must move per step if each array it touches is streamed once (a floor: cache
// misses in the neighbour loops, and the sort's extra radix passes, come on top). Counts: fluid
// slots nf, boundary slots nb (walls and grains). R = sizeof(Real), V = a Vec3.
struct Traffic {
  double cell_list = 0, mdbc = 0, forces = 0, integrate = 0;
};

Traffic traffic_model(double nf, double nb, bool mdbc) {
  const double R = sizeof(Real), V = 3 * R, id = sizeof(GlobalId), body = 4;
  const double fields = id + 8 * V + 5 * R + body;  // every field of a slot (ParticleSet)
  Traffic t;
  // Keys and order (8 + 4 B) written, two stable sorts reading and writing them once each, the
  // keys computed again from the positions, every field permuted through scratch (read, write,
  // read, write), the cell starts marked from the keys.
  t.cell_list = nf * (V + id + 12 + 2 * 2 * 12 + V + 12 + 4 * fields + 8);
  // Pressure of the fluid; per boundary slot its position, ghost nodes, normal and velocity read
  // and its density, pressure and mDBC velocity written; the fluid's position, mass, density and
  // velocity read once.
  t.mdbc = nf * 2 * R + (mdbc ? nb * (5 * V + 2 * R + V) + nf * (2 * V + 2 * R) : 0);
  // Fluid: position, velocity, density, pressure, mass in; acceleration, density rate, viscous
  // rate out. Boundary: position, velocity (mDBC), density, pressure, mass, normal, body in;
  // acceleration and density rate out.
  t.forces = nf * (2 * V + 3 * R + V + 2 * R) + nb * (3 * V + 3 * R + body + V + R);
  // Verlet: position, velocity, previous velocity, density, previous density, rates in; the
  // first five out.
  t.integrate = nf * (4 * V + 3 * R + 3 * V + 2 * R);
  return t;
}

// STREAM-style triad a = b + s c over 64 MiB arrays with the OpenMP threads, best of 5, in GB/s
// (24 bytes per element, as STREAM counts it).
double host_triad_gbs() {
  const Index n = Index(1) << 23;
  std::vector<double> a(std::size_t(n), 0.0), b(std::size_t(n), 1.0), c(std::size_t(n), 2.0);
  double* pa = a.data();
  const double* pb = b.data();
  const double* pc = c.data();
  double best = 0;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    for_each(Host{}, n, [=](Index i) { pa[i] = pb[i] + 3.0 * pc[i]; });
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (s > 0) best = std::max(best, 24.0 * double(n) / s / 1e9);
  }
  return best;
}

struct Row {
  const char* name;
  double seconds;  // over the timed steps
  double items;    // fluid particles (grains for dem_contacts) per step, for the rate
  bool pairs;      // a pass over all neighbour pairs: PIPS applies
  double bytes;    // per step, from the traffic model (0: not modelled)
};

// A temporary run folder for scenes with grains, the same on every rank.
std::string temporary_folder() {
  std::string path;
  if (world_rank() == 0) {
    std::string tmpl = (std::filesystem::temp_directory_path() / "sphdem_bench_XXXXXX").string();
    if (!mkdtemp(tmpl.data()))
      throw RuntimeFault("bench: cannot create a temporary run folder from '" + tmpl + "'");
    path = tmpl;
  }
  if (world_size() == 1) return path;
  int len = int(path.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
  path.resize(std::size_t(len));
  MPI_Bcast(path.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
  return path;
}

}  // namespace

void run_bench(const BenchOptions& opt, std::ostream& os_rank) {
  // Under mpirun every rank steps; rank 0 prints (phase times are rank 0's, counts global).
  std::ostringstream sink;
  std::ostream& os = world_rank() == 0 ? os_rank : sink;
  Scene scene = load_scene(opt.scene_path, opt.overrides);
  if (opt.target_particles < 0)
    throw InputError("--particles: " + std::to_string(opt.target_particles) +
                     " is negative; give a fluid particle count > 0");
  if (opt.steps < 1)
    throw InputError("--steps: " + std::to_string(opt.steps) + " is not a step count; give >= 1");
  if (opt.warmup < 0)
    throw InputError("--warmup: " + std::to_string(opt.warmup) + " is negative; give >= 0");
  if (opt.target_particles > 0) {
    // Scale dp from the fluid count at the scene's dp: N ~ dp^-dim.
    BuildReport rep;
    build_particles(scene, &rep);
    if (rep.fluid == 0)
      throw InputError("--particles: scene '" + scene.name + "' (" + scene.source +
                       ") has no fluid to scale");
    const double ratio = double(rep.fluid) / double(opt.target_particles);
    std::vector<std::string> ov = opt.overrides;
    std::ostringstream dp;
    dp << std::setprecision(10) << scene.sph.dp * std::pow(ratio, 1.0 / scene.dim);
    ov.push_back("sph.dp=" + dp.str());
    scene = load_scene(opt.scene_path, ov);
  }

  if (!scene.dem.enabled && !opt.out_dir.empty())
    throw InputError("--out '" + opt.out_dir + "': scene '" + scene.name + "' (" + scene.source +
                     ") has no grains, and the bench writes a run folder only for scenes with "
                     "grains; leave --out out");
  RunTiming t;
  std::string space, log_text;
  if (scene.dem.enabled) {
    // Grains (with or without fluid): the run loop steps the DEM and the coupling, so the bench
    // runs the scene as `sphdem run` does, into a run folder, and times the steps after warm-up.
    RunOptions ro;
    const bool temporary = opt.out_dir.empty();
    ro.out_dir = temporary ? temporary_folder() : opt.out_dir;
    ro.backend = opt.backend;
    ro.max_steps = opt.warmup + opt.steps;
    ro.time_after_steps = opt.warmup;
    ro.quiet = true;
    ro.handle_signals = false;
    // The temporary folder goes when the bench ends, by error too (rank 0 removes it).
    struct Remove {
      std::string path;
      ~Remove() {
        std::error_code ec;
        if (!path.empty() && world_rank() == 0) std::filesystem::remove_all(path, ec);
      }
    } remove{temporary ? ro.out_dir : std::string()};
    const RunResult r = run_scene(scene, ro);
    if (world_size() > 1) MPI_Barrier(MPI_COMM_WORLD);  // every rank is done with the folder
    if (r.unstable)
      throw StabilityError("bench: scene '" + scene.name + "' went unstable: " + r.failure);
    if (r.timing.steps < opt.steps && r.at_rest) {
      std::ostringstream m;
      m << "bench: scene '" << scene.name << "' (" << scene.source
        << ") came to rest (dem.stop_at_rest: kinetic energy below " << scene.dem.rest_energy
        << " J after t = " << scene.dem.rest_after << " s) at t = " << r.sim_time << " s, after "
        << r.steps << " steps, before " << opt.warmup + opt.steps
        << " (warm-up and timed); lower --steps, or move the check later with --set "
           "dem.stop_at_rest.after=T";
      throw InputError(m.str());
    }
    if (r.timing.steps < opt.steps)
      throw InputError("bench: scene '" + scene.name + "' (" + scene.source + ") ended after " +
                       std::to_string(r.steps) + " steps, before " +
                       std::to_string(opt.warmup + opt.steps) +
                       " (warm-up and timed); raise time.end or lower --steps");
    t = r.timing;
    space = r.space;
  } else {
    std::ostringstream slog;
    BuildReport rep;
    auto solver = make_solver(scene, opt.backend, slog, &rep);
    for (int i = 0; i < opt.warmup; ++i) solver->step();
    if (std::string(solver->space_name()) == "device") cuda::synchronize();
    const PhaseTimes before = solver->phase_times();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < opt.steps; ++i) solver->step();
    if (std::string(solver->space_name()) == "device") cuda::synchronize();
    t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t.steps = opt.steps;
    t.solver = solver->phase_times() - before;
    t.pairs = solver->last_pair_count();
    t.fluid = solver->fluid_count();
    t.boundary = rep.wall + rep.grain;
    space = solver->space_name();
    log_text = slog.str();
  }
  double pairs = t.pairs;
  if (world_size() > 1) MPI_Allreduce(MPI_IN_PLACE, &pairs, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  const double n = double(t.fluid);
  const double grains = double(t.grains);
  const int steps = int(t.steps);

  // Bandwidth the achieved figures are set against: the GPU's theoretical peak, or the host's
  // measured triad.
  double bandwidth = 0;
  std::string bandwidth_source;
  if (space == "device") {
    const int d = cuda::current_device();
    const std::vector<cuda::GpuInfo> gpus = cuda::list_gpus();
    for (const cuda::GpuInfo& g : gpus)
      if (g.index == d) {
        bandwidth = g.bandwidth_gbs;
        bandwidth_source = g.name + " peak (memory clock x bus width)";
      }
  } else {
    bandwidth = host_triad_gbs();
    bandwidth_source = "host triad, measured (" + std::to_string(host_thread_count()) + " threads)";
  }
  // The traffic model counts this rank's slots (fluid owned on one rank; on many, rank 0's
  // phase times are set against rank 0's share).
  const double nf_rank = world_size() > 1 ? n / world_size() : n;
  const double nb_rank = world_size() > 1 ? double(t.boundary) / world_size() : double(t.boundary);
  const Traffic tr = traffic_model(nf_rank, nb_rank, scene.sph.boundary == BoundaryMethod::kMdbc);
  const Row rows[] = {
      {"cell_list", t.solver.cell_list, n, false, tr.cell_list},
      {"mdbc", t.solver.mdbc, n, false, tr.mdbc},
      {"fluid_forces", t.solver.forces, n, true, tr.forces},
      {"dem_contacts", t.loop.dem, grains, false, 0},
      {"coupling", t.loop.coupling, n, false, 0},
      {"integration", t.solver.integrate, n, false, tr.integrate},
      {"halo", t.solver.halo, n, false, 0},
      {"io", t.loop.io, n, false, 0},
      {"guards", t.loop.guards, n, false, 0},
  };
  auto rate = [&](const Row& r) { return r.seconds > 0 ? r.items * steps / r.seconds : 0.0; };
  auto pips = [&](const Row& r) {
    return r.pairs && r.seconds > 0 ? pairs * steps / r.seconds : 0;
  };
  auto gbs = [&](const Row& r) {
    return r.bytes > 0 && r.seconds > 0 ? r.bytes * steps / r.seconds / 1e9 : 0.0;
  };
  const char* boundary = scene.sph.boundary == BoundaryMethod::kMdbc ? "mdbc" : "dbc";
  if (opt.json) {
    os << std::setprecision(6) << "{\n  \"scene\": \"" << scene.name << "\",\n  \"backend\": \""
       << space << "\",\n  \"threads\": " << host_thread_count()
       << ",\n  \"ranks\": " << world_size() << ",\n  \"precision\": \"" << SPHDEM_PRECISION_NAME
       << "\",\n  \"boundary\": \"" << boundary
       << "\",\n  \"h_over_dp\": " << scene.sph.h_factor * std::sqrt(double(scene.dim))
       << ",\n  \"fluid_particles\": " << n << ",\n  \"boundary_particles\": " << t.boundary
       << ",\n  \"grains\": " << t.grains << ",\n  \"contact_points\": " << t.contacts
       << ",\n  \"steps\": " << steps << ",\n  \"pairs_per_step\": " << pairs
       << ",\n  \"seconds_per_step\": " << t.wall / steps
       << ",\n  \"particle_steps_per_second\": " << n * steps / t.wall
       << ",\n  \"grain_steps_per_second\": " << grains * steps / t.wall
       << ",\n  \"bandwidth_gbs\": " << bandwidth << ",\n  \"bandwidth_source\": \""
       << bandwidth_source << "\",\n  \"phases\": {";
    bool first = true;
    for (const Row& r : rows) {
      os << (first ? "\n" : ",\n") << "    \"" << r.name
         << "\": {\"seconds_per_step\": " << r.seconds / steps << ", \"pips\": " << pips(r)
         << ", \"model_bytes_per_step\": " << r.bytes << ", \"gbs\": " << gbs(r) << "}";
      first = false;
    }
    os << "\n  }\n}\n";
    return;
  }
  os << log_text;
  os << "scene " << scene.name << ", " << n << " fluid + " << t.boundary << " boundary particles";
  if (t.grains > 0) os << ", " << t.grains << " grains (" << t.contacts << " contact points)";
  os << ", " << SPHDEM_PRECISION_NAME << ", " << space << " (" << host_thread_count()
     << " threads x " << world_size() << " ranks), " << steps << " steps after " << opt.warmup
     << " warm-up\n";
  os << std::left << std::setw(14) << "phase" << std::right << std::setw(12) << "ms/step"
     << std::setw(18) << "particle-steps/s" << std::setw(12) << "PIPS" << std::setw(10) << "GB/s"
     << std::setw(11) << "of peak"
     << "\n";
  for (const Row& r : rows) {
    const double ms = 1e3 * r.seconds / steps;
    os << std::left << std::setw(14) << r.name << std::right << std::setw(12)
       << std::setprecision(4) << ms << std::setw(18) << rate(r) << std::setw(12) << pips(r)
       << std::setw(10) << std::setprecision(3) << gbs(r) << std::setw(10) << std::setprecision(2)
       << (bandwidth > 0 ? 100 * gbs(r) / bandwidth : 0) << "%\n";
  }
  os << std::left << std::setw(14) << "total" << std::right << std::setw(12) << std::setprecision(4)
     << 1e3 * t.wall / steps << std::setw(18) << (n > 0 ? n : grains) * steps / t.wall
     << std::setw(12) << pairs * steps / t.wall << "\n";
  if (n > 0)
    os << "neighbour pairs within 2h per step: " << pairs << " (" << pairs / n
       << " per fluid particle)\n";
  os << "particle-steps/s counts fluid particles (grains in dem_contacts";
  if (n == 0) os << " and the total";
  os << "). GB/s: bytes each phase must move (every array it touches read or written once; "
        "model in app/bench.cpp) per second, against "
     << std::setprecision(4) << bandwidth << " GB/s (" << bandwidth_source << ")\n";
}

}  // namespace sphdem
