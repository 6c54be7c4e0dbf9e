#include "diagnostics/guards.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/error.hpp"

namespace sphdem {

namespace {
[[noreturn]] void fail(const std::string& cause, Real time, std::int64_t step,
                       const std::string& detail, const std::string& hint) {
  std::ostringstream os;
  os << "unstable: " << cause << " at t = " << time << " s (step " << step << "): " << detail;
  if (!hint.empty()) os << ". " << hint;
  throw StabilityError(os.str());
}
bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
}  // namespace

ExtremeFluid extreme_fluid(const ParticleSet<Host>& ps, Extreme e) {
  ExtremeFluid f;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    const double k = e == Extreme::fastest   ? std::sqrt(double(norm2(ps.vel[i])))
                     : e == Extreme::densest ? double(ps.rho[i])
                                             : -double(ps.rho[i]);
    if (k > f.key) f = ExtremeFluid{k, ps.id[i], ps.pos[i], ps.vel[i], ps.rho[i]};
  }
  return f;
}

std::string fluid_particle_text(const ExtremeFluid& f) {
  if (!f.found()) return "no fluid particle";
  std::ostringstream d;
  d << "fluid particle id " << f.id << " at (" << f.pos.x << ", " << f.pos.y << ", " << f.pos.z
    << "), speed " << std::sqrt(double(norm2(f.vel))) << " m/s, velocity (" << f.vel.x << ", "
    << f.vel.y << ", " << f.vel.z << "), density " << f.rho << " kg/m^3";
  return d.str();
}

void GuardSpan::add(const StepStats& st) {
  ++steps;
  // Written so that a NaN replaces the extreme (a comparison with NaN is false).
  if (!(st.max_speed <= max_speed)) max_speed = st.max_speed;
  if (!(st.rho_min >= rho_min)) rho_min = st.rho_min;
  if (!(st.rho_max <= rho_max)) rho_max = st.rho_max;
  if (!(st.dt >= dt_min)) dt_min = st.dt;
}

std::string near_solid_text(const Scene& scene, Real time, const Vec3& x, Real reach,
                            const std::vector<ThinSolid>& thin, Real boundary_depth) {
  const Real dp = scene.sph.dp;
  const Solid* best = nullptr;
  Real best_phi = reach;
  for (const Solid& s : scene.solids) {
    if (s.removed_by(time)) continue;
    const Real phi = s.sdf->phi(x);
    if (phi < best_phi) {
      best_phi = phi;
      best = &s;
    }
  }
  if (!best) return "";
  std::ostringstream d;
  d << "; it is " << std::fabs(best_phi) * 1000 << " mm "
    << (best_phi < 0 ? "inside solid '" : "from the surface of solid '") << best->name << "'";
  // The first fluid layer sits dp/2 off a wall: nearer, the particle is pressed against it.
  if (best_phi >= 0 && best_phi < Real(0.5) * dp)
    d << " (nearer than dp/2 = " << Real(0.5) * dp * 1000
      << " mm, where the first fluid layer sits)";
  // A thin solid leaks only the fluid pressed into it: inside it or within one dp of its
  // surface (the first layer sits at dp/2). Farther out, its thickness is reported without
  // blaming it.
  for (const ThinSolid& t : thin)
    if (t.name == best->name) {
      d << ", which is " << t.thickness * 1000 << " mm thick, less than the boundary depth "
        << boundary_depth * 1000 << " mm";
      if (best_phi < dp)
        d << ": its truncated boundary lets fluid be pressed into it and shot out; thicken the "
             "solid or refine dp (a higher c0 only stiffens the fluid)";
      else
        d << " (the particle is " << best_phi / dp
          << " dp from it, farther than a particle pressed into it)";
    }
  return d.str();
}

