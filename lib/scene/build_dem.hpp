// Turns a scene's `dem` section into a DEM system (dem/dem_system.hpp): grain templates (one per
// shape variant), packs of grains on a lattice, solids as fixed or moving walls.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "dem/dem_system.hpp"
#include "scene/scene.hpp"

namespace sphdem {

dem::DemParams dem_params(const Scene& scene);

struct DemBuild {
  std::unique_ptr<dem::DemSystem> system;
  std::vector<int> wall_index;           // scene.dem.walls[k] -> system wall index
  std::vector<const Solid*> wall_solid;  // scene.dem.walls[k] -> its solid (in the Scene)
  Real min_diameter = 0;                 // smallest equivalent diameter of any grain
  Real max_radius = 0;                   // largest bounding radius
  Real dt = 0;                           // the step: time.dt_fixed, or dt_factor * t_c / 50
};

// Builds the templates, places the packs and adds the walls; writes one line per template
// (node count, grid spacing, volume) to `log`. Throws InputError naming the scene file and key
// (a pack that does not fit, a mesh that cannot be read).
DemBuild build_dem(const Scene& scene, std::ostream& log);

// The velocity of scene wall k at time t (its velocity in [start, stop), else 0).
Vec3 wall_velocity(const GrainWall& w, Real t);

// Sets each scene wall's velocity at time t, and switches off the walls whose solid has been
// removed by t (Solid::removed_at: a gate that opens). Returns the names of the solids whose
// walls went off in this call.
std::vector<std::string> update_walls(const Scene& scene, const DemBuild& dem, Real t);

}  // namespace sphdem
