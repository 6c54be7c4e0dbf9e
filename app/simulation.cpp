#include "simulation.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "core/error.hpp"
#include "cuda/device.hpp"
#include "diagnostics/guards.hpp"
#include "diagnostics/probes.hpp"
#include "io/csv_series.hpp"

namespace sphdem {

Backend parse_backend(const std::string& s) {
  if (s == "auto") return Backend::kAuto;
  if (s == "host" || s == "cpu") return Backend::kHost;
  if (s == "device" || s == "gpu") return Backend::kDevice;
  throw InputError("--backend: '" + s + "' is not one of auto, host, device");
}

std::unique_ptr<SolverBase> make_solver(const Scene& scene, Backend backend, std::ostream& log,
                                        BuildReport* report) {
  BuildReport rep;
  ParticleSet<Host> ps = build_particles(scene, &rep);
  if (report) *report = rep;
  const Real c0 = resolve_sound_speed(scene, rep);
  if (rep.fluid == 0)
    throw InputError(scene.source + ": fluid_blocks: the scene holds no fluid particles");
  bool device = false;
  if (backend != Backend::kHost) {
    std::string why;
    const auto gpus = cuda::list_gpus(&why);
    if (!gpus.empty()) {
      device = true;
      log << "backend: device (" << gpus[0].name << ")\n";
    } else if (backend == Backend::kDevice) {
      throw InputError("--backend device: no usable GPU (" + why + ")");
    } else {
      log << "backend: host, " << host_thread_count() << " OpenMP threads (no GPU: " << why
          << ")\n";
    }
  } else {
    log << "backend: host, " << host_thread_count() << " OpenMP threads\n";
  }
  if (device) return make_device_solver(scene, std::move(ps), c0);
  return make_host_solver(scene, std::move(ps), c0);
}

namespace {

// Writes every particle as CSV: the emergency state dump when a guard fires.
void write_state_csv(const ParticleSet<Host>& ps, const std::string& path) {
  std::ofstream f(path);
  f << "id,role,x,y,z,vx,vy,vz,rho,p\n" << std::setprecision(12);
  for (Index i = 0; i < ps.size(); ++i) {
    f << ps.id[i] << ',' << (i < ps.n_fluid ? "fluid" : "boundary") << ',' << ps.pos[i].x << ','
      << ps.pos[i].y << ',' << ps.pos[i].z << ',' << ps.vel[i].x << ',' << ps.vel[i].y << ','
      << ps.vel[i].z << ',' << ps.rho[i] << ',' << ps.press[i] << '\n';
  }
}

// Diagnostics of a run: one CSV per named diagnostic.
class DiagnosticWriter {
 public:
  DiagnosticWriter(const Scene& s, const std::string& dir) : scene_(s) {
    const Diagnostics& d = s.diagnostics;
    for (const auto& g : d.pressure_gauges)
      pressure_.emplace_back(dir + "/" + g.name + ".csv", std::vector<std::string>{"t", "p"});
    for (const auto& g : d.height_gauges)
      height_.emplace_back(dir + "/" + g.name + ".csv", std::vector<std::string>{"t", "h"});
    for (const auto& g : d.fronts)
      front_.emplace_back(dir + "/" + g.name + ".csv", std::vector<std::string>{"t", "x_front"});
    for (const auto& g : d.forces)
      force_.emplace_back(dir + "/" + g.name + ".csv",
                          std::vector<std::string>{"t", "fx", "fy", "fz"});
    for (const auto& g : d.profiles) {
      profile_.emplace_back(dir + "/" + g.name + ".csv",
                            std::vector<std::string>{"t", "s", "x", "y", "z_surface"});
      profile_next_.push_back(0);
    }
    if (d.energy) energy_.open(dir + "/energy.csv", {"t", "kinetic", "potential", "total"});
  }

  void write(Real t, const ParticleSet<Host>& ps, const StepParams& p) {
    const Diagnostics& d = scene_.diagnostics;
    for (std::size_t i = 0; i < d.pressure_gauges.size(); ++i)
      pressure_[i].row({t, probe_pressure(ps, p, d.pressure_gauges[i].point)});
    for (std::size_t i = 0; i < d.height_gauges.size(); ++i) {
      const Real h = probe_surface_height(ps, p, d.height_gauges[i].x, d.height_gauges[i].y);
      height_[i].row({t, std::isfinite(h) ? h : 0.0});
    }
    for (std::size_t i = 0; i < d.fronts.size(); ++i)
      front_[i].row({t, probe_front(ps, d.fronts[i].origin, d.fronts[i].direction)});
    for (std::size_t i = 0; i < d.forces.size(); ++i) {
      int idx = -1;
      for (std::size_t s = 0; s < scene_.solids.size(); ++s)
        if (scene_.solids[s].name == d.forces[i].solid) idx = int(s);
      const Vec3 f = probe_solid_force(ps, idx);
      force_[i].row({t, f.x, f.y, f.z});
    }
    for (std::size_t i = 0; i < d.profiles.size(); ++i) {
      const ProfileSpec& pr = d.profiles[i];
      while (profile_next_[i] < pr.times.size() && t >= pr.times[profile_next_[i]]) {
        const int n = std::max(2, pr.samples);
        for (int k = 0; k < n; ++k) {
          const Real s = Real(k) / Real(n - 1);
          const Vec3 x = pr.from + (pr.to - pr.from) * s;
          const Real z = probe_surface_height(ps, p, x.x, x.y);
          profile_[i].row({t, s * norm(pr.to - pr.from), x.x, x.y, std::isfinite(z) ? z : 0.0});
        }
        ++profile_next_[i];
      }
    }
    if (d.energy) {
      const Energy e = probe_energy(ps, scene_.gravity);
      energy_.row({t, e.kinetic, e.potential, e.kinetic + e.potential});
    }
  }

