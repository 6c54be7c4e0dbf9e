// Running a scene and reading what the run leaves in its folder, for the validation tests: numeric
// CSV rows, whole files, and a checkpoint's particles by global id.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/simulation.hpp"
#include "io/checkpoint.hpp"

namespace sphdem::runfiles {

// A quiet run of `s` on the host into `out`, with no signal handlers. A fresh run (no restart)
// starts from an empty folder; `restart` (a checkpoint, or "latest") continues in `out` as it is.
// max_steps < 0 runs to time.end.
inline RunResult run_host(const Scene& s, const std::string& out, std::int64_t max_steps = -1,
                          const std::string& restart = "") {
  if (restart.empty()) std::filesystem::remove_all(out);
  RunOptions o;
  o.out_dir = out;
  o.backend = Backend::kHost;
  o.quiet = true;
  o.handle_signals = false;
  o.max_steps = max_steps;
  o.restart = restart;
  return run_scene(s, o);
}

// The rows of a CSV file with one header row, every cell a number.
inline std::vector<std::vector<double>> read_numeric_csv(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(f, line)) {
    std::vector<double> r;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Every field of every particle, keyed by global id, as raw bytes (bit-identity checks).
inline std::map<GlobalId, std::string> state_by_id(const CheckpointData& cp) {
  auto& ps = const_cast<ParticleSet<Host>&>(cp.particles);
  std::map<GlobalId, std::string> m;
  for (Index i = 0; i < ps.size(); ++i) {
    std::string bytes;
    ps.for_each_field([&](const char*, auto& b) {
      bytes.append(reinterpret_cast<const char*>(&b[std::size_t(i)]), sizeof(b[0]));
    });
    m[ps.id[i]] = bytes;
  }
  return m;
}

}  // namespace sphdem::runfiles
