#include "decomposition/wall_plan.hpp"

#include <petscsf.h>

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

WallPlan::WallPlan(MPI_Comm comm, const GlobalId* id, const std::uint8_t* mine, Index n) {
  MPI_Type_contiguous(3, real_type(), &vec3_);
  MPI_Type_commit(&vec3_);
  int size = 1, me = 0;
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &me);
  // Every owner's (id, root) pairs to every rank; root k is this rank's k-th owned slot.
  std::vector<long long> pairs;
  for (Index s = 0; s < n; ++s)
    if (mine[s]) {
      pairs.push_back((long long)id[s]);
      pairs.push_back((long long)root_slots_.size());
      root_slots_.push_back(s);
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
  std::vector<PetscSFNode> remote;
  leaf_slots_.reserve(want.size());
  remote.reserve(want.size());
  for (int r = 0; r < size; ++r) {
    if (r == me) continue;
    const long long* p = all.data() + displs[std::size_t(r)];
    for (int k = 0; k < counts[std::size_t(r)]; k += 2) {
      const auto it = want.find(GlobalId(p[k]));
      if (it == want.end()) continue;
      leaf_slots_.push_back(it->second);
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
  PetscSF sf = nullptr;
  SPHDEM_PETSC(PetscSFCreate(comm, &sf));
  sf_ = sf;
  // Leaves are contiguous (ilocal NULL): leaf j is this rank's copy slot leaf_slots_[j].
  SPHDEM_PETSC(PetscSFSetGraph(sf, PetscInt(root_slots_.size()), PetscInt(leaf_slots_.size()),
                               nullptr, PETSC_COPY_VALUES, remote.data(), PETSC_COPY_VALUES));
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
  root_slots_ = std::move(o.root_slots_);
  leaf_slots_ = std::move(o.leaf_slots_);
  return *this;
}

void WallPlan::run(MPI_Datatype unit, const void* from, void* to, bool reduce) const {
  if (!sf_) return;
  static char dummy[64];  // PETSc wants a pointer even for no values
  const void* src = from ? from : dummy;
  void* dst = to ? to : dummy;
  if (reduce) {
    SPHDEM_PETSC(PetscSFReduceBegin(sf_, unit, src, dst, MPI_SUM));
    SPHDEM_PETSC(PetscSFReduceEnd(sf_, unit, src, dst, MPI_SUM));
  } else {
    SPHDEM_PETSC(PetscSFBcastBegin(sf_, unit, src, dst, MPI_REPLACE));
    SPHDEM_PETSC(PetscSFBcastEnd(sf_, unit, src, dst, MPI_REPLACE));
  }
}

void WallPlan::bcast(const Real* roots, Real* leaves) const {
  run(real_type(), roots, leaves, false);
}
void WallPlan::bcast(const Vec3* roots, Vec3* leaves) const {
  run(vec3_, roots, leaves, false);
}
void WallPlan::reduce_sum(const Real* leaves, Real* roots) const {
  run(real_type(), leaves, roots, true);
}
void WallPlan::reduce_sum(const Vec3* leaves, Vec3* roots) const {
  run(vec3_, leaves, roots, true);
}

}  // namespace sphdem
