#include "decomposition/halo.hpp"

#include <petscsf.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>

#include "core/error.hpp"
#include "decomposition/petsc_check.hpp"

namespace sphdem {

namespace {

// One copy a source sends to a target: the source's owned slot and the shift of the copy.
struct Wire {
  std::int64_t slot;
  Real shift[3];
};

// Along one axis: a process index whose slab lies within the halo width of a coordinate after
// shifting it by t periods, and the squared distance to that slab.
struct AxisCandidate {
  int p;
  int t;
  Real d2;
};

}  // namespace

HaloPlan::HaloPlan(const DomainDecomposition& dd, const Vec3* owned_pos, Index n_owned, Real width)
    : n_owned_(n_owned), width_(width) {
  const double t0 = MPI_Wtime();
  MPI_Comm comm = dd.comm();
  const int me = dd.rank(), size = dd.size();
  const CellGrid& g = dd.grid();
  const auto np = dd.procs();
  real_ = std::is_same<Real, double>::value ? MPI_DOUBLE : MPI_FLOAT;
  MPI_Type_contiguous(3, real_, &vec3_);
  MPI_Type_commit(&vec3_);

  // Slab bounds per process along each axis. Outer faces of non-periodic axes (and y in 2D)
  // reach to infinity, matching owner_of, which clamps points outside the grid.
  constexpr Real kInf = std::numeric_limits<Real>::infinity();
  std::vector<Real> lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    const auto& s = dd.cell_starts(k);
    for (int p = 0; p < np[std::size_t(k)]; ++p) {
      lo[k].push_back(g.lo[k] + Real(s[std::size_t(p)]) * g.cell[k]);
      hi[k].push_back(g.lo[k] + Real(s[std::size_t(p) + 1]) * g.cell[k]);
    }
    if (!g.periodic[k] || (g.dim == 2 && k == 1)) {
      lo[k].front() = -kInf;
      hi[k].back() = kInf;
    }
  }

  // Every (target rank, owned slot, shift) with the shifted particle within width of the target's
  // box, in slot order. Per axis first (few candidates), then their combinations.
  const Real w2 = width * width;
  std::vector<std::vector<Wire>> out(static_cast<std::size_t>(size));
  std::vector<AxisCandidate> cand[3];
  for (Index i = 0; i < n_owned; ++i) {
    const Vec3& x = owned_pos[i];
    for (int k = 0; k < 3; ++k) {
      cand[k].clear();
      const bool per = g.periodic[k] && !(g.dim == 2 && k == 1);
      const int tmax = per ? 1 : 0;
      for (int t = -tmax; t <= tmax; ++t) {
        const Real v = x[k] + Real(t) * (per ? g.period[k] : Real(0));
        for (int p = 0; p < np[std::size_t(k)]; ++p) {
          const Real d = std::max({Real(0), lo[k][std::size_t(p)] - v, v - hi[k][std::size_t(p)]});
          if (d * d <= w2) cand[k].push_back({p, t, d * d});
        }
      }
    }
    for (const auto& a : cand[0])
      for (const auto& b : cand[1])
        for (const auto& c : cand[2]) {
          if (a.d2 + b.d2 + c.d2 > w2) continue;
          const int q = dd.rank_at(a.p, b.p, c.p);
          if (q == me && a.t == 0 && b.t == 0 && c.t == 0) continue;  // the particle itself
          Wire wv;
          wv.slot = std::int64_t(i);
          wv.shift[0] = Real(a.t) * g.period[0];
          wv.shift[1] = Real(b.t) * g.period[1];
          wv.shift[2] = Real(c.t) * g.period[2];
          out[std::size_t(q)].push_back(wv);
        }
  }
  for (const auto& o : out) n_sent_ += Index(o.size());

  // Tell each target how many copies it gets (self-copies stay local).
  std::vector<PetscMPIInt> to_ranks, to_counts;
  for (int q = 0; q < size; ++q)
    if (q != me && !out[std::size_t(q)].empty()) {
      to_ranks.push_back(q);
      to_counts.push_back(PetscMPIInt(out[std::size_t(q)].size()));
    }
  PetscMPIInt n_from = 0, *from_ranks = nullptr, *from_counts = nullptr;
  SPHDEM_PETSC(PetscCommBuildTwoSided(comm, 1, MPI_INT, PetscMPIInt(to_ranks.size()),
                                      to_ranks.data(), to_counts.data(), &n_from, &from_ranks,
                                      &from_counts));
  std::vector<std::pair<int, int>> sources;  // (rank, count), sorted by rank
  for (PetscMPIInt j = 0; j < n_from; ++j) sources.emplace_back(from_ranks[j], from_counts[j]);
  PetscFree(from_ranks);
  PetscFree(from_counts);
  if (!out[std::size_t(me)].empty()) sources.emplace_back(me, int(out[std::size_t(me)].size()));
  std::sort(sources.begin(), sources.end());

