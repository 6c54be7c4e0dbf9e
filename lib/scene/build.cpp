#include "scene/build.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

#include "core/error.hpp"
#include "sph/eos.hpp"

namespace sphdem {

Real boundary_depth(const Scene& scene) {
  if (scene.sph.boundary_layers > 0) return Real(scene.sph.boundary_layers) * scene.sph.dp;
  return Real(2) * scene.h();
}

namespace {

// Lattice points (i + 1/2) dp inside [lo, hi] along one axis.
void lattice_range(Real lo, Real hi, Real dp, long& i0, long& i1) {
  i0 = long(std::ceil(lo / dp - Real(0.5) - Real(1e-9)));
  i1 = long(std::floor(hi / dp - Real(0.5) + Real(1e-9)));
}

Real solids_phi(const Scene& scene, const Vec3& x, int* which) {
  Real best = Real(1e30);
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    if (scene.solids[s].removed_by(0)) continue;  // a gate open from the start: not there
    const Real v = scene.solids[s].sdf->phi(x);
    if (v < best) {
      best = v;
      if (which) *which = int(s);
    }
  }
  return best;
}

// Below zero inside a solid or behind a container's dry face (outside a tank): the space no fluid
// reaches from the scene's wet side. A solid that is removed during the run (a gate) does not
// close space for the others: the floor under a gate must mirror into the space the gate leaves
// (`own`: the solid whose particle asks, which sees itself).
Real open_phi(const Scene& scene, const Vec3& p, int own) {
  Real best = Real(1e30);
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    const Solid& so = scene.solids[s];
    if (int(s) != own && so.removed_at < Real(1e29)) continue;
    best = std::min(best, so.sdf->wet_phi(p));
  }
  return best;
}

// Unit directions to search for an exposed surface: the 26 neighbours of a cube cell (3D) or the
// 8 of a square in the x-z plane (2D).
const std::vector<Vec3>& search_directions(int dim) {
  static const std::vector<Vec3> d3 = [] {
    std::vector<Vec3> v;
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          if (i || j || k) v.push_back(Vec3(i, j, k) / std::sqrt(Real(i * i + j * j + k * k)));
    return v;
  }();
  static const std::vector<Vec3> d2 = [] {
    std::vector<Vec3> v;
    for (int i = -1; i <= 1; ++i)
      for (int k = -1; k <= 1; ++k)
        if (i || k) v.push_back(Vec3(i, 0, k) / std::sqrt(Real(i * i + k * k)));
    return v;
  }();
  return dim == 2 ? d2 : d3;
}

// Distance from x along unit d to open space (open_phi > 0), or `limit` if farther. Steps by the
// distance to the nearest surface (safe), at least dp/20.
Real exposure_distance(const Scene& scene, const Vec3& x, const Vec3& d, Real limit, int own) {
  const Real min_step = scene.sph.dp / Real(20);
  Real t = 0;
  for (int it = 0; it < 100000 && t < limit; ++it) {
    const Real ph = open_phi(scene, x + d * t, own);
    if (ph > Real(0)) return t;  // strictly: a face touching another solid is not open
    t += std::max(-ph, min_step);
  }
  return limit;
}

// Distance from boundary particle x, along -n, to where its solid ends (the far face of a thin
// solid), marching from t0 by the distance to the nearest surface (a safe step), at least dp/20;
// `limit` when the solid does not end within it. Used for the mirror through a thin solid's other
// face and for the solid's thickness.
Real far_face_distance(const geom::Sdf& sdf, const Vec3& x, const Vec3& n, Real t0, Real limit,
                       Real dp) {
  Real t = std::max(t0, Real(0));
  for (int it = 0; it < 1000 && t < limit; ++it) {
    const Real ph = sdf.phi(x - n * t);
    if (ph >= Real(0)) return t - ph;  // back to the face
    t += std::max(-ph, dp / Real(20));
  }
  return limit;
}

// A lattice point (i + 1/2) dp by its indices, for sets of points.
struct LatticeKey {
  long long i, j, k;
  bool operator==(const LatticeKey& o) const { return i == o.i && j == o.j && k == o.k; }
};
struct LatticeKeyHash {
  std::size_t operator()(const LatticeKey& a) const {
    return std::hash<long long>()(a.i * 73856093LL ^ a.j * 19349663LL ^ a.k * 83492791LL);
  }
};

