#include "diagnostics/mirror.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/error.hpp"
#include "scene/barrier.hpp"
#include "solver/mirror_exchange.hpp"

namespace sphdem {

std::vector<std::int32_t> mirror_solids(const Scene& scene, std::vector<std::string>* unpaired) {
  std::vector<std::int32_t> m(scene.solids.size());
  for (std::size_t s = 0; s < m.size(); ++s) m[s] = std::int32_t(s);
  const SymmetryPlane& sym = scene.symmetry;
  if (!sym.enabled() || !scene.barrier.enabled) return m;
  const std::vector<BarrierWall> walls = barrier_walls(scene.barrier);
  auto index = [&](std::size_t k) {
    const std::string name = "barrier_" + std::to_string(k + 1);
    for (std::size_t s = 0; s < scene.solids.size(); ++s)
      if (scene.solids[s].name == name) return std::int32_t(s);
    return std::int32_t(-1);
  };
  // Pairs match to a millionth of dp and 1e-9 rad, or to 100 round-offs of Real where that is
  // larger (a float build: one ulp of a 0.6 m coordinate is 6e-8 m).
  const Real eps100 = Real(100) * std::numeric_limits<Real>::epsilon();
  const Real angle_tol = std::max(Real(1e-9), eps100);
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const Vec3 c = sym.reflect_point(walls[k].center);
    const Real tol = std::max(Real(1e-6) * scene.sph.dp, eps100 * (norm(c) + scene.sph.dp));
    // A reflection in a vertical plane turns the rotation about z the other way.
    const Real a = sym.axis == 2 ? walls[k].angle : -walls[k].angle;
    bool found = false;
    for (std::size_t j = 0; j < walls.size() && !found; ++j) {
      const Real da = std::remainder(walls[j].angle - a, Real(kPi));  // a box turned by pi
      if (norm(walls[j].center - c) <= tol && std::fabs(da) <= angle_tol) {
        const std::int32_t sk = index(k), sj = index(j);
        if (sk >= 0 && sj >= 0) m[std::size_t(sk)] = sj;
        found = true;
      }
    }
    if (!found && unpaired) unpaired->push_back("barrier_" + std::to_string(k + 1));
  }
  return m;
}

ParticleSet<Host> mirror_full(const ParticleSet<Host>& ps, const SymmetryPlane& plane,
                              const std::vector<std::int32_t>& solid_mirror) {
  if (ps.n_grain != 0) throw RuntimeFault("mirror_full: grains are not mirrored");
  // A wall particle's force is that of the modelled fluid alone (the solver sums owned fluid
  // into walls, never halo copies). The mirror fluid's force on a wall particle is the image of
  // the modelled fluid's force on the particle's mirror image, so the full scene's force on a
  // solid is the modelled force on all its particles (both sides of the plane) plus the image of
  // the modelled force on all its mirror solid's particles: every wall and its image.
  const Index nf = ps.n_fluid, wb = ps.wall_begin(), nw = ps.n_wall;
  ParticleSet<Host> out;
  out.n_fluid = 2 * nf;
  out.n_wall = 2 * nw;
  auto& src = const_cast<ParticleSet<Host>&>(ps);  // for_each_field is not const; read only
  std::vector<void*> outs;
  out.for_each_field([&](const char*, auto& o) { outs.push_back(&o); });
  std::size_t k = 0;
  src.for_each_field([&](const char* name, auto& b) {
    auto& v = static_cast<std::decay_t<decltype(b)>*>(outs[k++])->vec();
    using T = std::decay_t<decltype(v[0])>;
    auto image = [&](const T& x) { return mirror_field_value(plane, name, x); };
    v.reserve(std::size_t(2 * (nf + nw)));
    for (Index i = 0; i < nf; ++i) v.push_back(b[std::size_t(i)]);
    for (Index i = 0; i < nf; ++i) v.push_back(image(b[std::size_t(i)]));
    for (Index i = wb; i < wb + nw; ++i) v.push_back(b[std::size_t(i)]);
    for (Index i = wb; i < wb + nw; ++i) v.push_back(image(b[std::size_t(i)]));
  });
  for (Index i = out.wall_begin() + nw; i < out.size(); ++i) {
    const std::int32_t b = out.body[i];
    if (b >= 0 && std::size_t(b) < solid_mirror.size()) out.body[i] = solid_mirror[std::size_t(b)];
  }
  return out;
}

}  // namespace sphdem
