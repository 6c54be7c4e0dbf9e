#include "decomposition/distributed.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <numeric>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "decomposition/migration.hpp"

namespace sphdem {

namespace {

MPI_Datatype mpi_real() {
  return std::is_same<Real, double>::value ? MPI_DOUBLE : MPI_FLOAT;
}

// A new set holding the fluid slots [0, n_fluid) of `ps` and the wall slots whose flag is set.
ParticleSet<Host> select(const ParticleSet<Host>& ps, const std::vector<std::uint8_t>& mine) {
  ParticleSet<Host> out;
  const Index nf = ps.n_fluid, wb = ps.wall_begin(), n = ps.size();
  std::vector<Index> slots;
  for (Index i = 0; i < nf; ++i) slots.push_back(i);
  for (Index i = wb; i < n; ++i)
    if (mine[std::size_t(i - wb)]) slots.push_back(i);
  auto& src = const_cast<ParticleSet<Host>&>(ps);  // for_each_field is not const; read only
  std::vector<void*> outs;
  out.for_each_field([&](const char*, auto& o) { outs.push_back(&o); });
  std::size_t k = 0;
  src.for_each_field([&](const char*, auto& b) {
    auto* o = static_cast<std::decay_t<decltype(b)>*>(outs[k++]);
    auto& v = o->vec();
    v.resize(slots.size());
    for (std::size_t j = 0; j < slots.size(); ++j) v[j] = b[std::size_t(slots[j])];
  });
  out.n_fluid = nf;
  Index walls = 0;
  for (Index i = wb; i < wb + ps.n_wall && i < n; ++i) walls += mine[std::size_t(i - wb)] ? 1 : 0;
  out.n_wall = walls;
  out.n_grain = Index(slots.size()) - nf - walls;
  return out;
}

// Byte counts and displacements for an MPI_(All)Gatherv of n elements of `bytes` each.
struct Counts {
  std::vector<int> count, disp;
  long long total = 0;
};
Counts gather_counts(MPI_Comm comm, Index n, std::size_t bytes, bool all) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  std::vector<long long> ns(static_cast<std::size_t>(size));
  long long mine = n;
  if (all) {
    MPI_Allgather(&mine, 1, MPI_LONG_LONG, ns.data(), 1, MPI_LONG_LONG, comm);
  } else {
    MPI_Gather(&mine, 1, MPI_LONG_LONG, ns.data(), 1, MPI_LONG_LONG, 0, comm);
  }
  Counts c;
  c.count.resize(std::size_t(size));
  c.disp.resize(std::size_t(size));
  long long off = 0;
  for (int r = 0; r < size; ++r) {
    const long long b = ns[std::size_t(r)] * (long long)bytes;
    if (off + b > 2147483647LL)
      throw RuntimeFault("gather: more than 2 GiB in one field; write frames in parallel");
    c.count[std::size_t(r)] = int(b);
    c.disp[std::size_t(r)] = int(off);
    off += b;
  }
  c.total = ns.empty() ? 0 : std::accumulate(ns.begin(), ns.end(), 0LL);
  return c;
}

}  // namespace

MpiExchange::MpiExchange(MPI_Comm comm, const CellGrid& grid, std::array<int, 3> procs, Real width,
                         double imbalance)
    : dd_(comm, grid, procs), width_(width), threshold_(imbalance) {}

bool MpiExchange::rebalance(ParticleSet<Host>& ps) {
  if (ps.n_halo != 0) throw RuntimeFault("MpiExchange::rebalance: drop the halo first");
  const auto rep = dd_.rebalance(ps.pos.data(), ps.n_fluid, threshold_);
  last_imbalance_ = rep.applied ? rep.after : rep.before;
  if (!rep.applied) return false;
  redistribute(dd_, ps);
  ++rebalances_;
  return true;
}

void MpiExchange::migrate(ParticleSet<Host>& ps) {
  if (ps.n_halo != 0) throw RuntimeFault("MpiExchange::migrate: drop the halo first");
  exchange_leavers(dd_, ps);
}

void MpiExchange::build_halo(ParticleSet<Host>& ps) {
  plan_.reset();
  plan_.emplace(dd_, ps, width_);
  plan_->fill(ps);
}

void MpiExchange::sum(Real* v, Index n) {
  MPI_Allreduce(MPI_IN_PLACE, v, int(n), mpi_real(), MPI_SUM, dd_.comm());
}
void MpiExchange::max(Real* v, Index n) {
  MPI_Allreduce(MPI_IN_PLACE, v, int(n), mpi_real(), MPI_MAX, dd_.comm());
}
std::int64_t MpiExchange::sum(std::int64_t v) {
  std::int64_t t = 0;
  MPI_Allreduce(&v, &t, 1, MPI_INT64_T, MPI_SUM, dd_.comm());
  return t;
}

