// Pieces shared by the run drivers (simulation.cpp: SPH and coupled runs; granular.cpp: grains
// only): the run log, the summary file, signal handling.
#pragma once

#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <string>

#include "core/error.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"

namespace sphdem {

class Log {
 public:
  // Only rank 0 logs (enabled = false: a sink).
  Log(const std::string& path, bool quiet, bool append, bool enabled = true)
      : quiet_(quiet || !enabled) {
    if (!enabled) return;
    file_.open(path, append ? std::ios::app : std::ios::trunc);
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

// Creates the output folder and resolves --restart before anything is written there: returns the
// checkpoint to continue from ("latest": the newest in the folder), or "" for a fresh run.
// Throws InputError naming --out or --restart.
std::string prepare_output(const RunOptions& opt);

std::string fmt_duration(double s);
void write_summary(const std::string& path, const Scene& scene, const RunResult& r);

// Runs f() and adds its wall seconds to `acc`.
template <class F>
void timed(double& acc, F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  acc += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The timing of steps [from, now) of a run: `loop` and `solver` minus their values at `from`.
struct TimingMark {
  std::chrono::steady_clock::time_point t;
  PhaseTimes solver;
  LoopTimes loop;
};
RunTiming timing_since(const TimingMark& from, std::int64_t steps, const PhaseTimes& solver_now,
                       const LoopTimes& loop_now);

// Set by SIGTERM / SIGUSR1; polled once per step.
extern volatile std::sig_atomic_t g_signal;

// Installs the handlers for the run's lifetime (when `on`), restoring the old ones after.
struct SignalGuard {
  explicit SignalGuard(bool on);
  ~SignalGuard();
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;
  bool on_;
  void (*old_term_)(int) = SIG_DFL;
  void (*old_usr1_)(int) = SIG_DFL;
};

}  // namespace sphdem