template <class F>
void for_lattice(const Scene& scene, Vec3 lo, Vec3 hi, F&& f) {
  const Real dp = scene.sph.dp;
  long ix0, ix1, iy0 = 0, iy1 = 0, iz0, iz1;
  lattice_range(lo.x, hi.x, dp, ix0, ix1);
  lattice_range(lo.z, hi.z, dp, iz0, iz1);
  if (scene.dim == 3) lattice_range(lo.y, hi.y, dp, iy0, iy1);
  for (long iz = iz0; iz <= iz1; ++iz)
    for (long iy = iy0; iy <= iy1; ++iy)
      for (long ix = ix0; ix <= ix1; ++ix) {
        const Vec3 x((Real(ix) + Real(0.5)) * dp,
                     scene.dim == 3 ? (Real(iy) + Real(0.5)) * dp : Real(0),
                     (Real(iz) + Real(0.5)) * dp);
        f(x);
      }
}

}  // namespace

ParticleSet<Host> build_particles(const Scene& scene, BuildReport* report,
                                  const WallFilter& keep_wall) {
  const Real dp = scene.sph.dp;
  const Real mass = scene.fluid.rho0 * std::pow(dp, Real(scene.dim));
  const Real gmag = norm(scene.gravity);
  const Vec3 ghat = gmag > 0 ? scene.gravity / gmag : Vec3();

  std::vector<Vec3> fpos, fvel;
  std::vector<Real> fsurface;  // height of the block's surface along -g, per particle
  BuildReport rep;
  for (const FluidBlock& b : scene.fluid_blocks) {
    // The block's free surface: its highest corner along -g.
    Real top = -1e30, bottom = 1e30;
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                        (c & 4) ? b.hi.z : b.lo.z);
      const Real up = -dot(corner, ghat);
      top = std::max(top, up);
      bottom = std::min(bottom, up);
    }
    if (b.has_level) top = std::min(top, b.level);  // a level surface below the block's top
    rep.fluid_height = std::max(rep.fluid_height, top - bottom);
    for_lattice(scene, b.lo, b.hi, [&](const Vec3& x) {
      if (b.has_level && -dot(x, ghat) > b.level) return;
      if (solids_phi(scene, x, nullptr) <= Real(0)) return;
      fpos.push_back(x);
      fvel.push_back(b.velocity);
      fsurface.push_back(b.hydrostatic && gmag > 0 ? top : Real(-1e30));
    });
  }

  // A symmetry plane: the fluid on the mirrored side goes; a lattice row on the plane would
  // overlap its own mirror image.
  const SymmetryPlane& sym = scene.symmetry;
  const Real h = scene.h();
  if (sym.enabled()) {
    std::size_t w = 0;
    for (std::size_t i = 0; i < fpos.size(); ++i) {
      const Real d = sym.side(fpos[i]);
      if (std::fabs(d) < Real(0.25) * dp) {
        std::ostringstream os;
        os << scene.source << ": symmetry.at: " << sym.at << " lies on a row of fluid particles ("
           << "xyz"[sym.axis] << " = " << fpos[i][sym.axis] << "); put the plane halfway between "
           << "two rows (move it by dp/2 = " << Real(0.5) * dp << " m)";
        throw InputError(os.str());
      }
      if (d < 0) continue;
      fpos[w] = fpos[i];
      fvel[w] = fvel[i];
      fsurface[w] = fsurface[i];
      ++w;
    }
    rep.symmetry_fluid_dropped = Index(fpos.size() - w);
    fpos.resize(w);
    fvel.resize(w);
    fsurface.resize(w);
  }

  // Boundary particles: lattice points in the domain with -depth < phi < 0.
  const Real depth = boundary_depth(scene);
  rep.boundary_depth = depth;
  std::vector<Real> thin_min(scene.solids.size(), Real(0));
  std::vector<Index> thin_count(scene.solids.size(), 0);
  std::vector<Vec3> bpos, bghost, balt, bnormal;
  std::vector<std::int32_t> bbody;
  std::vector<Index> bnumber;  // each stored wall's number among all the scene's walls
  std::vector<Index> by_solid(scene.solids.size(), 0);
  Index walls_made = 0;
  // With a symmetry plane: every wall particle of the full scene, by lattice point.
  std::unordered_set<LatticeKey, LatticeKeyHash> full_walls;
  const auto lattice_key = [&](const Vec3& x) {
    auto c = [&](Real v) { return static_cast<long long>(std::llround(v / dp - Real(0.5))); };
    return LatticeKey{c(x.x), c(x.y), c(x.z)};
  };
  // The domain bounds the fluid; walls may lie up to `depth` outside it (non-periodic axes).
  Vec3 lo = scene.domain_lo, hi = scene.domain_hi;
  for (int k = 0; k < 3; ++k) {
    if (scene.periodic[k]) continue;
    lo[k] -= depth;
    hi[k] += depth;
  }
  // Lattice points this near a surface are on it. Which side they fall on is arbitrary: a dp
  // given to 11 digits (0.00714285714 for 0.4 m / 56) puts row k about k x 3e-12 m off, and
  // with an exact dp round-off decides.
  const Real tie = Real(1e-6) * dp;
  std::vector<Index> ties(scene.solids.size(), 0);
  for_lattice(scene, lo, hi, [&](const Vec3& x) {
    int which = -1;
    const Real phi_x = solids_phi(scene, x, &which);
    if (which >= 0 && std::fabs(phi_x) < tie) {
      const Solid& s = scene.solids[std::size_t(which)];
      if (s.in_boundary_region(x) && s.sdf->wet_phi(x) > -depth) ++ties[std::size_t(which)];
    }
    if (!(phi_x < Real(0))) return;
    // Depth and mirror from the wet surface (a tank's back layers mirror through its inner face).
    const Solid& solid = scene.solids[std::size_t(which)];
    if (!solid.in_boundary_region(x)) return;
    const geom::Sdf& sdf = *solid.sdf;
    const Real phi = std::min(sdf.wet_phi(x), Real(0));
    if (!(phi > -depth)) return;
    Vec3 n = sdf.wet_grad(x);
    const Real nn = norm(n);
    n = nn > 0 ? n / nn : Vec3(0, 0, 1);
    if (scene.dim == 2) {
      n.y = 0;
      const Real n2 = norm(n);
      n = n2 > 0 ? n / n2 : Vec3(0, 0, 1);
    }
    Real depth_x = -phi;
    // The ghost must land in open space. Where a face of this solid touches another solid (a
    // barrier wall's foot on the floor, its end against a side wall, two walls side by side) or
    // the nearest face is a tie that picked such a face, search for the nearest exposed surface.
    // A junction particle can be near open space on two sides (under a barrier wall's foot:
    // upstream and downstream); the nearest exposure at 90 degrees or more from the first is its
    // second ghost, and the solver uses whichever sees more fluid.
    bool searched = false;
    Vec3 alt_ghost;
    if (!(open_phi(scene, x - n * (Real(2) * phi), which) > Real(0))) {
      const auto& dirs = search_directions(scene.dim);
      std::vector<Real> dist(dirs.size());
      std::size_t best = dirs.size();
      for (std::size_t k = 0; k < dirs.size(); ++k) {
        dist[k] = exposure_distance(scene, x, dirs[k], depth, which);
        if (dist[k] < depth && (best == dirs.size() || dist[k] < dist[best])) best = k;
      }
      if (best == dirs.size()) return;  // buried: no exposed surface within the kernel support
      n = dirs[best];
      depth_x = dist[best];
      searched = true;
      alt_ghost = x + n * (Real(2) * depth_x);
      std::size_t other = dirs.size();
      for (std::size_t k = 0; k < dirs.size(); ++k)
        if (dot(dirs[k], n) <= Real(1e-9) && dist[k] < depth &&
            (other == dirs.size() || dist[k] < dist[other]))
          other = k;
      if (other < dirs.size()) alt_ghost = x + dirs[other] * (Real(2) * dist[other]);
    }
    // The solid's far face behind x along -n, within the boundary depth: a thin solid with fluid
    // on either side (a barrier wall a few dp thick) mirrors through it too. The particle is
    // depth_x inside the near face, so that face's march starts past the midpoint. A container's
    // outer faces are dry (no second ghost); its far face is looked for only from the first
    // layer, for the thickness.
    const bool dry = sdf.has_dry_faces();
    Real far = depth;  // depth: no far face that near
    if (!searched && !dry) far = far_face_distance(sdf, x, n, depth_x, depth, dp);
    if (!searched && dry && depth_x < dp)
      far = far_face_distance(sdf, x, n, 0, depth - depth_x, dp);
    // Beyond 2h on the mirrored side of a symmetry plane no fluid reaches a wall.
    if (sym.enabled()) {
      full_walls.insert(lattice_key(x));
      if (sym.side(x) <= Real(-2.02) * h) {
        ++rep.symmetry_walls_dropped;
        return;
      }
    }
    // A first-layer particle of a face: is the solid behind it thinner than the boundary depth?
    // (Half a spacing of slack: a lattice cannot resolve a thickness finer than that.)
    if (!searched && depth_x < dp && depth_x + far < depth - Real(0.5) * dp) {
      const std::size_t s = std::size_t(which);
      const Real t = depth_x + far;
      thin_min[s] = thin_count[s] == 0 ? t : std::min(thin_min[s], t);
      ++thin_count[s];
    }
    const Vec3 ghost = x + n * (Real(2) * depth_x);
    const Vec3 alt = searched ? alt_ghost : (!dry && far < depth ? x - n * (Real(2) * far) : ghost);
    rep.ghost_spread = std::max(rep.ghost_spread, norm(alt - ghost));
    ++by_solid[std::size_t(which)];
    const Index number = walls_made++;
    if (keep_wall && !keep_wall(x, ghost)) return;
    bnumber.push_back(number);
    bpos.push_back(x);
    bghost.push_back(ghost);
    balt.push_back(alt);
    bnormal.push_back(n);
    bbody.push_back(which);
  });

  ParticleSet<Host> ps;
  ps.n_fluid = Index(fpos.size());
  ps.n_wall = Index(bpos.size());
  ps.resize(ps.size());
  GlobalId next_id = 0;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    ps.id[i] = next_id++;
    ps.pos[i] = fpos[std::size_t(i)];
    ps.vel[i] = fvel[std::size_t(i)];
    ps.vel_prev[i] = ps.vel[i];
    ps.mass[i] = mass;
    ps.body[i] = -1;
  }
  for (Index k = 0; k < ps.n_wall; ++k) {
    const Index i = ps.wall_begin() + k;
    ps.id[i] = next_id + GlobalId(bnumber[std::size_t(k)]);
    ps.pos[i] = bpos[std::size_t(k)];
    ps.ghost[i] = bghost[std::size_t(k)];
    ps.ghost_alt[i] = balt[std::size_t(k)];
    ps.normal[i] = bnormal[std::size_t(k)];
    ps.body[i] = bbody[std::size_t(k)];
    ps.mass[i] = mass;
  }
  rep.fluid = ps.n_fluid;
  rep.wall = walls_made;
  rep.wall_by_solid = by_solid;
  if (sym.enabled()) {
    // Every wall on the modelled side and its mirror image among the full scene's walls: a run
    // that models half of a scene equals the full run only if the walls are symmetric, near the
    // plane (where the mirror fluid meets them) and far from it (a barrier wall and its image).
    for (const Vec3& x : bpos) {
      if (!(sym.side(x) > 0) || full_walls.count(lattice_key(sym.reflect_point(x)))) continue;
      Vec3& a = rep.symmetry_unmatched_lo;
      Vec3& b = rep.symmetry_unmatched_hi;
      if (rep.symmetry_unmatched++ == 0) a = b = x;
      a = Vec3(std::min(a.x, x.x), std::min(a.y, x.y), std::min(a.z, x.z));
      b = Vec3(std::max(b.x, x.x), std::max(b.y, x.y), std::max(b.z, x.z));
    }
  }
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    if (thin_count[s] > 0) rep.thin.push_back({scene.solids[s].name, thin_min[s], thin_count[s]});
    if (ties[s] > 0) rep.ties.push_back({scene.solids[s].name, ties[s]});
  }

  // Initial density: hydrostatic pressure from each block's surface, through the Tait EOS.
  const Real c0 = resolve_sound_speed(scene, rep);
  const EosParams e = make_eos(scene.fluid.rho0, c0, scene.fluid.gamma, scene.fluid.p_min);
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const Real surf = fsurface[std::size_t(i)];
    Real p = 0;
    if (surf > Real(-1e29))
      p = scene.fluid.rho0 * gmag * std::max(Real(0), surf - (-dot(ps.pos[i], ghat)));
    ps.rho[i] = tait_density(e, p);
    ps.rho_prev[i] = ps.rho[i];
    ps.press[i] = p;
  }
  for (Index k = 0; k < ps.n_wall; ++k) {
    const Index i = ps.wall_begin() + k;
    ps.rho[i] = scene.fluid.rho0;
    ps.rho_prev[i] = scene.fluid.rho0;
  }
  if (report) *report = rep;
  return ps;
}

