// Scene helpers. Parsing and validation live in io/scene_yaml.cpp.
#include "scene/scene.hpp"

#include <cmath>

namespace sphdem {

// h = h_factor * sqrt(dim) * dp, the DualSPHysics "coefh" convention (h in 2D is sqrt(2) dp times
// the factor, in 3D sqrt(3) dp times it).
Real Scene::h() const {
  return sph.h_factor * std::sqrt(Real(dim)) * sph.dp;
}

const Solid* Scene::find_solid(const std::string& solid_name) const {
  for (const Solid& s : solids) {
    if (s.name == solid_name) return &s;
  }
  return nullptr;
}

}  // namespace sphdem
