// Unit quaternions and 3x3 matrices for rigid-body orientation (DEM grains, transformed SDFs).
// A quaternion q = (w, x, y, z) with |q| = 1 rotates a vector v as q v q*. All functions are
// SPHDEM_HD so the CPU and CUDA backends share them.
#pragma once

#include <cmath>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

// A 3x3 matrix, row-major: m[row][col].
struct Mat3 {
  Real m[3][3];
};

// The identity matrix.
SPHDEM_HD inline Mat3 mat3_identity() {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = (i == j) ? Real(1) : Real(0);
  return r;
}

// The matrix-vector product A v.
SPHDEM_HD inline Vec3 matvec(const Mat3& a, const Vec3& v) {
  return Vec3(a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
              a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
              a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z);
}

// The transpose A^T.
SPHDEM_HD inline Mat3 transpose(const Mat3& a) {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}

// The matrix product A B.
SPHDEM_HD inline Mat3 multiply(const Mat3& a, const Mat3& b) {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Real s = 0;
      for (int k = 0; k < 3; ++k) s += a.m[i][k] * b.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

// A quaternion w + x i + y j + z k. Default: the identity rotation.
struct Quat {
  Real w = 1, x = 0, y = 0, z = 0;
};

// The unit quaternion of a rotation by angle_rad (right-handed) about axis (any nonzero length).
// A zero axis gives the identity.
SPHDEM_HD inline Quat from_axis_angle(const Vec3& axis, Real angle_rad) {
  const Real n = norm(axis);
  if (!(n > Real(0))) return Quat{};
  const Real s = std::sin(Real(0.5) * angle_rad) / n;
  return Quat{std::cos(Real(0.5) * angle_rad), axis.x * s, axis.y * s, axis.z * s};
}

// The Hamilton product a b (apply b first, then a, when both rotate vectors).
SPHDEM_HD inline Quat multiply(const Quat& a, const Quat& b) {
  return Quat{
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

// The conjugate (w, -x, -y, -z): the inverse rotation of a unit quaternion.
SPHDEM_HD inline Quat conjugate(const Quat& q) {
  return Quat{q.w, -q.x, -q.y, -q.z};
}

// The Euclidean norm sqrt(w^2 + x^2 + y^2 + z^2).
SPHDEM_HD inline Real norm(const Quat& q) {
  return std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
}

// q / |q|; the identity when |q| = 0.
SPHDEM_HD inline Quat normalize(const Quat& q) {
  const Real n = norm(q);
  if (!(n > Real(0))) return Quat{};
  const Real inv = Real(1) / n;
  return Quat{q.w * inv, q.x * inv, q.y * inv, q.z * inv};
}

// The rotated vector q v q* for a unit quaternion q, computed as
// v + 2 w (u x v) + 2 u x (u x v) with u = (x, y, z).
SPHDEM_HD inline Vec3 rotate(const Quat& q, const Vec3& v) {
  const Vec3 u(q.x, q.y, q.z);
  const Vec3 t = Real(2) * cross(u, v);
  return v + q.w * t + cross(u, t);
}

// The rotation matrix R of a unit quaternion, with R v = rotate(q, v).
SPHDEM_HD inline Mat3 to_matrix(const Quat& q) {
  const Real ww = q.w * q.w, xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const Real xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const Real wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  Mat3 r{};
  r.m[0][0] = ww + xx - yy - zz;
  r.m[0][1] = Real(2) * (xy - wz);
  r.m[0][2] = Real(2) * (xz + wy);
  r.m[1][0] = Real(2) * (xy + wz);
  r.m[1][1] = ww - xx + yy - zz;
  r.m[1][2] = Real(2) * (yz - wx);
  r.m[2][0] = Real(2) * (xz - wy);
  r.m[2][1] = Real(2) * (yz + wx);
  r.m[2][2] = ww - xx - yy + zz;
  return r;
}

}  // namespace sphdem
