// Grain templates: shape sources, mass properties by SDF quadrature, principal axes, surface
// nodes and the body-frame phi grid (grain_template.hpp).
#include "dem/grain_template.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <type_traits>
#include <tuple>
#include <unordered_set>

#include "core/error.hpp"

namespace sphdem::dem {

namespace {

// ---- small geometry helpers ------------------------------------------------------------------

// The point of triangle (a, b, c) nearest to p, by the Voronoi regions of its vertices, edges and
// face (written from the barycentric conditions of each region).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const Real d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const Real d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const Real denom = Real(1) / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

Real det3(const Vec3& a, const Vec3& b, const Vec3& c) {
  return dot(a, cross(b, c));
}

// Points on the triangles of a surface, about `spacing` apart: a barycentric lattice on each
// triangle (vertices and edges included), with coincident points merged.
std::vector<Vec3> sample_triangles(const std::vector<Vec3>& v, const std::vector<int>& tri,
                                   Real spacing) {
  std::vector<Vec3> out;
  std::unordered_set<std::uint64_t> seen;
  const Real quantum = spacing * Real(1e-4);
  auto key = [&](const Vec3& p) {
    const auto q = [&](Real x) { return std::uint64_t(std::llround(x / quantum)) & 0x1FFFFFu; };
    return (q(p.x) << 42) | (q(p.y) << 21) | q(p.z);
  };
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Vec3 a = v[tri[t]], b = v[tri[t + 1]], c = v[tri[t + 2]];
    const Real lmax = std::max({norm(b - a), norm(c - a), norm(c - b)});
    const int n = std::max(1, int(std::ceil(lmax / spacing)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Vec3 p = a + (b - a) * (Real(i) / n) + (c - a) * (Real(j) / n);
        if (seen.insert(key(p)).second) out.push_back(p);
      }
  }
  return out;
}

// Points on the faces of a convex polyhedron, about `spacing` apart: the vertices, points along
// every edge, and a square lattice in each face plane aligned with the face's first edge, keeping
// lattice points at least spacing/2 inside the face. A box whose sides are multiples of the
// spacing gets a regular grid of nodes on each face.
std::vector<Vec3> sample_faces(const ConvexPolyhedron& poly, Real spacing) {
  std::vector<Vec3> out;
  std::unordered_set<std::uint64_t> seen;
  const Real quantum = spacing * Real(1e-4);
  auto add = [&](const Vec3& p) {
    const auto q = [&](Real x) { return std::uint64_t(std::llround(x / quantum)) & 0x1FFFFFu; };
    if (seen.insert((q(p.x) << 42) | (q(p.y) << 21) | q(p.z)).second) out.push_back(p);
  };
  const auto& v = poly.vertices;
  for (std::size_t f = 0; f < poly.faces.size(); ++f) {
    const auto& face = poly.faces[f];
    const Vec3 nrm = poly.normals[f];
    const std::size_t m = face.size();
    // Edges (vertices included).
    for (std::size_t e = 0; e < m; ++e) {
      const Vec3 a = v[face[e]], b = v[face[(e + 1) % m]];
      const int n = std::max(1, int(std::ceil(norm(b - a) / spacing - Real(1e-9))));
      for (int i = 0; i < n; ++i) add(a + (b - a) * (Real(i) / n));
    }
    // Interior lattice.
    const Vec3 o = v[face[0]];
    Vec3 e1 = v[face[1]] - o;
    e1 = e1 / norm(e1);
    const Vec3 e2 = cross(nrm, e1);
    Real u0 = 0, u1 = 0, w0 = 0, w1 = 0;
    for (int k : face) {
      u0 = std::min(u0, dot(v[k] - o, e1));
      u1 = std::max(u1, dot(v[k] - o, e1));
      w0 = std::min(w0, dot(v[k] - o, e2));
      w1 = std::max(w1, dot(v[k] - o, e2));
    }
    for (int i = int(std::floor(u0 / spacing)); i <= int(std::ceil(u1 / spacing)); ++i)
      for (int j = int(std::floor(w0 / spacing)); j <= int(std::ceil(w1 / spacing)); ++j) {
        const Vec3 p = o + e1 * (i * spacing) + e2 * (j * spacing);
        bool inside = true;
        for (std::size_t e = 0; e < m && inside; ++e) {
          const Vec3 a = v[face[e]], b = v[face[(e + 1) % m]];
          const Vec3 inward = cross(nrm, (b - a) / norm(b - a));  // faces are counter-clockwise
          inside = dot(p - a, inward) >= Real(0.5) * spacing - Real(1e-9) * spacing;
        }
        if (inside) add(p);
      }
  }
  return out;
}

// n points spread evenly over the unit sphere (Fibonacci spiral).
std::vector<Vec3> fibonacci_sphere(int n) {
  std::vector<Vec3> out;
  const Real golden = kPi * (Real(3) - std::sqrt(Real(5)));
  for (int i = 0; i < n; ++i) {
    const Real z = Real(1) - (Real(2) * i + Real(1)) / Real(n);
    const Real r = std::sqrt(std::max(Real(0), Real(1) - z * z));
    out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return out;
}

// ---- SDFs -----------------------------------------------------------------------------------

class PolyhedronSdf : public geom::Sdf {
 public:
  explicit PolyhedronSdf(ConvexPolyhedron p) : p_(std::move(p)) {
    const Real inf = std::numeric_limits<Real>::max();
    box_ = geom::Aabb{Vec3(inf, inf, inf), Vec3(-inf, -inf, -inf)};
    for (const Vec3& x : p_.vertices)
      for (int d = 0; d < 3; ++d) {
        box_.lo[d] = std::min(box_.lo[d], x[d]);
        box_.hi[d] = std::max(box_.hi[d], x[d]);
      }
  }
  Real phi(const Vec3& x) const override {
    Real m = -std::numeric_limits<Real>::max();
    for (std::size_t k = 0; k < p_.normals.size(); ++k)
      m = std::max(m, dot(p_.normals[k], x) - p_.offsets[k]);
    if (m <= 0) return m;  // inside a convex body the nearest face plane gives the distance
    Real best = std::numeric_limits<Real>::max();
    for (std::size_t t = 0; t + 2 < p_.triangles.size(); t += 3) {
      const Vec3 c =
          closest_on_triangle(x, p_.vertices[p_.triangles[t]], p_.vertices[p_.triangles[t + 1]],
                              p_.vertices[p_.triangles[t + 2]]);
      best = std::min(best, norm2(x - c));
    }
    return std::sqrt(best);
  }
  geom::Aabb bounds() const override { return box_; }

 private:
  ConvexPolyhedron p_;
  geom::Aabb box_;
};

class EllipsoidSdf : public geom::Sdf {
 public:
  explicit EllipsoidSdf(Vec3 a) : a_(a) {}
  Real phi(const Vec3& x) const override {
    const Vec3 u(x.x / a_.x, x.y / a_.y, x.z / a_.z);
    const Vec3 w(u.x / a_.x, u.y / a_.y, u.z / a_.z);
    const Real k0 = norm(u), k1 = norm(w);
    if (!(k1 > 0)) return -std::min({a_.x, a_.y, a_.z});
    return k0 * (k0 - Real(1)) / k1;
  }
  geom::Aabb bounds() const override { return geom::Aabb{-a_, a_}; }

 private:
  Vec3 a_;
};

Mat3 from_columns(const Vec3& c0, const Vec3& c1, const Vec3& c2) {
  Mat3 m{};
  for (int i = 0; i < 3; ++i) {
    m.m[i][0] = c0[i];
    m.m[i][1] = c1[i];
    m.m[i][2] = c2[i];
  }
  return m;
}

}  // namespace

// ---- linear algebra --------------------------------------------------------------------------

void symmetric_eigen(const Mat3& a_in, Vec3* lambda, Mat3* v_out) {
  double a[3][3], v[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      a[i][j] = 0.5 * (double(a_in.m[i][j]) + double(a_in.m[j][i]));
      v[i][j] = i == j ? 1.0 : 0.0;
    }
  // The rotations stop once the off-diagonal part is round-off. The tensor comes from
  // quadrature sums in Real: in a float build they leave off-diagonal noise of about
  // eps_float times the diagonal, and rotating on it would set the frame of a shape with equal
  // moments (a cube) at random, its axes off the faces. So the test there is (100 eps_float)^2
  // on the squares; double keeps 1e-32.
  const double off_tol = std::is_same_v<Real, float>
                             ? 1e4 * double(std::numeric_limits<float>::epsilon()) *
                                   double(std::numeric_limits<float>::epsilon())
                             : 1e-32;
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= off_tol * diag || off == 0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0) continue;
        // Rotation in the (p, q) plane that zeroes a[p][q].
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  std::array<int, 3> idx{0, 1, 2};
  std::sort(idx.begin(), idx.end(), [&](int i, int j) { return a[i][i] < a[j][j]; });
  Vec3 cols[3];
  for (int j = 0; j < 3; ++j) {
    (*lambda)[j] = Real(a[idx[j]][idx[j]]);
    cols[j] = Vec3(Real(v[0][idx[j]]), Real(v[1][idx[j]]), Real(v[2][idx[j]]));
  }
  if (det3(cols[0], cols[1], cols[2]) < 0) cols[2] = -cols[2];
  *v_out = from_columns(cols[0], cols[1], cols[2]);
}

Quat quat_from_matrix(const Mat3& r) {
  const Real tr = r.m[0][0] + r.m[1][1] + r.m[2][2];
  Quat q;
  if (tr > 0) {
    const Real s = std::sqrt(tr + Real(1)) * 2;
    q = Quat{Real(0.25) * s, (r.m[2][1] - r.m[1][2]) / s, (r.m[0][2] - r.m[2][0]) / s,
             (r.m[1][0] - r.m[0][1]) / s};
  } else if (r.m[0][0] > r.m[1][1] && r.m[0][0] > r.m[2][2]) {
    const Real s = std::sqrt(Real(1) + r.m[0][0] - r.m[1][1] - r.m[2][2]) * 2;
    q = Quat{(r.m[2][1] - r.m[1][2]) / s, Real(0.25) * s, (r.m[0][1] + r.m[1][0]) / s,
             (r.m[0][2] + r.m[2][0]) / s};
  } else if (r.m[1][1] > r.m[2][2]) {
    const Real s = std::sqrt(Real(1) + r.m[1][1] - r.m[0][0] - r.m[2][2]) * 2;
    q = Quat{(r.m[0][2] - r.m[2][0]) / s, (r.m[0][1] + r.m[1][0]) / s, Real(0.25) * s,
             (r.m[1][2] + r.m[2][1]) / s};
  } else {
    const Real s = std::sqrt(Real(1) + r.m[2][2] - r.m[0][0] - r.m[1][1]) * 2;
    q = Quat{(r.m[1][0] - r.m[0][1]) / s, (r.m[0][2] + r.m[2][0]) / s, (r.m[1][2] + r.m[2][1]) / s,
             Real(0.25) * s};
  }
  return normalize(q);
}

// ---- convex polyhedra ------------------------------------------------------------------------

ConvexPolyhedron make_convex_polyhedron(const std::vector<Vec3>& normals_in,
                                        const std::vector<Real>& offsets_in) {
  if (normals_in.size() != offsets_in.size() || normals_in.size() < 4)
    throw InputError("convex polyhedron: needs at least 4 planes with one offset each");
  std::vector<Vec3> nrm;
  std::vector<Real> off;
  for (std::size_t k = 0; k < normals_in.size(); ++k) {
    const Real l = norm(normals_in[k]);
    if (!(l > 0))
      throw InputError("convex polyhedron: plane normal " + std::to_string(k) + " is zero");
    nrm.push_back(normals_in[k] / l);
    off.push_back(offsets_in[k] / l);
  }
  Real scale = 0;
  for (Real d : off) scale = std::max(scale, std::fabs(d));
  if (!(scale > 0)) throw InputError("convex polyhedron: all planes pass through the origin");
  // 1e-9 of the size, but never below round-off: in a float build (epsilon 1.2e-7) a vertex that
  // three planes meet at misses the other planes by more than 1e-9, and the solid came out empty.
  const Real tol = std::max(Real(1e-9), Real(100) * std::numeric_limits<Real>::epsilon()) * scale;
  const std::size_t np = nrm.size();
  // Vertices: intersections of three planes that satisfy every constraint.
  std::vector<Vec3> verts;
  for (std::size_t i = 0; i < np; ++i)
    for (std::size_t j = i + 1; j < np; ++j)
      for (std::size_t k = j + 1; k < np; ++k) {
        const Real det = det3(nrm[i], nrm[j], nrm[k]);
        if (std::fabs(det) < Real(1e-10)) continue;
        const Vec3 x = (off[i] * cross(nrm[j], nrm[k]) + off[j] * cross(nrm[k], nrm[i]) +
                        off[k] * cross(nrm[i], nrm[j])) /
                       det;
        bool ok = true;
        for (std::size_t m = 0; m < np && ok; ++m) ok = dot(nrm[m], x) <= off[m] + tol;
        if (!ok) continue;
        bool dup = false;
        for (const Vec3& y : verts) dup = dup || norm(y - x) < 10 * tol;
        if (!dup) verts.push_back(x);
      }
  if (verts.size() < 4) throw InputError("convex polyhedron: the half-spaces bound no solid");
  ConvexPolyhedron p;
  p.vertices = verts;
  // Faces: the vertices on each plane, ordered by angle about their centroid, fanned.
  for (std::size_t k = 0; k < np; ++k) {
    std::vector<int> on;
    for (std::size_t v = 0; v < verts.size(); ++v)
      if (std::fabs(dot(nrm[k], verts[v]) - off[k]) <= 10 * tol) on.push_back(int(v));
    if (on.size() < 3) continue;  // redundant plane
    Vec3 c(0, 0, 0);
    for (int v : on) c += verts[v];
    c = c / Real(on.size());
    Vec3 e1 = verts[on[0]] - c;
    e1 = e1 / norm(e1);
    const Vec3 e2 = cross(nrm[k], e1);
    std::sort(on.begin(), on.end(), [&](int a, int b) {
      return std::atan2(dot(verts[a] - c, e2), dot(verts[a] - c, e1)) <
             std::atan2(dot(verts[b] - c, e2), dot(verts[b] - c, e1));
    });
    p.faces.push_back(on);
    for (std::size_t t = 1; t + 1 < on.size(); ++t) {
      p.triangles.push_back(on[0]);
      p.triangles.push_back(on[t]);
      p.triangles.push_back(on[t + 1]);
    }
    p.normals.push_back(nrm[k]);
    p.offsets.push_back(off[k]);
  }
  // Closed surface: every directed edge appears once, and its reverse once.
  std::map<std::pair<int, int>, int> edges;
  for (std::size_t t = 0; t < p.triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e) ++edges[{p.triangles[t + e], p.triangles[t + (e + 1) % 3]}];
  for (const auto& [e, count] : edges)
    if (count != 1 || edges.count({e.second, e.first}) == 0)
      throw InputError("convex polyhedron: the half-spaces do not bound a closed solid");
  for (std::size_t t = 0; t < p.triangles.size(); t += 3)
    p.volume +=
        det3(verts[p.triangles[t]], verts[p.triangles[t + 1]], verts[p.triangles[t + 2]]) / Real(6);
  if (!(p.volume > 0)) throw InputError("convex polyhedron: zero volume");
  return p;
}

ConvexPolyhedron make_tetrahedron(const Vec3 p[4]) {
  std::vector<Vec3> n;
  std::vector<Real> d;
  for (int f = 0; f < 4; ++f) {
    const Vec3 a = p[(f + 1) % 4], b = p[(f + 2) % 4], c = p[(f + 3) % 4], o = p[f];
    Vec3 nn = cross(b - a, c - a);
    if (dot(nn, o - a) > 0) nn = -nn;  // outward: away from the opposite vertex
    n.push_back(nn);
    d.push_back(dot(nn, a));
  }
  return make_convex_polyhedron(n, d);
}

geom::SdfPtr make_polyhedron_sdf(const ConvexPolyhedron& poly) {
  return std::make_shared<PolyhedronSdf>(poly);
}

geom::SdfPtr make_ellipsoid_sdf(Vec3 a) {
  if (!(a.x > 0 && a.y > 0 && a.z > 0)) throw InputError("ellipsoid: semi-axes must be positive");
  return std::make_shared<EllipsoidSdf>(a);
}

// ---- templates -------------------------------------------------------------------------------

GrainTemplate GrainTemplate::from_sdf(const geom::Sdf& sdf, const std::vector<Vec3>& src_nodes,
                                      const TemplateOptions& opt, bool is_sphere,
                                      Real sphere_radius) {
  if (src_nodes.empty()) throw InputError("grain template: no surface nodes");
  const Real inf = std::numeric_limits<Real>::max();
  Vec3 lo(inf, inf, inf), hi(-inf, -inf, -inf);
  for (const Vec3& x : src_nodes)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], x[d]);
      hi[d] = std::max(hi[d], x[d]);
    }
  const Real size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  GrainTemplate t;
  t.spacing_ = opt.grid_spacing > 0 ? opt.grid_spacing : size / Real(30);
  t.node_spacing_ = opt.node_spacing > 0 ? opt.node_spacing : t.spacing_;
  t.is_sphere_ = is_sphere;
  t.radius_ = sphere_radius;

  // Mass properties (per unit density) by quadrature with a smoothed Heaviside; exact values for
  // the analytic sphere.
  if (!is_sphere) {
    const int sub = std::max(1, opt.quad_sub);
    const Real hq = t.spacing_ / Real(sub);
    int nq[3];
    Vec3 qlo;
    for (int d = 0; d < 3; ++d) {
      qlo[d] = lo[d] - Real(1.5) * hq;
      nq[d] = int(std::ceil((hi[d] - lo[d] + 3 * hq) / hq));
    }
    // Per-slab partial sums combined in slab order, so the result does not depend on threads.
    struct Moments {
      double v = 0, m1[3] = {0, 0, 0}, m2[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    };
    std::vector<Moments> slab(static_cast<std::size_t>(nq[2]));
    const double dv = double(hq) * hq * hq;
#pragma omp parallel for schedule(static)
    for (int k = 0; k < nq[2]; ++k) {
      Moments& l = slab[std::size_t(k)];
      for (int j = 0; j < nq[1]; ++j)
        for (int i = 0; i < nq[0]; ++i) {
          const Vec3 x =
              qlo + Vec3((i + Real(0.5)) * hq, (j + Real(0.5)) * hq, (k + Real(0.5)) * hq);
          const Real ph = sdf.phi(x);
          const double h = std::clamp(0.5 - double(ph) / hq, 0.0, 1.0);
          if (h == 0) continue;
          l.v += h;
          for (int a = 0; a < 3; ++a) {
            l.m1[a] += h * x[a];
            for (int b = 0; b < 3; ++b) l.m2[a][b] += h * x[a] * x[b];
          }
        }
    }
    double vol = 0, m1[3] = {0, 0, 0}, m2[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (const Moments& l : slab) {
      vol += l.v;
      for (int a = 0; a < 3; ++a) {
        m1[a] += l.m1[a];
        for (int b = 0; b < 3; ++b) m2[a][b] += l.m2[a][b];
      }
    }
    if (!(vol > 0)) throw InputError("grain template: the shape has no volume on its grid");
    double c[3];
    for (int a = 0; a < 3; ++a) c[a] = m1[a] / vol;
    double s[3][3];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s[a][b] = (m2[a][b] - vol * c[a] * c[b]) * dv;
    const double tr = s[0][0] + s[1][1] + s[2][2];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) t.tensor_.m[a][b] = Real((a == b ? tr : 0.0) - s[a][b]);
    t.volume_ = Real(vol * dv);
    t.centroid_ = Vec3(Real(c[0]), Real(c[1]), Real(c[2]));
  }
  if (is_sphere) {
    t.volume_ = Real(4) / Real(3) * kPi * sphere_radius * sphere_radius * sphere_radius;
    t.centroid_ = Vec3(0, 0, 0);
    const Real i0 = Real(0.4) * t.volume_ * sphere_radius * sphere_radius;
    t.tensor_ = mat3_identity();
    for (int a = 0; a < 3; ++a) t.tensor_.m[a][a] = i0;
  }
  t.d_eq_ = std::cbrt(Real(6) * t.volume_ / kPi);  // every pair law reads it
  symmetric_eigen(t.tensor_, &t.inertia_, &t.rotation_);
  if (is_sphere) t.rotation_ = mat3_identity();

  // Nodes and the phi grid in the body frame: x_source = c + R y.
  const Mat3 rt = transpose(t.rotation_);
  Vec3 blo(inf, inf, inf), bhi(-inf, -inf, -inf);
  for (const Vec3& x : src_nodes) {
    const Vec3 y = matvec(rt, x - t.centroid_);
    t.nodes_.push_back(y);
    t.bounding_radius_ = std::max(t.bounding_radius_, norm(y));
    for (int d = 0; d < 3; ++d) {
      blo[d] = std::min(blo[d], y[d]);
      bhi[d] = std::max(bhi[d], y[d]);
    }
  }
  if (is_sphere) t.bounding_radius_ = sphere_radius;
  t.group_nodes();
  const Real h = t.spacing_;
  for (int d = 0; d < 3; ++d) {
    t.lo_[d] = blo[d] - opt.pad_cells * h;
    t.n_[d] = int(std::ceil((bhi[d] - blo[d]) / h)) + 2 * opt.pad_cells + 1;
  }
  t.phi_.resize(std::size_t(t.n_[0]) * t.n_[1] * t.n_[2]);
  const Mat3 r = t.rotation_;
  const Vec3 c0 = t.centroid_, glo = t.lo_;
  const int nx = t.n_[0], ny = t.n_[1], nz = t.n_[2];
  Real* phi = t.phi_.data();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 y = glo + Vec3(i * h, j * h, k * h);
        phi[i + nx * (j + ny * std::size_t(k))] = sdf.phi(c0 + matvec(r, y));
      }
  t.grid_bounds();
  return t;
}

