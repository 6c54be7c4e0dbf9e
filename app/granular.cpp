#include "granular.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/error.hpp"
#include "dem/dem_system.hpp"
#include "diagnostics/heap.hpp"
#include "io/checkpoint.hpp"
#include "io/csv_series.hpp"
#include "io/frames.hpp"
#include "run_common.hpp"
#include "scene/build_dem.hpp"

namespace sphdem {

bool is_granular(const Scene& scene) {
  return scene.dem.enabled && scene.fluid_blocks.empty();
}

namespace {

// The points that stand for a grain's surface in frames and in the heap measurement: its
// level-set nodes, or for a sphere 26 points on its radius (the face, edge and corner directions
// of a cube). A sphere template also carries ~1,400 nodes for contacts with non-spherical grains;
// writing those for 32,000 spheres made a 1.3 GB final_nodes.csv and 50 s of formatting.
template <class F>
void for_each_surface_point(const dem::GrainTemplate& t, F&& f) {
  if (!t.is_sphere()) {
    for (const Vec3& node : t.nodes()) f(node);
    return;
  }
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        const Vec3 d{Real(i), Real(j), Real(k)};
        f(d * (t.radius() / norm(d)));
      }
}

// World positions (and velocities) of every grain's surface points, as the "grains" block.
ParticleSet<Host> node_particles(const dem::DemSystem& sys) {
  Index n = 0;
  for (const dem::RigidBody& b : sys.bodies())
    for_each_surface_point(sys.shape(b.shape), [&](const Vec3&) { ++n; });
  ParticleSet<Host> ps;
  ps.resize(n);
  ps.n_grain = n;
  Index k = 0;
  for (std::size_t i = 0; i < sys.bodies().size(); ++i) {
    const dem::RigidBody& b = sys.bodies()[i];
    for_each_surface_point(sys.shape(b.shape), [&](const Vec3& node) {
      const Vec3 x = b.x + rotate(b.q, node);
      ps.pos[std::size_t(k)] = x;
      ps.vel[std::size_t(k)] = dem::point_velocity(b, x);
      ps.id[std::size_t(k)] = b.id;
      ps.body[std::size_t(k)] = kGrainBodyBase - std::int32_t(i);
      ps.mass[std::size_t(k)] = b.mass;
      ++k;
    });
  }
  return ps;
}

std::vector<Vec3> node_positions(const dem::DemSystem& sys) {
  std::vector<Vec3> out;
  for (const dem::RigidBody& b : sys.bodies())
    for_each_surface_point(sys.shape(b.shape),
                           [&](const Vec3& node) { out.push_back(b.x + rotate(b.q, node)); });
  return out;
}

}  // namespace

void check_grain_guards(const Scene& scene, const dem::DemSystem& sys, Real min_d) {
  const Real ratio = sys.max_overlap() / min_d;
  if (ratio > scene.dem.overlap_max) {
    std::ostringstream m;
    m << "DEM overlap " << sys.max_overlap() << " m = " << ratio
      << " of the smallest grain diameter at t = " << sys.time()
      << " s exceeds dem.overlap_max = " << scene.dem.overlap_max
      << ": the contacts are too soft for the load or the step is too large (raise kn or young, "
         "lower dem.dt_factor or time.dt_fixed)";
    throw StabilityError(m.str());
  }
  for (const dem::RigidBody& b : sys.bodies()) {
    for (int a = 0; a < 3; ++a) {
      if (!(b.x[a] >= scene.domain_lo[a] && b.x[a] <= scene.domain_hi[a])) {
        std::ostringstream m;
        m << "DEM: grain " << b.id << " left the domain at t = " << sys.time()
          << " s (x = " << b.x.x << ", " << b.x.y << ", " << b.x.z
          << " m): a wall let it through (step too large for the contact stiffness?)";
        throw StabilityError(m.str());
      }
    }
  }
}

