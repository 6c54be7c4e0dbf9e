// The fluid rates on the CPU with each owned fluid pair evaluated once for both particles.
#pragma once

#include "solver/fluid_drivers.hpp"

namespace sphdem {

// The same sums as compute_rates(Host, ..., 0, n, true, rate) over owned fluid slots [0, n), with
// every pair of owned fluid particles evaluated once (pair_core with `both`) instead of from each
// side; halo and boundary neighbours are gathered as before. Returns false, having written
// nothing, when the grid's periodic axes do not allow the colouring below (the caller then
// gathers).
//
// Threads take tiles of reach^3 cells (reach^2 in 2D). A particle visits only neighbours in
// later slots; slots are sorted by cell key (z, y, x), so those lie in its own tile or in the
// next tiles along z and the adjacent ones along x and y. Tiles are coloured (x mod 3, y mod 3,
// z mod 2; mod 3 on a periodic z) so that no two tiles of a colour write the same particle, and
// the colours run one after another. Each particle therefore receives its terms in an order
// fixed by the grid, not by the thread count: results are bit-identical for any number of
// threads (tested), and equal to the gather's to round-off.
// Whether the colouring holds on this grid: false when a periodic axis is not a whole number of
// tiles, or its tile count is not a multiple of its colour count (two tiles of one colour would
// meet across the wrap).
bool pairwise_tiling_ok(const CellGrid& g);

bool compute_fluid_rates_pairwise(ParticleView v, const NeighborLists& nl, const StepParams& p,
                                  Index n, Real* rate);

}  // namespace sphdem
