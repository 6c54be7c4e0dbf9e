// Halo copies of other ranks' fluid particles through a PetscSF (DESIGN.md §5, "Halo").
//
// Built at each neighbour rebuild from the owned positions: an owned particle within `width`
// (2h + skin) of another rank's box becomes a leaf on that rank, once for every rank that needs
// it, so edge and corner copies are all there. Along periodic axes a particle is also copied
// across the period: the copy's position is shifted by +-period, and the shift is recorded per
// halo slot. That includes a rank that needs an image of its own particle (one process along a
// periodic axis), so halo positions are plain coordinates: neighbour searches over owned + halo
// particles use plain distances, with no minimum-image wrap.
//
// Roots are the owned slots [0, n_owned) of each rank; leaves are the halo slots [0, n_halo),
// ordered by source rank, then by the source's slot, then by shift: the same on every run.
// The graph is built with PetscCommBuildTwoSided (each source tells each target how many copies
// it gets, then sends the slots and shifts) and PetscSFSetGraph. bcast() sends owned values to
// the halo (PetscSFBcast, MPI_REPLACE); reduce_sum() adds per-halo contributions back into the
// owners (PetscSFReduce, MPI_SUM), e.g. forces on grain particles. Host buffers only: the solver
// packs the values in its execution space and, on the device, stages them through pinned host
// memory (HostStage in core/exec.hpp and cuda/device_buffer.hpp).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <vector>

#include "core/exec.hpp"
#include "core/types.hpp"
#include "decomposition/domain_decomposition.hpp"
#include "solver/particles.hpp"

struct _p_PetscSF;  // PETSc's PetscSF is a pointer to this

namespace sphdem {

class HaloPlan {
 public:
  // Collective over dd.comm(). width: the distance from a rank's box within which that rank
  // needs a copy (2h + skin). The plan keeps no pointer to dd or to the positions.
  HaloPlan(const DomainDecomposition& dd, const Vec3* owned_pos, Index n_owned, Real width);
  HaloPlan(const DomainDecomposition& dd, const ParticleSet<Host>& ps, Real width)
      : HaloPlan(dd, ps.pos.data(), ps.n_fluid, width) {}
  ~HaloPlan();
  HaloPlan(HaloPlan&& o) noexcept;
  HaloPlan& operator=(HaloPlan&& o) noexcept;
  HaloPlan(const HaloPlan&) = delete;
  HaloPlan& operator=(const HaloPlan&) = delete;

  Index n_owned() const { return n_owned_; }
  Index n_halo() const { return Index(shift_.size()); }
  Index n_copies_sent() const { return n_sent_; }  // leaves this rank's particles feed, all ranks
  Real width() const { return width_; }
  double build_seconds() const { return build_seconds_; }

  // Per halo slot: the rank owning the original, and the shift added to its position.
  const std::vector<int>& source_rank() const { return source_rank_; }
  const std::vector<Vec3>& shift() const { return shift_; }

  // owned: n_owned() values; halo: n_halo() values. Collective.
  void bcast(const Real* owned, Real* halo) const;
  void bcast(const Vec3* owned, Vec3* halo) const;  // as 3 Reals, unshifted
  void bcast(const GlobalId* owned, GlobalId* halo) const;
  void bcast(const std::int32_t* owned, std::int32_t* halo) const;
  // Positions: as bcast, plus each slot's periodic shift.
  void bcast_positions(const Vec3* owned, Vec3* halo) const;
  // owned[i] += sum of halo[j] over the copies j of particle i, on all ranks. Collective.
  void reduce_sum(const Real* halo, Real* owned) const;
  void reduce_sum(const Vec3* halo, Vec3* owned) const;

  // Fills the halo slots of ps (which must still have n_fluid == n_owned()): resizes them to
  // n_halo(), keeps wall and grain slots after them, and broadcasts every field (positions
  // shifted). Sets ps.n_halo. Collective.
  void fill(ParticleSet<Host>& ps) const;

 private:
  void bcast_raw(MPI_Datatype unit, const void* owned, void* halo) const;
  void reduce_raw(MPI_Datatype unit, const void* halo, void* owned) const;
  void release();

  _p_PetscSF* sf_ = nullptr;
  MPI_Datatype real_ = MPI_DATATYPE_NULL;  // MPI type of Real
  MPI_Datatype vec3_ = MPI_DATATYPE_NULL;  // 3 contiguous Reals (owned by the plan)
  Index n_owned_ = 0, n_sent_ = 0;
  Real width_ = 0;
  double build_seconds_ = 0;
  std::vector<int> source_rank_;
  std::vector<Vec3> shift_;
};

}  // namespace sphdem
