// Triangle meshes: STL (ascii and binary) and OBJ readers, and the conversion of a closed mesh to
// a grid SDF (exact unsigned distance to the triangles, sign from ray parity along +x).
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "geometry/grid_sdf.hpp"
#include "geometry/sdf.hpp"

namespace sphdem::geom {

namespace {

// ---- reading ---------------------------------------------------------------------------------

// The whole file as bytes, or InputError "cannot open mesh file 'X'".
std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open mesh file '" + path + "'");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError("cannot open mesh file '" + path + "'");
  return data;
}

// "path:line: what".
[[noreturn]] void parse_error(const std::string& path, long line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

// Parses a whole token as a finite real number.
bool parse_real(const std::string& tok, Real* out) {
  if (tok.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(tok.c_str(), &end);
  if (end != tok.c_str() + tok.size() || errno == ERANGE || !std::isfinite(v)) return false;
  *out = Real(v);
  return true;
}

// Parses a whole token as an integer.
bool parse_long(const std::string& tok, long* out) {
  if (tok.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(tok.c_str(), &end, 10);
  if (end != tok.c_str() + tok.size() || errno == ERANGE) return false;
  *out = v;
  return true;
}

// Splits text into lines (without '\n' or a trailing '\r').
std::vector<std::string> split_lines(const std::string& data) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= data.size()) {
    std::size_t end = data.find('\n', start);
    if (end == std::string::npos) end = data.size();
    std::string line = data.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    start = end + 1;
  }
  return lines;
}

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream s(line);
  std::vector<std::string> t;
  std::string w;
  while (s >> w) t.push_back(w);
  return t;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Adds a polygon (vertex indices) as a fan of triangles.
void add_fan(const std::vector<int>& poly, std::vector<int>* tris) {
  for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
    tris->push_back(poly[0]);
    tris->push_back(poly[i]);
    tris->push_back(poly[i + 1]);
  }
}

// Binary STL: 80-byte header, uint32 count, then per triangle 12 little-endian floats (normal,
// three vertices) and a uint16 attribute.
void read_binary_stl(const std::string& path, const std::string& data, std::uint32_t ntri,
                     std::vector<Vec3>* verts, std::vector<int>* tris) {
  verts->reserve(std::size_t(ntri) * 3);
  tris->reserve(std::size_t(ntri) * 3);
  for (std::uint32_t t = 0; t < ntri; ++t) {
    const char* rec = data.data() + 84 + std::size_t(t) * 50;
    for (int v = 0; v < 3; ++v) {
      float c[3];
      std::memcpy(c, rec + 12 + 12 * v, sizeof c);
      if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
        throw InputError("mesh file '" + path + "': triangle " + std::to_string(t + 1) +
                         " has a coordinate that is not finite");
      tris->push_back(static_cast<int>(verts->size()));
      verts->push_back(Vec3(Real(c[0]), Real(c[1]), Real(c[2])));
    }
  }
}

// Ascii STL: solid / facet normal / outer loop / vertex x y z (x3) / endloop / endfacet /
// endsolid. Loops with more than three vertices are fan-triangulated.
void read_ascii_stl(const std::string& path, const std::string& data, std::vector<Vec3>* verts,
                    std::vector<int>* tris) {
  const std::vector<std::string> lines = split_lines(data);
  std::vector<int> loop;
  bool in_loop = false;
  long loop_line = 0;
  for (std::size_t li = 0; li < lines.size(); ++li) {
    const long ln = static_cast<long>(li) + 1;
    const std::vector<std::string> t = tokens(lines[li]);
    if (t.empty()) continue;
    const std::string key = lower(t[0]);
    if (key == "solid" || key == "endsolid" || key == "facet" || key == "endfacet") {
      if (in_loop) parse_error(path, ln, "'" + t[0] + "' inside an unfinished 'outer loop'");
    } else if (key == "outer") {
      if (in_loop) parse_error(path, ln, "'outer loop' inside another 'outer loop'");
      in_loop = true;
      loop_line = ln;
      loop.clear();
    } else if (key == "vertex") {
      if (!in_loop) parse_error(path, ln, "'vertex' outside an 'outer loop'");
      Vec3 p;
      if (t.size() != 4 || !parse_real(t[1], &p.x) || !parse_real(t[2], &p.y) ||
          !parse_real(t[3], &p.z))
        parse_error(path, ln, "expected three numbers after 'vertex'");
      loop.push_back(static_cast<int>(verts->size()));
      verts->push_back(p);
    } else if (key == "endloop") {
      if (!in_loop) parse_error(path, ln, "'endloop' without 'outer loop'");
      if (loop.size() < 3)
        parse_error(path, loop_line,
                    "loop has " + std::to_string(loop.size()) + " vertices; need at least 3");
      add_fan(loop, tris);
      in_loop = false;
    } else {
      parse_error(path, ln, "unexpected '" + t[0] + "' in ascii STL");
    }
  }
  if (in_loop) parse_error(path, loop_line, "'outer loop' is never closed by 'endloop'");
}

// OBJ: 'v x y z [w]' and 'f a b c ...' with a, a/t, a//n or a/t/n; negative indices count back
// from the last vertex defined so far. Other statements are ignored.
void read_obj(const std::string& path, const std::string& data, std::vector<Vec3>* verts,
              std::vector<int>* tris) {
  const std::vector<std::string> lines = split_lines(data);
  struct Face {
    std::vector<long> idx;  // 1-based, already resolved if given as negative
    long line;
  };
  std::vector<Face> faces;
  for (std::size_t li = 0; li < lines.size(); ++li) {
    const long ln = static_cast<long>(li) + 1;
    std::string line = lines[li];
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    const std::vector<std::string> t = tokens(line);
    if (t.empty()) continue;
    if (t[0] == "v") {
      Vec3 p;
      if (t.size() < 4 || !parse_real(t[1], &p.x) || !parse_real(t[2], &p.y) ||
          !parse_real(t[3], &p.z))
        parse_error(path, ln, "vertex needs three numbers: 'v x y z'");
      verts->push_back(p);
    } else if (t[0] == "f") {
      Face f{{}, ln};
      for (std::size_t k = 1; k < t.size(); ++k) {
        const std::string head = t[k].substr(0, t[k].find('/'));
        long v = 0;
        if (!parse_long(head, &v)) parse_error(path, ln, "bad face vertex '" + t[k] + "'");
        if (v == 0) parse_error(path, ln, "face refers to vertex 0; OBJ vertex numbers start at 1");
        if (v < 0) {
          const long resolved = static_cast<long>(verts->size()) + 1 + v;
          if (resolved < 1)
            parse_error(path, ln,
                        "face refers to vertex " + std::to_string(v) + " but only " +
                            std::to_string(verts->size()) + " are defined");
          v = resolved;
        }
        f.idx.push_back(v);
      }
      if (f.idx.size() < 3)
        parse_error(path, ln,
                    "face has " + std::to_string(f.idx.size()) + " vertices; need at least 3");
      faces.push_back(std::move(f));
    }
  }
  const long nv = static_cast<long>(verts->size());
  for (const Face& f : faces) {
    std::vector<int> poly;
    for (long v : f.idx) {
      if (v > nv)
        parse_error(path, f.line,
                    "face refers to vertex " + std::to_string(v) + " but only " +
                        std::to_string(nv) + " are defined");
      poly.push_back(static_cast<int>(v - 1));
    }
    add_fan(poly, tris);
  }
}

// Merges vertices with identical coordinates and drops triangles that repeat a vertex.
void deduplicate(TriMesh* m) {
  std::map<std::array<Real, 3>, int> seen;
  std::vector<int> remap(m->vertices.size());
  std::vector<Vec3> unique;
  for (std::size_t i = 0; i < m->vertices.size(); ++i) {
    const Vec3& p = m->vertices[i];
    const auto it = seen.emplace(std::array<Real, 3>{p.x, p.y, p.z}, int(unique.size()));
    if (it.second) unique.push_back(p);
    remap[i] = it.first->second;
  }
  std::vector<int> tris;
  tris.reserve(m->triangles.size());
  for (std::size_t t = 0; t + 2 < m->triangles.size(); t += 3) {
    const int a = remap[m->triangles[t]], b = remap[m->triangles[t + 1]],
              c = remap[m->triangles[t + 2]];
    if (a == b || b == c || a == c) continue;
    tris.push_back(a);
    tris.push_back(b);
    tris.push_back(c);
  }
  m->vertices = std::move(unique);
  m->triangles = std::move(tris);
}

// ---- geometry helpers ------------------------------------------------------------------------

std::string describe(const TriMesh& m) {
  return m.source.empty() ? std::string("mesh") : "mesh file '" + m.source + "'";
}

std::string str(const Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

// Squared distance from p to the segment [a, b] (a point if a == b).
Real dist2_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const Real l2 = norm2(ab);
  Real t = l2 > 0 ? dot(p - a, ab) / l2 : Real(0);
  t = std::min(std::max(t, Real(0)), Real(1));
  return norm2(p - (a + t * ab));
}

// Squared distance from p to the closed triangle (a, b, c): the distance to the plane when p
// projects inside the triangle, else the smallest distance to the three edges.
Real dist2_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const Real nn = norm2(n);
  if (nn > 0) {
    const Real h = dot(p - a, n);
    const Vec3 q = p - (h / nn) * n;  // projection onto the plane
    if (dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
        dot(cross(a - c, q - c), n) >= 0)
      return h * h / nn;
  }
  return std::min({dist2_segment(p, a, b), dist2_segment(p, b, c), dist2_segment(p, c, a)});
}

