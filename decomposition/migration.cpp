#include "decomposition/migration.hpp"

#include <petscdmswarm.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "decomposition/petsc_check.hpp"

namespace sphdem {

namespace {

template <class B>
using ElementOf = std::decay_t<decltype(std::declval<B&>()[0])>;

// Byte offset of every field inside a packed particle record, in for_each_field order.
struct RecordLayout {
  std::vector<std::size_t> offset;
  std::size_t bytes = 0;
};

RecordLayout record_layout(ParticleSet<Host>& ps) {
  RecordLayout l;
  ps.for_each_field([&](const char* name, auto& buf) {
    if (Index(buf.size()) != ps.size())
      throw RuntimeFault(std::string("migration: field '") + name + "' holds " +
                         std::to_string(buf.size()) + " entries for " + std::to_string(ps.size()) +
                         " particle slots");
    l.offset.push_back(l.bytes);
    l.bytes += sizeof(ElementOf<decltype(buf)>);
  });
  return l;
}

// Moves x into [lo, lo + L) along periodic axes; other axes are left alone.
void wrap_periodic(const CellGrid& g, Vec3& x) {
  for (int k = 0; k < 3; ++k) {
    if (!g.periodic[k]) continue;
    const Real L = g.period[k], lo = g.lo[k];
    Real v = x[k] - std::floor((x[k] - lo) / L) * L;
    if (v >= lo + L) v -= L;  // rounding of the line above
    if (v < lo) v = lo;
    x[k] = v;
  }
}

bool finite(const Vec3& x) {
  return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z);
}

// Rebuilds every field as: owned slots `keep` (ascending, compacted in place), then `n_in`
// packed records, then the wall and grain slots of the old set. The halo is dropped.
void assemble(ParticleSet<Host>& ps, const std::vector<Index>& keep, const char* incoming,
              Index n_in, const RecordLayout& layout) {
  const Index tail_begin = ps.fluid_end(), tail_end = ps.size();
  const Index n_keep = Index(keep.size()), n_owned = n_keep + n_in;
  std::size_t f = 0;
  ps.for_each_field([&](const char*, auto& buf) {
    using T = ElementOf<decltype(buf)>;
    auto& v = buf.vec();
    const std::vector<T> tail(v.begin() + tail_begin, v.begin() + tail_end);
    for (Index w = 0; w < n_keep; ++w)
      if (keep[std::size_t(w)] != w) v[std::size_t(w)] = v[std::size_t(keep[std::size_t(w)])];
    v.resize(std::size_t(n_owned) + tail.size());
    const std::size_t off = layout.offset[f++];
    for (Index r = 0; r < n_in; ++r)
      std::memcpy(&v[std::size_t(n_keep + r)], incoming + std::size_t(r) * layout.bytes + off,
                  sizeof(T));
    std::copy(tail.begin(), tail.end(), v.begin() + n_owned);
  });
  ps.n_fluid = n_owned;
  ps.n_halo = 0;
}

// Reorders the owned range by global id, so the layout after a redistribution does not depend
// on the order in which messages arrived.
void sort_owned_by_id(ParticleSet<Host>& ps) {
  const Index n = ps.n_fluid;
  std::vector<Index> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), Index(0));
  const GlobalId* id = ps.id.data();
  if (std::is_sorted(id, id + n)) return;
  std::sort(perm.begin(), perm.end(),
            [id](Index a, Index b) { return id[std::size_t(a)] < id[std::size_t(b)]; });
  ps.for_each_field([&](const char*, auto& buf) {
    using T = ElementOf<decltype(buf)>;
    std::vector<T> tmp(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) tmp[std::size_t(i)] = buf[std::size_t(perm[std::size_t(i)])];
    std::copy(tmp.begin(), tmp.end(), buf.vec().begin());
  });
}

// Throws on every rank if any rank holds an owned particle with a non-finite position (its owner
// is undefined). Collective.
void check_finite(const DomainDecomposition& dd, const ParticleSet<Host>& ps, const char* what) {
  std::int64_t bad = 0;
  GlobalId example = std::numeric_limits<GlobalId>::max();
  for (Index i = 0; i < ps.n_fluid; ++i)
    if (!finite(ps.pos[std::size_t(i)])) {
      ++bad;
      example = std::min(example, ps.id[std::size_t(i)]);
    }
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT64_T, MPI_SUM, dd.comm());
  if (bad == 0) return;
  MPI_Allreduce(MPI_IN_PLACE, &example, 1, MPI_UINT64_T, MPI_MIN, dd.comm());
  std::ostringstream os;
  os << what << ": " << bad << " particles have a non-finite position (e.g. particle id " << example
     << "), so they have no owner rank";
  throw RuntimeFault(os.str());
}

