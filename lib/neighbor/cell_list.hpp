// Sort-based cell list over a contiguous range of particle slots (DESIGN.md §4):
//   1. sort the range by (cell key, global id): a stable sort by id, then a stable sort by cell;
//   2. permute every field of the range by the resulting order (the caller owns the fields);
//   3. mark each cell's [start, end) where the key changes.
// Because each cell's particles are in id order, sums over neighbours come out in the same order
// on every run and under any decomposition.
#pragma once

#include <cstdint>

#include "core/exec.hpp"
#include "neighbor/cell_grid.hpp"

namespace sphdem {

template <class Space>
struct CellList {
  Index begin = 0, count = 0;            // the slots this list covers
  Buffer<std::uint32_t, Space> start;    // ncell + 1 offsets: cell c is [start[c], start[c+1])
  Buffer<std::uint64_t, Space> keys;     // sorted cell key of each slot in the range
  Buffer<std::uint32_t, Space> order;    // source slot (relative to begin) of each sorted slot
  Buffer<std::uint8_t, Space> occupied;  // per block of cells (mark_blocks); empty: not built

  CellListView view() const {
    return CellListView{start.data(), occupied.size() ? occupied.data() : nullptr};
  }
};

// Step 1: computes the sorted order of slots [begin, begin+count) into cl.order.
template <class Space>
void sort_cells(Space s, const CellGrid& g, const Vec3* pos, const GlobalId* id, GlobalId max_id,
                Index begin, Index count, CellList<Space>& cl) {
  cl.begin = begin;
  cl.count = count;
  cl.keys.resize(std::size_t(count));
  cl.order.resize(std::size_t(count));
  std::uint64_t* keys = cl.keys.data();
  std::uint32_t* order = cl.order.data();
  for_each(
      s, count, SPHDEM_LAMBDA(Index i) {
        keys[i] = std::uint64_t(id[begin + i]);
        order[i] = std::uint32_t(i);
      });
  sort_pairs_stable(s, keys, order, count, std::uint64_t(max_id));
  const CellGrid grid = g;
  for_each(
      s, count, SPHDEM_LAMBDA(Index i) { keys[i] = grid.key_of(pos[begin + order[i]]); });
  sort_pairs_stable(s, keys, order, count, grid.cell_count() - 1);
}

// Step 2 helper: gathers field[begin + order[i]] into slot begin + i, using scratch storage.
template <class T, class Space>
void permute_range(Space s, Buffer<T, Space>& field, const CellList<Space>& cl,
                   Buffer<T, Space>& scratch) {
  const Index begin = cl.begin, count = cl.count;
  if (count == 0) return;
  scratch.resize(std::size_t(count));
  T* f = field.data();
  T* t = scratch.data();
  const std::uint32_t* order = cl.order.data();
  for_each(
      s, count, SPHDEM_LAMBDA(Index i) { t[i] = f[begin + order[i]]; });
  for_each(
      s, count, SPHDEM_LAMBDA(Index i) { f[begin + i] = t[i]; });
}

// Step 3: fills the cell offsets from the sorted keys: start[c] is the first slot whose key is
// >= c (absolute index), and start[ncell] is the end of the range. Each entry is written once.
template <class Space>
void mark_cells(Space s, const CellGrid& g, CellList<Space>& cl) {
  const Index ncell = Index(g.cell_count());
  cl.start.resize(std::size_t(ncell + 1));
  std::uint32_t* st = cl.start.data();
  const std::uint64_t* keys = cl.keys.data();
  const Index begin = cl.begin, count = cl.count;
  const std::uint32_t last = std::uint32_t(begin + count);
  // Cells after the last key (all cells if the range is empty) end the range.
  for_each(
      s, ncell + 1, SPHDEM_LAMBDA(Index c) { st[c] = last; });
  for_each(
      s, count, SPHDEM_LAMBDA(Index i) {
        const std::uint64_t k = keys[i];
        const std::uint64_t prev = i == 0 ? std::uint64_t(0) : keys[i - 1] + 1;
        if (i == 0 || keys[i - 1] != k) {
          for (std::uint64_t c = prev; c <= k; ++c) st[c] = std::uint32_t(begin + i);
        }
      });
}

// Step 4 (optional, after mark_cells): flags each block of kBlock^d cells that holds a slot of
// the range, so that neighbour queries in empty regions return at once. Each flag is written
// once, from its own block's rows.
template <class Space>
void mark_blocks(Space s, const CellGrid& g, CellList<Space>& cl) {
  const int nbx = block_count(g, 0), nby = block_count(g, 1), nbz = block_count(g, 2);
  const Index nb = Index(nbx) * nby * nbz;
  cl.occupied.resize(std::size_t(nb));
  std::uint8_t* occ = cl.occupied.data();
  const std::uint32_t* st = cl.start.data();
  const CellGrid grid = g;
  for_each(
      s, nb, SPHDEM_LAMBDA(Index b) {
        const int bx = int(b % nbx), by = int((b / nbx) % nby), bz = int(b / (Index(nbx) * nby));
        const int x0 = bx << kBlockShift;
        const int x1 = x0 + kBlock - 1 < grid.n[0] ? x0 + kBlock - 1 : grid.n[0] - 1;
        std::uint8_t any = 0;
        for (int z = bz << kBlockShift; z < ((bz + 1) << kBlockShift) && z < grid.n[2]; ++z)
          for (int y = by << kBlockShift; y < ((by + 1) << kBlockShift) && y < grid.n[1]; ++y)
            if (st[grid.key(x1, y, z) + 1] > st[grid.key(x0, y, z)]) any = 1;
        occ[b] = any;
      });
}

}  // namespace sphdem