// Squared distance from p to the box b (0 inside).
Real dist2_box(const Vec3& p, const Aabb& b) {
  Real s = 0;
  for (int d = 0; d < 3; ++d) {
    const Real e = std::max({b.lo[d] - p[d], Real(0), p[d] - b.hi[d]});
    s += e * e;
  }
  return s;
}

// A bounding-volume hierarchy over triangles for nearest-distance queries.
class TriangleBvh {
 public:
  explicit TriangleBvh(const TriMesh& m) : m_(m) {
    const int nt = static_cast<int>(m.triangles.size() / 3);
    order_.resize(nt);
    centroid_.resize(nt);
    for (int t = 0; t < nt; ++t) {
      order_[t] = t;
      centroid_[t] = (vtx(t, 0) + vtx(t, 1) + vtx(t, 2)) / Real(3);
    }
    nodes_.reserve(2 * std::size_t(nt) / kLeaf + 2);
    build(0, nt);
  }

  // The distance from p to the nearest triangle and that triangle's index (*tri), given an
  // upper bound `upper` of the distance (use the largest Real if none is known). If no triangle
  // is closer than `upper`, returns `upper` and leaves *tri unchanged.
  Real distance(const Vec3& p, Real upper, int* tri) const {
    Real best2 = upper < std::sqrt(std::numeric_limits<Real>::max())
                     ? upper * upper
                     : std::numeric_limits<Real>::max();
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& nd = nodes_[stack[--top]];
      if (dist2_box(p, nd.box) >= best2) continue;
      if (nd.left < 0) {
        for (int i = nd.first; i < nd.first + nd.count; ++i) {
          const int t = order_[i];
          const Real d2 = dist2_triangle(p, vtx(t, 0), vtx(t, 1), vtx(t, 2));
          if (d2 < best2) {
            best2 = d2;
            *tri = t;
          }
        }
        continue;
      }
      // Push the farther child first so the nearer one is searched first.
      const Real dl = dist2_box(p, nodes_[nd.left].box), dr = dist2_box(p, nodes_[nd.right].box);
      if (dl < dr) {
        stack[top++] = nd.right;
        stack[top++] = nd.left;
      } else {
        stack[top++] = nd.left;
        stack[top++] = nd.right;
      }
    }
    return std::sqrt(best2);
  }

 private:
  static constexpr int kLeaf = 4;
  struct Node {
    Aabb box;
    int left = -1, right = -1;  // children (left < 0: a leaf)
    int first = 0, count = 0;   // leaf range in order_
  };

  const Vec3& vtx(int t, int k) const { return m_.vertices[m_.triangles[3 * t + k]]; }

  // Builds the node for order_[first, first + count) by a median split of centroids along the
  // longest axis of their box. Returns its index. Depth is at most ~log2(n) + 1.
  int build(int first, int count) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back(Node{});
    const Real inf = std::numeric_limits<Real>::max();
    Aabb box{Vec3(inf, inf, inf), Vec3(-inf, -inf, -inf)};
    Aabb cbox = box;
    for (int i = first; i < first + count; ++i) {
      const int t = order_[i];
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) {
          box.lo[d] = std::min(box.lo[d], vtx(t, k)[d]);
          box.hi[d] = std::max(box.hi[d], vtx(t, k)[d]);
        }
      for (int d = 0; d < 3; ++d) {
        cbox.lo[d] = std::min(cbox.lo[d], centroid_[t][d]);
        cbox.hi[d] = std::max(cbox.hi[d], centroid_[t][d]);
      }
    }
    nodes_[id].box = box;
    if (count <= kLeaf) {
      nodes_[id].first = first;
      nodes_[id].count = count;
      return id;
    }
    const Vec3 ext = cbox.hi - cbox.lo;
    const int axis = (ext.x >= ext.y && ext.x >= ext.z) ? 0 : (ext.y >= ext.z ? 1 : 2);
    const int half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half,
                     order_.begin() + first + count,
                     [&](int a, int b) { return centroid_[a][axis] < centroid_[b][axis]; });
    const int l = build(first, half);
    const int r = build(first + half, count - half);
    nodes_[id].left = l;
    nodes_[id].right = r;
    return id;
  }

  const TriMesh& m_;
  std::vector<int> order_;
  std::vector<Vec3> centroid_;
  std::vector<Node> nodes_;
};

