// The full scene behind a run that models one side of a symmetry plane (core/symmetry.hpp):
// the diagnostics (gauges, profiles, forces, run-up, trap, energy) are evaluated on it, so their
// CSV files read as those of the full scene.
#pragma once

#include <cstdint>
#include <vector>

#include "core/symmetry.hpp"
#include "scene/scene.hpp"
#include "solver/particles.hpp"

namespace sphdem {

// For each solid of the scene, the solid its mirror image is: itself, except barrier walls, which
// pair with the wall at the mirrored place and angle (a wall without one pairs with itself and is
// listed in `unpaired`, if given).
std::vector<std::int32_t> mirror_solids(const Scene& scene,
                                        std::vector<std::string>* unpaired = nullptr);

// The modelled fluid and its mirror images, and every wall particle and its mirror image (with
// the paired solid's index and the fluid force m a reflected): a wall particle's force is that of
// the modelled fluid alone, so these sum to the full scene's force on each solid (mirror.cpp).
// No halo. Grains are not mirrored (a scene with a symmetry plane has none).
ParticleSet<Host> mirror_full(const ParticleSet<Host>& ps, const SymmetryPlane& plane,
                              const std::vector<std::int32_t>& solid_mirror);

}  // namespace sphdem
