// Moving owned fluid particles to the rank whose box holds them (DESIGN.md §5, "Migration").
//
// Two paths, both host-side, both moving only the owned fluid range [0, n_fluid) with every
// field of ParticleSet (for_each_field):
//
//  - redistribute(): through a PETSc DMSwarm with the decomposition's DMDA as its cell DM and one
//    registered swarm field per particle field. Each particle's destination is written into the
//    swarm's rank field from DomainDecomposition::owner_of, and DMSwarmMigrate pushes it there,
//    however far that is. For the initial distribution, restarts on any rank count and after
//    rebalance(). The owned range comes back sorted by global id.
//
//    Why not the PIC swarm's own cell-DM scatter: in PETSc 3.18 a DMSWARM_PIC swarm always
//    migrates by locating points in the cell DM and sending the points it cannot place to its
//    DMDA neighbours only; a point more than one rank away is then dropped silently (measured on
//    this machine: 3000 -> 2401 particles on 3 ranks, 3x1x1 layout), the neighbour list
//    it builds skips rank 0 (`_rank > 0`), and its DMDA point location is vertex-based, half a
//    cell off our cell ownership and unaware of periodic axes. The explicit-rank push has none of
//    these problems, and 3.18 offers no public DMSwarmSetMigrateType to use it on a PIC swarm, so
//    the swarm is of the basic type with the DMDA attached as its cell DM.
//
//  - exchange_leavers(): between neighbour rebuilds, only the particles that left this rank's box
//    go, straight to a neighbouring rank (MPI point-to-point with the process-grid neighbours).
//    Stayers keep their order; arrivals follow, by source rank. A leaver whose new owner is not a
//    neighbour (it moved more than one rank away) is detected on every rank BEFORE anything
//    moves, and the call throws RuntimeFault("migration would lose N particles (M kg): ...")
//    with the particle set untouched.
//
// Both check the global particle count and an order-independent, exact global mass checksum
// before and after (MPI_Allreduce) and throw RuntimeFault if either changed. Both are collective.
// Afterwards the halo is empty (n_halo = 0: build a new HaloPlan); wall and grain slots are kept,
// after the new owned range. Positions along periodic axes are wrapped into the primary period.
#pragma once

#include <cstdint>

#include "core/exec.hpp"
#include "decomposition/domain_decomposition.hpp"
#include "solver/particles.hpp"

namespace sphdem {

struct MigrationReport {
  Index sent = 0;                 // particles this rank sent away
  Index received = 0;             // particles this rank received
  std::int64_t global_count = 0;  // owned fluid particles over all ranks (unchanged)
  double global_mass = 0;         // their total mass, kg (unchanged)
  double seconds = 0;             // wall time of the call on this rank
};

// Through DMSwarm, any distance. Collective.
MigrationReport redistribute(const DomainDecomposition& dd, ParticleSet<Host>& ps);

// Leavers to neighbouring ranks only; throws (set untouched) on a jump of more than one rank.
// Collective.
MigrationReport exchange_leavers(const DomainDecomposition& dd, ParticleSet<Host>& ps);

// Global count and total mass of the owned fluid range, the mass summed exactly and in an
// order-independent way (masses quantised to a common binary scale, integer sums), so two sets
// holding the same particles in any arrangement give identical results. Collective.
struct ParticleTotals {
  std::int64_t count = 0;
  double mass = 0;
  std::int64_t mass_hi = 0, mass_lo = 0;  // the exact checksum
  int scale_exp = 0;                      // binary scale of the quantisation
  bool operator==(const ParticleTotals& o) const {
    return count == o.count && mass_hi == o.mass_hi && mass_lo == o.mass_lo &&
           scale_exp == o.scale_exp;
  }
  bool operator!=(const ParticleTotals& o) const { return !(*this == o); }
};
// Without `like` the scale comes from this set's largest mass; pass an earlier result to reuse
// its scale, so that the two can be compared exactly.
ParticleTotals particle_totals(MPI_Comm comm, const ParticleSet<Host>& ps,
                               const ParticleTotals* like = nullptr);

}  // namespace sphdem
