// Precision-aware checks for the unit tests. The tests were written for Real = double; a float
// build (SPHDEM_PRECISION=float) rounds every Real to 24 bits, so a check that holds to 1e-12 in
// double holds there only to the float round-off of the same computation.
//
// tol(for_double, for_float) keeps the double build's tolerance exactly as written and gives the
// float build its own, which each test derives from kFloatEps times the size of the quantities and
// the number of roundings (see the comment at each use).
#pragma once

#include <gtest/gtest.h>

#include <type_traits>

#include "core/types.hpp"

namespace sphdem::test {

inline constexpr bool kRealIsFloat = std::is_same_v<Real, float>;

// Machine epsilon of float (2^-23): one unit in the last place of 1. The unit round-off of one
// correctly rounded float operation is kFloatEps / 2.
inline constexpr double kFloatEps = 1.1920928955078125e-7;

// The double build's tolerance, or the float build's.
constexpr double tol(double for_double, double for_float) {
  return kRealIsFloat ? for_float : for_double;
}

}  // namespace sphdem::test

// Equality to within 4 units in the last place of Real: EXPECT_DOUBLE_EQ in a double build
// (unchanged), EXPECT_FLOAT_EQ in a float build. For values computed by a few exact or correctly
// rounded operations (e.g. 0.1 + 0.05, a reflection 2 a - y) that the double build checks with
// EXPECT_DOUBLE_EQ against a double literal.
#if defined(SPHDEM_USE_FLOAT)
#define EXPECT_REAL_EQ(a, b) EXPECT_FLOAT_EQ(a, b)
#else
#define EXPECT_REAL_EQ(a, b) EXPECT_DOUBLE_EQ(a, b)
#endif
