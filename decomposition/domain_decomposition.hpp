// Domain decomposition over the neighbour-search cell grid (DESIGN.md §5, "Ownership").
//
// A PETSc DMDA with one point per cell gives every rank a box of whole cells: a 2D DMDA over the
// (x, z) cells for 2D runs, a 3D DMDA over (x, y, z) cells for 3D runs, box stencil of width 1,
// periodic where the cell grid is periodic. Ownership ranges can be rebalanced from the particle
// histogram per cell slab; the DMDA is then recreated with DMDASetOwnershipRanges.
//
// Conventions used by migration.hpp and halo.hpp:
//  - Axes are always (x, y, z). In 2D the y axis has one process and one cell.
//  - rank = i + px * (j + py * k) for process coordinates (i, j, k), the DMDA ordering.
//  - A point outside the grid along a non-periodic axis belongs to the outermost rank on that
//    side (owner_of clamps like CellGrid::coord), so outer boxes extend to infinity there.
//  - Along a periodic axis a point is wrapped into the primary period first.
//
// PETSc stays inside decomposition/*.cpp: the DMDA handle is only forward declared here.
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "neighbor/cell_grid.hpp"

struct _p_DM;  // PETSc's DM is a pointer to this

namespace sphdem {

class DomainDecomposition {
 public:
  // procs = process grid along (x, y, z); 0 lets PETSc choose that axis. In 2D procs[1] must be
  // 0 or 1. Throws InputError when the grid cannot be split that way (a rank would own no cell).
  // Collective over comm.
  DomainDecomposition(MPI_Comm comm, const CellGrid& grid, std::array<int, 3> procs = {0, 0, 0});
  ~DomainDecomposition();
  DomainDecomposition(const DomainDecomposition&) = delete;
  DomainDecomposition& operator=(const DomainDecomposition&) = delete;

  MPI_Comm comm() const { return comm_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  int dim() const { return grid_.dim; }
  const CellGrid& grid() const { return grid_; }

  // Process grid and this rank's process coordinates, along (x, y, z).
  std::array<int, 3> procs() const { return procs_; }
  std::array<int, 3> proc_coord(int rank) const;
  int rank_at(int i, int j, int k) const { return i + procs_[0] * (j + procs_[1] * k); }

  // Process p along axis k owns cells [cell_starts(k)[p], cell_starts(k)[p + 1]).
  const std::vector<int>& cell_starts(int k) const { return starts_[std::size_t(k)]; }

  // This rank's box in metres: whole cells, [lo, hi) along each axis. In 2D the y extent is the
  // grid's single cell layer.
  Vec3 owned_lo() const { return box_lo(rank_); }
  Vec3 owned_hi() const { return box_hi(rank_); }
  Vec3 box_lo(int rank) const;
  Vec3 box_hi(int rank) const;
  // Whether p lies in this rank's box (half-open), after the periodic wrap; points outside the
  // grid on a non-periodic axis count as inside the outermost box (as in owner_of).
  bool owns(const Vec3& p) const { return owner_of(p) == rank_; }

  // The rank whose box holds p (see the conventions above).
  int owner_of(const Vec3& p) const;
  // Process index along axis k of the slab holding coordinate v.
  int proc_along(Real v, int k) const;

  // Ranks adjacent to this one in the process grid (including diagonals and across periodic
  // axes), sorted, without duplicates and without this rank.
  const std::vector<int>& neighbours() const { return neighbours_; }
  bool is_neighbour(int rank) const;

  // Global number of the given (owned) points that each rank's box holds, indexed by rank.
  // Collective. The points may sit on any rank: each is counted where its owner is.
  std::vector<std::int64_t> loads(const Vec3* pos, Index n) const;
  // max / mean of loads(); 1 for an empty set. Collective.
  double imbalance(const Vec3* pos, Index n) const;

  struct RebalanceReport {
    double before = 1;     // max/mean load with the ranges on entry
    double after = 1;      // max/mean load with the ranges on exit
    bool applied = false;  // whether new ranges were applied (the DMDA was recreated)
  };
  // When max/mean load exceeds threshold, recomputes the ownership ranges along each axis from
  // the global histogram of particles per cell slab (prefix sums over MPI_Allreduce'd counts, one
  // split per axis), and applies them if they lower the imbalance. The particles do not move:
  // call redistribute() (migration.hpp) afterwards. Collective.
  RebalanceReport rebalance(const Vec3* pos, Index n, double threshold);
  RebalanceReport rebalance(const std::vector<Vec3>& pos, double threshold) {
    return rebalance(pos.data(), Index(pos.size()), threshold);
  }

  // The DMDA (for DMSwarm in migration.cpp).
  _p_DM* dm() const { return da_; }

 private:
  void create_dmda(const std::array<std::vector<int>, 3>* ranges);
  void set_ranges_from_dmda();
  std::vector<std::int64_t> loads_for(const std::array<std::vector<int>, 3>& starts,
                                      const Vec3* pos, Index n) const;
  std::array<std::vector<int>, 3> split_from_histogram(const Vec3* pos, Index n) const;

  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  CellGrid grid_;
  std::array<int, 3> procs_ = {1, 1, 1};
  std::array<std::vector<int>, 3> starts_;     // cell starts per process, size procs+1
  std::array<std::vector<int>, 3> cell_proc_;  // process index of each cell along each axis
  std::vector<int> neighbours_;
  _p_DM* da_ = nullptr;
};

}  // namespace sphdem