// Mesh SDF distances are computed exactly (BVH nearest-triangle queries) at nodes within
// kExactBand cells of a triangle's box; beyond, by closest-triangle propagation.
constexpr int kExactBand = 3;

// Squared distance from p to triangle t of m.
Real dist2_tri(const TriMesh& m, int t, const Vec3& p) {
  return dist2_triangle(p, m.vertices[m.triangles[3 * t]], m.vertices[m.triangles[3 * t + 1]],
                        m.vertices[m.triangles[3 * t + 2]]);
}

// For each vertex, the triangles that use it, as CSR offsets (nv + 1) and triangle indices.
void vertex_triangles(const TriMesh& m, std::vector<int>* start, std::vector<int>* tris) {
  const std::size_t nv = m.vertices.size();
  start->assign(nv + 1, 0);
  for (int v : m.triangles) ++(*start)[v + 1];
  for (std::size_t v = 0; v < nv; ++v) (*start)[v + 1] += (*start)[v];
  tris->assign(m.triangles.size(), 0);
  std::vector<int> fill(start->begin(), start->end() - 1);
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    (*tris)[fill[m.triangles[i]]++] = static_cast<int>(i / 3);
}

// Unsigned distances from the nodes of the grid (lo, h, n) to the mesh.
// 1. Nodes within kExactBand cells of some triangle's bounding box get the exact distance to
//    the nearest triangle (BVH query) and remember that triangle.
// 2. The other nodes (all farther than kExactBand cells from the surface) are filled by fast
//    sweeping (8 sweep orders): a node takes the nearest of the triangles remembered by its
//    already-swept axis neighbours, then walks over vertex-adjacent triangles while they are
//    closer. Each value is the exact distance to some triangle (never below the true distance),
//    in practice the nearest one.
std::vector<Real> unsigned_distances(const TriMesh& m, const Vec3& lo, Real h, const int n[3]) {
  const std::size_t nx = n[0], nxy = std::size_t(n[0]) * n[1];
  const std::size_t total = nxy * std::size_t(n[2]);
  auto at = [&](int i, int j, int k) { return std::size_t(i) + nx * j + nxy * k; };
  const int ntri = static_cast<int>(m.triangles.size() / 3);

  std::vector<unsigned char> near(total, 0);
  for (int t = 0; t < ntri; ++t) {
    int a[3], b[3];
    for (int d = 0; d < 3; ++d) {
      Real vlo = std::numeric_limits<Real>::max(), vhi = -vlo;
      for (int k = 0; k < 3; ++k) {
        vlo = std::min(vlo, m.vertices[m.triangles[3 * t + k]][d]);
        vhi = std::max(vhi, m.vertices[m.triangles[3 * t + k]][d]);
      }
      a[d] = std::max(0, static_cast<int>(std::floor((vlo - lo[d]) / h)) - kExactBand);
      b[d] = std::min(n[d] - 1, static_cast<int>(std::ceil((vhi - lo[d]) / h)) + kExactBand);
    }
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) near[at(i, j, k)] = 1;
  }

  const TriangleBvh bvh(m);
  const Real big = std::numeric_limits<Real>::max();
  std::vector<Real> dist(total, big);
  std::vector<int> closest(total, -1);
  const long nrows = long(n[1]) * n[2];
