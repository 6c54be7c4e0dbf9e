#include "decomposition/wall_plan.hpp"

#include <petscsf.h>

#include <cstring>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include "core/error.hpp"
#include "decomposition/petsc_check.hpp"

namespace sphdem {

namespace {
MPI_Datatype real_type() {
  return std::is_same<Real, double>::value ? MPI_DOUBLE : MPI_FLOAT;
}
}  // namespace

WallPlan::WallPlan(MPI_Comm comm, const GlobalId* id, const std::uint8_t* mine, Index n) : n_(n) {
  MPI_Type_contiguous(3, real_type(), &vec3_);
  MPI_Type_commit(&vec3_);
  int size = 1, me = 0;
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &me);
  // Every owner's (id, slot) pairs to every rank.
  std::vector<long long> pairs;
  for (Index s = 0; s < n; ++s)
    if (mine[s]) {
      pairs.push_back((long long)id[s]);
      pairs.push_back((long long)s);
    }
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size));
  int mycount = int(pairs.size());
  MPI_Allgather(&mycount, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  long long total = 0;
  for (int r = 0; r < size; ++r) {
    displs[std::size_t(r)] = int(total);
    total += counts[std::size_t(r)];
  }
  if (total > 2147483647LL) throw RuntimeFault("WallPlan: more than 1e9 wall particles");
  std::vector<long long> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(pairs.data(), mycount, MPI_LONG_LONG, all.data(), counts.data(), displs.data(),
                 MPI_LONG_LONG, comm);
  // This rank's copies, by id.
  std::unordered_map<GlobalId, Index> want;
  for (Index s = 0; s < n; ++s)
    if (!mine[s]) want.emplace(id[s], s);
  std::vector<PetscInt> ilocal;
  std::vector<PetscSFNode> remote;
  ilocal.reserve(want.size());
  remote.reserve(want.size());
  for (int r = 0; r < size; ++r) {
    if (r == me) continue;
    const long long* p = all.data() + displs[std::size_t(r)];
    for (int k = 0; k < counts[std::size_t(r)]; k += 2) {
      const auto it = want.find(GlobalId(p[k]));
      if (it == want.end()) continue;
      ilocal.push_back(PetscInt(it->second));
      PetscSFNode node;
      node.rank = r;
      node.index = PetscInt(p[k + 1]);
      remote.push_back(node);
      want.erase(it);
    }
  }
  int orphans = int(want.size()), any = 0;
  MPI_Allreduce(&orphans, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any > 0)
    throw RuntimeFault("WallPlan: " + std::to_string(any) +
                       " wall particles kept on some rank have no owner (no rank's box holds "
                       "their ghost node)");
  n_copies_ = Index(ilocal.size());
  PetscSF sf = nullptr;
  SPHDEM_PETSC(PetscSFCreate(comm, &sf));
  sf_ = sf;
  SPHDEM_PETSC(PetscSFSetGraph(sf, PetscInt(n), PetscInt(ilocal.size()), ilocal.data(),
                               PETSC_COPY_VALUES, remote.data(), PETSC_COPY_VALUES));
  SPHDEM_PETSC(PetscSFSetUp(sf));
}

WallPlan::~WallPlan() {
  release();
}

void WallPlan::release() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized || PetscFinalizeCalled) return;
  if (sf_) {
    PetscSF sf = sf_;
    PetscSFDestroy(&sf);
    sf_ = nullptr;
  }
  if (vec3_ != MPI_DATATYPE_NULL) MPI_Type_free(&vec3_);
}

WallPlan::WallPlan(WallPlan&& o) noexcept {
  *this = std::move(o);
}

WallPlan& WallPlan::operator=(WallPlan&& o) noexcept {
  if (this == &o) return *this;
  release();
  sf_ = std::exchange(o.sf_, nullptr);
  vec3_ = std::exchange(o.vec3_, MPI_DATATYPE_NULL);
  n_ = o.n_;
  n_copies_ = o.n_copies_;
  return *this;
}

// Roots and leaves are slots of the same array (owners' slots and copies' slots, disjoint); the
// source side goes through a copy so PETSc never reads what it writes.
void WallPlan::run(MPI_Datatype unit, std::size_t bytes, void* f, bool reduce) const {
  if (!sf_) return;
  static char dummy[64];
  std::vector<char> src(std::max<std::size_t>(std::size_t(n_) * bytes, 1));
  if (n_ > 0) std::memcpy(src.data(), f, std::size_t(n_) * bytes);
  void* dst = n_ > 0 ? f : dummy;
  if (reduce) {
    SPHDEM_PETSC(PetscSFReduceBegin(sf_, unit, src.data(), dst, MPI_SUM));
    SPHDEM_PETSC(PetscSFReduceEnd(sf_, unit, src.data(), dst, MPI_SUM));
  } else {
    SPHDEM_PETSC(PetscSFBcastBegin(sf_, unit, src.data(), dst, MPI_REPLACE));
    SPHDEM_PETSC(PetscSFBcastEnd(sf_, unit, src.data(), dst, MPI_REPLACE));
  }
}

void WallPlan::bcast(Real* f) const {
  run(real_type(), sizeof(Real), f, false);
}
void WallPlan::bcast(Vec3* f) const {
  run(vec3_, sizeof(Vec3), f, false);
}
void WallPlan::reduce_sum(Real* f) const {
  run(real_type(), sizeof(Real), f, true);
}
void WallPlan::reduce_sum(Vec3* f) const {
  run(vec3_, sizeof(Vec3), f, true);
}

}  // namespace sphdem