void check_conserved(const ParticleTotals& before, const ParticleTotals& after, const char* what) {
  if (before == after) return;
  std::ostringstream os;
  const std::int64_t lost = before.count - after.count;
  os << what << ": migration " << (lost >= 0 ? "lost " : "created ") << (lost >= 0 ? lost : -lost)
     << " particles (" << std::abs(before.mass - after.mass) << " kg of " << before.mass
     << " kg): global count " << before.count << " -> " << after.count << ", mass checksum changed";
  throw RuntimeFault(os.str());
}

// Destroys the swarm however the migration ends.
struct SwarmGuard {
  DM dm = nullptr;
  ~SwarmGuard() {
    if (dm) DMDestroy(&dm);
  }
};

struct TypeGuard {
  MPI_Datatype t = MPI_DATATYPE_NULL;
  ~TypeGuard() {
    if (t != MPI_DATATYPE_NULL) MPI_Type_free(&t);
  }
};

}  // namespace

ParticleTotals particle_totals(MPI_Comm comm, const ParticleSet<Host>& ps,
                               const ParticleTotals* like) {
  ParticleTotals t;
  const Index n = ps.n_fluid;
  const Real* m = ps.mass.data();
  if (like) {
    t.scale_exp = like->scale_exp;
  } else {
    double mx = 0;
    for (Index i = 0; i < n; ++i) mx = std::max(mx, std::abs(double(m[i])));
    MPI_Allreduce(MPI_IN_PLACE, &mx, 1, MPI_DOUBLE, MPI_MAX, comm);
    int e = 0;
    std::frexp(mx, &e);    // mx < 2^e
    t.scale_exp = 52 - e;  // so every |m| * 2^scale_exp < 2^52 is an exact-enough integer
  }
  // Each mass becomes an integer multiple of 2^-scale_exp; integer sums do not depend on order.
  __int128 q = 0;
  double kg = 0;
  constexpr double kLimit = 4.0e18;  // below 2^62: llrint cannot overflow
  for (Index i = 0; i < n; ++i) {
    double s = std::ldexp(double(m[i]), t.scale_exp);
    if (!(std::abs(s) < kLimit)) s = std::isnan(s) ? 0.0 : std::copysign(kLimit, s);
    q += __int128(std::llrint(s));
    kg += double(m[i]);
  }
  // Split so that an MPI_INT64_T sum cannot overflow: hi carries bits 32 and up.
  const __int128 hi = q >> 32;
  std::int64_t v[3] = {std::int64_t(n), std::int64_t(hi), std::int64_t(q - (hi << 32))};
  MPI_Allreduce(MPI_IN_PLACE, v, 3, MPI_INT64_T, MPI_SUM, comm);
  MPI_Allreduce(MPI_IN_PLACE, &kg, 1, MPI_DOUBLE, MPI_SUM, comm);
  // Canonical form, independent of how the sum was split across ranks.
  const __int128 total = (__int128(v[1]) << 32) + __int128(v[2]);
  const __int128 thi = total >> 32;
  t.count = v[0];
  t.mass_hi = std::int64_t(thi);
  t.mass_lo = std::int64_t(total - (thi << 32));
  t.mass = kg;
  return t;
}

