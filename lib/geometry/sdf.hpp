// Signed-distance functions (DESIGN.md §2). Every solid is an SDF: phi < 0 inside, phi > 0 outside,
// |grad phi| = 1 near the surface. The same SDF places boundary particles (-2h < phi < 0), mirrors
// mDBC ghost nodes (r_G = r_B - 2 phi grad phi), carves fluid blocks and detects penetration.
//
// Fixed geometry is a tree of host-side primitives. Grains (and meshes) use a grid SDF with
// trilinear lookup (geometry/grid_sdf.hpp), which is also usable on the device.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace sphdem::geom {

struct Aabb {
  Vec3 lo, hi;
};

class Sdf {
 public:
  virtual ~Sdf() = default;
  virtual Real phi(const Vec3& x) const = 0;
  // Gradient of phi (unit length where phi is a true distance). Default: central differences.
  virtual Vec3 grad(const Vec3& x) const;
  // A box that contains the solid (the part with phi <= 0). Half-spaces return a huge box.
  virtual Aabb bounds() const = 0;
  // Signed distance to the surface the fluid wets, for points inside the solid (phi < 0). It is
  // phi itself except for shapes with faces no fluid reaches: a tank's outer faces. Boundary
  // particles are placed by it and their mDBC ghost nodes mirrored through it, so a wall thicker
  // than half the kernel support does not mirror its back layers out through the dry face (where
  // they find no fluid and read zero pressure).
  virtual Real wet_phi(const Vec3& x) const { return phi(x); }
  virtual Vec3 wet_grad(const Vec3& x) const { return grad(x); }
  // True if some faces are never wet (wet_phi differs from phi somewhere).
  virtual bool has_dry_faces() const { return false; }
};

using SdfPtr = std::shared_ptr<const Sdf>;

// Primitives.
SdfPtr make_box(Vec3 lo, Vec3 hi);                          // solid box
SdfPtr make_plane(Vec3 point, Vec3 outward_normal);         // solid where dot(x-point, n) < 0
SdfPtr make_slab(Vec3 point, Vec3 normal, Real thickness);  // |dot(x-point,n)| < thickness/2
SdfPtr make_cylinder(Vec3 a, Vec3 b, Real radius);          // capped cylinder from a to b
SdfPtr make_sphere(Vec3 center, Real radius);
// A tank: the walls of thickness t around the open-topped (or closed, closed_top=true) inner box.
// Only the inner faces are wet (wet_phi is minus the distance to the inner box).
SdfPtr make_tank(Vec3 inner_lo, Vec3 inner_hi, Real thickness, bool closed_top);

// Combinations and transforms.
SdfPtr make_union(std::vector<SdfPtr> parts);
SdfPtr make_difference(SdfPtr a, SdfPtr b);  // a minus b
// x_world = R * x_body + t; R from axis (any length > 0) and angle in radians.
SdfPtr make_transform(SdfPtr body, Vec3 axis, Real angle_rad, Vec3 translation);

// Triangle meshes.
struct TriMesh {
  std::vector<Vec3> vertices;
  std::vector<int> triangles;  // 3 indices per triangle
  std::string source;          // the file it was loaded from (named in error messages), or empty
};
// STL (ascii or binary, detected) or OBJ by extension. Errors name the file and the line.
TriMesh load_mesh(const std::string& path);
// A closed mesh turned into a grid SDF with the given spacing and padding (cells) around it.
SdfPtr make_mesh_sdf(const TriMesh& mesh, Real spacing, int pad_cells = 3);

}  // namespace sphdem::geom
