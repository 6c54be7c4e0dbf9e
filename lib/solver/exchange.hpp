// What the solver needs from a domain decomposition (DESIGN.md §5). The solver stays free of MPI
// and PETSc: decomposition/distributed.cpp implements this with a DMDA, neighbour migration and a
// PetscSF halo. A solver without an Exchange runs on one rank.
//
// Per step, on every rank (all calls are collective):
//   drop the halo -> remove/wrap -> migrate(leavers) -> sort owned by (cell, id)
//   -> build_halo (every field) -> sort the halo range by (cell, id)
// and within the step, bcast() refreshes halo copies of fields that changed (the symplectic
// predictor; mu_eff and the SPS stress). Each rank holds only the fixed-wall particles near its
// box (keep_walls, deal_walls); a wall's mDBC state and fluid force are computed by its owner (the
// rank owning the ghost node, or with DBC the particle) and the wall plan copies them to the other
// ranks' copies.
#pragma once

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/types.hpp"
#include "solver/particles.hpp"

namespace sphdem {

// What a Vec3 field holds, for an exchange whose halo copies are transformed images of their
// owners (a symmetry plane's mirror, solver/mirror_exchange.hpp); a plain copy ignores it.
enum class HaloField { kValue, kVelocity, kOffDiagonal };

class Exchange {
 public:
  virtual ~Exchange() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Whether x lies in this rank's box (every point has exactly one owner).
  virtual bool owns(const Vec3& x) const = 0;
  // Moves the owned fluid [0, n_fluid) that left this rank's box to its owner. The set must have
  // no halo. Throws RuntimeFault (nothing moved) if a particle would be lost.
  virtual void migrate(ParticleSet<Host>& ps) = 0;
  // When the owned-fluid imbalance (max/mean over ranks) exceeds the threshold, recomputes the
  // boxes from the particle histogram and redistributes the owned fluid (no halo allowed).
  // Returns whether it did.
  virtual bool rebalance(ParticleSet<Host>& ps) = 0;
  // Builds the halo plan from the owned positions and fills the halo slots with every field.
  virtual void build_halo(ParticleSet<Host>& ps) = 0;
  virtual Index halo_count() const = 0;
  // Owned values [0, n_owned) to the halo copies, in the plan's leaf order.
  virtual void bcast(const Real* owned, Real* halo) = 0;
  virtual void bcast(const Vec3* owned, Vec3* halo) = 0;
  virtual void bcast_positions(const Vec3* owned, Vec3* halo) = 0;
  virtual void bcast_field(const Vec3* owned, Vec3* halo, HaloField) { bcast(owned, halo); }
  // Walls: 1 for each of n wall particles this rank keeps (within the halo width of its box, or,
  // by_ghost, with the ghost node in its box). ghost_alt: each wall's second ghost node (a thin
  // solid's other face, or a corner's other wall; equal to ghost where there is none), whose
  // gather needs fluid around it too.
  virtual std::vector<std::uint8_t> keep_walls(const Vec3* pos, const Vec3* ghost,
                                               const Vec3* ghost_alt, Index n,
                                               bool by_ghost) const = 0;
  // Walls to the ranks that keep them, after the boxes changed (rebalance) or a checkpoint read:
  // each rank passes a set of wall slots only (n_wall = size) that no other rank passes, and gets
  // back every passed wall it keeps, sorted by global id, with its values as passed. Throws
  // RuntimeFault if a wall was passed twice or the ranks do not own every passed wall once
  // afterwards. Collective. An exchange on one rank keeps them all.
  virtual ParticleSet<Host> deal_walls(ParticleSet<Host>& walls, bool /*by_ghost*/) const {
    return std::move(walls);
  }
  // The plan between wall owners and copies (mine: 1 where this rank owns the slot).
  virtual void build_wall_plan(const GlobalId* id, const std::uint8_t* mine, Index n) = 0;
  // The plan's roots (this rank's owned wall slots, in slot order) and leaves (its copies), as
  // offsets from the first wall slot. The values travel packed in that order.
  virtual void wall_slots(std::vector<Index>& roots, std::vector<Index>& leaves) const = 0;
  // Owner values to the copies; the copies' partial sums added into the owners.
  virtual void wall_bcast(const Real* roots, Real* leaves) = 0;
  virtual void wall_bcast(const Vec3* roots, Vec3* leaves) = 0;
  virtual void wall_reduce(const Real* leaves, Real* roots) = 0;
  virtual void wall_reduce(const Vec3* leaves, Vec3* roots) = 0;
  // Grain boundary particles (DESIGN.md §5, "Grains"): each rank holds those whose ghost node
  // (DBC: position) its box owns, plus copies of other ranks' within the halo width. Only an
  // exchange over many ranks implements these; one that owns every point (a symmetry plane's
  // mirror) never needs them.
  // This rank's box, with the outer faces of non-periodic axes at infinity.
  virtual void owned_box(Vec3& lo, Vec3& hi) const {
    const Real inf = std::numeric_limits<Real>::infinity();
    lo = Vec3(-inf, -inf, -inf);
    hi = Vec3(inf, inf, inf);
  }
  // Builds the grains' own halo plan over the owned grain particles of g, laid out as fluid
  // [0, g.n_fluid), and fills g's halo slots with every field (as build_halo). Collective.
  virtual void build_grain_halo(ParticleSet<Host>&) { no_grains(); }
  // Owned values to the copies, in the plan's root and leaf order; and the copies' partial sums
  // added into the owners.
  virtual void grain_bcast(const Real*, Real*) { no_grains(); }
  virtual void grain_bcast(const Vec3*, Vec3*) { no_grains(); }
  virtual void grain_reduce(const Real*, Real*) { no_grains(); }
  virtual void grain_reduce(const Vec3*, Vec3*) { no_grains(); }
  // In-place reductions over all ranks.
  virtual void sum(Real* v, Index n) = 0;
  virtual void max(Real* v, Index n) = 0;
  virtual std::int64_t sum(std::int64_t v) = 0;

 private:
  [[noreturn]] static void no_grains() {
    throw std::logic_error("Exchange: grain halo on an exchange that holds every grain particle");
  }
};

}  // namespace sphdem