void GrainTemplate::grid_bounds() {
  const int nx = n_[0], ny = n_[1], nz = n_[2];
  const auto at = [&](int i, int j, int k) {
    return phi_[std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * k)];
  };
  // In a cell, d/dx of the trilinear interpolant is bilinear in (ty, tz) and free of tx (and so
  // on), so |grad|^2 is convex along each axis and peaks at a corner, where its components are
  // the differences along the three edges that meet there.
  Real l2max = 0;
  const auto diff = [&](int d, int i, int j, int k) {  // along axis d from node (i, j, k)
    if (n_[d] < 2) return Real(0);
    const int e[3] = {d == 0, d == 1, d == 2};
    return at(i + e[0], j + e[1], k + e[2]) - at(i, j, k);
  };
  for (int k = 0; k + 1 < std::max(nz, 2); ++k)
    for (int j = 0; j + 1 < std::max(ny, 2); ++j)
      for (int i = 0; i + 1 < std::max(nx, 2); ++i)
        for (int c = 0; c < 8; ++c) {
          // Corner (ci, cj, ck) of the cell; the edge along d that meets it starts at the cell's
          // lower face in d and at the corner's position in the other two axes.
          const int ci = std::min(i + (c & 1), nx - 1), cj = std::min(j + ((c >> 1) & 1), ny - 1),
                    ck = std::min(k + ((c >> 2) & 1), nz - 1);
          const Real gx = diff(0, i, cj, ck), gy = diff(1, ci, j, ck), gz = diff(2, ci, cj, k);
          l2max = std::max(l2max, gx * gx + gy * gy + gz * gz);
        }
  // Outside the box phi = v(c) + |x - c| with c the nearest point of the box; a projection onto
  // a convex set gives |dc|^2 + |d(x - c)|^2 <= |dx|^2, so phi is sqrt(Lv^2 + 1)-Lipschitz.
  phi_lipschitz_ = std::sqrt(l2max / (spacing_ * spacing_) + 1);
  Real bmin = std::numeric_limits<Real>::max();
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1)
          bmin = std::min(bmin, at(i, j, k));
  phi_box_min_ = bmin;
}

