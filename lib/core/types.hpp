// Basic numeric types: Real (double by default, float with SPHDEM_PRECISION=float), Vec3, Index.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/hd.hpp"

namespace sphdem {

#if defined(SPHDEM_USE_FLOAT)
using Real = float;
#else
using Real = double;
#endif

using Index = std::int64_t;      // particle index on a rank
using GlobalId = std::uint64_t;  // particle id, unique over the whole run

struct Vec3 {
  Real x = 0, y = 0, z = 0;
  constexpr Vec3() = default;  // defaulted: usable on both sides without SPHDEM_HD
  SPHDEM_HD constexpr Vec3(Real a, Real b, Real c) : x(a), y(b), z(c) {}
  SPHDEM_HD Real operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
  SPHDEM_HD Real& operator[](int k) { return k == 0 ? x : (k == 1 ? y : z); }
  SPHDEM_HD Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  SPHDEM_HD Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  SPHDEM_HD Vec3& operator*=(Real s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
};

SPHDEM_HD inline Vec3 operator+(Vec3 a, const Vec3& b) {
  return a += b;
}
SPHDEM_HD inline Vec3 operator-(Vec3 a, const Vec3& b) {
  return a -= b;
}
SPHDEM_HD inline Vec3 operator-(const Vec3& a) {
  return Vec3(-a.x, -a.y, -a.z);
}
SPHDEM_HD inline Vec3 operator*(Vec3 a, Real s) {
  return a *= s;
}
SPHDEM_HD inline Vec3 operator*(Real s, Vec3 a) {
  return a *= s;
}
SPHDEM_HD inline Vec3 operator/(const Vec3& a, Real s) {
  return Vec3(a.x / s, a.y / s, a.z / s);
}
SPHDEM_HD inline Real dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
SPHDEM_HD inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return Vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
SPHDEM_HD inline Real norm2(const Vec3& a) {
  return dot(a, a);
}
SPHDEM_HD inline Real norm(const Vec3& a) {
  return std::sqrt(dot(a, a));
}

constexpr Real kPi = Real(3.14159265358979323846);

}  // namespace sphdem