#pragma omp parallel for schedule(dynamic, 1)
  for (long r = 0; r < nrows; ++r) {
    const int j = static_cast<int>(r % n[1]), k = static_cast<int>(r / n[1]);
    Real upper = big;  // distance is 1-Lipschitz: the previous node's distance + h bounds it
    for (int i = 0; i < n[0]; ++i) {
      const std::size_t id = at(i, j, k);
      if (!near[id]) {
        upper = big;
        continue;
      }
      const Vec3 p = lo + h * Vec3(Real(i), Real(j), Real(k));
      int tri = -1;
      Real d = bvh.distance(p, upper, &tri);
      if (tri < 0) d = bvh.distance(p, big, &tri);  // the bound was not attained
      dist[id] = d;
      closest[id] = tri;
      upper = d + h * Real(1.000001);
    }
  }

  for (int dir = 0; dir < 8; ++dir) {
    const int di = (dir & 1) ? -1 : 1, dj = (dir & 2) ? -1 : 1, dk = (dir & 4) ? -1 : 1;
    for (int kk = 0; kk < n[2]; ++kk) {
      const int k = dk > 0 ? kk : n[2] - 1 - kk;
      for (int jj = 0; jj < n[1]; ++jj) {
        const int j = dj > 0 ? jj : n[1] - 1 - jj;
        for (int ii = 0; ii < n[0]; ++ii) {
          const int i = di > 0 ? ii : n[0] - 1 - ii;
          const std::size_t id = at(i, j, k);
          if (near[id]) continue;
          const int ni[3] = {i - di, i, i}, nj[3] = {j, j - dj, j}, nk[3] = {k, k, k - dk};
          for (int q = 0; q < 3; ++q) {
            if (ni[q] < 0 || ni[q] >= n[0] || nj[q] < 0 || nj[q] >= n[1] || nk[q] < 0 ||
                nk[q] >= n[2])
              continue;
            const int t = closest[at(ni[q], nj[q], nk[q])];
            if (t < 0 || t == closest[id]) continue;
            const Real d = std::sqrt(dist2_tri(m, t, lo + h * Vec3(Real(i), Real(j), Real(k))));
            if (d < dist[id]) {
              dist[id] = d;
              closest[id] = t;
            }
          }
        }
      }
    }
  }

  // Polish: from its candidate, each far node walks to a triangle sharing a vertex with the
  // current one while that is closer (a local descent over the surface; vertex rather than edge
  // neighbours, so that it does not stall where the nearest point is a vertex).
  std::vector<int> vstart, vtris;
  vertex_triangles(m, &vstart, &vtris);
