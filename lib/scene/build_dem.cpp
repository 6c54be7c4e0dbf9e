#include "scene/build_dem.hpp"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <random>
#include <string>

#include "core/error.hpp"
#include "geometry/sdf.hpp"

namespace sphdem {

namespace {

dem::ContactModel contact_model(const ContactParams& c, Real stiffness_overlap) {
  dem::ContactModel m;
  m.law = c.law == "hertz" ? dem::NormalLaw::kHertz : dem::NormalLaw::kLinear;
  m.kn = c.kn;
  m.restitution = c.restitution;
  m.mu = c.friction;
  m.young = c.young;
  m.poisson = c.poisson;
  m.wall_young = c.wall_young;
  m.wall_poisson = c.wall_poisson;
  m.stiffness_overlap = stiffness_overlap;
  return m;
}

std::vector<dem::GrainTemplate> make_templates(const GrainShape& s, const std::string& where) {
  dem::TemplateOptions opt;
  opt.grid_spacing = s.grid_spacing;
  opt.node_spacing = s.node_spacing;
  std::vector<dem::GrainTemplate> out;
  for (int v = 0; v < s.variants; ++v) {
    const std::uint32_t seed = s.seed + std::uint32_t(v) * 7919u;
    switch (s.type) {
      case GrainShapeType::kSphere:
        out.push_back(dem::GrainTemplate::sphere(s.diameter / 2, opt));
        break;
      case GrainShapeType::kBox:
        out.push_back(dem::GrainTemplate::box(s.size / Real(2), opt));
        break;
      case GrainShapeType::kEllipsoid:
        out.push_back(dem::GrainTemplate::ellipsoid(s.size / Real(2), opt));
        break;
      case GrainShapeType::kTrigonalPyramid:
        out.push_back(dem::GrainTemplate::trigonal_pyramid(s.diameter, s.perturbation, seed,
                                                           s.diameter, opt));
        break;
      case GrainShapeType::kPolyhedron:
        out.push_back(dem::GrainTemplate::random_polyhedron(s.diameter, s.planes, seed, opt));
        break;
      case GrainShapeType::kMesh: {
        geom::TriMesh mesh;
        try {
          mesh = geom::load_mesh(s.file);
        } catch (const std::exception& e) {
          throw InputError(where + ".file: " + e.what());
        }
        out.push_back(dem::GrainTemplate::mesh(mesh, s.scale, opt));
        break;
      }
    }
    if (s.type == GrainShapeType::kSphere || s.type == GrainShapeType::kBox ||
        s.type == GrainShapeType::kEllipsoid || s.type == GrainShapeType::kMesh)
      break;  // variants only differ for seeded shapes
  }
  return out;
}

// A uniformly distributed random rotation (Shoemake 1992).
Quat random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double u1 = u(rng), u2 = u(rng), u3 = u(rng);
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  const double t2 = 2 * M_PI * u2, t3 = 2 * M_PI * u3;
  return normalize(Quat{Real(b * std::cos(t3)), Real(a * std::sin(t2)), Real(a * std::cos(t2)),
                        Real(b * std::sin(t3))});
}

}  // namespace

dem::DemParams dem_params(const Scene& scene) {
  const DemScene& d = scene.dem;
  dem::DemParams p;
  p.gravity = scene.gravity;
  p.grain_grain = contact_model(d.grain_grain, d.stiffness_overlap);
  p.grain_wall = contact_model(d.grain_wall, d.stiffness_overlap);
  p.nodes_per_contact = d.nodes_per_contact;
  return p;
}

std::vector<std::string> update_walls(const Scene& scene, const DemBuild& dem, Real t) {
  std::vector<std::string> off;
  for (std::size_t k = 0; k < scene.dem.walls.size(); ++k) {
    dem::Wall& w = dem.system->walls()[std::size_t(dem.wall_index[k])];
    w.velocity = wall_velocity(scene.dem.walls[k], t);
    const Solid* s = dem.wall_solid[k];  // resolved at build: no name lookup per sub-step
    if (w.active && s->removed_at < Real(1e29) && s->removed_by(t)) {
      w.active = false;
      off.push_back(s->name);
    }
  }
  return off;
}