 private:
  const Scene& scene_;
  std::vector<CsvSeries> pressure_, height_, front_, force_, profile_;
  std::vector<std::size_t> profile_next_;
  CsvSeries energy_;
};

// Both to the terminal and to run.log.
class Log {
 public:
  explicit Log(const std::string& path, bool quiet) : file_(path), quiet_(quiet) {
    if (!file_) throw InputError("cannot write run log '" + path + "'");
  }
  template <class T>
  Log& operator<<(const T& v) {
    file_ << v;
    if (!quiet_) std::cout << v;
    return *this;
  }
  void flush() {
    file_.flush();
    std::cout.flush();
  }
  std::ofstream& file() { return file_; }

 private:
  std::ofstream file_;
  bool quiet_;
};

std::string fmt_duration(double s) {
  std::ostringstream os;
  if (!std::isfinite(s)) return "?";
  if (s < 120) {
    os << std::fixed << std::setprecision(0) << s << " s";
  } else if (s < 7200) {
    os << std::fixed << std::setprecision(1) << s / 60 << " min";
  } else {
    os << std::fixed << std::setprecision(1) << s / 3600 << " h";
  }
  return os.str();
}

void write_summary(const std::string& path, const Scene& scene, const RunResult& r) {
  std::ofstream f(path);
  f << std::setprecision(10) << "{\n"
    << "  \"scene\": \"" << scene.name << "\",\n"
    << "  \"backend\": \"" << r.space << "\",\n"
    << "  \"steps\": " << r.steps << ",\n"
    << "  \"sim_time\": " << r.sim_time << ",\n"
    << "  \"wall_seconds\": " << r.wall_seconds << ",\n"
    << "  \"particles\": {\"fluid\": " << r.fluid << ", \"wall_boundary\": " << r.wall
    << ", \"grain_boundary\": " << r.grain << "},\n"
    << "  \"removed\": {\"count\": " << r.removed << ", \"mass\": " << r.removed_mass << "},\n"
    << "  \"particle_steps_per_second\": " << r.particle_steps_per_second << ",\n"
    << "  \"status\": \"" << (r.unstable ? "unstable" : "completed") << "\"";
  if (r.unstable) {
    std::string msg;
    for (char c : r.failure)
      msg += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    f << ",\n  \"failure\": \"" << msg << "\"";
  }
  f << "\n}\n";
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& opt) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(opt.out_dir, ec);
  if (ec)
    throw InputError("--out: cannot create output folder '" + opt.out_dir + "': " + ec.message());
  Log log(opt.out_dir + "/run.log", opt.quiet);
  {
    std::ofstream y(opt.out_dir + "/scene.yaml");
    y << scene.yaml_text;
  }
  log << "sphdem " << SPHDEM_VERSION << " (" << SPHDEM_PRECISION_NAME << ") scene '" << scene.name
      << "' from " << scene.source << "\n";
  std::ostringstream slog;
  BuildReport rep;
  auto solver = make_solver(scene, opt.backend, slog, &rep);
  log << slog.str();
  const StepParams& p = solver->params();
  log << "particles: " << rep.fluid << " fluid, " << rep.wall << " wall boundary, " << rep.grain
      << " grain boundary; dp = " << p.dp << " m, h = " << p.h << " m, c0 = " << p.eos.c0
      << " m/s\n";