  // Then the slots and shifts themselves.
  MPI_Datatype wire_t;
  MPI_Type_contiguous(int(sizeof(Wire)), MPI_BYTE, &wire_t);
  MPI_Type_commit(&wire_t);
  constexpr int kTagWire = 7311;
  std::vector<std::size_t> off(sources.size() + 1, 0);
  for (std::size_t s = 0; s < sources.size(); ++s)
    off[s + 1] = off[s] + std::size_t(sources[s].second);
  std::vector<Wire> in(off.back());
  std::vector<MPI_Request> req;
  for (std::size_t s = 0; s < sources.size(); ++s) {
    const int r = sources[s].first;
    if (r == me) {
      std::copy(out[std::size_t(me)].begin(), out[std::size_t(me)].end(),
                in.begin() + std::ptrdiff_t(off[s]));
      continue;
    }
    req.emplace_back();
    MPI_Irecv(in.data() + off[s], sources[s].second, wire_t, r, kTagWire, comm, &req.back());
  }
  for (std::size_t j = 0; j < to_ranks.size(); ++j) {
    req.emplace_back();
    MPI_Isend(out[std::size_t(to_ranks[j])].data(), to_counts[j], wire_t, to_ranks[j], kTagWire,
              comm, &req.back());
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  MPI_Type_free(&wire_t);

  // The star forest: leaf j (halo slot j) reads root (source rank, source slot).
  const std::size_t nleaves = in.size();
  std::vector<PetscSFNode> remote(nleaves);
  source_rank_.resize(nleaves);
  shift_.resize(nleaves);
  for (std::size_t s = 0; s < sources.size(); ++s)
    for (std::size_t j = off[s]; j < off[s + 1]; ++j) {
      remote[j].rank = sources[s].first;
      remote[j].index = PetscInt(in[j].slot);
      source_rank_[j] = sources[s].first;
      shift_[j] = Vec3(in[j].shift[0], in[j].shift[1], in[j].shift[2]);
    }
  PetscSF sf = nullptr;
  SPHDEM_PETSC(PetscSFCreate(comm, &sf));
  sf_ = sf;
  SPHDEM_PETSC(PetscSFSetGraph(sf, PetscInt(n_owned), PetscInt(nleaves), nullptr, PETSC_COPY_VALUES,
                               remote.data(), PETSC_COPY_VALUES));
  SPHDEM_PETSC(PetscSFSetUp(sf));
  build_seconds_ = MPI_Wtime() - t0;
}

HaloPlan::~HaloPlan() {
  release();
}

void HaloPlan::release() {
  // Nothing to free once PETSc and MPI are gone (a plan outliving ParallelEnv).
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

HaloPlan::HaloPlan(HaloPlan&& o) noexcept {
  *this = std::move(o);
}

HaloPlan& HaloPlan::operator=(HaloPlan&& o) noexcept {
  if (this == &o) return *this;
  release();
  sf_ = std::exchange(o.sf_, nullptr);
  real_ = o.real_;
  vec3_ = std::exchange(o.vec3_, MPI_DATATYPE_NULL);
  n_owned_ = o.n_owned_;
  n_sent_ = o.n_sent_;
  width_ = o.width_;
  build_seconds_ = o.build_seconds_;
  source_rank_ = std::move(o.source_rank_);
  shift_ = std::move(o.shift_);
  return *this;
}

void HaloPlan::bcast_raw(MPI_Datatype unit, const void* owned, void* halo) const {
  static char dummy[64];
  const void* r = owned ? owned : dummy;
  void* l = halo ? halo : dummy;
  SPHDEM_PETSC(PetscSFBcastBegin(sf_, unit, r, l, MPI_REPLACE));
  SPHDEM_PETSC(PetscSFBcastEnd(sf_, unit, r, l, MPI_REPLACE));
}

void HaloPlan::reduce_raw(MPI_Datatype unit, const void* halo, void* owned) const {
  static char dummy[64];
  const void* l = halo ? halo : dummy;
  void* r = owned ? owned : dummy;
  SPHDEM_PETSC(PetscSFReduceBegin(sf_, unit, l, r, MPI_SUM));
  SPHDEM_PETSC(PetscSFReduceEnd(sf_, unit, l, r, MPI_SUM));
}

void HaloPlan::bcast(const Real* owned, Real* halo) const {
  bcast_raw(real_, owned, halo);
}
void HaloPlan::bcast(const Vec3* owned, Vec3* halo) const {
  bcast_raw(vec3_, owned, halo);
}
void HaloPlan::bcast(const GlobalId* owned, GlobalId* halo) const {
  bcast_raw(MPI_UINT64_T, owned, halo);
}
void HaloPlan::bcast(const std::int32_t* owned, std::int32_t* halo) const {
  bcast_raw(MPI_INT32_T, owned, halo);
}

void HaloPlan::bcast_positions(const Vec3* owned, Vec3* halo) const {
  bcast_raw(vec3_, owned, halo);
  for (std::size_t j = 0; j < shift_.size(); ++j) halo[j] += shift_[j];
}

void HaloPlan::reduce_sum(const Real* halo, Real* owned) const {
  reduce_raw(real_, halo, owned);
}
void HaloPlan::reduce_sum(const Vec3* halo, Vec3* owned) const {
  reduce_raw(vec3_, halo, owned);
}

void HaloPlan::fill(ParticleSet<Host>& ps) const {
  if (ps.n_fluid != n_owned_)
    throw RuntimeFault("HaloPlan::fill: the particle set has " + std::to_string(ps.n_fluid) +
                       " owned particles, the plan was built for " + std::to_string(n_owned_));
  const Index n = ps.n_fluid, nh = n_halo();
  const Index tail_begin = ps.fluid_end(), tail_end = ps.size();
  ps.for_each_field([&](const char* name, auto& buf) {
    using T = std::decay_t<decltype(buf[0])>;
    std::vector<T> v(std::size_t(n + nh + (tail_end - tail_begin)));
    std::copy(buf.vec().begin(), buf.vec().begin() + n, v.begin());
    std::copy(buf.vec().begin() + tail_begin, buf.vec().begin() + tail_end, v.begin() + (n + nh));
    if constexpr (std::is_same<T, Vec3>::value) {
      if (std::strcmp(name, "pos") == 0)
        bcast_positions(v.data(), v.data() + n);
      else
        bcast(v.data(), v.data() + n);
    } else {
      bcast(v.data(), v.data() + n);
    }
    buf.vec().swap(v);
  });
  ps.n_halo = nh;
}

}  // namespace sphdem
