#include "decomposition/domain_decomposition.hpp"

#include <petscdmda.h>

#include <algorithm>
#include <sstream>

#include "core/error.hpp"
#include "decomposition/petsc_check.hpp"

namespace sphdem {

namespace {

// DMDA axis a holds grid axis kDmdaAxis[dim][a]: (x, y, z) in 3D, (x, z) in 2D.
int grid_axis(int dim, int dmda_axis) {
  return dim == 3 ? dmda_axis : (dmda_axis == 0 ? 0 : 2);
}

double max_over_mean(const std::vector<std::int64_t>& loads) {
  std::int64_t total = 0, mx = 0;
  for (auto l : loads) {
    total += l;
    mx = std::max(mx, l);
  }
  if (total == 0) return 1.0;
  return double(mx) * double(loads.size()) / double(total);
}

// Process index of every cell along an axis, from the cell starts of the processes.
std::vector<int> cell_to_proc(const std::vector<int>& starts) {
  std::vector<int> map(static_cast<std::size_t>(starts.back()));
  for (std::size_t p = 0; p + 1 < starts.size(); ++p)
    for (int c = starts[p]; c < starts[p + 1]; ++c) map[std::size_t(c)] = int(p);
  return map;
}

}  // namespace

DomainDecomposition::DomainDecomposition(MPI_Comm comm, const CellGrid& grid,
                                         std::array<int, 3> procs)
    : comm_(comm), grid_(grid) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  if (grid_.dim != 2 && grid_.dim != 3) throw InputError("decomposition: dimension must be 2 or 3");
  if (grid_.dim == 2) {
    if (procs[1] > 1) throw InputError("decomposition: a 2D run has one process along y");
    procs[1] = 1;
  }
  std::int64_t product = 1;
  bool all_set = true;
  for (int k = 0; k < 3; ++k) {
    if (procs[std::size_t(k)] < 0) throw InputError("decomposition: negative process count");
    if (procs[std::size_t(k)] == 0) {
      all_set = false;
      continue;
    }
    product *= procs[std::size_t(k)];
    if (procs[std::size_t(k)] > grid_.n[k]) {
      std::ostringstream os;
      os << "decomposition: " << procs[std::size_t(k)] << " processes along "
         << "xyz"[k] << " but the cell grid has only " << grid_.n[k] << " cells there";
      throw InputError(os.str());
    }
  }
  if ((all_set && product != size_) || (!all_set && size_ % product != 0)) {
    std::ostringstream os;
    os << "decomposition: process grid " << procs[0] << "x" << procs[1] << "x" << procs[2]
       << " does not fit " << size_ << " ranks";
    throw InputError(os.str());
  }
  procs_ = procs;
  create_dmda(nullptr);
}

DomainDecomposition::~DomainDecomposition() {
  if (da_) {
    DM da = da_;
    DMDestroy(&da);
  }
}

void DomainDecomposition::create_dmda(const std::array<std::vector<int>, 3>* ranges) {
  const int d = grid_.dim;
  DM da = nullptr;
  SPHDEM_PETSC(DMDACreate(comm_, &da));
  SPHDEM_PETSC(DMSetDimension(da, d));
  PetscInt size[3] = {1, 1, 1}, np[3] = {PETSC_DECIDE, PETSC_DECIDE, PETSC_DECIDE};
  DMBoundaryType bnd[3] = {DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE};
  std::vector<PetscInt> counts[3];
  for (int a = 0; a < d; ++a) {
    const int k = grid_axis(d, a);
    size[a] = grid_.n[k];
    if (procs_[std::size_t(k)] > 0) np[a] = procs_[std::size_t(k)];
    if (grid_.periodic[k]) bnd[a] = DM_BOUNDARY_PERIODIC;
    if (ranges) {
      const auto& s = (*ranges)[std::size_t(k)];
      for (std::size_t p = 0; p + 1 < s.size(); ++p) counts[a].push_back(s[p + 1] - s[p]);
      np[a] = PetscInt(counts[a].size());
    }
  }
  SPHDEM_PETSC(DMDASetSizes(da, size[0], size[1], size[2]));
  SPHDEM_PETSC(DMDASetNumProcs(da, np[0], np[1], np[2]));
  SPHDEM_PETSC(DMDASetBoundaryType(da, bnd[0], bnd[1], bnd[2]));
  SPHDEM_PETSC(DMDASetDof(da, 1));
  SPHDEM_PETSC(DMDASetStencilType(da, DMDA_STENCIL_BOX));
  // Width 1: a rank's neighbours in the DMDA are exactly the ranks whose boxes touch its own.
  SPHDEM_PETSC(DMDASetStencilWidth(da, 1));
  if (ranges) {
    SPHDEM_PETSC(DMDASetOwnershipRanges(da, counts[0].data(), d > 1 ? counts[1].data() : nullptr,
                                        d > 2 ? counts[2].data() : nullptr));
  }
  SPHDEM_PETSC(DMSetUp(da));
  if (da_) {
    DM old = da_;
    DMDestroy(&old);
  }
  da_ = da;
  set_ranges_from_dmda();
}

