// Grain templates for level-set DEM (seed §2.2, Fig. 2a; Kawamoto et al. 2016; DESIGN.md §2).
//
// A grain shape is a signed-distance grid phi in its BODY frame (centroid at the origin, axes
// along the principal axes of inertia) plus a set of surface nodes. Grains of one shape share
// one template; a grain itself is only its rigid-body state (dem/rigid_body.hpp).
//
// Mass properties come from integrating the shape's SDF on a quadrature grid with a smoothed
// Heaviside H(phi) = clamp(1/2 - phi/h_q, 0, 1) (a linear ramp one quadrature cell wide):
//   V = sum H dV,  c = sum H x dV / V,  J = sum H (|r|^2 1 - r r^T) dV  (r = x - c, per unit
//   density)
// J is diagonalised (Jacobi rotations); its eigenvectors, ordered by increasing moment and made a
// right-handed frame, are the body axes.
//
// Sources: sphere (analytic phi, flagged for the one-point contact fast path), box, ellipsoid,
// trigonal pyramid with a seeded random perturbation of its vertices (the seed's crushed rock),
// random convex polyhedron of a given equivalent diameter (an "irregular boulder"), and a closed
// triangle mesh (STL/OBJ). Resolution: the grid spacing sets the accuracy of phi (trilinear) and
// the node spacing sets how finely the surface is sampled by contacts; both are reported by
// describe().
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/quat.hpp"
#include "core/types.hpp"
#include "geometry/grid_sdf.hpp"
#include "geometry/sdf.hpp"

namespace sphdem::dem {

struct TemplateOptions {
  Real grid_spacing = 0;  // phi grid spacing [m]; 0: size / 30
  Real node_spacing = 0;  // target surface node spacing [m]; 0: = grid_spacing
  int pad_cells = 3;      // grid cells added around the shape on each side
  int quad_sub = 4;       // quadrature points per grid cell along each axis (mass properties)
};

// A convex polyhedron {x : n_k . x <= d_k for all k} with its vertices and a triangulation of
// its boundary (faces fanned from their centroid-ordered vertices, outward orientation).
struct ConvexPolyhedron {
  std::vector<Vec3> normals;  // outward unit normals of the planes that bound a face
  std::vector<Real> offsets;  // n . x <= offset
  std::vector<Vec3> vertices;
  std::vector<int> triangles;           // 3 vertex indices each
  std::vector<std::vector<int>> faces;  // vertex indices of each face, counter-clockwise outside
  Real volume = 0;
};

// Builds the polyhedron bounded by the half-spaces n_k . x <= d_k (n_k need not be unit).
// Redundant planes are dropped. Throws sphdem::InputError if the region is empty, unbounded or
// degenerate.
ConvexPolyhedron make_convex_polyhedron(const std::vector<Vec3>& normals,
                                        const std::vector<Real>& offsets);
// The convex hull of exactly four non-coplanar points (a tetrahedron).
ConvexPolyhedron make_tetrahedron(const Vec3 p[4]);
// The exact SDF of a convex polyhedron: the largest plane distance inside, the distance to the
// nearest boundary triangle outside.
geom::SdfPtr make_polyhedron_sdf(const ConvexPolyhedron& poly);
// An SDF for the ellipsoid with semi-axes a: phi = k0 (k0 - 1) / k1, k0 = |x/a|, k1 = |x/a^2|
// (exact zero set, unit gradient on the surface; a close approximation of the distance nearby).
geom::SdfPtr make_ellipsoid_sdf(Vec3 semi_axes);

// The surface nodes of one octant of the body frame: node_order()[begin, end) are their indices,
// within `radius` of `centre` (body frame). A contact pass skips an octant facing away from the
// other grain without looking at its nodes.
struct NodeGroup {
  Vec3 centre;
  Real radius = 0;
  std::uint32_t begin = 0, end = 0;
};

class GrainTemplate {
 public:
  // ---- sources (all shapes are centred and rotated to principal axes on construction) -----
  static GrainTemplate sphere(Real radius, const TemplateOptions& opt = {});
  static GrainTemplate box(Vec3 half_extents, const TemplateOptions& opt = {});
  static GrainTemplate ellipsoid(Vec3 semi_axes, const TemplateOptions& opt = {});
  // A trigonal pyramid (tetrahedron with an equilateral base of edge `size` and its apex at height
  // `size` above the base centroid); each vertex moved by up to perturbation * size along each axis
  // (uniform, seeded). The result is scaled to equivalent diameter d_eq if d_eq > 0.
  static GrainTemplate trigonal_pyramid(Real size, Real perturbation, std::uint32_t seed,
                                        Real d_eq = 0, const TemplateOptions& opt = {});
  // A random convex polyhedron cut by n_planes (>= 6) planes with seeded random normals and
  // offsets, scaled to the equivalent diameter d_eq (volume = pi d_eq^3 / 6).
  static GrainTemplate random_polyhedron(Real d_eq, int n_planes, std::uint32_t seed,
                                         const TemplateOptions& opt = {});
  static GrainTemplate polyhedron(const ConvexPolyhedron& poly, const TemplateOptions& opt = {});
  // A closed triangle mesh (geom::load_mesh), scaled by `scale`.
  static GrainTemplate mesh(const geom::TriMesh& mesh, Real scale = 1,
                            const TemplateOptions& opt = {});
  // Any SDF with surface nodes given in the same (source) frame. Used by all of the above.
  static GrainTemplate from_sdf(const geom::Sdf& sdf, const std::vector<Vec3>& source_nodes,
                                const TemplateOptions& opt, bool is_sphere, Real sphere_radius);