#pragma omp parallel for schedule(dynamic, 1)
  for (long r = 0; r < nrows; ++r) {
    const int j = static_cast<int>(r % n[1]), k = static_cast<int>(r / n[1]);
    for (int i = 0; i < n[0]; ++i) {
      const std::size_t id = at(i, j, k);
      if (near[id]) continue;
      const Vec3 p = lo + h * Vec3(Real(i), Real(j), Real(k));
      if (closest[id] < 0) {  // not reached by the sweeps (not expected): query directly
        int tri = -1;
        dist[id] = bvh.distance(p, big, &tri);
        closest[id] = tri;
        continue;
      }
      int t = closest[id];
      Real d2 = dist2_tri(m, t, p);
      for (int step = 0; step < ntri; ++step) {
        int next = -1;
        for (int c = 0; c < 3; ++c) {
          const int v = m.triangles[3 * t + c];
          for (int q = vstart[v]; q < vstart[v + 1]; ++q) {
            const int u = vtris[q];
            if (u == t) continue;
            const Real u2 = dist2_tri(m, u, p);
            if (u2 < d2) {
              d2 = u2;
              next = u;
            }
          }
        }
        if (next < 0) break;
        t = next;
      }
      dist[id] = std::sqrt(d2);
      closest[id] = t;
    }
  }
  return dist;
}