void DomainDecomposition::set_ranges_from_dmda() {
  const int d = grid_.dim;
  PetscInt m[3] = {1, 1, 1};
  SPHDEM_PETSC(DMDAGetInfo(da_, nullptr, nullptr, nullptr, nullptr, &m[0], &m[1], &m[2], nullptr,
                           nullptr, nullptr, nullptr, nullptr, nullptr));
  const PetscInt* l[3] = {nullptr, nullptr, nullptr};
  SPHDEM_PETSC(DMDAGetOwnershipRanges(da_, &l[0], &l[1], &l[2]));
  for (int k = 0; k < 3; ++k) {
    procs_[std::size_t(k)] = 1;
    starts_[std::size_t(k)] = {0, grid_.n[k]};
  }
  for (int a = 0; a < d; ++a) {
    const int k = grid_axis(d, a);
    procs_[std::size_t(k)] = int(m[a]);
    auto& s = starts_[std::size_t(k)];
    s.assign(1, 0);
    for (PetscInt p = 0; p < m[a]; ++p) s.push_back(s.back() + int(l[a][p]));
  }
  for (int k = 0; k < 3; ++k) cell_proc_[std::size_t(k)] = cell_to_proc(starts_[std::size_t(k)]);

  // Our rank formula must agree with the DMDA's: check this rank's corner.
  PetscInt lo[3] = {0, 0, 0}, w[3] = {1, 1, 1};
  SPHDEM_PETSC(DMDAGetCorners(da_, &lo[0], &lo[1], &lo[2], &w[0], &w[1], &w[2]));
  const auto me = proc_coord(rank_);
  for (int a = 0; a < d; ++a) {
    const int k = grid_axis(d, a);
    const auto& s = starts_[std::size_t(k)];
    if (s[std::size_t(me[std::size_t(k)])] != lo[a] ||
        s[std::size_t(me[std::size_t(k)]) + 1] != lo[a] + w[a])
      throw RuntimeFault("decomposition: DMDA rank ordering differs from the expected x-fastest");
  }

  // Neighbours: the 3^d - 1 adjacent process-grid positions, wrapped on periodic axes.
  neighbours_.clear();
  const int ry = d == 3 ? 1 : 0;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -ry; dj <= ry; ++dj)
      for (int di = -1; di <= 1; ++di) {
        int c[3] = {me[0] + di, me[1] + dj, me[2] + dk};
        bool ok = true;
        for (int k = 0; k < 3; ++k) {
          const int pk = procs_[std::size_t(k)];
          if (c[k] >= 0 && c[k] < pk) continue;
          if (grid_.periodic[k]) {
            c[k] = (c[k] + pk) % pk;
          } else {
            ok = false;
          }
        }
        if (!ok) continue;
        const int r = rank_at(c[0], c[1], c[2]);
        if (r != rank_) neighbours_.push_back(r);
      }
  std::sort(neighbours_.begin(), neighbours_.end());
  neighbours_.erase(std::unique(neighbours_.begin(), neighbours_.end()), neighbours_.end());
}

std::array<int, 3> DomainDecomposition::proc_coord(int rank) const {
  const int i = rank % procs_[0];
  const int j = (rank / procs_[0]) % procs_[1];
  const int k = rank / (procs_[0] * procs_[1]);
  return {i, j, k};
}

Vec3 DomainDecomposition::box_lo(int rank) const {
  const auto c = proc_coord(rank);
  Vec3 v;
  for (int k = 0; k < 3; ++k)
    v[k] =
        grid_.lo[k] + Real(starts_[std::size_t(k)][std::size_t(c[std::size_t(k)])]) * grid_.cell[k];
  return v;
}

Vec3 DomainDecomposition::box_hi(int rank) const {
  const auto c = proc_coord(rank);
  Vec3 v;
  for (int k = 0; k < 3; ++k)
    v[k] = grid_.lo[k] +
           Real(starts_[std::size_t(k)][std::size_t(c[std::size_t(k)]) + 1]) * grid_.cell[k];
  return v;
}