GrainTemplate GrainTemplate::sphere(Real radius, const TemplateOptions& opt_in) {
  if (!(radius > 0)) throw InputError("sphere template: radius must be positive");
  TemplateOptions opt = opt_in;
  if (!(opt.grid_spacing > 0)) opt.grid_spacing = radius / 10;
  const Real ns = opt.node_spacing > 0 ? opt.node_spacing : opt.grid_spacing;
  const int n = std::max(12, int(std::lround(4 * kPi * radius * radius / (ns * ns))));
  std::vector<Vec3> nodes = fibonacci_sphere(n);
  for (Vec3& x : nodes) x *= radius;
  const auto sdf = geom::make_sphere(Vec3(0, 0, 0), radius);
  return from_sdf(*sdf, nodes, opt, true, radius);
}

GrainTemplate GrainTemplate::polyhedron(const ConvexPolyhedron& poly,
                                        const TemplateOptions& opt_in) {
  TemplateOptions opt = opt_in;
  if (!(opt.grid_spacing > 0)) {
    Real size = 0;
    for (const Vec3& a : poly.vertices)
      for (const Vec3& b : poly.vertices) size = std::max(size, norm(a - b));
    opt.grid_spacing = size / 30;
  }
  const Real ns = opt.node_spacing > 0 ? opt.node_spacing : opt.grid_spacing;
  const auto nodes = poly.faces.empty() ? sample_triangles(poly.vertices, poly.triangles, ns)
                                        : sample_faces(poly, ns);
  const auto sdf = make_polyhedron_sdf(poly);
  return from_sdf(*sdf, nodes, opt, false, 0);
}

