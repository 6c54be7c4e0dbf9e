// Fixed-wall particles across ranks (DESIGN.md §5, "Grains and walls across ranks").
//
// Each rank keeps only the wall particles it can use: those within the halo width of its box
// (fluid it owns sees them) and those whose mDBC ghost node lies in its box (it computes their
// state). A wall's state (mDBC density and velocity, DBC density rate, fluid force) is computed by
// exactly one rank, its "owner": the rank whose box holds the ghost node (mDBC) or the particle
// (DBC). The plan is a PetscSF from each owner's slot to every other rank's copy: bcast() copies
// owner values to the copies, reduce_sum() adds the copies' partial sums into the owner. Copies
// and owners are matched by global id once, when the plan is built (an all-gather of the owners'
// (id, slot) pairs), so the slots may be in any order on each rank.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <vector>

#include "core/types.hpp"

struct _p_PetscSF;

namespace sphdem {

class WallPlan {
 public:
  WallPlan() = default;
  // id: the global ids of this rank's n wall slots; mine: 1 where this rank owns the slot.
  // Throws RuntimeFault if a copy has no owner on any rank. Collective.
  WallPlan(MPI_Comm comm, const GlobalId* id, const std::uint8_t* mine, Index n);
  ~WallPlan();
  WallPlan(WallPlan&& o) noexcept;
  WallPlan& operator=(WallPlan&& o) noexcept;
  WallPlan(const WallPlan&) = delete;
  WallPlan& operator=(const WallPlan&) = delete;

  Index n_copies() const { return n_copies_; }  // this rank's slots owned elsewhere

  // f: n values (this rank's wall slots). Collective.
  void bcast(Real* f) const;
  void bcast(Vec3* f) const;
  void reduce_sum(Real* f) const;
  void reduce_sum(Vec3* f) const;

 private:
  void run(MPI_Datatype unit, std::size_t bytes, void* f, bool reduce) const;
  void release();
  _p_PetscSF* sf_ = nullptr;
  MPI_Datatype vec3_ = MPI_DATATYPE_NULL;
  Index n_ = 0, n_copies_ = 0;
};

}  // namespace sphdem
