// sphdem: SPH-DEM debris-flow simulation. Subcommands: run, check, bench, info.
#include <CLI/CLI.hpp>

#include <iostream>

#include "bench.hpp"
#include "core/error.hpp"
#include "core/exec.hpp"
#include "cuda/device.hpp"
#include "decomposition/parallel_env.hpp"
#include "io/hdf5_info.hpp"
#include "io/insitu.hpp"
#include "io/scene_yaml.hpp"
#include "simulation.hpp"

using namespace sphdem;

namespace {

void print_info(std::ostream& os) {
  os << "sphdem " << SPHDEM_VERSION << "\n"
     << "  precision:      " << SPHDEM_PRECISION_NAME << "\n"
     << "  host space:     OpenMP, " << host_thread_count() << " threads\n"
     << "  CUDA:           "
     << (cuda::compiled_with_cuda() ? "compiled, architectures " SPHDEM_CUDA_ARCHS : "not compiled")
     << "\n"
     << "  PETSc:          " << petsc_version() << "\n"
     << "  MPI:            " << mpi_version() << "\n"
     << "  HDF5:           " << hdf5_version() << "\n"
     << "  Catalyst:       "
     << (catalyst_compiled() ? "ParaView legacy Catalyst (insitu.scripts)"
                             : "not built (SPHDEM_ENABLE_CATALYST=OFF)")
     << "\n";
  std::string why;
  const auto gpus = cuda::list_gpus(&why);
  if (gpus.empty()) {
    os << "  GPUs:           none (" << why << ")\n";
  } else {
    for (const auto& g : gpus)
      os << "  GPU " << g.index << ":          " << g.name << ", " << g.memory_bytes / (1 << 20)
         << " MiB, sm_" << g.cc_major << g.cc_minor << ", " << g.bandwidth_gbs << " GB/s peak\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sphdem: SPH-DEM simulation of debris flows and barriers"};
  app.require_subcommand(1);
  std::string scene_path, out_dir = "out", backend = "auto";
  std::vector<std::string> sets;
  long long max_steps = -1;
  bool quiet = false;

  auto* run = app.add_subcommand("run", "run a scene");
  run->add_option("scene", scene_path, "scene file (YAML)")->required();
  run->add_option("--out", out_dir, "output folder")->capture_default_str();
  run->add_option("--set", sets, "override a scene key: --set sph.dp=0.002");
  run->add_option("--backend", backend, "auto, host or device")->capture_default_str();
  run->add_option("--max-steps", max_steps, "stop after this many steps");
  run->add_flag("--quiet", quiet, "no progress lines");
  std::string restart;
  run->add_option("--restart", restart, "continue from a checkpoint file, or 'latest' in --out");
  std::string procs;
  run->add_option("--procs", procs,
                  "under mpirun: process grid along x, y, z such as 2x1x1 (0 = PETSc chooses)");

  auto* check = app.add_subcommand("check", "print counts, memory, dt and cost, then exit");
  check->add_option("scene", scene_path, "scene file (YAML)")->required();
  check->add_option("--set", sets, "override a scene key");

  BenchOptions bo;
  bo.scene_path = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_3d.yaml";
  long long particles = 0;
  auto* bench = app.add_subcommand("bench", "time a scene per phase");
  bench->add_option("scene", bo.scene_path, "scene file (default: dam_break_3d)")
      ->capture_default_str();
  bench->add_option("--particles", particles, "scale dp to about this many fluid particles");
  bench->add_option("--steps", bo.steps, "timed steps")->capture_default_str();
  bench->add_option("--warmup", bo.warmup, "untimed steps first")->capture_default_str();
  bench->add_option("--set", sets, "override a scene key");
  bench->add_option("--backend", backend, "auto, host or device")->capture_default_str();
  bench->add_flag("--json", bo.json, "JSON output");
  bench->add_option("--out", bo.out_dir,
                    "run folder for scenes with grains (default: a temporary one, removed after)");

  app.add_subcommand("info", "print the build configuration and the GPUs seen");

  CLI11_PARSE(app, argc, argv);

  int status = 0;
  try {
    ParallelEnv env(&argc, &argv);
    try {
      if (run->parsed()) {
        const Scene scene = load_scene(scene_path, sets);
        RunOptions opt;
        opt.out_dir = out_dir;
        opt.backend = parse_backend(backend);
        opt.max_steps = max_steps;
        opt.quiet = quiet;
        opt.restart = restart;
        opt.procs = parse_procs(procs);
        const RunResult r = run_scene(scene, opt);
        status = r.unstable ? 3 : (r.interrupted ? 4 : 0);
      } else if (check->parsed()) {
        check_scene(load_scene(scene_path, sets), std::cout);
      } else if (bench->parsed()) {
        bo.overrides = sets;
        bo.target_particles = particles;
        bo.backend = parse_backend(backend);
        run_bench(bo, std::cout);
      } else {
        print_info(std::cout);
      }
    } catch (const InputError& e) {
      std::cerr << "error: " << e.what() << "\n";
      status = 2;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      status = 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return status;
}