GrainTemplate GrainTemplate::box(Vec3 half, const TemplateOptions& opt) {
  if (!(half.x > 0 && half.y > 0 && half.z > 0))
    throw InputError("box template: half extents must be positive");
  std::vector<Vec3> n{Vec3(1, 0, 0),  Vec3(-1, 0, 0), Vec3(0, 1, 0),
                      Vec3(0, -1, 0), Vec3(0, 0, 1),  Vec3(0, 0, -1)};
  std::vector<Real> d{half.x, half.x, half.y, half.y, half.z, half.z};
  return polyhedron(make_convex_polyhedron(n, d), opt);
}

GrainTemplate GrainTemplate::ellipsoid(Vec3 a, const TemplateOptions& opt_in) {
  const auto sdf = make_ellipsoid_sdf(a);
  TemplateOptions opt = opt_in;
  if (!(opt.grid_spacing > 0)) opt.grid_spacing = 2 * std::max({a.x, a.y, a.z}) / 30;
  const Real ns = opt.node_spacing > 0 ? opt.node_spacing : opt.grid_spacing;
  // Surface area (Knud Thomsen's approximation) sets the node count.
  const Real p = Real(1.6075);
  const Real area =
      4 * kPi *
      std::pow((std::pow(a.x * a.y, p) + std::pow(a.x * a.z, p) + std::pow(a.y * a.z, p)) / 3,
               1 / p);
  const int n = std::max(12, int(std::lround(area / (ns * ns))));
  std::vector<Vec3> nodes = fibonacci_sphere(n);
  for (Vec3& x : nodes) x = Vec3(x.x * a.x, x.y * a.y, x.z * a.z);
  return from_sdf(*sdf, nodes, opt, false, 0);
}