void describe_symmetry_mismatch(const BuildReport& r, std::ostream& os) {
  if (r.symmetry_unmatched == 0) return;
  const Vec3 &a = r.symmetry_unmatched_lo, &b = r.symmetry_unmatched_hi;
  os << "warning: symmetry: " << r.symmetry_unmatched << " wall particles of the modelled side, "
     << "between (" << a.x << ", " << a.y << ", " << a.z << ") and (" << b.x << ", " << b.y << ", "
     << b.z
     << "), have no mirror image among the full scene's walls: the walls are not symmetric "
        "about the plane, and the run is not the full scene's half (turned walls, or a solid's "
        "face on a lattice row, which the last digits of dp put inside the solid at one face "
        "and outside at its mirror image: change dp)\n";
}

void describe_surface_ties(const BuildReport& report, Real dp, std::ostream& os) {
  if (report.ties.empty()) return;
  Index points = 0;
  for (const SurfaceTie& t : report.ties) points += t.points;
  const std::size_t n = report.ties.size();
  os << "warning: " << points << " lattice points lie on the surface of solid"
     << (n > 1 ? "s " : " ");
  for (std::size_t k = 0; k < n; ++k)
    os << (k > 0 ? (k + 1 == n ? " and '" : ", '") : "'") << report.ties[k].name << "'";
  os << " (a face on a row of the lattice at dp = " << dp * 1000
     << " mm): the last digits of dp and of the solid's coordinates decide whether each is a "
        "boundary particle, so the solid's extent "
        "on the lattice is dp/2 off at some faces and a symmetric scene may be built "
        "asymmetric; move the solid by dp/2 or change dp\n";
}