// Sign of the edge function of the edge from vertex p to vertex q (p < q) at the point (y, z) of
// the yz-plane, with the point symbolically perturbed to (y + e, z + e^2) so that it is never
// zero unless the edge projects to a point. Both triangles that share an edge evaluate the very
// same expression, so a ray along +x crosses a closed mesh consistently (no double counts or
// misses at edges and vertices). Returns the value in *f and its sign (+1, -1, or 0).
int edge_sign(const Vec3& p, const Vec3& q, Real y, Real z, Real* f) {
  const Real a = q.y - p.y, b = q.z - p.z;
  *f = a * (z - p.z) - b * (y - p.y);
  if (*f > 0) return 1;
  if (*f < 0) return -1;
  if (b != 0) return b < 0 ? 1 : -1;
  if (a != 0) return a > 0 ? 1 : -1;
  return 0;
}

// The x where the ray {(s, y, z): s real} crosses triangle t, if it does (symbolic-perturbation
// rules as in edge_sign).
bool ray_hit(const TriMesh& m, int t, Real y, Real z, Real* x) {
  const int v[3] = {m.triangles[3 * t], m.triangles[3 * t + 1], m.triangles[3 * t + 2]};
  Real w[3];
  int s[3];
  for (int k = 0; k < 3; ++k) {
    // The edge opposite vertex k, directed v[k+1] -> v[k+2], evaluated from its lower index.
    const int u = v[(k + 1) % 3], e = v[(k + 2) % 3];
    const int lo = std::min(u, e), hi = std::max(u, e);
    Real f;
    const int sg = edge_sign(m.vertices[lo], m.vertices[hi], y, z, &f);
    const int dir = u < e ? 1 : -1;
    s[k] = sg * dir;
    w[k] = f * Real(dir);
  }
  if (s[0] == 0 || s[0] != s[1] || s[1] != s[2]) return false;
  const Real sum = w[0] + w[1] + w[2];
  if (sum != 0) {
    *x = (w[0] * m.vertices[v[0]].x + w[1] * m.vertices[v[1]].x + w[2] * m.vertices[v[2]].x) / sum;
  } else {
    *x = (m.vertices[v[0]].x + m.vertices[v[1]].x + m.vertices[v[2]].x) / Real(3);
  }
  return true;
}

// Generalised winding number of the mesh around p (sum of signed solid angles / 4 pi).
Real winding_number(const TriMesh& m, const Vec3& p) {
  double total = 0;
  for (std::size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
    const Vec3 a = m.vertices[m.triangles[t]] - p, b = m.vertices[m.triangles[t + 1]] - p,
               c = m.vertices[m.triangles[t + 2]] - p;
    const Real la = norm(a), lb = norm(b), lc = norm(c);
    const Real num = dot(a, cross(b, c));
    const Real den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    total += 2 * std::atan2(double(num), double(den));
  }
  return Real(total / (4 * kPi));
}

// Throws InputError unless every edge is shared by exactly two triangles.
void check_closed(const TriMesh& m) {
  std::unordered_map<std::uint64_t, int> uses;
  auto key = [](int a, int b) {
    return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
  };
  const std::size_t nt = m.triangles.size() / 3;
  uses.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      ++uses[key(m.triangles[3 * t + k], m.triangles[3 * t + (k + 1) % 3])];
  std::size_t bad = 0;
  for (const auto& kv : uses) bad += kv.second != 2;
  if (bad == 0) return;
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles[3 * t + k], b = m.triangles[3 * t + (k + 1) % 3];
      const int n = uses[key(a, b)];
      if (n == 2) continue;
      throw InputError(describe(m) + " is not closed: " + std::to_string(bad) +
                       (bad == 1 ? " edge is" : " edges are") +
                       " not shared by exactly two triangles, e.g. the edge " +
                       str(m.vertices[std::min(a, b)]) + "-" + str(m.vertices[std::max(a, b)]) +
                       " is used by " + std::to_string(n) + (n == 1 ? " triangle" : " triangles"));
    }
}

}  // namespace