void check_step_guards(const Scene& scene, const StepParams& p, const StepStats& st, Real time,
                       std::int64_t step, const std::function<std::string(Extreme)>& locate) {
  if (!std::isfinite(st.dt) || !std::isfinite(st.max_speed) || !std::isfinite(st.rho_min) ||
      !std::isfinite(st.rho_max)) {
    std::ostringstream d;
    d << "dt = " << st.dt << ", max speed = " << st.max_speed << ", density range [" << st.rho_min
      << ", " << st.rho_max << "]";
    fail("NaN or Inf", time, step, d.str(), "The step diverged; lower time.cfl");
  }
  if (scene.time.dt_fixed <= 0 && st.dt < scene.time.dt_min) {
    std::ostringstream d;
    d << "dt = " << st.dt << " s fell below the floor time.dt_min = " << scene.time.dt_min
      << " s (force limit " << st.dt_force << " s, acoustic limit " << st.dt_acoustic
      << " s, viscous limit " << st.dt_viscous << " s)";
    fail("time step at its floor", time, step, d.str(), "Accelerations are growing without bound");
  }
  // Density before speed: a state outside the density bounds has left weak compressibility,
  // the failure the Mach bound only predicts, so when both fire that is the one reported.
  const Real lo = scene.guards.rho_min_ratio * p.eos.rho0,
             hi = scene.guards.rho_max_ratio * p.eos.rho0;
  if (st.rho_min < lo || st.rho_max > hi) {
    std::ostringstream d;
    d << "fluid density range [" << st.rho_min << ", " << st.rho_max << "] kg/m^3 leaves [" << lo
      << ", " << hi << "] (guards.rho_min_ratio/rho_max_ratio times rho0)";
    if (locate) {
      const bool dense = st.rho_max > hi;
      d << "; the " << (dense ? "densest" : "lightest") << " is "
        << locate(dense ? Extreme::densest : Extreme::lightest);
    }
    fail("density out of bounds", time, step, d.str(),
         "Check density diffusion (fluid.diffusion), the CFL number and c0");
  }
  const Real mach = st.max_speed / p.eos.c0;
  if (mach > scene.guards.mach_max) {
    std::ostringstream d;
    d << "max speed " << st.max_speed << " m/s is Mach " << mach << " of c0 = " << p.eos.c0
      << " m/s, above guards.mach_max = " << scene.guards.mach_max;
    if (locate) d << "; the fastest is " << locate(Extreme::fastest);
    fail("Mach number too high", time, step, d.str(),
         "Raise fluid.c0 (or fluid.c0_factor) so the fluid stays weakly compressible");
  }
}

void check_particle_guards(const Scene& scene, const StepParams& p, const ParticleSet<Host>& ps,
                           Real time, std::int64_t step) {
  const Real lo = scene.guards.rho_min_ratio * p.eos.rho0,
             hi = scene.guards.rho_max_ratio * p.eos.rho0;
  for (Index i = 0; i < ps.n_fluid; ++i) {
    if (!finite(ps.pos[i]) || !finite(ps.vel[i]) || !std::isfinite(ps.rho[i])) {
      std::ostringstream d;
      d << "fluid particle id " << ps.id[i] << " has position (" << ps.pos[i].x << ", "
        << ps.pos[i].y << ", " << ps.pos[i].z << "), density " << ps.rho[i];
      fail("NaN or Inf", time, step, d.str(), "The step diverged; lower time.cfl");
    }
    if (ps.rho[i] < lo || ps.rho[i] > hi) {
      std::ostringstream d;
      d << "fluid particle id " << ps.id[i] << " has density " << ps.rho[i] << " kg/m^3, outside ["
        << lo << ", " << hi << "]";
      fail("density out of bounds", time, step, d.str(),
           "Check density diffusion (fluid.diffusion), the CFL number and c0");
    }
  }
  // Penetration: a fluid particle deeper than guards.penetration_depth (default dp/2) inside a
  // solid has crossed the wall (the first fluid layer sits at phi = +dp/2, the first boundary
  // layer at -dp/2).
  const Real tol = scene.guards.penetration_depth * p.dp;
  // A point outside a solid's bounding box (grown by tol) is not inside it: most particles are
  // far from most solids (the flume's seven barrier walls), and the SDF is evaluated only for
  // the solids whose box holds the particle. The scan runs on all threads and finds the first
  // offender in slot order, so the message is the same at any thread count.
  struct Candidate {
    const Solid* solid;
    geom::Aabb box;
  };
  std::vector<Candidate> solids;
  for (const Solid& s : scene.solids) {
    if (s.removed_by(time)) continue;  // an opened gate
    geom::Aabb b = s.sdf->bounds();
    b.lo -= Vec3(tol, tol, tol);
    b.hi += Vec3(tol, tol, tol);
    solids.push_back({&s, b});
  }
  auto inside = [](const geom::Aabb& b, const Vec3& x) {
    return x.x >= b.lo.x && x.x <= b.hi.x && x.y >= b.lo.y && x.y <= b.hi.y && x.z >= b.lo.z &&
           x.z <= b.hi.z;
  };
  const long n = long(ps.n_fluid), ns = long(solids.size());
  long first = n * ns;  // the first (particle, solid) pair inside, as particle * ns + solid
#pragma omp parallel for schedule(static) reduction(min : first)
  for (long i = 0; i < n; ++i) {
    for (long k = 0; k < ns; ++k) {
      if (!inside(solids[k].box, ps.pos[i])) continue;
      if (solids[k].solid->sdf->phi(ps.pos[i]) < -tol) {
        first = std::min(first, i * ns + k);
        break;
      }
    }
  }
  if (first < n * ns) {
    const Index i = Index(first / ns);
    const Solid& s = *solids[first % ns].solid;
    const Real phi = s.sdf->phi(ps.pos[i]);
    std::ostringstream d;
    d << "fluid particle id " << ps.id[i] << " is " << -phi << " m inside solid '" << s.name
      << "' at (" << ps.pos[i].x << ", " << ps.pos[i].y << ", " << ps.pos[i].z << ")";
    fail("fluid inside a solid", time, step, d.str(),
         "The wall is too thin for the kernel or the step too large; add boundary layers or "
         "lower time.cfl");
  }
}

}  // namespace sphdem