void describe_thin_solids(const BuildReport& report, Real dp, std::ostream& os) {
  // Solids of one thickness (a barrier's walls) share a line.
  for (std::size_t a = 0; a < report.thin.size();) {
    std::size_t b = a + 1;
    Index particles = report.thin[a].particles;
    while (b < report.thin.size() &&
           std::fabs(report.thin[b].thickness - report.thin[a].thickness) <= Real(1e-3) * dp)
      particles += report.thin[b++].particles;
    os << "warning: solid" << (b - a > 1 ? "s " : " ");
    for (std::size_t k = a; k < b; ++k)
      os << (k > a ? (k + 1 == b ? " and '" : ", '") : "'") << report.thin[k].name << "'";
    os << (b - a > 1 ? " are " : " is ") << report.thin[a].thickness * 1000 << " mm thick behind "
       << particles << " wall particles, less than the boundary depth "
       << report.boundary_depth * 1000
       << " mm (2h, or sph.boundary_layers x dp, at dp = " << dp * 1000
       << " mm): fluid there sees a truncated boundary and can leak through under impact; "
          "make the solid at least that thick, or refine dp\n";
    a = b;
  }
}

Real resolve_sound_speed(const Scene& scene, const BuildReport& report) {
  if (scene.fluid.c0 > 0) return scene.fluid.c0;
  const Real g = norm(scene.gravity);
  const Real vmax = Real(2) * std::sqrt(g * report.fluid_height);
  if (!(vmax > 0)) {
    std::ostringstream os;
    os << scene.source << ": fluid.c0: cannot derive the speed of sound (no gravity or no fluid); "
       << "set fluid.c0 explicitly";
    throw InputError(os.str());
  }
  return scene.fluid.c0_factor * vmax;
}

}  // namespace sphdem
