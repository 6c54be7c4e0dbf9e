// `sphdem bench`: a named scene for a fixed number of steps after warm-up, timed per phase.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "simulation.hpp"

namespace sphdem {

struct BenchOptions {
  std::string scene_path;
  std::vector<std::string> overrides;
  Index target_particles = 0;  // > 0: scale dp so the fluid count is about this
  int warmup = 5;
  int steps = 20;
  Backend backend = Backend::kAuto;
  bool json = false;
  std::string out_dir;  // scenes with grains run into it; empty: a temporary folder, removed after
};

void run_bench(const BenchOptions& opt, std::ostream& os);

}  // namespace sphdem
