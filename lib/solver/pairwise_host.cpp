#include "solver/pairwise_host.hpp"

#include <algorithm>

namespace sphdem {

namespace {

struct Tiling {
  int nt[3] = {1, 1, 1};  // tiles along each axis
  int nc[3] = {1, 1, 1};  // colours along each axis
};

// False when a periodic axis would let two tiles of one colour meet across the wrap.
bool make_tiling(const CellGrid& g, Tiling& t) {
  const int r = g.reach;
  for (int k = 0; k < 3; ++k) {
    if (k == 1 && g.dim == 2) continue;
    t.nt[k] = (g.n[k] + r - 1) / r;
    // A tile writes its own particles and those of the adjacent tiles on either side (boundary
    // neighbours, and later fluid slots across a periodic wrap): three colours per axis.
    t.nc[k] = std::min(3, t.nt[k]);
    if (g.periodic[k] && (g.n[k] % r != 0 || t.nt[k] % t.nc[k] != 0)) return false;
  }
  return true;
}

}  // namespace

bool pairwise_tiling_ok(const CellGrid& g) {
  Tiling t;
  return make_tiling(g, t);
}

bool compute_fluid_rates_pairwise(ParticleView v, const NeighborLists& nl, const StepParams& p,
                                  Index n, Index wall_begin, Index end, Real* rate) {
  const CellGrid& g = p.grid;
  Tiling t;
  if (!make_tiling(g, t)) return false;
  const int r = g.reach;
  const std::uint32_t* start = nl.fluid.start;

#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (Index i = 0; i < n; ++i) {
      v.acc[i] = Vec3();
      v.drho[i] = 0;
      rate[i] = 0;
    }
#pragma omp for schedule(static)
    for (Index b = wall_begin; b < end; ++b) {
      v.acc[b] = Vec3();
      v.drho[b] = 0;
      rate[b] = 0;
    }
    // Every fluid particle of the tile at tile coordinates (tx, ty, tz): its later fluid
    // neighbours and its boundary neighbours (both sides written), and its halo neighbours (its
    // side only: their owners compute the other side).
    auto tile = [&](int tx, int ty, int tz) {
      const int x0 = tx * r, x1 = std::min(x0 + r, g.n[0]) - 1;
      const int y0 = ty * r, y1 = g.dim == 2 ? 0 : std::min(y0 + r, g.n[1]) - 1;
      const int z0 = tz * r, z1 = std::min(z0 + r, g.n[2]) - 1;
      for (int z = z0; z <= z1; ++z)
        for (int y = y0; y <= y1; ++y) {
          const std::uint32_t b = start[g.key(x0, y, z)], e = start[g.key(x1, y, z) + 1];
          for (std::uint32_t s = b; s < e; ++s) {
            const Index i = Index(s);
            const Vec3 ri = v.pos[i];
            const Real m_i = v.mass[i];
            PairSums si;
            // One evaluation of the pair (i, j), written to both sides.
            auto both = [&](Index j, const Vec3& r_ij, Real r2, bool j_fluid) {
              if (r2 <= Real(0)) return;  // coincident particles, as in the gather
              const PairCore c = pair_core(p, v, i, j, r_ij, r2, true, j_fluid, true);
              const Real m_j = v.mass[j];
              si.acc += c.acc * m_j;
              si.drho += c.drho_i * m_j;
              if (c.rate > si.visc_rate) si.visc_rate = c.rate;
              v.acc[j] -= c.acc * m_i;
              v.drho[j] += c.drho_j * m_i;
              if (c.rate > rate[j]) rate[j] = c.rate;
            };
            for_each_neighbor_from(
                g, nl.fluid, v.pos, ri, p.radius2, s + 1,
                [&](Index j, const Vec3& r_ij, Real r2) { both(j, r_ij, r2, true); });
            if (nl.has_halo)
              for_each_neighbor(g, nl.halo, v.pos, ri, p.radius2,
                                [&](Index j, const Vec3& r_ij, Real r2) {
                                  accumulate_pair(p, v, i, j, r_ij, r2, true, true, si);
                                });
            // The fluid's side of a fluid-wall pair, and the wall's (the fluid force on it).
            for_each_boundary_neighbor(p, nl, v.pos, ri, [&](Index j, const Vec3& r_ij, Real r2) {
              both(j, r_ij, r2, false);
            });
            v.acc[i] += si.acc;
            v.drho[i] += si.drho;
            if (si.visc_rate > rate[i]) rate[i] = si.visc_rate;
          }
        }
    };
    for (int cz = 0; cz < t.nc[2]; ++cz)
      for (int cy = 0; cy < t.nc[1]; ++cy)
        for (int cx = 0; cx < t.nc[0]; ++cx) {
          // Tiles of this colour: (cx + nc0 kx, cy + nc1 ky, cz + nc2 kz).
          const int mx = (t.nt[0] - cx + t.nc[0] - 1) / t.nc[0];
          const int my = (t.nt[1] - cy + t.nc[1] - 1) / t.nc[1];
          const int mz = (t.nt[2] - cz + t.nc[2] - 1) / t.nc[2];
          const long count = long(mx) * my * mz;
#pragma omp for schedule(dynamic, 8)
          for (long k = 0; k < count; ++k) {
            const int kx = int(k % mx), ky = int((k / mx) % my), kz = int(k / (long(mx) * my));
            tile(cx + t.nc[0] * kx, cy + t.nc[1] * ky, cz + t.nc[2] * kz);
          }
        }
#pragma omp for schedule(static)
    for (Index i = 0; i < n; ++i) v.acc[i] += p.gravity;
  }
  return true;
}

}  // namespace sphdem
