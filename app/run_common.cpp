#include "run_common.hpp"

#include "io/checkpoint.hpp"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace sphdem {

std::string prepare_output(const RunOptions& opt) {
  std::error_code ec;
  std::filesystem::create_directories(opt.out_dir, ec);
  if (ec)
    throw InputError("--out: cannot create output folder '" + opt.out_dir + "': " + ec.message());
  std::string restart_file = opt.restart;
  if (restart_file == "latest") {
    restart_file = latest_checkpoint(opt.out_dir);
    if (restart_file.empty())
      throw InputError("--restart latest: no checkpoint_*.h5 in '" + opt.out_dir + "'");
  }
  return restart_file;
}

RunTiming timing_since(const TimingMark& from, std::int64_t steps, const PhaseTimes& solver_now,
                       const LoopTimes& loop_now) {
  RunTiming t;
  t.steps = steps;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - from.t).count();
  t.solver = solver_now - from.solver;
  t.loop.coupling = loop_now.coupling - from.loop.coupling;
  t.loop.dem = loop_now.dem - from.loop.dem;
  t.loop.io = loop_now.io - from.loop.io;
  t.loop.guards = loop_now.guards - from.loop.guards;
  return t;
}

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
    << "  \"guards\": {\"mach_max\": " << scene.guards.mach_max
    << ", \"rho_min_ratio\": " << scene.guards.rho_min_ratio
    << ", \"rho_max_ratio\": " << scene.guards.rho_max_ratio << "},\n"
    << "  \"checkpoints\": " << r.checkpoints << ",\n"
    << "  \"last_checkpoint\": \"" << r.last_checkpoint << "\",\n"
    << "  \"status\": \""
    << (r.unstable ? "unstable" : (r.interrupted ? "interrupted" : "completed")) << "\"";
  if (r.at_rest) f << ",\n  \"stopped_at_rest\": true";
  if (r.unstable) {
    std::string msg;
    for (char c : r.failure)
      msg += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    f << ",\n  \"failure\": \"" << msg << "\"";
  }
  f << "\n}\n";
}

volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_signal(int sig) {
  g_signal = sig;
}

SignalGuard::SignalGuard(bool on) : on_(on) {
  if (!on_) return;
  g_signal = 0;
  old_term_ = std::signal(SIGTERM, on_signal);
  old_usr1_ = std::signal(SIGUSR1, on_signal);
}
SignalGuard::~SignalGuard() {
  if (!on_) return;
  std::signal(SIGTERM, old_term_);
  std::signal(SIGUSR1, old_usr1_);
}

}  // namespace sphdem