void keep_owned_fluid(const Exchange& ex, ParticleSet<Host>& ps) {
  std::vector<Index> keep;
  for (Index i = 0; i < ps.n_fluid; ++i)
    if (ex.owns(ps.pos[i])) keep.push_back(i);
  const Index nf = Index(keep.size()), wb = ps.fluid_end(), n = ps.size();
  ps.for_each_field([&](const char*, auto& b) {
    auto& v = b.vec();
    for (Index w = 0; w < nf; ++w) v[std::size_t(w)] = v[std::size_t(keep[std::size_t(w)])];
    std::copy(v.begin() + wb, v.begin() + n, v.begin() + nf);
    v.resize(std::size_t(nf + n - wb));
  });
  ps.n_fluid = nf;
  ps.n_halo = 0;
}

ParticleSet<Host> output_share(const ParticleSet<Host>& ps, const std::vector<std::uint8_t>& mine) {
  return select(ps, mine);
}

namespace {

// On rank 0: slots [b, e) of every rank's `ps`, as one set sorted by global id (fields only; the
// counts are the caller's). Collective.
ParticleSet<Host> gather_sorted(MPI_Comm comm, ParticleSet<Host>& ps, Index b, Index e,
                                Index* total_out) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  ParticleSet<Host> out;
  std::vector<void*> outs;
  out.for_each_field([&](const char*, auto& o) { outs.push_back(&o); });
  std::size_t k = 0;
  long long total = 0;
  ps.for_each_field([&](const char*, auto& buf) {
    using T = std::decay_t<decltype(buf[0])>;
    const Counts c = gather_counts(comm, e - b, sizeof(T), false);
    total = c.total;
    std::vector<T> all(rank == 0 ? std::size_t(c.total) : 0);
    MPI_Gatherv(buf.data() + b, int((e - b) * Index(sizeof(T))), MPI_BYTE, all.data(),
                c.count.data(), c.disp.data(), MPI_BYTE, 0, comm);
    static_cast<std::decay_t<decltype(buf)>*>(outs[k++])->vec() = std::move(all);
  });
  *total_out = Index(total);
  if (rank != 0) return out;
  std::vector<Index> perm(static_cast<std::size_t>(total));
  std::iota(perm.begin(), perm.end(), Index(0));
  std::sort(perm.begin(), perm.end(),
            [&](Index x, Index y) { return out.id[std::size_t(x)] < out.id[std::size_t(y)]; });
  out.for_each_field([&](const char*, auto& o) {
    auto v = o.vec();
    for (std::size_t j = 0; j < perm.size(); ++j) o[j] = v[std::size_t(perm[j])];
  });
  return out;
}

}  // namespace

ParticleSet<Host> gather_on_root(MPI_Comm comm, const ParticleSet<Host>& ps,
                                 const std::vector<std::uint8_t>& mine) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  ParticleSet<Host> local = select(ps, mine);
  Index nf = 0, nw = 0;
  ParticleSet<Host> fl = gather_sorted(comm, local, 0, local.n_fluid, &nf);
  ParticleSet<Host> wl = gather_sorted(comm, local, local.n_fluid, local.size(), &nw);
  if (rank != 0) return ParticleSet<Host>{};
  std::vector<void*> walls;
  wl.for_each_field([&](const char*, auto& w) { walls.push_back(&w); });
  std::size_t k = 0;
  fl.for_each_field([&](const char*, auto& f) {
    auto* w = static_cast<std::decay_t<decltype(f)>*>(walls[k++]);
    f.vec().insert(f.vec().end(), w->vec().begin(), w->vec().end());
  });
  fl.n_fluid = nf;
  fl.n_wall = nw;
  grains_last(fl);  // grain particles after the walls, counted apart
  return fl;
}

void MpiExchange::owned_box(Vec3& lo, Vec3& hi) const {
  box_of(dd_.rank(), lo, hi);
}

void MpiExchange::box_of(int rank, Vec3& lo, Vec3& hi) const {
  // The outer faces of non-periodic axes (and y in 2D) at infinity, as in owner_of.
  constexpr Real kInf = std::numeric_limits<Real>::infinity();
  const Vec3 blo = dd_.box_lo(rank), bhi = dd_.box_hi(rank);
  const auto np = dd_.procs();
  const auto pc = dd_.proc_coord(rank);
  const CellGrid& g = dd_.grid();
  for (int k = 0; k < 3; ++k) {
    lo[k] = blo[k];
    hi[k] = bhi[k];
    const bool open = !g.periodic[k] || (g.dim == 2 && k == 1);
    if (open && pc[std::size_t(k)] == 0) lo[k] = -kInf;
    if (open && pc[std::size_t(k)] == np[std::size_t(k)] - 1) hi[k] = kInf;
  }
}

