#include "solver/mirror_exchange.hpp"

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "core/error.hpp"

namespace sphdem {

MirrorExchange::MirrorExchange(const SymmetryPlane& plane, Real width, Real support)
    : plane_(plane), width_(width), support_(support) {
  if (!plane.enabled()) throw RuntimeFault("MirrorExchange: no symmetry plane");
}

Real MirrorExchange::width() const {
  // Past the deepest wall or ghost node: the support, plus half the skin. Those points stand
  // still, and the halo is rebuilt before any fluid particle has moved skin/2 towards them.
  return std::max(width_, ghost_reach_ + support_ + Real(0.5) * (width_ - support_));
}

std::vector<std::uint8_t> MirrorExchange::keep_walls(const Vec3* pos, const Vec3* ghost,
                                                     const Vec3* ghost_alt, Index n,
                                                     bool by_ghost) const {
  Real reach = 0;
  for (Index i = 0; i < n; ++i) {
    reach = std::max(reach, -plane_.side(pos[i]));
    if (by_ghost) reach = std::max({reach, -plane_.side(ghost[i]), -plane_.side(ghost_alt[i])});
  }
  ghost_reach_ = reach;
  return std::vector<std::uint8_t>(std::size_t(n), 1);
}

void MirrorExchange::build_halo(ParticleSet<Host>& ps) {
  if (ps.n_halo != 0) throw RuntimeFault("MirrorExchange::build_halo: drop the halo first");
  const Real w = width();
  source_.clear();
  for (Index i = 0; i < ps.n_fluid; ++i)
    if (plane_.side(ps.pos[i]) < w) source_.push_back(i);
  const Index nf = ps.n_fluid, nh = Index(source_.size()), n = ps.size();
  ps.for_each_field([&](const char* name, auto& b) {
    auto& v = b.vec();
    using T = std::decay_t<decltype(v[0])>;
    std::vector<T> out;
    out.reserve(std::size_t(n + nh));
    out.insert(out.end(), v.begin(), v.begin() + nf);
    for (Index j = 0; j < nh; ++j)
      out.push_back(mirror_field_value(plane_, name, v[std::size_t(source_[std::size_t(j)])]));
    out.insert(out.end(), v.begin() + nf, v.begin() + n);
    v.swap(out);
  });
  ps.n_halo = nh;
}

void MirrorExchange::bcast(const Real* owned, Real* halo) {
  for (std::size_t j = 0; j < source_.size(); ++j) halo[j] = owned[source_[j]];
}

void MirrorExchange::bcast(const Vec3* owned, Vec3* halo) {
  for (std::size_t j = 0; j < source_.size(); ++j) halo[j] = owned[source_[j]];
}

void MirrorExchange::bcast_positions(const Vec3* owned, Vec3* halo) {
  for (std::size_t j = 0; j < source_.size(); ++j)
    halo[j] = plane_.reflect_point(owned[source_[j]]);
}

void MirrorExchange::bcast_field(const Vec3* owned, Vec3* halo, HaloField kind) {
  for (std::size_t j = 0; j < source_.size(); ++j) {
    const Vec3 x = owned[source_[j]];
    halo[j] = kind == HaloField::kVelocity      ? plane_.reflect_vector(x)
              : kind == HaloField::kOffDiagonal ? plane_.reflect_off_diagonal(x)
                                                : x;
  }
}

}  // namespace sphdem
