// Reading what a run leaves in its folder, for the validation tests: numeric CSV rows, whole
// files, and a checkpoint's particles by global id.
#pragma once

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"

namespace sphdem::runfiles {

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
