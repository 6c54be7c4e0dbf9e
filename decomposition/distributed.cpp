#include "decomposition/distributed.hpp"

#include <algorithm>
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

// A new set holding fluid slots [0, nf) and boundary slots [wb, we) of `ps`.
ParticleSet<Host> slice(const ParticleSet<Host>& ps, Index nf, Index wb, Index we) {
  ParticleSet<Host> out;
  out.n_fluid = nf;
  out.n_wall = we - wb;
  auto& src = const_cast<ParticleSet<Host>&>(ps);  // for_each_field is not const; read only
  src.for_each_field([&](const char* name, auto& b) {
    out.for_each_field([&](const char* n2, auto& o) {
      if (std::string(name) != n2) return;
      using T = std::decay_t<decltype(o[0])>;
      if constexpr (std::is_same_v<T, std::decay_t<decltype(b[0])>>) {
        auto& v = o.vec();
        v.assign(b.vec().begin(), b.vec().begin() + nf);
        v.insert(v.end(), b.vec().begin() + wb, b.vec().begin() + we);
      }
    });
  });
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

ParticleSet<Host> output_share(const ParticleSet<Host>& ps, int rank) {
  return slice(ps, ps.n_fluid, ps.wall_begin(), rank == 0 ? ps.size() : ps.wall_begin());
}

ParticleSet<Host> gather_on_root(MPI_Comm comm, const ParticleSet<Host>& ps) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  auto& src = const_cast<ParticleSet<Host>&>(ps);
  ParticleSet<Host> out;
  const Index nw = ps.size() - ps.wall_begin();
  long long total = 0;
  src.for_each_field([&](const char* name, auto& b) {
    using T = std::decay_t<decltype(b[0])>;
    const Counts c = gather_counts(comm, ps.n_fluid, sizeof(T), false);
    total = c.total;
    std::vector<T> all(rank == 0 ? std::size_t(c.total) : 0);
    MPI_Gatherv(b.data(), int(ps.n_fluid * Index(sizeof(T))), MPI_BYTE, all.data(), c.count.data(),
                c.disp.data(), MPI_BYTE, 0, comm);
    if (rank != 0) return;
    out.for_each_field([&](const char* n2, auto& o) {
      if constexpr (std::is_same_v<std::decay_t<decltype(o[0])>, T>) {
        if (std::string(name) == n2) o.vec() = std::move(all);
      }
    });
  });
  // The walls' fluid force: each rank holds its share.
  std::vector<Vec3> acc(static_cast<std::size_t>(nw));
  MPI_Reduce(ps.acc.data() + ps.wall_begin(), acc.data(), int(3 * nw), mpi_real(), MPI_SUM, 0,
             comm);
  if (rank != 0) return ParticleSet<Host>{};
  // Sort the fluid by id, then append the walls.
  const Index nf = Index(total);
  std::vector<Index> perm(static_cast<std::size_t>(nf));
  std::iota(perm.begin(), perm.end(), Index(0));
  std::sort(perm.begin(), perm.end(),
            [&](Index a, Index b) { return out.id[std::size_t(a)] < out.id[std::size_t(b)]; });
  const Index wb = ps.wall_begin();
  src.for_each_field([&](const char* name, auto& b) {
    using T = std::decay_t<decltype(b[0])>;
    out.for_each_field([&](const char* n2, auto& o) {
      if constexpr (std::is_same_v<std::decay_t<decltype(o[0])>, T>) {
        if (std::string(name) != n2) return;
        std::vector<T> v(std::size_t(nf + nw));
        for (Index i = 0; i < nf; ++i) v[std::size_t(i)] = o[std::size_t(perm[std::size_t(i)])];
        std::copy(b.vec().begin() + wb, b.vec().end(), v.begin() + nf);
        o.vec() = std::move(v);
      }
    });
  });
  std::copy(acc.begin(), acc.end(), out.acc.vec().begin() + nf);
  out.n_fluid = nf;
  out.n_wall = nw;
  return out;
}

void distribute_after_read(const MpiExchange& ex, ParticleSet<Host>& ps) {
  MPI_Comm comm = ex.comm();
  // Walls: every rank's block to every rank.
  const Index wb = ps.wall_begin(), nw = ps.size() - wb;
  long long nw_all = 0;
  ps.for_each_field([&](const char*, auto& b) {
    using T = std::decay_t<decltype(b[0])>;
    const Counts c = gather_counts(comm, nw, sizeof(T), true);
    std::vector<T> all(std::size_t(c.total));
    MPI_Allgatherv(b.data() + wb, int(nw * Index(sizeof(T))), MPI_BYTE, all.data(), c.count.data(),
                   c.disp.data(), MPI_BYTE, comm);
    auto& v = b.vec();
    v.resize(std::size_t(wb));
    v.insert(v.end(), all.begin(), all.end());
    nw_all = c.total;
  });
  ps.n_wall = Index(nw_all);
  ps.n_grain = 0;
  // Fluid: to its owner, however far.
  redistribute(ex.decomposition(), ps);
}

}  // namespace sphdem