Vec3 wall_velocity(const GrainWall& w, Real t) {
  return (t >= w.start && t < w.stop) ? w.velocity : Vec3();
}

DemBuild build_dem(const Scene& scene, std::ostream& log) {
  const DemScene& d = scene.dem;
  DemBuild out;
  out.system = std::make_unique<dem::DemSystem>(dem_params(scene));
  dem::DemSystem& sys = *out.system;
  // Templates per shape name.
  std::vector<std::vector<int>> tmpl(d.shapes.size());
  for (std::size_t s = 0; s < d.shapes.size(); ++s) {
    const std::string where = scene.source + ": dem.shapes[" + std::to_string(s) + "]";
    for (dem::GrainTemplate& t : make_templates(d.shapes[s], where)) {
      log << "grain shape '" << d.shapes[s].name << "' variant " << tmpl[s].size() << ": "
          << t.describe() << "\n";
      tmpl[s].push_back(sys.add_template(std::move(t)));
    }
  }
  auto shape_index = [&](const std::string& name) {
    for (std::size_t s = 0; s < d.shapes.size(); ++s)
      if (d.shapes[s].name == name) return s;
    return std::size_t(0);  // the parser checked the name
  };
  out.min_diameter = 1e30;
  for (std::size_t k = 0; k < d.packs.size(); ++k) {
    const GrainPack& p = d.packs[k];
    const std::vector<int>& ts = tmpl[shape_index(p.shape)];
    Real rb = 0;
    for (int t : ts) {
      rb = std::max(rb, sys.shape(t).bounding_radius());
      out.min_diameter = std::min(out.min_diameter, sys.shape(t).equivalent_diameter());
    }
    out.max_radius = std::max(out.max_radius, rb);
    const std::string where = scene.source + ": dem.packs[" + std::to_string(k) + "]";
    const Vec3 box = p.hi - p.lo;
    const Real v_box = box.x * box.y * box.z;
    int count = p.count;
    if (p.fraction > 0) {
      Real v_grain = 0;
      for (int t : ts) v_grain += sys.shape(t).volume() / Real(ts.size());
      count = int(std::lround(p.fraction * v_box / v_grain));
      log << where << ": solid fraction " << p.fraction << " of the box (" << v_box << " m^3) -> "
          << count << " grains of " << v_grain << " m^3 (fraction " << Real(count) * v_grain / v_box
          << ")\n";
      if (count == 0)
        throw InputError(where + ": fraction " + std::to_string(p.fraction) +
                         " of the box is less than half a grain (" + std::to_string(v_grain) +
                         " m^3 each, box " + std::to_string(v_box) +
                         " m^3): raise the fraction or give a count");
    }
    std::mt19937 rng(p.seed);
    if (p.placement == "random") {
      // Uniform centres in the box shrunk by the bounding radius; a candidate closer than
      // 2 rb (plus a 1 % gap) to a placed grain is drawn again.
      const Vec3 lo = p.lo + Vec3(rb, rb, rb), hi = p.hi - Vec3(rb, rb, rb);
      for (int a = 0; a < 3; ++a)
        if (!(hi[a] >= lo[a]))
          throw InputError(where + ": the box is narrower than one grain (bounding diameter " +
                           std::to_string(2 * rb) + " m)");
      std::uniform_real_distribution<Real> u(0, 1);
      std::vector<Vec3> placed;
      const Real d2 = Real(2.02) * rb * Real(2.02) * rb;
      for (int g = 0; g < count; ++g) {
        bool ok = false;
        for (int attempt = 0; attempt < 100000 && !ok; ++attempt) {
          const Vec3 c(lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
                       lo.z + (hi.z - lo.z) * u(rng));
          ok = true;
          for (const Vec3& o : placed)
            if (norm2(c - o) < d2) {
              ok = false;
              break;
            }
          if (ok) placed.push_back(c);
        }
        if (!ok)
          throw InputError(
              where + ": placed " + std::to_string(g) + " of " + std::to_string(count) +
              " grains at random; no room for more (bounding diameter " + std::to_string(2 * rb) +
              " m): lower the count or fraction, or use placement: shelf");
        const int t = ts[std::size_t(g) % ts.size()];
        const Quat q = p.random_orientation ? random_rotation(rng) : Quat{};
        sys.add_body(t, p.density, placed.back(), q, p.velocity);
      }
      continue;
    }
    // Shelf packing of the grains' world bounding boxes (each grain in its own random
    // orientation): rows along x, rows stacked along y, layers along z, each layer as tall as its
    // tallest grain. Boxes do not overlap, so neither do grains; a gap of 1 % of rb separates them.
    const Real gap = Real(0.01) * rb;
    Real x = p.lo.x, y = p.lo.y, z = p.lo.z, row_depth = 0, layer_height = 0;
    for (int g = 0; g < count; ++g) {
      const int t = ts[std::size_t(g) % ts.size()];
      const Quat q = p.random_orientation ? random_rotation(rng) : Quat{};
      Vec3 blo(1e30, 1e30, 1e30), bhi(-1e30, -1e30, -1e30);
      for (const Vec3& node : sys.shape(t).nodes()) {
        const Vec3 w = rotate(q, node);
        for (int a = 0; a < 3; ++a) {
          blo[a] = std::min(blo[a], w[a]);
          bhi[a] = std::max(bhi[a], w[a]);
        }
      }
      const Vec3 ext = bhi - blo + Vec3(gap, gap, gap);
      if (x + ext.x > p.hi.x) {  // next row
        x = p.lo.x;
        y += row_depth;
        row_depth = 0;
      }
      if (y + ext.y > p.hi.y) {  // next layer
        x = p.lo.x;
        y = p.lo.y;
        z += layer_height;
        row_depth = layer_height = 0;
      }
      if (x + ext.x > p.hi.x || y + ext.y > p.hi.y || z + ext.z > p.hi.z) {
        throw InputError(where + ": " + std::to_string(count) + " grains do not fit in the box; " +
                         std::to_string(g) + " were placed up to z = " + std::to_string(z) +
                         " m (grain bounding diameter " + std::to_string(2 * rb) +
                         " m; raise hi.z or widen the box)");
      }
      const Vec3 centre = Vec3(x, y, z) - blo + Real(0.5) * Vec3(gap, gap, gap);
      sys.add_body(t, p.density, centre, q, p.velocity);
      x += ext.x;
      row_depth = std::max(row_depth, ext.y);
      layer_height = std::max(layer_height, ext.z);
    }
  }
  for (std::size_t k = 0; k < d.bodies.size(); ++k) {
    const GrainBody& gb = d.bodies[k];
    for (int a = 0; a < 3; ++a)
      if (!(gb.position[a] > scene.domain_lo[a] && gb.position[a] < scene.domain_hi[a]))
        throw InputError(scene.source + ": dem.bodies[" + std::to_string(k) +
                         "].position: the centroid lies outside the domain");
    const std::vector<int>& ts = tmpl[shape_index(gb.shape)];
    const int t = ts.front();
    out.min_diameter = std::min(out.min_diameter, sys.shape(t).equivalent_diameter());
    out.max_radius = std::max(out.max_radius, sys.shape(t).bounding_radius());
    const Quat q = from_axis_angle(gb.axis, gb.angle_deg * Real(M_PI / 180));
    sys.add_body(t, gb.density, gb.position, q, gb.velocity, Vec3(),
                 gb.fixed ? dem::Motion::kFixed : dem::Motion::kFree);
  }
  for (const GrainWall& w : d.walls) {
    const Solid* s = scene.find_solid(w.solid);
    out.wall_index.push_back(sys.add_sdf_wall(s->sdf, wall_velocity(w, 0)));
    sys.set_wall_contact(out.wall_index.back(), w.friction, w.restitution);
    out.wall_solid.push_back(s);
  }
  out.dt = scene.time.dt_fixed > 0 ? scene.time.dt_fixed : d.dt_factor * sys.time_step();
  if (scene.time.dt_fixed <= 0 && scene.time.dt_max > 0)
    out.dt = std::min(out.dt, scene.time.dt_max);
  return out;
}

}  // namespace sphdem