  // ---- data ---------------------------------------------------------------------------------
  bool is_sphere() const { return is_sphere_; }
  Real radius() const { return radius_; }                    // sphere radius (spheres only)
  Real bounding_radius() const { return bounding_radius_; }  // max |node| (body frame), or R
  Real volume() const { return volume_; }
  Real equivalent_diameter() const { return d_eq_; }  // (6 V / pi)^{1/3}
  // Principal moments of inertia per unit density (multiply by rho), ascending.
  Vec3 inertia_per_density() const { return inertia_; }
  // The source frame of the shape seen from the body frame: x_source = centroid + R x_body.
  Vec3 source_centroid() const { return centroid_; }
  Mat3 source_rotation() const { return rotation_; }
  // Full inertia tensor about the centroid in the source frame, per unit density (diagnostic).
  Mat3 source_inertia_tensor() const { return tensor_; }

  const std::vector<Vec3>& nodes() const { return nodes_; }  // body frame
  // The nodes' indices grouped by octant, and the groups (non-empty ones only).
  const std::vector<std::uint32_t>& node_order() const { return node_order_; }
  const std::vector<NodeGroup>& node_groups() const { return groups_; }
  geom::GridSdfView view() const {
    return geom::GridSdfView{lo_, spacing_, {n_[0], n_[1], n_[2]}, phi_.data(), Real(1) / spacing_};
  }
  const std::vector<Real>& phi_values() const { return phi_; }
  // Bounds on geom::grid_phi over this grid, used to skip nodes that cannot reach the grain
  // (DemSystem's per-pair node lists): |phi(x) - phi(x')| <= phi_lipschitz() |x - x'| everywhere
  // (sqrt(L^2 + 1), L the interpolant's steepest gradient; the 1 is for the distance added
  // outside the grid box), and
  // phi(x) >= phi_box_min() + dist(x, grid box) outside the box (the least boundary value).
  Real phi_lipschitz() const { return phi_lipschitz_; }
  Real phi_box_min() const { return phi_box_min_; }
  Vec3 grid_lo() const { return lo_; }
  Vec3 grid_hi() const {
    return lo_ + spacing_ * Vec3(Real(n_[0] - 1), Real(n_[1] - 1), Real(n_[2] - 1));
  }
  Real grid_spacing() const { return spacing_; }
  Real node_spacing() const { return node_spacing_; }
  std::string describe() const;  // node count, grid size and spacing, volume, inertia

 private:
  void group_nodes();  // node_order_ and groups_ from nodes_
  void grid_bounds();  // phi_lipschitz_ and phi_box_min_ from phi_
  bool is_sphere_ = false;
  Real radius_ = 0, bounding_radius_ = 0, volume_ = 0, d_eq_ = 0;
  Vec3 inertia_, centroid_;
  Mat3 rotation_{}, tensor_{};
  std::vector<Vec3> nodes_;
  std::vector<std::uint32_t> node_order_;
  std::vector<NodeGroup> groups_;
  Vec3 lo_;
  Real spacing_ = 0, node_spacing_ = 0, phi_lipschitz_ = 0, phi_box_min_ = 0;
  int n_[3] = {1, 1, 1};
  std::vector<Real> phi_;
};

// Symmetric 3x3 eigen-decomposition by cyclic Jacobi rotations: a = V diag(lambda) V^T with
// eigenvalues ascending and V a proper rotation (det +1; columns are the eigenvectors).
void symmetric_eigen(const Mat3& a, Vec3* lambda, Mat3* v);

// The unit quaternion of a proper rotation matrix.
Quat quat_from_matrix(const Mat3& r);

}  // namespace sphdem::dem