bool MpiExchange::keeps_wall(int rank, const Vec3& pos, const Vec3& ghost, bool by_ghost) const {
  if (dd_.owner_of(by_ghost ? ghost : pos) == rank) return true;
  Vec3 lo, hi;
  box_of(rank, lo, hi);
  Real d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const Real x = pos[k];
    const Real d = x < lo[k] ? lo[k] - x : (x > hi[k] ? x - hi[k] : Real(0));
    d2 += d * d;
  }
  return d2 < width_ * width_;
}

void MpiExchange::build_grain_halo(ParticleSet<Host>& g) {
  grains_.reset();
  grains_.emplace(dd_, g, width_);
  grains_->fill(g);
}

std::vector<std::uint8_t> MpiExchange::keep_walls(const Vec3* pos, const Vec3* ghost,
                                                  const Vec3* /*ghost_alt*/, Index n,
                                                  bool by_ghost) const {
  std::vector<std::uint8_t> keep(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i)
    keep[std::size_t(i)] = keeps_wall(dd_.rank(), pos[i], ghost[i], by_ghost) ? 1 : 0;
  return keep;
}

ParticleSet<Host> MpiExchange::deal_walls(ParticleSet<Host>& walls, bool by_ghost) const {
  MPI_Comm comm = dd_.comm();
  const int nr = dd_.size();
  const Index n = walls.size();
  if (walls.n_wall != n || n != Index(walls.body.size()))
    throw std::logic_error("MpiExchange::deal_walls: pass a set of wall slots only");
  // Every rank that keeps each wall: the slabs within the halo width of it along each axis (one
  // more either side against round-off in the cell lookup), then the exact test, plus the owner
  // of its ghost node, which may lie farther away.
  const auto np = dd_.procs();
  std::vector<std::vector<Index>> to(static_cast<std::size_t>(nr));
  std::vector<int> cand;
  for (Index i = 0; i < n; ++i) {
    const Vec3 x = walls.pos[std::size_t(i)], gh = walls.ghost[std::size_t(i)];
    std::array<int, 3> a{}, b{};
    for (int k = 0; k < 3; ++k) {
      a[std::size_t(k)] = std::max(0, dd_.proc_along(x[k] - width_, k) - 1);
      b[std::size_t(k)] = std::min(np[std::size_t(k)] - 1, dd_.proc_along(x[k] + width_, k) + 1);
    }
    cand.clear();
    for (int pk = a[2]; pk <= b[2]; ++pk)
      for (int pj = a[1]; pj <= b[1]; ++pj)
        for (int pi = a[0]; pi <= b[0]; ++pi) cand.push_back(dd_.rank_at(pi, pj, pk));
    const int owner = dd_.owner_of(by_ghost ? gh : x);
    if (std::find(cand.begin(), cand.end(), owner) == cand.end()) cand.push_back(owner);
    for (const int r : cand)
      if (keeps_wall(r, x, gh, by_ghost)) to[std::size_t(r)].push_back(i);
  }
  std::vector<int> sn(static_cast<std::size_t>(nr)), rn(static_cast<std::size_t>(nr));
  for (int r = 0; r < nr; ++r) sn[std::size_t(r)] = int(to[std::size_t(r)].size());
  MPI_Alltoall(sn.data(), 1, MPI_INT, rn.data(), 1, MPI_INT, comm);
  long long n_in = 0, n_out = 0;
  for (int r = 0; r < nr; ++r) {
    n_in += rn[std::size_t(r)];
    n_out += sn[std::size_t(r)];
  }
  ParticleSet<Host> out;
  std::vector<void*> outs;
  out.for_each_field([&](const char*, auto& o) { outs.push_back(&o); });
  std::size_t f = 0;
  walls.for_each_field([&](const char*, auto& buf) {
    using T = std::decay_t<decltype(buf[0])>;
    std::vector<int> sc(static_cast<std::size_t>(nr)), sd(static_cast<std::size_t>(nr)),
        rc(static_cast<std::size_t>(nr)), rd(static_cast<std::size_t>(nr));
    const long long so = (long long)sizeof(T) * n_out, ro = (long long)sizeof(T) * n_in;
    if (so > 2147483647LL || ro > 2147483647LL)
      throw RuntimeFault("deal_walls: more than 2 GiB of one wall field on one rank");
    for (int r = 0, soff = 0, roff = 0; r < nr; ++r) {
      sc[std::size_t(r)] = int(sizeof(T)) * sn[std::size_t(r)];
      rc[std::size_t(r)] = int(sizeof(T)) * rn[std::size_t(r)];
      sd[std::size_t(r)] = soff;
      rd[std::size_t(r)] = roff;
      soff += sc[std::size_t(r)];
      roff += rc[std::size_t(r)];
    }
    std::vector<T> send(static_cast<std::size_t>(n_out)), recv(static_cast<std::size_t>(n_in));
    std::size_t j = 0;
    for (int r = 0; r < nr; ++r)
      for (const Index i : to[std::size_t(r)]) send[j++] = buf[std::size_t(i)];
    MPI_Alltoallv(send.data(), sc.data(), sd.data(), MPI_BYTE, recv.data(), rc.data(), rd.data(),
                  MPI_BYTE, comm);
    static_cast<std::decay_t<decltype(buf)>*>(outs[f++])->vec() = std::move(recv);
  });
  // Sorted by global id; a wall that arrives twice was passed by two ranks.
  const Index m = Index(n_in);
  std::vector<Index> perm(static_cast<std::size_t>(m));
  std::iota(perm.begin(), perm.end(), Index(0));
  std::sort(perm.begin(), perm.end(),
            [&](Index x, Index y) { return out.id[std::size_t(x)] < out.id[std::size_t(y)]; });
  GlobalId twice = std::numeric_limits<GlobalId>::max();
  for (Index k = 1; k < m; ++k)
    if (out.id[std::size_t(perm[std::size_t(k)])] == out.id[std::size_t(perm[std::size_t(k - 1)])])
      twice = std::min(twice, out.id[std::size_t(perm[std::size_t(k)])]);
  MPI_Allreduce(MPI_IN_PLACE, &twice, 1, MPI_UINT64_T, MPI_MIN, comm);
  if (twice != std::numeric_limits<GlobalId>::max())
    throw RuntimeFault("deal_walls: wall particle id " + std::to_string(twice) +
                       " was passed by more than one rank; each wall must come from one rank");
  out.for_each_field([&](const char*, auto& o) {
    auto v = o.vec();
    for (std::size_t j = 0; j < perm.size(); ++j) o[j] = v[std::size_t(perm[j])];
  });
  out.n_wall = m;
  // Every wall passed has exactly one owner after the deal.
  std::int64_t counts[2] = {std::int64_t(n), 0};
  for (Index k = 0; k < m; ++k)
    if (dd_.owns(by_ghost ? out.ghost[std::size_t(k)] : out.pos[std::size_t(k)])) ++counts[1];
  MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INT64_T, MPI_SUM, comm);
  if (counts[0] != counts[1])
    throw RuntimeFault("deal_walls: " + std::to_string(counts[0]) +
                       " wall particles were passed, but the ranks own " +
                       std::to_string(counts[1]) + " after the deal");
  return out;
}

