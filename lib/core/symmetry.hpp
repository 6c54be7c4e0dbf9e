// A symmetry plane x_axis = at (scene key `symmetry`): the scene is modelled on one side of it
// (keep = +1: x_axis > at; -1: x_axis < at) and the other side is the mirror image. The fluid near
// the plane sees mirror copies of the fluid (solver/mirror_exchange.hpp), so the plane acts as a
// free-slip wall with no boundary particles; fluid that crosses it is reflected back; the
// diagnostics evaluate the mirrored full scene (diagnostics/mirror.hpp).
#pragma once

#include "core/types.hpp"

namespace sphdem {

struct SymmetryPlane {
  int axis = -1;  // 0, 1, 2; -1 = none
  Real at = 0;
  int keep = 1;  // +1 keeps x_axis > at, -1 keeps x_axis < at

  SPHDEM_HD bool enabled() const { return axis >= 0; }
  // Signed distance from the plane, positive on the modelled side.
  SPHDEM_HD Real side(const Vec3& x) const { return (x[axis] - at) * Real(keep); }
  SPHDEM_HD Vec3 reflect_point(Vec3 x) const {
    x[axis] = Real(2) * at - x[axis];
    return x;
  }
  SPHDEM_HD Vec3 reflect_vector(Vec3 v) const {
    v[axis] = -v[axis];
    return v;
  }
  // The off-diagonal part (xy, xz, yz) of a symmetric tensor: a component changes sign when
  // exactly one of its indices is the plane's axis.
  SPHDEM_HD Vec3 reflect_off_diagonal(Vec3 o) const {
    if (axis == 0) {
      o.x = -o.x;
      o.y = -o.y;
    } else if (axis == 1) {
      o.x = -o.x;
      o.z = -o.z;
    } else {
      o.y = -o.y;
      o.z = -o.z;
    }
    return o;
  }
};

}  // namespace sphdem