  RunResult r;
  r.fluid = rep.fluid;
  r.wall = rep.wall;
  r.grain = rep.grain;
  r.space = solver->space_name();
  DiagnosticWriter diag(scene, opt.out_dir);
  const bool tty = !opt.quiet && isatty(STDOUT_FILENO);
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last_progress = start;
  Real next_diag = 0;
  const Real end = scene.time.end;
  double particle_steps = 0;
  std::int64_t steps = 0;
  try {
    while (solver->time() < end - Real(1e-12) * end &&
           (opt.max_steps < 0 || steps < opt.max_steps)) {
      if (solver->time() >= next_diag - Real(1e-12)) {
        diag.write(solver->time(), solver->host_particles(), p);
        next_diag += scene.diagnostics.every;
      }
      const StepStats st = solver->step();
      ++steps;
      particle_steps += double(solver->host_particles().n_fluid);
      if (st.removed > 0)
        log << "t = " << solver->time() << " s: " << st.removed
            << " fluid particles left the domain\n";
      check_step_guards(scene, p, st, solver->time(), solver->step_count());
      if (scene.guards.check_every > 0 && steps % scene.guards.check_every == 0)
        check_particle_guards(scene, p, solver->host_particles(), solver->time(),
                              solver->step_count());
      const auto now = clock::now();
      const double since = std::chrono::duration<double>(now - last_progress).count();
      if (!opt.quiet && (since > (tty ? 0.25 : opt.progress_every_s))) {
        last_progress = now;
        const double wall = std::chrono::duration<double>(now - start).count();
        const double rate = steps / wall;
        const double eta = (end - solver->time()) / st.dt / rate;
        std::ostringstream line;
        line << "t = " << std::setprecision(4) << solver->time()
             << " s, dt = " << std::setprecision(3) << st.dt << " s, step " << solver->step_count()
             << ", " << std::setprecision(3) << rate << " steps/s, " << particle_steps / wall
             << " particle-steps/s, ETA " << fmt_duration(eta);
        if (tty) {
          std::cout << "\r" << line.str() << "   " << std::flush;
        } else {
          std::cout << line.str() << "\n";
        }
        log.file() << line.str() << "\n";
      }
    }
    diag.write(solver->time(), solver->host_particles(), p);
  } catch (const StabilityError& e) {
    r.unstable = true;
    r.failure = e.what();
    const std::string dump =
        opt.out_dir + "/emergency_step" + std::to_string(solver->step_count()) + ".csv";
    write_state_csv(solver->host_particles(), dump);
    if (tty) std::cout << "\n";
    log << "ERROR: " << e.what() << "\n"
        << "emergency state written to " << dump << "\n";
  }
  if (tty && !r.unstable) std::cout << "\n";
  r.steps = steps;
  r.sim_time = solver->time();
  r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  r.removed = solver->removed_count();
  r.removed_mass = solver->removed_mass();
  r.particle_steps_per_second = r.wall_seconds > 0 ? particle_steps / r.wall_seconds : 0;
  if (r.removed > 0)
    log << "removed (open ends): " << r.removed << " particles, " << r.removed_mass << " kg\n";
  log << "done: " << r.steps << " steps, t = " << r.sim_time << " s, " << r.wall_seconds
      << " s wall, " << r.particle_steps_per_second << " particle-steps/s\n";
  write_summary(opt.out_dir + "/summary.json", scene, r);
  log.flush();
  return r;
}

void check_scene(const Scene& scene, std::ostream& os) {
  BuildReport rep;
  ParticleSet<Host> ps = build_particles(scene, &rep);
  const Real c0 = resolve_sound_speed(scene, rep);
  const StepParams p = make_step_params(scene, c0);
  // Estimated dt: acoustic limit at rest, force limit from gravity, viscous limit.
  const Real g = std::max(p.g_mag, Real(1e-12));
  const Real dt_f = std::sqrt(p.h / g);
  const Real dt_cv = p.h / c0;
  const Real dt_v = p.laminar && p.nu > 0 ? Real(0.125) * p.h * p.h / p.nu : Real(1e30);
  Real dt = std::min(scene.time.cfl * std::min(dt_f, dt_cv), dt_v);
  if (scene.time.dt_fixed > 0) dt = scene.time.dt_fixed;
  const double steps = std::ceil(scene.time.end / dt);
  // Memory: every field of every particle, plus the cell lists.
  std::size_t bytes_per = 0;
  ps.for_each_field([&](const char*, auto& b) { bytes_per += sizeof(*b.data()); });
  const double mem = double(bytes_per) * double(ps.size()) + 8.0 * double(p.grid.cell_count()) * 2;
  // Rough cost from the CPU figure in docs/BENCHMARKS.md (about 1e6 particle-steps/s per core).
  const double cost = double(rep.fluid) * steps / (1e6 * host_thread_count());
  os << "scene '" << scene.name << "' (" << scene.source << "), " << scene.dim << "D\n"
     << "particles: fluid " << rep.fluid << ", wall boundary " << rep.wall << ", grain boundary "
     << rep.grain << ", total " << ps.size() << "\n"
     << "dp = " << p.dp << " m, h = " << p.h << " m, c0 = " << c0 << " m/s, cells " << p.grid.n[0]
     << " x " << p.grid.n[1] << " x " << p.grid.n[2] << "\n"
     << "memory estimate: " << std::setprecision(3) << mem / 1048576.0 << " MiB\n"
     << "time step estimate: " << dt << " s (force " << dt_f << ", acoustic " << dt_cv
     << ", viscous " << dt_v << "; CFL " << scene.time.cfl << ")\n"
     << "steps to t = " << scene.time.end << " s: about " << std::setprecision(6) << steps << "\n"
     << "rough cost on " << host_thread_count() << " CPU threads: " << fmt_duration(cost) << "\n";
}

}  // namespace sphdem
