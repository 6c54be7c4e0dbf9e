// The shape of a granular heap at rest (rock collapse, seed §3.3): repose angle and run-out,
// measured from points on the grains' surfaces (DEM surface nodes in the world frame).
//
// Surface: the points are binned in columns of `cell` x `cell` in (x, y); the top of a column is
// its highest point above the floor z_floor. Repose angle: a plane z = a + b x + c y fitted by
// least squares to the column tops whose height lies between lo_frac and hi_frac of the heap's
// height (the crest and the toe are left out, as with a protractor on the straight part of the
// slope) and whose x lies in [x_min, x_max]; angle = atan(|(b, c)|). Toe: the far (+x) edge of
// the last column of the run of occupied x-bins that starts at the highest one; grains that
// bounced off on their own beyond a gap do not count.
#pragma once

#include <vector>

#include "core/types.hpp"

namespace sphdem {

struct HeapOptions {
  Real cell = 0.005;  // column size [m], about one grain
  Real z_floor = 0;
  Real x_min = -1e30, x_max = 1e30;  // slope fit window
  Real lo_frac = 0.15, hi_frac = 0.85;
};

struct HeapShape {
  Real repose_deg = 0;  // NaN if fewer than 3 columns qualify
  Real height = 0;      // highest column top above the floor
  Real toe = 0;         // x of the heap's far edge
  Real fit_rms = 0;     // rms distance of the fitted column tops from the plane [m]
  int columns = 0;      // columns used by the fit
};

HeapShape measure_heap(const std::vector<Vec3>& points, const HeapOptions& opt);

}  // namespace sphdem