MigrationReport redistribute(const DomainDecomposition& dd, ParticleSet<Host>& ps) {
  const double t0 = MPI_Wtime();
  const char* what = "redistribute";
  const RecordLayout layout = record_layout(ps);
  (void)layout;
  check_finite(dd, ps, what);
  const Index n = ps.n_fluid;
  for (Index i = 0; i < n; ++i) wrap_periodic(dd.grid(), ps.pos[std::size_t(i)]);
  const ParticleTotals before = particle_totals(dd.comm(), ps);

  MigrationReport rep;
  SwarmGuard sw;
  SPHDEM_PETSC(DMCreate(dd.comm(), &sw.dm));
  SPHDEM_PETSC(DMSetType(sw.dm, DMSWARM));
  SPHDEM_PETSC(DMSetDimension(sw.dm, dd.dim()));
  SPHDEM_PETSC(DMSwarmSetType(sw.dm, DMSWARM_BASIC));
  SPHDEM_PETSC(DMSwarmSetCellDM(sw.dm, dd.dm()));
  // One swarm field per particle field, registered as raw bytes of the element type.
  ps.for_each_field([&](const char* name, auto& buf) {
    const std::string fname = std::string("sphdem_") + name;
    SPHDEM_PETSC(DMSwarmRegisterUserDatatypeField(sw.dm, fname.c_str(),
                                                  sizeof(ElementOf<decltype(buf)>), 1));
  });
  SPHDEM_PETSC(DMSwarmFinalizeFieldRegister(sw.dm));
  SPHDEM_PETSC(DMSwarmSetLocalSizes(sw.dm, PetscInt(n), 16));
  SPHDEM_PETSC(DMSetUp(sw.dm));
  ps.for_each_field([&](const char* name, auto& buf) {
    const std::string fname = std::string("sphdem_") + name;
    void* p = nullptr;
    SPHDEM_PETSC(DMSwarmGetField(sw.dm, fname.c_str(), nullptr, nullptr, &p));
    std::memcpy(p, buf.data(), std::size_t(n) * sizeof(ElementOf<decltype(buf)>));
    SPHDEM_PETSC(DMSwarmRestoreField(sw.dm, fname.c_str(), nullptr, nullptr, &p));
  });
  {
    PetscInt* rank = nullptr;
    SPHDEM_PETSC(DMSwarmGetField(sw.dm, DMSwarmField_rank, nullptr, nullptr, (void**)&rank));
    for (Index i = 0; i < n; ++i) {
      rank[i] = PetscInt(dd.owner_of(ps.pos[std::size_t(i)]));
      if (rank[i] != dd.rank()) ++rep.sent;
    }
    SPHDEM_PETSC(DMSwarmRestoreField(sw.dm, DMSwarmField_rank, nullptr, nullptr, (void**)&rank));
  }
  SPHDEM_PETSC(DMSwarmMigrate(sw.dm, PETSC_TRUE));
  PetscInt m = 0;
  SPHDEM_PETSC(DMSwarmGetLocalSize(sw.dm, &m));

  // Owned range from the swarm, then the old wall and grain slots.
  const Index tail_begin = ps.fluid_end(), tail_end = ps.size();
  ps.for_each_field([&](const char* name, auto& buf) {
    using T = ElementOf<decltype(buf)>;
    const std::string fname = std::string("sphdem_") + name;
    std::vector<T> out(std::size_t(m) + std::size_t(tail_end - tail_begin));
    void* p = nullptr;
    SPHDEM_PETSC(DMSwarmGetField(sw.dm, fname.c_str(), nullptr, nullptr, &p));
    std::memcpy(out.data(), p, std::size_t(m) * sizeof(T));
    SPHDEM_PETSC(DMSwarmRestoreField(sw.dm, fname.c_str(), nullptr, nullptr, &p));
    std::copy(buf.vec().begin() + tail_begin, buf.vec().begin() + tail_end,
              out.begin() + std::ptrdiff_t(m));
    buf.vec().swap(out);
  });
  ps.n_fluid = Index(m);
  ps.n_halo = 0;
  sort_owned_by_id(ps);
  rep.received = Index(m) - (n - rep.sent);

  const ParticleTotals after = particle_totals(dd.comm(), ps, &before);
  check_conserved(before, after, what);
  rep.global_count = after.count;
  rep.global_mass = after.mass;
  rep.seconds = MPI_Wtime() - t0;
  return rep;
}

