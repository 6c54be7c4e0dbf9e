// A run on many ranks (DESIGN.md §5): the Exchange the solver uses, and the whole-set operations
// the run loop needs around it (initial distribution, output shares, gathering for diagnostics,
// redistribution after a restart).
//
// Data layout on a rank: owned fluid [0, n_fluid), halo copies, then the fixed-wall particles near
// its box, then the grain particles it owns and its copies of other ranks' near its box.
// Each rank holds only the fixed-wall particles it keeps (keep_walls: within the halo width of its
// box, or with the ghost node, DBC: the particle, in it). Every rank builds the whole scene once
// and culls it; after a rebalance or a checkpoint read the walls are dealt to the ranks that keep
// them (deal_walls), so no rank holds the whole wall set during a run. A wall's mDBC state and
// fluid force are computed by its owner and copied to the other ranks by the wall plan.
// Checkpoints and frames take each wall from its owner.
#pragma once

#include <mpi.h>

#include <array>
#include <memory>
#include <optional>

#include "decomposition/domain_decomposition.hpp"
#include "decomposition/halo.hpp"
#include "decomposition/wall_plan.hpp"
#include "solver/exchange.hpp"

namespace sphdem {

class MpiExchange final : public Exchange {
 public:
  // width: the halo reach (2h plus a margin). procs: the process grid, 0 = PETSc chooses.
  // imbalance: the max/mean owned-fluid ratio above which rebalance() acts.
  MpiExchange(MPI_Comm comm, const CellGrid& grid, std::array<int, 3> procs, Real width,
              double imbalance);

  const DomainDecomposition& decomposition() const { return dd_; }
  Real width() const { return width_; }  // the halo reach
  MPI_Comm comm() const { return dd_.comm(); }

  int rank() const override { return dd_.rank(); }
  int size() const override { return dd_.size(); }
  bool owns(const Vec3& x) const override { return dd_.owns(x); }
  void migrate(ParticleSet<Host>& ps) override;
  void build_halo(ParticleSet<Host>& ps) override;
  bool rebalance(ParticleSet<Host>& ps) override;
  int rebalance_count() const { return rebalances_; }
  double last_imbalance() const { return last_imbalance_; }
  Index halo_count() const override { return plan_ ? plan_->n_halo() : 0; }
  void bcast(const Real* owned, Real* halo) override { plan_->bcast(owned, halo); }
  void bcast(const Vec3* owned, Vec3* halo) override { plan_->bcast(owned, halo); }
  void bcast_positions(const Vec3* owned, Vec3* halo) override {
    plan_->bcast_positions(owned, halo);
  }
  // ghost_alt is not needed here: the halo width already adds the scene's largest distance
  // between a wall's two ghost nodes (BuildReport::ghost_spread), so the rank owning the first
  // holds the fluid around the second.
  std::vector<std::uint8_t> keep_walls(const Vec3* pos, const Vec3* ghost, const Vec3* ghost_alt,
                                       Index n, bool by_ghost) const override;
  ParticleSet<Host> deal_walls(ParticleSet<Host>& walls, bool by_ghost) const override;
  void build_wall_plan(const GlobalId* id, const std::uint8_t* mine, Index n) override {
    walls_.reset();
    walls_.emplace(dd_.comm(), id, mine, n);
  }
  void wall_slots(std::vector<Index>& roots, std::vector<Index>& leaves) const override {
    roots = walls_->root_slots();
    leaves = walls_->leaf_slots();
  }
  void wall_bcast(const Real* roots, Real* leaves) override { walls_->bcast(roots, leaves); }
  void wall_bcast(const Vec3* roots, Vec3* leaves) override { walls_->bcast(roots, leaves); }
  void wall_reduce(const Real* leaves, Real* roots) override { walls_->reduce_sum(leaves, roots); }
  void wall_reduce(const Vec3* leaves, Vec3* roots) override { walls_->reduce_sum(leaves, roots); }
  void owned_box(Vec3& lo, Vec3& hi) const override;
  // Rank r's box, with the outer faces of non-periodic axes at infinity.
  void box_of(int rank, Vec3& lo, Vec3& hi) const;
  // Whether rank r keeps a wall particle at pos (ghost node ghost): see keep_walls.
  bool keeps_wall(int rank, const Vec3& pos, const Vec3& ghost, bool by_ghost) const;
  void build_grain_halo(ParticleSet<Host>& g) override;
  void grain_bcast(const Real* owned, Real* halo) override { grains_->bcast(owned, halo); }
  void grain_bcast(const Vec3* owned, Vec3* halo) override { grains_->bcast(owned, halo); }
  void grain_reduce(const Real* halo, Real* owned) override { grains_->reduce_sum(halo, owned); }
  void grain_reduce(const Vec3* halo, Vec3* owned) override { grains_->reduce_sum(halo, owned); }
  void sum(Real* v, Index n) override;
  void max(Real* v, Index n) override;
  std::int64_t sum(std::int64_t v) override;

 private:
  DomainDecomposition dd_;
  Real width_;
  double threshold_;
  int rebalances_ = 0;
  double last_imbalance_ = 1;
  std::optional<HaloPlan> plan_;
  std::optional<WallPlan> walls_;
  std::optional<HaloPlan> grains_;  // owned grain particles to the ranks near them
};

// Keeps the fluid this rank owns out of a set every rank built alike; walls stay.
void keep_owned_fluid(const Exchange& ex, ParticleSet<Host>& ps);

// What this rank writes to a checkpoint or frame: its owned fluid and the walls it owns (`mine`:
// one flag per wall slot).
ParticleSet<Host> output_share(const ParticleSet<Host>& ps, const std::vector<std::uint8_t>& mine);

// On rank 0: every rank's owned fluid, then every rank's owned walls, each sorted by global id
// (owned walls carry the whole fluid force in `acc`). Empty on the other ranks. Collective.
ParticleSet<Host> gather_on_root(MPI_Comm comm, const ParticleSet<Host>& ps,
                                 const std::vector<std::uint8_t>& mine);

// After each rank read its block of a checkpoint: the wall particles to the ranks that keep them
// (deal_walls; by_ghost as the run's boundary: mDBC), every grain particle to every rank (each
// keeps its own at the first neighbour rebuild), and the fluid to the rank owning it (through
// DMSwarm). Collective.
void distribute_after_read(const MpiExchange& ex, ParticleSet<Host>& ps, bool by_ghost);

}  // namespace sphdem
