// The fluid rates on the CPU with each owned fluid pair evaluated once for both particles.
#pragma once

#include "solver/fluid_drivers.hpp"

namespace sphdem {

// The same sums as compute_rates(Host, ..., 0, n, true, rate) over owned fluid slots [0, n) and
// compute_rates(Host, ..., wall_begin, end, false, rate) over the boundary slots, with every pair
// of owned fluid particles, and every pair of an owned fluid particle and a boundary particle,
// evaluated once (pair_core with `both`) instead of from each side; halo neighbours are gathered
// as before. Returns false, having written nothing, when the grid's periodic axes do not allow
// the colouring below (the caller then gathers).
//
// Threads take tiles of reach^3 cells (reach^2 in 2D). A fluid particle visits only fluid
// neighbours in later slots; slots are sorted by cell key (z, y, x), so those lie in its own
// tile or in the adjacent tiles; its boundary neighbours lie in the adjacent tiles on every
// side. Tiles are coloured (x, y, z mod 3) so that no two tiles of a colour write the same
// particle, and the colours run one after another. Each particle therefore receives its terms
// in an order fixed by the grid, not by the thread count: results are bit-identical for any
// number of threads (tested), and equal to the gather's to round-off.
//
// Whether the colouring holds on this grid: false when a periodic axis is not a whole number of
// tiles, or its tile count is not a multiple of its colour count (two tiles of one colour would
// meet across the wrap).
bool pairwise_tiling_ok(const CellGrid& g);

bool compute_fluid_rates_pairwise(ParticleView v, const NeighborLists& nl, const StepParams& p,
                                  Index n, Index wall_begin, Index end, Real* rate);

}  // namespace sphdem
