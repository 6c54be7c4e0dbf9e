// Fixed-wall particles across ranks (DESIGN.md §5, "Grains and walls across ranks").
//
// Each rank keeps only the wall particles it can use: those within the halo width of its box
// (fluid it owns sees them) and those whose mDBC ghost node lies in its box (it computes their
// state). A wall's state (mDBC density and velocity, DBC density rate, fluid force) is computed by
// exactly one rank, its "owner": the rank whose box holds the ghost node (mDBC) or the particle
// (DBC). The plan is a PetscSF over packed values: its roots are this rank's owned slots in slot
// order (root_slots()), its leaves this rank's copies (leaf_slots()), each fed by its owner's
// root. bcast() copies owner values to the copies, reduce_sum() adds the copies' partial sums into
// the owners; the caller packs and unpacks (in its execution space, so only packed values travel).
// Copies and owners are matched by global id once, when the plan is built (an all-gather of the
// owners' ids), so the slots may be in any order on each rank.
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

  Index n_copies() const { return Index(leaf_slots_.size()); }  // slots owned elsewhere
  const std::vector<Index>& root_slots() const { return root_slots_; }
  const std::vector<Index>& leaf_slots() const { return leaf_slots_; }

  // roots: root_slots().size() values; leaves: leaf_slots().size(). Collective.
  void bcast(const Real* roots, Real* leaves) const;
  void bcast(const Vec3* roots, Vec3* leaves) const;
  void reduce_sum(const Real* leaves, Real* roots) const;
  void reduce_sum(const Vec3* leaves, Vec3* roots) const;

 private:
  void run(MPI_Datatype unit, const void* from, void* to, bool reduce) const;
  void release();
  _p_PetscSF* sf_ = nullptr;
  MPI_Datatype vec3_ = MPI_DATATYPE_NULL;
  std::vector<Index> root_slots_, leaf_slots_;
};

}  // namespace sphdem
