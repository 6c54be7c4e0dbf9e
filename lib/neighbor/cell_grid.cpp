#include "neighbor/cell_grid.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"

namespace sphdem {

CellGrid make_cell_grid(int dim, Vec3 lo, Vec3 hi, Real min_cell, const bool periodic[3],
                        int reach) {
  if (dim != 2 && dim != 3) throw InputError("dimension must be 2 or 3");
  if (!(min_cell > 0)) throw InputError("cell size must be positive");
  if (reach < 1) throw InputError("cell reach must be at least 1");
  CellGrid g;
  g.dim = dim;
  g.reach = reach;
  g.lo = lo;
  for (int k = 0; k < 3; ++k) {
    const Real len = hi[k] - lo[k];
    g.periodic[k] = periodic[k] && !(dim == 2 && k == 1);
    if (dim == 2 && k == 1) {
      g.n[k] = 1;
      g.cell[k] = std::max(len, min_cell);
      continue;
    }
    if (!(len > 0)) {
      std::ostringstream os;
      os << "domain has zero or negative length along axis "
         << "xyz"[k];
      throw InputError(os.str());
    }
    if (g.periodic[k]) {
      g.n[k] = int(std::floor(len / min_cell));
      if (g.n[k] < 3) {
        std::ostringstream os;
        os << "periodic axis "
           << "xyz"[k] << " of length " << len << " m holds fewer than 3 cells of " << min_cell
           << " m";
        throw InputError(os.str());
      }
      g.cell[k] = len / g.n[k];
      g.period[k] = len;
    } else {
      g.n[k] = std::max(1, int(std::ceil(len / min_cell)));
      g.cell[k] = min_cell;
    }
  }
  return g;
}

}  // namespace sphdem