GrainTemplate GrainTemplate::trigonal_pyramid(Real size, Real perturbation, std::uint32_t seed,
                                              Real d_eq, const TemplateOptions& opt) {
  if (!(size > 0)) throw InputError("trigonal pyramid: size must be positive");
  if (!(perturbation >= 0 && perturbation < Real(0.25)))
    throw InputError("trigonal pyramid: perturbation must be in [0, 0.25)");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(-1, 1);
  Vec3 p[4];
  const Real rb = size / std::sqrt(Real(3));
  for (int k = 0; k < 3; ++k) {
    const Real ang = kPi / 2 + k * 2 * kPi / 3;
    p[k] = Vec3(rb * std::cos(ang), rb * std::sin(ang), 0);
  }
  p[3] = Vec3(0, 0, size);
  for (auto& x : p)
    for (int d = 0; d < 3; ++d) x[d] += perturbation * size * u(rng);
  ConvexPolyhedron poly = make_tetrahedron(p);
  if (d_eq > 0) {
    const Real s = std::cbrt(kPi * d_eq * d_eq * d_eq / 6 / poly.volume);
    for (auto& x : p) x *= s;
    poly = make_tetrahedron(p);
  }
  return polyhedron(poly, opt);
}

GrainTemplate GrainTemplate::random_polyhedron(Real d_eq, int n_planes, std::uint32_t seed,
                                               const TemplateOptions& opt) {
  if (!(d_eq > 0)) throw InputError("random polyhedron: equivalent diameter must be positive");
  if (n_planes < 6) throw InputError("random polyhedron: needs at least 6 planes");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(-1, 1);
  // Evenly spread directions, randomly rotated and jittered, at jittered distances.
  const Quat spin = normalize(Quat{u(rng), u(rng), u(rng), u(rng)});
  std::vector<Vec3> normals = fibonacci_sphere(n_planes);
  std::vector<Real> offsets;
  const Real jitter = Real(0.6) / std::sqrt(Real(n_planes));
  for (Vec3& n : normals) {
    n = rotate(spin, n) + jitter * Vec3(u(rng), u(rng), u(rng));
    n = n / norm(n);
    offsets.push_back(Real(1) + Real(0.15) * u(rng));
  }
  ConvexPolyhedron poly = make_convex_polyhedron(normals, offsets);
  const Real s = std::cbrt(kPi * d_eq * d_eq * d_eq / 6 / poly.volume);
  for (Real& d : offsets) d *= s;
  poly = make_convex_polyhedron(normals, offsets);
  return polyhedron(poly, opt);
}