MigrationReport exchange_leavers(const DomainDecomposition& dd, ParticleSet<Host>& ps) {
  const double t0 = MPI_Wtime();
  const char* what = "exchange_leavers";
  const RecordLayout layout = record_layout(ps);
  check_finite(dd, ps, what);
  const Index n = ps.n_fluid;
  const int me = dd.rank();

  // Destinations, and the far jumps among them, before anything moves.
  std::vector<int> dest(static_cast<std::size_t>(n));
  std::int64_t far = 0;
  double far_mass = 0;
  GlobalId example = std::numeric_limits<GlobalId>::max();
  for (Index i = 0; i < n; ++i) {
    const int d = dd.owner_of(ps.pos[std::size_t(i)]);
    dest[std::size_t(i)] = d;
    if (d != me && !dd.is_neighbour(d)) {
      ++far;
      far_mass += double(ps.mass[std::size_t(i)]);
      example = std::min(example, ps.id[std::size_t(i)]);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, &far, 1, MPI_INT64_T, MPI_SUM, dd.comm());
  if (far > 0) {
    MPI_Allreduce(MPI_IN_PLACE, &far_mass, 1, MPI_DOUBLE, MPI_SUM, dd.comm());
    GlobalId first = example;
    MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_UINT64_T, MPI_MIN, dd.comm());
    int hop[2] = {-1, -1};  // (from, to) of that particle
    for (Index i = 0; i < n; ++i)
      if (ps.id[std::size_t(i)] == first && dest[std::size_t(i)] != me) {
        hop[0] = me;
        hop[1] = dest[std::size_t(i)];
      }
    MPI_Allreduce(MPI_IN_PLACE, hop, 2, MPI_INT, MPI_MAX, dd.comm());
    std::ostringstream os;
    os << "migration would lose " << far << " particles (" << far_mass
       << " kg): a particle moved more than one rank away between neighbour rebuilds (particle id "
       << first << " from rank " << hop[0] << " to rank " << hop[1]
       << ", which is not a neighbour). The leaver exchange only reaches neighbouring ranks "
          "(DMSwarm's PIC migration would drop such a particle silently). Nothing was moved. "
          "Rebuild the neighbour lists more often, or call redistribute()";
    throw RuntimeFault(os.str());
  }

  for (Index i = 0; i < n; ++i) wrap_periodic(dd.grid(), ps.pos[std::size_t(i)]);
  const ParticleTotals before = particle_totals(dd.comm(), ps);

  // Pack the leavers per neighbour, particle-major records of every field.
  const auto& nb = dd.neighbours();
  std::vector<int> slot(static_cast<std::size_t>(dd.size()), -1);
  for (std::size_t s = 0; s < nb.size(); ++s) slot[std::size_t(nb[s])] = int(s);
  std::vector<std::vector<Index>> leave(nb.size());
  std::vector<Index> keep;
  keep.reserve(std::size_t(n));
  for (Index i = 0; i < n; ++i) {
    const int d = dest[std::size_t(i)];
    if (d == me)
      keep.push_back(i);
    else
      leave[std::size_t(slot[std::size_t(d)])].push_back(i);
  }
  std::vector<std::vector<char>> send(nb.size());
  for (std::size_t s = 0; s < nb.size(); ++s) send[s].resize(leave[s].size() * layout.bytes);
  {
    std::size_t f = 0;
    ps.for_each_field([&](const char*, auto& buf) {
      using T = ElementOf<decltype(buf)>;
      const std::size_t off = layout.offset[f++];
      for (std::size_t s = 0; s < nb.size(); ++s)
        for (std::size_t r = 0; r < leave[s].size(); ++r)
          std::memcpy(send[s].data() + r * layout.bytes + off, &buf[std::size_t(leave[s][r])],
                      sizeof(T));
    });
  }

  // Counts, then records, with every neighbour (the neighbour relation is symmetric).
  const int nn = int(nb.size());
  constexpr int kTagCount = 7301, kTagData = 7302;
  std::vector<std::int64_t> scount(nb.size()), rcount(nb.size());
  std::vector<MPI_Request> req(2 * nb.size());
  for (int s = 0; s < nn; ++s) {
    scount[std::size_t(s)] = std::int64_t(leave[std::size_t(s)].size());
    MPI_Irecv(&rcount[std::size_t(s)], 1, MPI_INT64_T, nb[std::size_t(s)], kTagCount, dd.comm(),
              &req[std::size_t(s)]);
    MPI_Isend(&scount[std::size_t(s)], 1, MPI_INT64_T, nb[std::size_t(s)], kTagCount, dd.comm(),
              &req[std::size_t(nn + s)]);
  }
  MPI_Waitall(2 * nn, req.data(), MPI_STATUSES_IGNORE);
  TypeGuard record;
  MPI_Type_contiguous(int(layout.bytes), MPI_BYTE, &record.t);
  MPI_Type_commit(&record.t);
  std::vector<std::size_t> roff(nb.size() + 1, 0);
  for (std::size_t s = 0; s < nb.size(); ++s) roff[s + 1] = roff[s] + std::size_t(rcount[s]);
  for (std::size_t s = 0; s < nb.size(); ++s)
    if (scount[s] > INT_MAX || rcount[s] > INT_MAX)
      throw RuntimeFault("exchange_leavers: more than 2^31 leavers between two ranks");
  std::vector<char> incoming(roff.back() * layout.bytes);
  for (int s = 0; s < nn; ++s) {
    MPI_Irecv(incoming.data() + roff[std::size_t(s)] * layout.bytes, int(rcount[std::size_t(s)]),
              record.t, nb[std::size_t(s)], kTagData, dd.comm(), &req[std::size_t(s)]);
    MPI_Isend(send[std::size_t(s)].data(), int(scount[std::size_t(s)]), record.t,
              nb[std::size_t(s)], kTagData, dd.comm(), &req[std::size_t(nn + s)]);
  }
  MPI_Waitall(2 * nn, req.data(), MPI_STATUSES_IGNORE);

  MigrationReport rep;
  rep.sent = n - Index(keep.size());
  rep.received = Index(roff.back());
  assemble(ps, keep, incoming.data(), rep.received, layout);

  const ParticleTotals after = particle_totals(dd.comm(), ps, &before);
  check_conserved(before, after, what);
  rep.global_count = after.count;
  rep.global_mass = after.mass;
  rep.seconds = MPI_Wtime() - t0;
  return rep;
}

}  // namespace sphdem