TriMesh load_mesh(const std::string& path) {
  const std::size_t dot_pos = path.find_last_of('.');
  const std::size_t slash_pos = path.find_last_of('/');
  const std::string ext =
      (dot_pos == std::string::npos || (slash_pos != std::string::npos && dot_pos < slash_pos))
          ? std::string()
          : lower(path.substr(dot_pos));
  if (ext != ".stl" && ext != ".obj")
    throw InputError("mesh file '" + path + "' has an unknown extension (expected .stl or .obj)");
  const std::string data = read_all(path);

  TriMesh m;
  m.source = path;
  if (ext == ".obj") {
    read_obj(path, data, &m.vertices, &m.triangles);
  } else {
    std::uint32_t ntri = 0;
    if (data.size() >= 84) std::memcpy(&ntri, data.data() + 80, 4);
    const bool binary =
        data.size() >= 84 && std::uint64_t(data.size()) == 84 + 50 * std::uint64_t(ntri);
    const std::size_t first = data.find_first_not_of(" \t\r\n");
    const bool ascii = first != std::string::npos && lower(data.substr(first, 5)) == "solid" &&
                       data.find("facet") != std::string::npos;
    if (binary) {
      read_binary_stl(path, data, ntri, &m.vertices, &m.triangles);
    } else if (ascii) {
      read_ascii_stl(path, data, &m.vertices, &m.triangles);
    } else {
      throw InputError("mesh file '" + path +
                       "' is not an STL file: it is not ascii (starting with 'solid' and "
                       "holding 'facet'), and its size (" +
                       std::to_string(data.size()) +
                       " bytes) is not 84 + 50 x the triangle count of a binary STL");
    }
  }
  deduplicate(&m);
  if (m.triangles.empty()) throw InputError("mesh file '" + path + "' has no triangles");
  return m;
}