RunResult run_granular(const Scene& scene, const RunOptions& opt) {
  if (world_size() > 1)
    throw InputError(scene.source +
                     ": a scene of grains only runs on one rank (the DEM is not decomposed yet); "
                     "run it without mpirun");
  if (opt.backend == Backend::kDevice)
    throw InputError("--backend device: the DEM has no GPU path yet; run '" + scene.name +
                     "' with --backend host or auto");
  if (!scene.dem.subcycle)
    throw InputError(scene.source +
                     ": dem.subcycle: false applies to grains in a fluid (fluid_blocks); a run of "
                     "grains only has one step already");
  const std::string restart_file = prepare_output(opt);
  const bool restarting = !restart_file.empty();
  Log log(opt.out_dir + "/run.log", opt.quiet, restarting);
  {
    std::ofstream y(opt.out_dir + "/scene.yaml");
    y << scene.yaml_text;
  }
  log << "sphdem " << SPHDEM_VERSION << " (" << SPHDEM_PRECISION_NAME << ") scene '" << scene.name
      << "' from " << scene.source << "\n";
  std::ostringstream blog;
  DemBuild build = build_dem(scene, blog);
  dem::DemSystem& sys = *build.system;
  log << blog.str();
  log << "grains: " << sys.bodies().size() << ", walls: " << sys.walls().size() << "; DEM step "
      << build.dt << " s (t_c/50 = " << sys.time_step()
      << " s); backend: host (the DEM runs on the CPU)\n";

  Real next_diag = 0;
  std::int64_t step = 0;
  if (restarting) {
    CheckpointData cp = read_checkpoint(restart_file);
    if (cp.dem.bodies.empty())
      throw InputError(restart_file + ": holds no grains; it is not a checkpoint of '" +
                       scene.name + "'");
    if (cp.scene_yaml != scene.yaml_text)
      log << "note: the checkpoint was written with a different scene text; continuing with "
          << scene.source << "\n";
    try {
      sys.restore(cp.dem);
    } catch (const InputError& e) {
      throw InputError(restart_file + ": " + e.what());
    }
    next_diag = cp.next_output_time;
    step = cp.counters.step;
    log << "restarted from " << restart_file << " at t = " << sys.time() << " s, step " << step
        << "\n";
  }

  RunResult r;
  r.space = "host";
  r.grain = Index(sys.bodies().size());
  // grains.csv
  const std::string csv = opt.out_dir + "/grains.csv";
  if (restarting) CsvSeries::trim(csv, double(sys.time()));  // rows after the checkpoint go first
  std::ofstream diag(csv, restarting ? std::ios::app : std::ios::trunc);
  if (!diag) throw InputError("cannot write '" + csv + "'");
  diag << std::setprecision(10);
  if (!restarting) diag << "t,kinetic_energy,contacts,pairs,max_overlap_per_d,front_x,top_z\n";
  auto write_diag = [&]() {
    Real front = -1e30, top = -1e30;
    for (const dem::RigidBody& b : sys.bodies()) {
      front = std::max(front, b.x.x);
      top = std::max(top, b.x.z);
    }
    diag << sys.time() << "," << sys.kinetic_energy() << "," << sys.contact_count() << ","
         << sys.pair_count() << "," << sys.max_overlap() / build.min_diameter << "," << front << ","
         << top << "\n";
  };
  std::unique_ptr<FrameWriter> frames;
  Real next_frame = 0;
  if (scene.frames.every > 0) {
    FrameParams fp = scene.frames;
    fp.boundary = true;  // the grains block
    frames = std::make_unique<FrameWriter>(opt.out_dir, fp, scene.dim);
    if (restarting) {
      frames->adopt_existing(sys.time());
      next_frame = scene.frames.every * Real(frames->count());
    }
  }
  auto save = [&](const std::string& path) {
    CheckpointData cp;
    cp.dem = sys.state();
    cp.counters.time = sys.time();
    cp.counters.step = step;
    cp.next_output_time = next_diag;
    cp.scene_yaml = scene.yaml_text;
    cp.dim = scene.dim;
    cp.dp = scene.sph.dp;
    const std::uint64_t bytes = write_checkpoint(path, cp);
    ++r.checkpoints;
    r.last_checkpoint = path;
    log << "checkpoint " << path << " (" << bytes / 1048576.0 << " MiB) at t = " << sys.time()
        << " s\n";
  };

  SignalGuard signals(opt.handle_signals);
  const bool tty = !opt.quiet && isatty(STDOUT_FILENO);
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last_progress = start, last_checkpoint_wall = start;
  const CheckpointParams& ck = scene.checkpoint;
  Real next_checkpoint_time =
      ck.every_time > 0 ? ck.every_time * (std::floor(sys.time() / ck.every_time + Real(1e-9)) + 1)
                        : Real(0);
  const Real end = scene.time.end;
  const Real dt = build.dt;
  std::int64_t steps = 0;
  bool damping_on = false;
  LoopTimes lt;  // bench: opt.time_after_steps
  TimingMark mark;
  try {
    while (sys.time() < end - Real(1e-12) * end && (opt.max_steps < 0 || steps < opt.max_steps)) {
      if (steps == opt.time_after_steps) mark = {clock::now(), PhaseTimes{}, lt};
      bool frame_now = false;
      timed(lt.io, [&] {
        if (sys.time() >= next_diag - Real(1e-12)) {
          write_diag();
          next_diag += scene.diagnostics.every;
          // dem.stop_at_rest, checked at diagnostics times only: a restart (which resumes the
          // same schedule) stops at the same step as a straight run.
          const Real ke = scene.dem.stop_at_rest && sys.time() >= scene.dem.rest_after - Real(1e-12)
                              ? sys.kinetic_energy()
                              : Real(-1);
          if (ke >= 0 && ke < scene.dem.rest_energy) {
            r.at_rest = true;
            log << "t = " << sys.time() << " s: at rest (kinetic energy " << ke << " J < "
                << scene.dem.rest_energy << " J, dem.stop_at_rest); stopping\n";
          }
        }
        if (frames && sys.time() >= next_frame - Real(1e-12)) {
          frames->write(sys.time(), node_particles(sys));
          next_frame += scene.frames.every;
          frame_now = true;
        }
        if (r.at_rest && frames && !frame_now) frames->write(sys.time(), node_particles(sys));
      });
      if (r.at_rest) break;
      timed(lt.dem, [&] {
        // Moving walls and the packing drag.
        for (const std::string& gate : update_walls(scene, build, sys.time()))
          log << "t = " << sys.time() << " s: solid '" << gate << "' removed (removed_at)\n";
        const bool damp = sys.time() < scene.dem.settle_until && scene.dem.settle_damping > 0;
        if (damp || damping_on) {
          for (std::size_t i = 0; i < sys.bodies().size(); ++i) {
            const dem::RigidBody& b = sys.bodies()[i];
            sys.set_external(i, damp ? -scene.dem.settle_damping * b.mass * b.v : Vec3(), Vec3());
          }
          damping_on = damp;
        }
        sys.step(dt);
      });
      ++steps;
      ++step;
      timed(lt.guards, [&] { check_grain_guards(scene, sys, build.min_diameter); });
      const auto now = clock::now();
      const int sig = g_signal;
      const bool by_steps = ck.every_steps > 0 && step % ck.every_steps == 0;
      const bool by_time = ck.every_time > 0 && sys.time() >= next_checkpoint_time - Real(1e-12);
      const bool by_wall =
          ck.every_wall > 0 &&
          std::chrono::duration<double>(now - last_checkpoint_wall).count() >= ck.every_wall;
      if (by_steps || by_time || by_wall || sig != 0) {
        if (sig != 0) log << "signal " << (sig == SIGTERM ? "SIGTERM" : "SIGUSR1") << " received\n";
        diag.flush();
        timed(lt.io, [&] {
          save(checkpoint_path(opt.out_dir, step));
          prune_checkpoints(opt.out_dir, ck.keep);
        });
        last_checkpoint_wall = now;
        while (ck.every_time > 0 && next_checkpoint_time <= sys.time() + Real(1e-12))
          next_checkpoint_time += ck.every_time;
        g_signal = 0;
        if (sig == SIGTERM) {
          r.interrupted = true;
          log << "stopping on SIGTERM; continue with --restart latest\n";
          break;
        }
      }
      const double since = std::chrono::duration<double>(now - last_progress).count();
      if (!opt.quiet && since > (tty ? 0.25 : opt.progress_every_s)) {
        last_progress = now;
        const double wall = std::chrono::duration<double>(now - start).count();
        const double rate = double(steps) / wall;
        std::ostringstream line;
        line << "t = " << std::setprecision(4) << sys.time() << " s, step " << step << ", "
             << std::setprecision(3) << rate << " steps/s, " << rate * double(sys.bodies().size())
             << " grain-steps/s, " << sys.contact_count() << " contact points, ETA "
             << fmt_duration((end - sys.time()) / dt / rate);
        if (tty) {
          std::cout << "\r" << line.str() << "   " << std::flush;
        } else {
          std::cout << line.str() << "\n";
        }
        log.file() << line.str() << std::endl;  // flushed: tail -f run.log shows progress
      }
    }
    if (opt.time_after_steps >= 0 && steps > opt.time_after_steps) {
      r.timing = timing_since(mark, steps - opt.time_after_steps, PhaseTimes{}, lt);
      r.timing.grains = Index(sys.bodies().size());
      r.timing.contacts = double(sys.contact_count());
    }
    // The final row and frame only at the end time: a run stopped early (--max-steps, SIGTERM)
    // and continued from its checkpoint then writes the same rows as one straight run.
    if (sys.time() >= end - Real(1e-12) * end) {
      write_diag();
      if (frames) frames->write(sys.time(), node_particles(sys));
    }
  } catch (const StabilityError& e) {
    r.unstable = true;
    r.failure = e.what();
    if (tty) std::cout << "\n";
    log << "ERROR: " << e.what() << "\n";
    const std::string dump = opt.out_dir + "/emergency_step" + std::to_string(step) + ".h5";
    save(dump);
    log << "emergency state written to " << dump << "\n";
  }
  if (tty && !r.unstable) std::cout << "\n";
  diag.flush();
  r.steps = steps;
  r.sim_time = sys.time();
  r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  const double grain_steps = double(steps) * double(sys.bodies().size());
  r.particle_steps_per_second = r.wall_seconds > 0 ? grain_steps / r.wall_seconds : 0;
  log << "done: " << r.steps << " steps, t = " << r.sim_time << " s, " << r.wall_seconds
      << " s wall, " << (r.wall_seconds > 0 ? 1e3 * r.wall_seconds / double(steps) : 0)
      << " ms/step, " << r.particle_steps_per_second << " grain-steps/s\n";
  if (scene.dem.heap && !r.unstable && !r.interrupted) {
    HeapOptions ho;
    ho.cell = build.min_diameter;
    ho.z_floor = scene.dem.heap_floor;
    ho.x_min = scene.dem.heap_x_min;
    ho.x_max = scene.dem.heap_x_max;
    const std::vector<Vec3> nodes = node_positions(sys);
    const HeapShape h = measure_heap(nodes, ho);
    {  // the heap's surface nodes, for plots (app/plot_heap.py)
      std::ofstream f(opt.out_dir + "/final_nodes.csv");
      f << std::setprecision(7) << "x,y,z\n";
      for (const Vec3& x : nodes) f << x.x << "," << x.y << "," << x.z << "\n";
    }
    log << "heap: repose angle " << h.repose_deg << " deg (plane fit over " << h.columns
        << " columns, rms " << h.fit_rms << " m), height " << h.height << " m, toe at x = " << h.toe
        << " m, run-out from x = " << scene.dem.heap_origin << ": " << h.toe - scene.dem.heap_origin
        << " m\n";
    std::ofstream j(opt.out_dir + "/heap.json");
    j << std::setprecision(8) << "{\n  \"repose_deg\": " << h.repose_deg
      << ",\n  \"height\": " << h.height << ",\n  \"toe\": " << h.toe
      << ",\n  \"runout\": " << h.toe - scene.dem.heap_origin << ",\n  \"columns\": " << h.columns
      << ",\n  \"fit_rms\": " << h.fit_rms << ",\n  \"kinetic_energy\": " << sys.kinetic_energy()
      << "\n}\n";
  }
  write_summary(opt.out_dir + "/summary.json", scene, r);
  log.flush();
  return r;
}

void check_granular(const Scene& scene, std::ostream& os) {
  std::ostringstream blog;
  DemBuild build = build_dem(scene, blog);
  dem::DemSystem& sys = *build.system;
  std::size_t nodes = 0;
  for (const dem::RigidBody& b : sys.bodies()) nodes += sys.shape(b.shape).nodes().size();
  const double steps = std::ceil(scene.time.end / build.dt);
  os << "scene '" << scene.name << "' (" << scene.source << "): grains only\n"
     << blog.str() << "grains: " << sys.bodies().size() << " (" << nodes
     << " surface nodes), walls: " << sys.walls().size() << "\n"
     << "DEM step: " << build.dt << " s (t_c/50 = " << sys.time_step() << " s), " << steps
     << " steps to t = " << scene.time.end << " s\n";
}

}  // namespace sphdem
