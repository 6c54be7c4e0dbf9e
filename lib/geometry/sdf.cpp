// Analytic signed-distance functions: primitives, CSG combinations, rigid transforms, and the
// host-side grid SDF owner. See sdf.hpp for the conventions (phi < 0 inside).
#include "geometry/sdf.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "core/error.hpp"
#include "core/quat.hpp"
#include "geometry/grid_sdf.hpp"

namespace sphdem::geom {

namespace {

// Half-spaces and other unbounded solids report this box.
constexpr Real kHuge = Real(1e30);

Aabb huge_box() {
  return Aabb{Vec3(-kHuge, -kHuge, -kHuge), Vec3(kHuge, kHuge, kHuge)};
}

bool is_huge(const Aabb& b) {
  for (int d = 0; d < 3; ++d)
    if (b.lo[d] <= -Real(0.5) * kHuge || b.hi[d] >= Real(0.5) * kHuge) return true;
  return false;
}

// v / |v|; the zero vector when |v| = 0.
Vec3 unit_or_zero(const Vec3& v) {
  const Real n = norm(v);
  return n > Real(0) ? v / n : Vec3(0, 0, 0);
}

// A unit vector perpendicular to the unit vector u.
Vec3 any_perpendicular(const Vec3& u) {
  const Real ax = std::abs(u.x), ay = std::abs(u.y), az = std::abs(u.z);
  const Vec3 e =
      (ax <= ay && ax <= az) ? Vec3(1, 0, 0) : (ay <= az ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
  return unit_or_zero(cross(u, e));
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string str(const Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

// Solid axis-aligned box. phi: distance to the box outside, minus the distance to the nearest
// face inside (exact everywhere).
class BoxSdf : public Sdf {
 public:
  BoxSdf(Vec3 lo, Vec3 hi)
      : c_((lo + hi) * Real(0.5)), h_((hi - lo) * Real(0.5)), lo_(lo), hi_(hi) {}

  Real phi(const Vec3& x) const override {
    Vec3 q;
    for (int d = 0; d < 3; ++d) q[d] = std::abs(x[d] - c_[d]) - h_[d];
    const Vec3 qp(std::max(q.x, Real(0)), std::max(q.y, Real(0)), std::max(q.z, Real(0)));
    return norm(qp) + std::min(std::max(q.x, std::max(q.y, q.z)), Real(0));
  }

  // Outside: direction from the nearest box point to x. Inside: normal of the nearest face.
  Vec3 grad(const Vec3& x) const override {
    Vec3 q, s;
    for (int d = 0; d < 3; ++d) {
      q[d] = std::abs(x[d] - c_[d]) - h_[d];
      s[d] = x[d] < c_[d] ? Real(-1) : Real(1);
    }
    if (q.x > 0 || q.y > 0 || q.z > 0) {
      Vec3 g;
      for (int d = 0; d < 3; ++d) g[d] = q[d] > 0 ? q[d] * s[d] : Real(0);
      return unit_or_zero(g);
    }
    const int k = (q.x >= q.y && q.x >= q.z) ? 0 : (q.y >= q.z ? 1 : 2);
    Vec3 g(0, 0, 0);
    g[k] = s[k];
    return g;
  }

  Aabb bounds() const override { return Aabb{lo_, hi_}; }

 private:
  Vec3 c_, h_, lo_, hi_;
};

// Half-space dot(x - p, n) < 0 with unit n. phi is the signed distance to the plane.
class PlaneSdf : public Sdf {
 public:
  PlaneSdf(Vec3 p, Vec3 n) : p_(p), n_(n) {}
  Real phi(const Vec3& x) const override { return dot(x - p_, n_); }
  Vec3 grad(const Vec3&) const override { return n_; }
  Aabb bounds() const override { return huge_box(); }

 private:
  Vec3 p_, n_;
};

// Infinite slab |dot(x - p, n)| < t/2 with unit n.
class SlabSdf : public Sdf {
 public:
  SlabSdf(Vec3 p, Vec3 n, Real t) : p_(p), n_(n), half_(Real(0.5) * t) {}
  Real phi(const Vec3& x) const override { return std::abs(dot(x - p_, n_)) - half_; }
  Vec3 grad(const Vec3& x) const override { return dot(x - p_, n_) < 0 ? -n_ : n_; }
  // Bounded along an axis only when the normal is that axis.
  Aabb bounds() const override {
    Aabb b = huge_box();
    for (int d = 0; d < 3; ++d) {
      const int e1 = (d + 1) % 3, e2 = (d + 2) % 3;
      if (n_[e1] == Real(0) && n_[e2] == Real(0)) {
        b.lo[d] = p_[d] - half_;
        b.hi[d] = p_[d] + half_;
      }
    }
    return b;
  }

 private:
  Vec3 p_, n_;
  Real half_;
};

// Solid sphere: phi = |x - c| - r.
class SphereSdf : public Sdf {
 public:
  SphereSdf(Vec3 c, Real r) : c_(c), r_(r) {}
  Real phi(const Vec3& x) const override { return norm(x - c_) - r_; }
  // Radial direction; +z at the centre.
  Vec3 grad(const Vec3& x) const override {
    const Vec3 g = unit_or_zero(x - c_);
    return norm2(g) > 0 ? g : Vec3(0, 0, 1);
  }
  Aabb bounds() const override { return Aabb{c_ - Vec3(r_, r_, r_), c_ + Vec3(r_, r_, r_)}; }

 private:
  Vec3 c_;
  Real r_;
};

// Capped solid cylinder from a to b with radius r (exact SDF of the finite cylinder).
class CylinderSdf : public Sdf {
 public:
  CylinderSdf(Vec3 a, Vec3 b, Real r) : a_(a), b_(b), r_(r), len_(norm(b - a)) {
    u_ = (b - a) / len_;
  }

  Real phi(const Vec3& x) const override {
    Real dr, da;
    Vec3 rdir;
    Real asign;
    split(x, &dr, &da, &rdir, &asign);
    const Real dro = std::max(dr, Real(0)), dao = std::max(da, Real(0));
    return std::min(std::max(dr, da), Real(0)) + std::sqrt(dro * dro + dao * dao);
  }

  // Outside: direction from the nearest surface point. Inside: normal of the nearest face
  // (side or cap).
  Vec3 grad(const Vec3& x) const override {
    Real dr, da;
    Vec3 rdir;
    Real asign;
    split(x, &dr, &da, &rdir, &asign);
    if (dr > 0 || da > 0)
      return unit_or_zero(std::max(dr, Real(0)) * rdir + std::max(da, Real(0)) * asign * u_);
    return dr > da ? rdir : asign * u_;
  }

  // Each axis: the end points widened by r * sqrt(1 - u_d^2) (the end discs' extent).
  Aabb bounds() const override {
    Aabb b;
    for (int d = 0; d < 3; ++d) {
      const Real e = r_ * std::sqrt(std::max(Real(0), Real(1) - u_[d] * u_[d]));
      b.lo[d] = std::min(a_[d], b_[d]) - e;
      b.hi[d] = std::max(a_[d], b_[d]) + e;
    }
    return b;
  }

 private:
  // dr: radial distance minus r; da: axial distance from the mid-plane minus half the length;
  // rdir: unit radial direction; asign: +1 on the b side of the mid-plane, -1 on the a side.
  void split(const Vec3& x, Real* dr, Real* da, Vec3* rdir, Real* asign) const {
    const Vec3 p = x - a_;
    const Real s = dot(p, u_);
    const Vec3 rv = p - s * u_;
    const Real r = norm(rv);
    *dr = r - r_;
    *da = std::abs(s - Real(0.5) * len_) - Real(0.5) * len_;
    *rdir = r > 0 ? rv / r : any_perpendicular(u_);
    *asign = s >= Real(0.5) * len_ ? Real(1) : Real(-1);
  }

  Vec3 a_, b_;
  Real r_, len_;
  Vec3 u_;
};

// Union: phi = min over parts; grad of the part that attains the minimum.
class UnionSdf : public Sdf {
 public:
  explicit UnionSdf(std::vector<SdfPtr> parts) : parts_(std::move(parts)) {}

  Real phi(const Vec3& x) const override {
    Real v = std::numeric_limits<Real>::max();
    for (const auto& p : parts_) v = std::min(v, p->phi(x));
    return v;
  }

  Vec3 grad(const Vec3& x) const override { return deepest(x)->grad(x); }
  // The wet surface of the part that holds x deepest.
  Real wet_phi(const Vec3& x) const override { return deepest(x)->wet_phi(x); }
  Vec3 wet_grad(const Vec3& x) const override { return deepest(x)->wet_grad(x); }
  bool has_dry_faces() const override {
    for (const auto& p : parts_)
      if (p->has_dry_faces()) return true;
    return false;
  }

  // The box around all parts' boxes.
  Aabb bounds() const override {
    Aabb b = parts_.front()->bounds();
    for (const auto& p : parts_) {
      const Aabb pb = p->bounds();
      for (int d = 0; d < 3; ++d) {
        b.lo[d] = std::min(b.lo[d], pb.lo[d]);
        b.hi[d] = std::max(b.hi[d], pb.hi[d]);
      }
    }
    return b;
  }

 private:
  const Sdf* deepest(const Vec3& x) const {
    Real v = std::numeric_limits<Real>::max();
    const Sdf* best = parts_.front().get();
    for (const auto& p : parts_) {
      const Real pv = p->phi(x);
      if (pv < v) {
        v = pv;
        best = p.get();
      }
    }
    return best;
  }

  std::vector<SdfPtr> parts_;
};

// Difference a minus b: phi = max(phi_a, -phi_b); grad of the term that attains the maximum.
class DifferenceSdf : public Sdf {
 public:
  DifferenceSdf(SdfPtr a, SdfPtr b) : a_(std::move(a)), b_(std::move(b)) {}
  Real phi(const Vec3& x) const override { return std::max(a_->phi(x), -b_->phi(x)); }
  Vec3 grad(const Vec3& x) const override {
    return a_->phi(x) >= -b_->phi(x) ? a_->grad(x) : -b_->grad(x);
  }
  // The solid lies inside a.
  Aabb bounds() const override { return a_->bounds(); }

 private:
  SdfPtr a_, b_;
};

// A container: the solid a minus the cavity b, whose only wet faces are the cavity's.
class CavitySdf : public DifferenceSdf {
 public:
  CavitySdf(SdfPtr a, SdfPtr b) : DifferenceSdf(a, b), cavity_(std::move(b)) {}
  Real wet_phi(const Vec3& x) const override { return -cavity_->phi(x); }
  Vec3 wet_grad(const Vec3& x) const override { return -cavity_->grad(x); }
  bool has_dry_faces() const override { return true; }

 private:
  SdfPtr cavity_;
};

// A body placed by x_world = R x_body + t: phi(x) = body.phi(R^T (x - t)).
class TransformSdf : public Sdf {
 public:
  TransformSdf(SdfPtr body, const Mat3& r, Vec3 t)
      : body_(std::move(body)), r_(r), rt_(transpose(r)), t_(t) {}

  Real phi(const Vec3& x) const override { return body_->phi(matvec(rt_, x - t_)); }
  Vec3 grad(const Vec3& x) const override { return matvec(r_, body_->grad(matvec(rt_, x - t_))); }
  Real wet_phi(const Vec3& x) const override { return body_->wet_phi(matvec(rt_, x - t_)); }
  Vec3 wet_grad(const Vec3& x) const override {
    return matvec(r_, body_->wet_grad(matvec(rt_, x - t_)));
  }
  bool has_dry_faces() const override { return body_->has_dry_faces(); }

  // The box around the 8 transformed corners of the body's box (huge stays huge).
  Aabb bounds() const override {
    const Aabb bb = body_->bounds();
    if (is_huge(bb)) return huge_box();
    const Real inf = std::numeric_limits<Real>::max();
    Aabb b{Vec3(inf, inf, inf), Vec3(-inf, -inf, -inf)};
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner((c & 1) ? bb.hi.x : bb.lo.x, (c & 2) ? bb.hi.y : bb.lo.y,
                        (c & 4) ? bb.hi.z : bb.lo.z);
      const Vec3 w = matvec(r_, corner) + t_;
      for (int d = 0; d < 3; ++d) {
        b.lo[d] = std::min(b.lo[d], w[d]);
        b.hi[d] = std::max(b.hi[d], w[d]);
      }
    }
    return b;
  }

 private:
  SdfPtr body_;
  Mat3 r_, rt_;
  Vec3 t_;
};

void require_finite(const Vec3& v, const char* what, const char* fn) {
  if (!finite(v)) throw InputError(std::string(fn) + ": " + what + " is not finite");
}

void require_positive(Real v, const char* what, const char* fn) {
  if (!(v > Real(0)) || !std::isfinite(v)) {
    std::ostringstream s;
    s << fn << ": " << what << " must be positive and finite, got " << v;
    throw InputError(s.str());
  }
}

// n / |n|, or an InputError if n has zero length.
Vec3 unit_normal(const Vec3& n, const char* fn) {
  require_finite(n, "normal", fn);
  const Real len = norm(n);
  if (!(len > Real(0))) throw InputError(std::string(fn) + ": normal has zero length");
  return n / len;
}

}  // namespace

// Central differences with step h = cbrt(eps) * max(1, |x|_inf), then normalised. The zero
// vector if the differences vanish.
Vec3 Sdf::grad(const Vec3& x) const {
  const Real scale = std::max({Real(1), std::abs(x.x), std::abs(x.y), std::abs(x.z)});
  const Real h = std::cbrt(std::numeric_limits<Real>::epsilon()) * scale;
  Vec3 g;
  for (int d = 0; d < 3; ++d) {
    Vec3 xp = x, xm = x;
    xp[d] += h;
    xm[d] -= h;
    g[d] = (phi(xp) - phi(xm)) / (xp[d] - xm[d]);
  }
  return unit_or_zero(g);
}

SdfPtr make_box(Vec3 lo, Vec3 hi) {
  require_finite(lo, "lo", "make_box");
  require_finite(hi, "hi", "make_box");
  if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
    throw InputError("make_box: lo " + str(lo) + " must be below hi " + str(hi) + " on every axis");
  return std::make_shared<BoxSdf>(lo, hi);
}

SdfPtr make_plane(Vec3 point, Vec3 outward_normal) {
  require_finite(point, "point", "make_plane");
  return std::make_shared<PlaneSdf>(point, unit_normal(outward_normal, "make_plane"));
}

SdfPtr make_slab(Vec3 point, Vec3 normal, Real thickness) {
  require_finite(point, "point", "make_slab");
  require_positive(thickness, "thickness", "make_slab");
  return std::make_shared<SlabSdf>(point, unit_normal(normal, "make_slab"), thickness);
}

SdfPtr make_cylinder(Vec3 a, Vec3 b, Real radius) {
  require_finite(a, "a", "make_cylinder");
  require_finite(b, "b", "make_cylinder");
  require_positive(radius, "radius", "make_cylinder");
  if (!(norm(b - a) > Real(0))) throw InputError("make_cylinder: end points a and b coincide");
  return std::make_shared<CylinderSdf>(a, b, radius);
}

SdfPtr make_sphere(Vec3 center, Real radius) {
  require_finite(center, "center", "make_sphere");
  require_positive(radius, "radius", "make_sphere");
  return std::make_shared<SphereSdf>(center, radius);
}

// Solid = outer box minus inner box, with outer = inner grown by t on every side (not above an
// open top). For an open top the inner box reaches well above the outer box, so the top is cut
// open. phi = max(phi_outer, -phi_inner): exact inside the walls and inside the fluid region; a
// lower bound on the distance above the rim.
SdfPtr make_tank(Vec3 inner_lo, Vec3 inner_hi, Real thickness, bool closed_top) {
  require_finite(inner_lo, "inner_lo", "make_tank");
  require_finite(inner_hi, "inner_hi", "make_tank");
  require_positive(thickness, "thickness", "make_tank");
  if (!(inner_lo.x < inner_hi.x && inner_lo.y < inner_hi.y && inner_lo.z < inner_hi.z))
    throw InputError("make_tank: inner_lo " + str(inner_lo) + " must be below inner_hi " +
                     str(inner_hi) + " on every axis");
  const Vec3 t(thickness, thickness, thickness);
  Vec3 outer_hi = inner_hi + t;
  Vec3 cut_hi = inner_hi;
  if (!closed_top) {
    outer_hi.z = inner_hi.z;
    const Vec3 ext = inner_hi - inner_lo;
    cut_hi.z = inner_hi.z + Real(2) * (std::max({ext.x, ext.y, ext.z}) + thickness);
  }
  return std::make_shared<CavitySdf>(make_box(inner_lo - t, outer_hi), make_box(inner_lo, cut_hi));
}

SdfPtr make_union(std::vector<SdfPtr> parts) {
  if (parts.empty()) throw InputError("make_union: no parts");
  for (const auto& p : parts)
    if (!p) throw InputError("make_union: a part is null");
  if (parts.size() == 1) return parts.front();
  return std::make_shared<UnionSdf>(std::move(parts));
}

SdfPtr make_difference(SdfPtr a, SdfPtr b) {
  if (!a || !b) throw InputError("make_difference: an operand is null");
  return std::make_shared<DifferenceSdf>(std::move(a), std::move(b));
}

SdfPtr make_transform(SdfPtr body, Vec3 axis, Real angle_rad, Vec3 translation) {
  if (!body) throw InputError("make_transform: body is null");
  require_finite(axis, "axis", "make_transform");
  require_finite(translation, "translation", "make_transform");
  if (!(norm(axis) > Real(0))) throw InputError("make_transform: rotation axis has zero length");
  if (!std::isfinite(angle_rad)) throw InputError("make_transform: angle is not finite");
  const Mat3 r = to_matrix(from_axis_angle(axis, angle_rad));
  return std::make_shared<TransformSdf>(std::move(body), r, translation);
}

// ---- GridSdf ---------------------------------------------------------------------------------

GridSdf::GridSdf(Vec3 lo, Real spacing, int nx, int ny, int nz, std::vector<Real> values)
    : lo_(lo), spacing_(spacing), n_{nx, ny, nz}, values_(std::move(values)) {
  require_finite(lo, "lo", "GridSdf");
  require_positive(spacing, "spacing", "GridSdf");
  if (nx < 1 || ny < 1 || nz < 1) {
    std::ostringstream s;
    s << "GridSdf: node counts must be >= 1, got " << nx << " x " << ny << " x " << nz;
    throw InputError(s.str());
  }
  const std::size_t expected = std::size_t(nx) * std::size_t(ny) * std::size_t(nz);
  if (values_.size() != expected) {
    std::ostringstream s;
    s << "GridSdf: " << nx << " x " << ny << " x " << nz << " grid needs " << expected
      << " values, got " << values_.size();
    throw InputError(s.str());
  }
  // Index range of nodes with phi <= 0, widened by one cell (clamped to the grid).
  int imin[3] = {n_[0], n_[1], n_[2]}, imax[3] = {-1, -1, -1};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!(values_[std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * k)] <=
              Real(0)))
          continue;
        const int ijk[3] = {i, j, k};
        for (int d = 0; d < 3; ++d) {
          imin[d] = std::min(imin[d], ijk[d]);
          imax[d] = std::max(imax[d], ijk[d]);
        }
      }
  if (imax[0] < 0) {
    bounds_ = Aabb{lo_, lo_};
    return;
  }
  for (int d = 0; d < 3; ++d) {
    bounds_.lo[d] = lo_[d] + spacing_ * Real(std::max(imin[d] - 1, 0));
    bounds_.hi[d] = lo_[d] + spacing_ * Real(std::min(imax[d] + 1, n_[d] - 1));
  }
}

}  // namespace sphdem::geom
