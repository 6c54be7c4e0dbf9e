// Uniform cell grid for the neighbour search (DESIGN.md §4).
//
// The cell edge is at least the search radius divided by `reach` (radius = 2h plus a skin), so
// all neighbours of a particle lie within `reach` cells of its own along each axis. reach = 1
// scans 3^d cells of edge 2h; reach = 2 scans 5^d cells of edge h, which holds 42% fewer
// candidates in 3D (125 h^3 against 216 h^3). 2D runs in the x-z plane with one cell layer in y.
// Axes may be periodic; then the cell count along the axis divides the period exactly and
// distances use the minimum image.
#pragma once

#include <cstdint>

#include "core/hd.hpp"
#include "core/types.hpp"

namespace sphdem {

struct CellGrid {
  int dim = 3;           // 2 (x-z plane) or 3
  Vec3 lo;               // lower corner of the grid
  Vec3 cell;             // cell edge along each axis (>= search radius)
  int n[3] = {1, 1, 1};  // cells along x, y, z
  bool periodic[3] = {false, false, false};
  Vec3 period;    // domain length along periodic axes
  int reach = 1;  // cells scanned on each side along each axis

  SPHDEM_HD std::uint64_t cell_count() const {
    return std::uint64_t(n[0]) * std::uint64_t(n[1]) * std::uint64_t(n[2]);
  }

  // Integer cell coordinate along axis k, clamped into the grid (periodic axes wrap).
  SPHDEM_HD int coord(Real v, int k) const {
    const Real lo_k = lo[k];
    int c = int(std::floor((v - lo_k) / cell[k]));
    if (periodic[k]) {
      c %= n[k];
      if (c < 0) c += n[k];
      return c;
    }
    return c < 0 ? 0 : (c >= n[k] ? n[k] - 1 : c);
  }

  SPHDEM_HD std::uint64_t key(int cx, int cy, int cz) const {
    return (std::uint64_t(cz) * std::uint64_t(n[1]) + std::uint64_t(cy)) * std::uint64_t(n[0]) +
           std::uint64_t(cx);
  }

  SPHDEM_HD std::uint64_t key_of(const Vec3& p) const {
    return key(coord(p.x, 0), dim == 2 ? 0 : coord(p.y, 1), coord(p.z, 2));
  }