SdfPtr make_mesh_sdf(const TriMesh& mesh, Real spacing, int pad_cells) {
  const std::string name = describe(mesh);
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw InputError(name + ": grid spacing must be positive, got " + std::to_string(spacing));
  if (pad_cells < 0)
    throw InputError(name + ": padding must be >= 0 cells, got " + std::to_string(pad_cells));
  if (mesh.triangles.empty() || mesh.triangles.size() % 3 != 0)
    throw InputError(name + ": needs a positive multiple of 3 triangle indices, got " +
                     std::to_string(mesh.triangles.size()));
  const long nv = static_cast<long>(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (mesh.triangles[i] < 0 || mesh.triangles[i] >= nv)
      throw InputError(name + ": triangle " + std::to_string(i / 3 + 1) + " refers to vertex " +
                       std::to_string(mesh.triangles[i]) + " but only " + std::to_string(nv) +
                       " are defined");
  for (const Vec3& p : mesh.vertices)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError(name + ": a vertex coordinate is not finite");

  // Merge coincident vertices and drop degenerate triangles, then require a closed surface.
  TriMesh m = mesh;
  deduplicate(&m);
  if (m.triangles.empty()) throw InputError(name + " has no non-degenerate triangles");
  check_closed(m);

  // Grid: the mesh box centred in n nodes per axis with pad_cells cells on each side.
  const Real inf = std::numeric_limits<Real>::max();
  Aabb bb{Vec3(inf, inf, inf), Vec3(-inf, -inf, -inf)};
  for (const Vec3& p : m.vertices)
    for (int d = 0; d < 3; ++d) {
      bb.lo[d] = std::min(bb.lo[d], p[d]);
      bb.hi[d] = std::max(bb.hi[d], p[d]);
    }
  int n[3];
  Vec3 lo;
  double total = 1;
  for (int d = 0; d < 3; ++d) {
    const double cells = std::ceil(double(bb.hi[d] - bb.lo[d]) / double(spacing) - 1e-9);
    const double nd = std::max(cells, 0.0) + 2.0 * pad_cells + 1;
    total *= nd;
    if (nd > 1e6 || total > double(1 << 28)) {
      std::ostringstream s;
      s << name << ": a grid SDF with spacing " << spacing << " over the mesh box " << str(bb.lo)
        << "-" << str(bb.hi) << " would need too many nodes (limit 2^28)";
      throw InputError(s.str());
    }
    n[d] = static_cast<int>(nd);
    lo[d] = Real(0.5) * (bb.lo[d] + bb.hi[d]) - Real(0.5) * spacing * Real(n[d] - 1);
  }

  const std::vector<Real> dist = unsigned_distances(m, lo, spacing, n);
  const int ntri = static_cast<int>(m.triangles.size() / 3);

  // Bin triangles by the rows (j, k) whose ray may cross them (yz box widened by one node).
  const long nrows = long(n[1]) * n[2];
  std::vector<long> row_start(nrows + 1, 0);
  std::vector<std::array<int, 4>> tri_rows(ntri);  // j0, j1, k0, k1
  for (int t = 0; t < ntri; ++t) {
    Real ylo = inf, yhi = -inf, zlo = inf, zhi = -inf;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.vertices[m.triangles[3 * t + k]];
      ylo = std::min(ylo, p.y);
      yhi = std::max(yhi, p.y);
      zlo = std::min(zlo, p.z);
      zhi = std::max(zhi, p.z);
    }
    auto first = [&](Real v, int d) {
      return std::max(0, static_cast<int>(std::floor((v - lo[d]) / spacing)) - 1);
    };
    auto last = [&](Real v, int d) {
      return std::min(n[d] - 1, static_cast<int>(std::ceil((v - lo[d]) / spacing)) + 1);
    };
    tri_rows[t] = {first(ylo, 1), last(yhi, 1), first(zlo, 2), last(zhi, 2)};
    for (int k = tri_rows[t][2]; k <= tri_rows[t][3]; ++k)
      for (int j = tri_rows[t][0]; j <= tri_rows[t][1]; ++j) ++row_start[long(k) * n[1] + j + 1];
  }
  for (long r = 0; r < nrows; ++r) row_start[r + 1] += row_start[r];
  std::vector<int> row_tris(row_start[nrows]);
  {
    std::vector<long> fill(row_start.begin(), row_start.end() - 1);
    for (int t = 0; t < ntri; ++t)
      for (int k = tri_rows[t][2]; k <= tri_rows[t][3]; ++k)
        for (int j = tri_rows[t][0]; j <= tri_rows[t][1]; ++j)
          row_tris[fill[long(k) * n[1] + j]++] = t;
  }

  // Each row of nodes along x: the sign from the parity of the ray crossings to the left of
  // the node. A row with an odd crossing count (which a closed mesh should not give) falls back
  // to the generalised winding number.
  std::vector<Real> values(dist.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long r = 0; r < nrows; ++r) {
    const int j = static_cast<int>(r % n[1]), k = static_cast<int>(r / n[1]);
    const Real y = lo.y + spacing * Real(j), z = lo.z + spacing * Real(k);
    std::vector<Real> hits;
    for (long q = row_start[r]; q < row_start[r + 1]; ++q) {
      Real x;
      if (ray_hit(m, row_tris[q], y, z, &x)) hits.push_back(x);
    }
    std::sort(hits.begin(), hits.end());
    const bool parity_ok = hits.size() % 2 == 0;
    std::size_t left = 0;
    for (int i = 0; i < n[0]; ++i) {
      const Vec3 p(lo.x + spacing * Real(i), y, z);
      bool inside;
      if (parity_ok) {
        while (left < hits.size() && hits[left] < p.x) ++left;
        inside = left % 2 == 1;
      } else {
        inside = std::abs(winding_number(m, p)) > Real(0.5);
      }
      const std::size_t id = std::size_t(i) + std::size_t(n[0]) * std::size_t(r);
      values[id] = inside ? -dist[id] : dist[id];
    }
  }
  return std::make_shared<GridSdf>(lo, spacing, n[0], n[1], n[2], std::move(values));
}

}  // namespace sphdem::geom