int DomainDecomposition::proc_along(Real v, int k) const {
  if (grid_.dim == 2 && k == 1) return 0;
  return cell_proc_[std::size_t(k)][std::size_t(grid_.coord(v, k))];
}

int DomainDecomposition::owner_of(const Vec3& p) const {
  return rank_at(proc_along(p.x, 0), proc_along(p.y, 1), proc_along(p.z, 2));
}

bool DomainDecomposition::is_neighbour(int rank) const {
  return std::binary_search(neighbours_.begin(), neighbours_.end(), rank);
}

std::vector<std::int64_t> DomainDecomposition::loads_for(
    const std::array<std::vector<int>, 3>& starts, const Vec3* pos, Index n) const {
  std::array<std::vector<int>, 3> map;
  std::array<int, 3> np;
  for (int k = 0; k < 3; ++k) {
    map[std::size_t(k)] = cell_to_proc(starts[std::size_t(k)]);
    np[std::size_t(k)] = int(starts[std::size_t(k)].size()) - 1;
  }
  std::vector<std::int64_t> loads(std::size_t(size_), 0);
  for (Index i = 0; i < n; ++i) {
    int c[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      if (!(grid_.dim == 2 && k == 1))
        c[k] = map[std::size_t(k)][std::size_t(grid_.coord(pos[i][k], k))];
    ++loads[std::size_t(c[0] + np[0] * (c[1] + np[1] * c[2]))];
  }
  MPI_Allreduce(MPI_IN_PLACE, loads.data(), size_, MPI_INT64_T, MPI_SUM, comm_);
  return loads;
}

std::vector<std::int64_t> DomainDecomposition::loads(const Vec3* pos, Index n) const {
  return loads_for(starts_, pos, n);
}

double DomainDecomposition::imbalance(const Vec3* pos, Index n) const {
  return max_over_mean(loads(pos, n));
}

std::array<std::vector<int>, 3> DomainDecomposition::split_from_histogram(const Vec3* pos,
                                                                          Index n) const {
  std::array<std::vector<int>, 3> starts = starts_;
  for (int k = 0; k < 3; ++k) {
    const int parts = procs_[std::size_t(k)];
    if (parts == 1) continue;
    const int cells = grid_.n[k];
    // Global particle count per cell slab along k, then its prefix sums.
    std::vector<std::int64_t> hist(std::size_t(cells), 0);
    for (Index i = 0; i < n; ++i) ++hist[std::size_t(grid_.coord(pos[i][k], k))];
    MPI_Allreduce(MPI_IN_PLACE, hist.data(), cells, MPI_INT64_T, MPI_SUM, comm_);
    std::vector<std::int64_t> prefix(std::size_t(cells) + 1, 0);
    for (int c = 0; c < cells; ++c)
      prefix[std::size_t(c) + 1] = prefix[std::size_t(c)] + hist[std::size_t(c)];
    const double total = double(prefix.back());
    // Boundary p goes where the prefix sum is nearest p/parts of the total, leaving at least one
    // cell to every process (the DMDA needs a stencil width of cells on each).
    auto& s = starts[std::size_t(k)];
    s.assign(std::size_t(parts) + 1, 0);
    s[std::size_t(parts)] = cells;
    for (int p = 1; p < parts; ++p) {
      const double target = total * p / parts;
      const int lo = s[std::size_t(p) - 1] + 1, hi = cells - (parts - p);
      int b = int(std::lower_bound(prefix.begin(), prefix.end(), std::int64_t(std::ceil(target))) -
                  prefix.begin());
      if (b > 0 &&
          target - double(prefix[std::size_t(b) - 1]) < double(prefix[std::size_t(b)]) - target)
        --b;
      s[std::size_t(p)] = std::clamp(b, lo, hi);
    }
  }
  return starts;
}

DomainDecomposition::RebalanceReport DomainDecomposition::rebalance(const Vec3* pos, Index n,
                                                                    double threshold) {
  RebalanceReport r;
  r.before = max_over_mean(loads_for(starts_, pos, n));
  r.after = r.before;
  if (!(r.before > threshold)) return r;
  const auto starts = split_from_histogram(pos, n);
  const double after = max_over_mean(loads_for(starts, pos, n));
  if (!(after < r.before)) return r;
  create_dmda(&starts);
  if (starts_ != starts)
    throw RuntimeFault("decomposition: the DMDA did not take the rebalanced ownership ranges");
  r.after = after;
  r.applied = true;
  return r;
}

}  // namespace sphdem