  // r_i - r_j with the minimum image on periodic axes.
  SPHDEM_HD Vec3 separation(const Vec3& a, const Vec3& b) const {
    Vec3 d = a - b;
    for (int k = 0; k < 3; ++k) {
      if (periodic[k]) {
        const Real L = period[k];
        if (d[k] > Real(0.5) * L) d[k] -= L;
        if (d[k] < Real(-0.5) * L) d[k] += L;
      }
    }
    if (dim == 2) d.y = 0;
    return d;
  }
};

// Builds a grid covering [lo, hi] with cells of edge >= min_cell, to be scanned `reach` cells
// on each side. Periodic axes must be at least 2 reach + 1 cells long so a cell never appears
// twice among a particle's neighbour cells.
CellGrid make_cell_grid(int dim, Vec3 lo, Vec3 hi, Real min_cell, const bool periodic[3],
                        int reach = 1);

// A cell list over a contiguous range of particle slots that has been sorted by cell key, as
// offsets: cell c holds the slots [start[c], start[c + 1]) (ncell + 1 entries; empty cells have
// equal offsets). Consecutive cells along x are therefore one contiguous range of slots.
//
// `occupied` (optional) flags each block of kBlock^d cells that holds any slot of the list. A
// query whose cells all fall in empty blocks returns after at most 2^d flag reads instead of
// scanning (2 reach + 1)^(d-1) rows: a wall particle far from the fluid costs almost nothing.
struct CellListView {
  const std::uint32_t* start = nullptr;
  const std::uint8_t* occupied = nullptr;
};

// Cells per block edge for CellListView::occupied (a power of two).
constexpr int kBlockShift = 2;
constexpr int kBlock = 1 << kBlockShift;

SPHDEM_HD inline int block_count(const CellGrid& g, int k) {
  return (g.n[k] + kBlock - 1) >> kBlockShift;
}

// False only when every cell within `reach` of cell (cx, cy, cz) lies in an empty block. A
// periodic axis whose window wraps is not tested (the query scans).
SPHDEM_HD inline bool window_occupied(const CellGrid& g, const std::uint8_t* occ, int cx, int cy,
                                      int cz) {
  const int c[3] = {cx, cy, cz};
  int b0[3], b1[3];
  for (int k = 0; k < 3; ++k) {
    const int r = (k == 1 && g.dim == 2) ? 0 : g.reach;
    int lo = c[k] - r, hi = c[k] + r;
    if (lo < 0 || hi >= g.n[k]) {
      if (g.periodic[k]) return true;
      lo = lo < 0 ? 0 : lo;
      hi = hi >= g.n[k] ? g.n[k] - 1 : hi;
    }
    b0[k] = lo >> kBlockShift;
    b1[k] = hi >> kBlockShift;
  }
  const int nbx = block_count(g, 0), nby = block_count(g, 1);
  for (int z = b0[2]; z <= b1[2]; ++z)
    for (int y = b0[1]; y <= b1[1]; ++y)
      for (int x = b0[0]; x <= b1[0]; ++x)
        if (occ[(std::size_t(z) * std::size_t(nby) + std::size_t(y)) * std::size_t(nbx) +
                std::size_t(x)])
          return true;
  return false;
}

// Calls f(j, r_ij, r2) for every particle slot j of the list within sqrt(radius2) of point xi
// (the particle itself included when it is in the list: the caller skips j == i when needed).
// The visiting order is fixed: cells by (dz, dy, dx), then slots in sorted (cell, id) order, so
// sums over neighbours are reproducible.
//
// for_each_neighbor_from visits only slots >= `first`: from slot i with first = i + 1 it visits
// each pair of the list once (the pairwise fluid pass, solver/pairwise_host.cpp). Rows of cells
// wholly below `first` cost two loads.
template <class F>
SPHDEM_HD SPHDEM_FLATTEN inline void for_each_neighbor_from(const CellGrid& g,
                                                            const CellListView& cl, const Vec3* pos,
                                                            const Vec3& xi, Real radius2,
                                                            std::uint32_t first, F&& f) {
  const int r = g.reach;
  const int cx = g.coord(xi.x, 0);
  const int cy = g.dim == 2 ? 0 : g.coord(xi.y, 1);
  const int cz = g.coord(xi.z, 2);
  if (cl.occupied && !window_occupied(g, cl.occupied, cx, cy, cz)) return;
  const int ry = g.dim == 2 ? 0 : r;
  // The row of cells [x0, x1] along x is one contiguous slot range; a periodic row that wraps
  // splits into two.
  auto scan = [&](int x0, int x1, int y, int z) {
    std::uint32_t b = cl.start[g.key(x0, y, z)];
    const std::uint32_t e = cl.start[g.key(x1, y, z) + 1];
    if (b < first) b = first;
    for (std::uint32_t j = b; j < e; ++j) {
      const Vec3 rij = g.separation(xi, pos[j]);
      const Real r2 = norm2(rij);
      if (r2 < radius2) f(Index(j), rij, r2);
    }
  };
  for (int dz = -r; dz <= r; ++dz) {
    int z = cz + dz;
    if (g.periodic[2]) {
      z = (z + g.n[2]) % g.n[2];
    } else if (z < 0 || z >= g.n[2]) {
      continue;
    }
    for (int dy = -ry; dy <= ry; ++dy) {
      int y = cy + dy;
      if (g.periodic[1]) {
        y = (y + g.n[1]) % g.n[1];
      } else if (y < 0 || y >= g.n[1]) {
        continue;
      }
      int x0 = cx - r, x1 = cx + r;
      if (g.periodic[0]) {
        if (x0 < 0) {
          scan(x0 + g.n[0], g.n[0] - 1, y, z);
          x0 = 0;
        }
        if (x1 >= g.n[0]) {
          scan(x0, g.n[0] - 1, y, z);
          scan(0, x1 - g.n[0], y, z);
          continue;
        }
      } else {
        x0 = x0 < 0 ? 0 : x0;
        x1 = x1 >= g.n[0] ? g.n[0] - 1 : x1;
      }
      scan(x0, x1, y, z);
    }
  }
}

template <class F>
SPHDEM_HD SPHDEM_FLATTEN inline void for_each_neighbor(const CellGrid& g, const CellListView& cl,
                                                       const Vec3* pos, const Vec3& xi,
                                                       Real radius2, F&& f) {
  for_each_neighbor_from(g, cl, pos, xi, radius2, 0, f);
}

}  // namespace sphdem