void distribute_after_read(const MpiExchange& ex, ParticleSet<Host>& ps, bool by_ghost) {
  MPI_Comm comm = ex.comm();
  grains_last(ps);  // this rank's block: fluid, walls, then grain particles
  const Index wb = ps.wall_begin(), gb = wb + ps.n_wall, n = ps.size();
  // Walls: to the ranks that keep them (near their box, or owning the ghost node).
  ParticleSet<Host> walls;
  std::vector<void*> ws;
  walls.for_each_field([&](const char*, auto& w) { ws.push_back(&w); });
  std::size_t k = 0;
  ps.for_each_field([&](const char*, auto& b) {
    auto& w = static_cast<std::decay_t<decltype(b)>*>(ws[k++])->vec();
    w.assign(b.vec().begin() + wb, b.vec().begin() + gb);
  });
  walls.n_wall = gb - wb;
  ParticleSet<Host> mine = ex.deal_walls(walls, by_ghost);
  // Grain particles: every block to every rank (each rank keeps its own at the first rebuild).
  long long ng_all = 0;
  std::vector<void*> ms;
  mine.for_each_field([&](const char*, auto& w) { ms.push_back(&w); });
  k = 0;
  ps.for_each_field([&](const char*, auto& b) {
    using T = std::decay_t<decltype(b[0])>;
    const Counts c = gather_counts(comm, n - gb, sizeof(T), true);
    std::vector<T> all(std::size_t(c.total));
    MPI_Allgatherv(b.data() + gb, int((n - gb) * Index(sizeof(T))), MPI_BYTE, all.data(),
                   c.count.data(), c.disp.data(), MPI_BYTE, comm);
    auto& v = b.vec();
    auto& w = static_cast<std::decay_t<decltype(b)>*>(ms[k++])->vec();
    v.resize(std::size_t(wb));
    v.insert(v.end(), w.begin(), w.end());
    v.insert(v.end(), all.begin(), all.end());
    ng_all = c.total;
  });
  ps.n_wall = mine.n_wall;
  ps.n_grain = Index(ng_all);
  grains_last(ps);  // every grain particle in id order after the walls, until the first rebuild
  // Fluid: to its owner, however far.
  redistribute(ex.decomposition(), ps);
}

}  // namespace sphdem
