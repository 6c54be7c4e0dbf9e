// Turns a scene into particles (DESIGN.md §2): fluid blocks on the dp lattice minus solids,
// boundary particles on the same lattice where -depth < phi < 0, inside the domain, with their
// mDBC ghost nodes r_G = r_B - 2 phi grad phi.
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "solver/particles.hpp"

namespace sphdem {

// A solid thinner than the boundary depth (the kernel support 2h, or sph.boundary_layers dp)
// somewhere on its wet surface: fluid there sees a truncated boundary.
struct ThinSolid {
  std::string name;
  Real thickness = 0;   // the least thickness found across the solid, behind its wet face [m]
  Index particles = 0;  // boundary particles in its first layer where it is that thin
};

// A solid with lattice points on its surface (within 1e-6 dp), where the boundary depth would
// make them wall particles: whether each one is depends on the last digits of dp and of the
// solid's coordinates, or on round-off.
struct SurfaceTie {
  std::string name;
  Index points = 0;
};

struct BuildReport {
  Index fluid = 0, wall = 0, grain = 0;
  Real fluid_height = 0;  // largest fluid depth along gravity, for c0
  Real boundary_depth = 0;
  // The largest distance between a wall particle's two mDBC ghost nodes (ghost, ghost_alt): a
  // thin solid's two faces, or a corner's two walls. On many ranks the halo reaches this much
  // farther, so that the rank owning a particle's ghost node holds the fluid around both.
  Real ghost_spread = 0;
  std::vector<ThinSolid> thin;       // in scene order
  std::vector<SurfaceTie> ties;      // in scene order
  std::vector<Index> wall_by_solid;  // boundary particles of each solid, in scene order
  // Symmetry plane (scene.symmetry): fluid and walls dropped on the mirrored side, and the wall
  // particles on the modelled side whose mirror image is not a wall particle of the full scene
  // (0 when the full scene's walls are symmetric about the plane), with their bounding box.
  // A solid's face that falls on a lattice row is one cause: the last digits of dp put the row
  // inside the solid at one face and outside at its mirror image (BuildReport::ties).
  Index symmetry_fluid_dropped = 0, symmetry_walls_dropped = 0, symmetry_unmatched = 0;
  Vec3 symmetry_unmatched_lo, symmetry_unmatched_hi;
};

// "warning: symmetry: N wall particles ..., between (..) and (..), have no mirror image ...: the
// run is not the full scene's half\n", or nothing when the walls are symmetric (report of a
// build with a symmetry plane).
void describe_symmetry_mismatch(const BuildReport& report, std::ostream& os);

// One line per thin solid of `report`, each starting with "warning: " and naming the solid, its
// thickness, the boundary depth and the remedy; nothing when no solid is thin.
void describe_thin_solids(const BuildReport& report, Real dp, std::ostream& os);

// One warning line naming the solids of `report.ties` and how many lattice points lie on their
// surfaces, with the remedy; nothing when there are none.
void describe_surface_ties(const BuildReport& report, Real dp, std::ostream& os);

// Which fixed-wall particles a build stores (many ranks: those near this rank's box, by position
// and mDBC ghost node). Every wall particle is still generated, numbered and counted in the
// report, so ids and counts do not depend on the filter; only the kept ones are stored.
using WallFilter = std::function<bool(const Vec3& pos, const Vec3& ghost)>;

ParticleSet<Host> build_particles(const Scene& scene, BuildReport* report = nullptr,
                                  const WallFilter& keep_wall = {});

// Speed of sound: scene value, or c0_factor * 2 sqrt(g H) with H the deepest fluid column:
// 2 sqrt(g H) is the dam-break front speed (Ritter), the fastest a column of depth H flows.
Real resolve_sound_speed(const Scene& scene, const BuildReport& report);

// Boundary depth: boundary_layers * dp, or the kernel support 2h when layers is 0.
Real boundary_depth(const Scene& scene);

}  // namespace sphdem