GrainTemplate GrainTemplate::mesh(const geom::TriMesh& mesh_in, Real scale,
                                  const TemplateOptions& opt_in) {
  geom::TriMesh m = mesh_in;
  for (Vec3& v : m.vertices) v *= scale;
  TemplateOptions opt = opt_in;
  if (!(opt.grid_spacing > 0)) {
    const Real inf = std::numeric_limits<Real>::max();
    Vec3 lo(inf, inf, inf), hi(-inf, -inf, -inf);
    for (const Vec3& v : m.vertices)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], v[d]);
        hi[d] = std::max(hi[d], v[d]);
      }
    opt.grid_spacing = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / 30;
  }
  const Real ns = opt.node_spacing > 0 ? opt.node_spacing : opt.grid_spacing;
  // A finer grid for the source SDF so resampling it to the body frame loses little.
  const auto sdf = geom::make_mesh_sdf(m, opt.grid_spacing / 2, 2 * opt.pad_cells + 2);
  return from_sdf(*sdf, sample_triangles(m.vertices, m.triangles, ns), opt, false, 0);
}

void GrainTemplate::group_nodes() {
  node_order_.clear();
  groups_.clear();
  for (int o = 0; o < 8; ++o) {
    NodeGroup g;
    g.begin = std::uint32_t(node_order_.size());
    Vec3 lo(1e30, 1e30, 1e30), hi(-1e30, -1e30, -1e30);
    for (std::size_t k = 0; k < nodes_.size(); ++k) {
      const Vec3& y = nodes_[k];
      const int ok = (y.x > 0 ? 1 : 0) | (y.y > 0 ? 2 : 0) | (y.z > 0 ? 4 : 0);
      if (ok != o) continue;
      node_order_.push_back(std::uint32_t(k));
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], y[d]);
        hi[d] = std::max(hi[d], y[d]);
      }
    }
    g.end = std::uint32_t(node_order_.size());
    if (g.end == g.begin) continue;
    g.centre = Real(0.5) * (lo + hi);
    for (std::uint32_t i = g.begin; i < g.end; ++i)
      g.radius = std::max(g.radius, norm(nodes_[node_order_[i]] - g.centre));
    groups_.push_back(g);
  }
}

std::string GrainTemplate::describe() const {
  std::ostringstream os;
  os << (is_sphere_ ? "sphere" : "level-set grain") << ": " << nodes_.size() << " nodes (spacing "
     << node_spacing_ << " m), phi grid " << n_[0] << " x " << n_[1] << " x " << n_[2]
     << " (spacing " << spacing_ << " m), volume " << volume_ << " m^3, d_eq "
     << equivalent_diameter() << " m, principal inertia/rho (" << inertia_.x << ", " << inertia_.y
     << ", " << inertia_.z << ") m^5, bounding radius " << bounding_radius_ << " m";
  return os.str();
}

}  // namespace sphdem::dem
