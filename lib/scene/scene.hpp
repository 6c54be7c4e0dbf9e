// The resolved scene: everything a run needs, after YAML parsing, overrides and defaults.
// io/scene_yaml.cpp fills it (and validates every key); scene/build.cpp turns it into particles.
// Units are SI throughout. Viscosities say whether they are dynamic (Pa s) or kinematic (m^2/s).
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/symmetry.hpp"
#include "core/types.hpp"
#include "geometry/sdf.hpp"

namespace sphdem {

enum class DiffusionModel { kNone, kMolteni, kFourtakas };
enum class ViscosityModel { kLaminar, kArtificial };
enum class BoundaryMethod { kDbc, kMdbc };
enum class SlipCondition { kNoSlip, kFreeSlip };
enum class Integrator { kVerlet, kSymplectic };

enum class RheologyModel { kNewtonian, kHbp };

// Herschel-Bulkley-Papanastasiou with Mohr-Coulomb yield (seed Eqs. 11-15); see
// lib/sph/rheology.hpp.
struct RheologyParams {
  RheologyModel model = RheologyModel::kNewtonian;
  Real k = 1e-3;          // consistency K, Pa s^n (dynamic)
  Real n = 1;             // flow index
  Real m = 100;           // Papanastasiou exponent, s
  Real cohesion = 0;      // c, Pa
  Real friction_deg = 0;  // phi, degrees
  Real mu_max = 1e3;      // cap on mu_eff, Pa s
  bool yield = true;      // false drops the yield term (diagnostic use)
};

// Sub-particle-scale turbulence, Dalrymple & Rogers (2006).
struct SpsParams {
  bool enabled = false;
  Real cs = 0.12;  // Smagorinsky constant
  Real ci = 0.0066;
};

struct FluidParams {
  Real rho0 = 1000;     // reference density, kg/m^3
  Real c0 = 0;          // speed of sound, m/s; 0 = derive from c0_factor * sqrt(g * H_max)
  Real c0_factor = 10;  // c0 = c0_factor * expected max speed when c0 is 0
  Real gamma = 7;       // Tait exponent (Eq. 6)
  Real p_min = -1e30;   // lowest pressure, Pa (gauge); -1e30 = no limit
  ViscosityModel viscosity = ViscosityModel::kLaminar;
  Real nu = 1e-6;     // laminar kinematic viscosity, m^2/s (Lo-Shao term, Eq. 9)
  Real alpha = 0.01;  // artificial viscosity coefficient (Monaghan)
  DiffusionModel diffusion = DiffusionModel::kFourtakas;
  Real delta = 0.1;  // delta-SPH coefficient (Eq. 8)
  RheologyParams rheology;
  SpsParams sps;
};

struct SphParams {
  Real dp = 0.01;       // initial particle spacing, m
  Real h_factor = 1.2;  // h = h_factor * sqrt(dim) * dp (DualSPHysics "coefh")
  BoundaryMethod boundary = BoundaryMethod::kMdbc;
  SlipCondition slip = SlipCondition::kNoSlip;
  int boundary_layers = 0;  // 0 = enough layers to fill the kernel support (2h)
  // mDBC penetration control (sph/mdbc.hpp, wall_pair_*): walls never pull fluid, and fluid
  // moving toward a wall sees the wall approach at the mirrored speed in the continuity equation.
  bool no_penetration = false;
  // mDBC: keep each wall particle's extrapolated density within the range of the fluid densities
  // at its ghost node, widened by their spread (sph/mdbc.hpp, mdbc_limit_density).
  bool mdbc_limiter = false;
  // CPU: each pair of owned fluid particles is evaluated once for both (solver/pairwise_host.hpp;
  // LAMMPS' `newton on`); false gathers every pair from both sides, as the GPU does.
  bool pairwise = true;
};

struct TimeParams {
  Real end = 1.0;      // simulated time, s
  Real cfl = 0.2;      // Courant number (Eq. 23)
  Real dt_fixed = 0;   // > 0: fixed time step (verification only)
  Real dt_min = 1e-9;  // floor: a step stuck here is a stability fault
  Real dt_max = 0;     // > 0: cap on the adaptive step (dem.subcycle: false sets the DEM step)
  Integrator integrator = Integrator::kVerlet;
  int verlet_euler_every = 40;
};

struct GuardParams {
  Real rho_min_ratio = 0.7;  // density outside [rho_min_ratio, rho_max_ratio] * rho0 is a fault
  Real rho_max_ratio = 1.3;
  Real mach_max = 0.1;  // v_max / c0 above this is a fault
  // Steps between the per-particle guard checks (penetration into solids, the particle's id).
  // 0 = auto: every step on the host, every 20 steps on the device, where the check costs a
  // download of every particle (38 ms of a 50 ms step at 1 M particles on an H200). The density,
  // Mach and NaN guards run every step in both spaces (from the step's reductions).
  int check_every = 0;
  Real penetration_depth = 0.5;  // fluid deeper than this many dp inside a solid is a fault
};

// When to write checkpoints (any that is > 0 triggers one). SIGTERM/SIGUSR1 and stability
// guards always write one.
struct CheckpointParams {
  Real every_time = 0;           // simulated seconds
  std::int64_t every_steps = 0;  // steps
  Real every_wall = 0;           // wall-clock seconds
  int keep = 3;                  // newest checkpoints kept
};

// Runs on many ranks (mpirun): when to rebalance the boxes from the particle histogram.
struct ParallelParams {
  int rebalance_every = 100;  // steps between imbalance checks; 0 = never after the start
  Real imbalance = 1.2;       // rebalance when max/mean owned fluid per rank exceeds this
  Real skin = 0.2;            // halo margin, in h: the halo plan is reused until an owned
                              // particle has moved skin/2 (0 = rebuild every step)
};

// ParaView frames: parallel HDF5 files indexed by one XDMF file.
struct FrameParams {
  Real every = 0;  // simulated seconds between frames; 0 = no frames
  std::vector<std::string> fields{"vel", "rho", "press"};  // fields written besides positions
  bool boundary = true;  // also write the boundary particles (walls) as a block
  bool region = false;   // limit to the box [region_lo, region_hi]
  Vec3 region_lo, region_hi;
};

// In-situ analysis (io/insitu.hpp): ParaView Catalyst Python scripts run every `every_steps`
// steps on the live particles. No scripts = off.
struct InSituParams {
  std::vector<std::string> scripts;  // paths, resolved against the scene file's folder
  std::int64_t every_steps = 10;
};

// A slit-type barrier (seed §4.1, Fig. 17): a row of `walls` rectangular walls standing on the
// channel floor across a channel running along +x between y_lo and y_hi. Wall k (k = 0..n-1) has
// its centre at y = y_lo + (k + 1/2) (y_hi - y_lo)/n and is `thickness` along the flow, `width`
// across it and `height` tall, turned by `angle_deg` about the vertical (z):
//   P (parallel): every wall turned by +angle, centres on the line x = x;
//   V: walls left of the centre line turned by +angle, the others by -angle, centres on a V whose
//      arms make `angle` with the cross-channel direction, apex at the centre wall (x = x), arms
//      trailing downstream (apex: upstream) or upstream (apex: downstream).
// The builder adds the walls as solids barrier_1 .. barrier_n (y order); impact_force.csv has the
// fluid force on each. Presets P00, P30, P45, V30, V45 set layout and angle.
struct Barrier {
  bool enabled = false;
  std::string preset;  // as given, or "" (layout + angle given directly)
  char layout = 'P';   // 'P' or 'V'
  Real angle_deg = 0;
  int walls = 7;
  Real width = 0.05, thickness = 0.013, height = 0.09;
  Real x = 0;  // x of the centre wall's centre
  Real y_lo = 0, y_hi = 0.4;
  Real floor_z = 0;
  bool apex_upstream = true;
  Real runup_band = 0.1;  // run-up is measured from this far upstream of the row to its end
};

struct Solid {
  std::string name;
  geom::SdfPtr sdf;  // phi < 0 inside the solid
  // Boundary particles only inside these boxes (none: everywhere). A wall costs particles only
  // where the flow can reach it; fluid that gets past a trimmed wall still trips the
  // fluid-inside-a-solid guard, since the SDF is whole.
  std::vector<std::pair<Vec3, Vec3>> boundary_regions;
  // The solid goes at this time (a gate that opens): its boundary particles leave the run, a DEM
  // wall made from it stops touching grains, and the fluid-inside-a-solid guard forgets it.
  Real removed_at = Real(1e30);
  bool removed_by(Real t) const {
    return t >= removed_at - Real(1e-9) * std::max(removed_at, Real(1));
  }
  bool in_boundary_region(const Vec3& x) const {
    if (boundary_regions.empty()) return true;
    for (const auto& [lo, hi] : boundary_regions)
      if (x.x >= lo.x && x.y >= lo.y && x.z >= lo.z && x.x <= hi.x && x.y <= hi.y && x.z <= hi.z)
        return true;
    return false;
  }
};

struct FluidBlock {
  Vec3 lo, hi;              // filled on the dp lattice, minus solids
  Vec3 velocity;            // initial velocity
  bool hydrostatic = true;  // initial pressure rho0 g (surface - z), surface = block top
  // A level free surface: only lattice points at height -g_hat . x <= level are filled, and the
  // hydrostatic pressure starts from it (the block's water at rest under tilted gravity).
  bool has_level = false;
  Real level = 0;
};

struct PressureGauge {
  std::string name;
  Vec3 point;
};
struct HeightGauge {
  std::string name;
  Real x = 0, y = 0;
};  // vertical line at (x, y)
struct FrontTracker {
  std::string name;
  Vec3 origin;
  Vec3 direction{1, 0, 0};
};
// A line sampled at given times: the free-surface elevation above each sample point (surface:
// columns t,s,x,y,z_surface), or the kernel-interpolated fluid velocity at it (velocity:
// t,s,x,y,z,u,v,w; a velocity profile across a channel).
struct ProfileSpec {
  std::string name;
  Vec3 from, to;
  int samples = 100;
  std::vector<Real> times;
  bool velocity = false;
};
struct ForceProbe {
  std::string name;
  std::string solid;
};
// Flow at a station (x, y) of a channel along +x with its bed at z = 0: mean fluid velocity along
// x over the particles within h of the bed-normal line, flow depth (bed-normal kernel-sum
// surface), and the Froude number u / sqrt(g_n depth) with g_n the bed-normal part of gravity
// (seed Eq. 27: g cos theta).
struct VelocityGauge {
  std::string name;
  Real x = 0, y = 0;
};

struct Diagnostics {
  Real every = 0.01;  // simulated seconds between CSV rows
  std::vector<PressureGauge> pressure_gauges;
  std::vector<HeightGauge> height_gauges;
  std::vector<FrontTracker> fronts;
  std::vector<ProfileSpec> profiles;
  std::vector<ForceProbe> forces;
  std::vector<VelocityGauge> velocity_gauges;  // all in velocity_gauges.csv
  bool energy = true;
};

// ---- DEM grains (lib/dem; seed §2.2) --------------------------------------------------------
enum class GrainShapeType { kSphere, kBox, kEllipsoid, kTrigonalPyramid, kPolyhedron, kMesh };

// One grain shape; `variants` > 1 makes that many seeded templates (pyramids, polyhedra) and the
// packs cycle through them.
struct GrainShape {
  std::string name;
  GrainShapeType type = GrainShapeType::kSphere;
  Real diameter = 0;         // sphere diameter; equivalent diameter of pyramids and polyhedra
  Vec3 size;                 // box full extents; ellipsoid full axes
  Real perturbation = 0.15;  // pyramid vertex jitter, in units of its edge
  int planes = 12;           // polyhedron cutting planes
  int variants = 1;
  std::uint32_t seed = 1;
  std::string file;  // mesh (STL/OBJ), resolved against the scene file's folder
  Real scale = 1;    // mesh scale
  Real grid_spacing = 0, node_spacing = 0;  // 0: template defaults (size / 30)
};

// A block of grains: `count` grains, each in a seeded random orientation, placed without overlap
// by shelf-packing their world bounding boxes into [lo, hi] from the bottom up (rows along x,
// then y, then layers along z). Packs are usually rained into place under gravity (dem.settle).
//
// Instead of `count`, `fraction` gives the grains' solid volume fraction of the box [lo, hi]:
// count = round(fraction V_box / V_grain), V_grain the mean volume of the shape's variants (the
// flume's boulders: the fraction of the debris block). placement: random scatters the grains
// uniformly through the box instead (bounding spheres kept apart; seeded), for a few boulders
// spread through a fluid block rather than stacked in one corner.
struct GrainPack {
  std::string shape;
  int count = 0;
  Real fraction = 0;                // > 0: the count follows from it at build
  std::string placement = "shelf";  // shelf | random
  Real density = 2500;
  Vec3 lo, hi;
  Vec3 velocity;
  bool random_orientation = true;
  std::uint32_t seed = 1;
};

// One grain placed by hand: centroid, orientation (axis-angle) and velocity.
struct GrainBody {
  std::string shape;
  Real density = 1000;
  Vec3 position, velocity;
  Vec3 axis{0, 0, 1};
  Real angle_deg = 0;
  bool fixed = false;
};

// A solid used as a DEM wall; moving walls translate at `velocity` for start <= t < stop.
struct GrainWall {
  std::string solid;
  Vec3 velocity;
  Real start = 0, stop = 1e30;
  // This wall's own contact friction and restitution; negative: grain_wall's.
  Real friction = -1, restitution = -1;
};

struct ContactParams {
  std::string law = "linear";  // linear | hertz (hertz: sphere contacts only)
  Real kn = 0;                 // per node [N/m]; 0: from young (dem/contact_law.hpp)
  Real young = 0, poisson = 0.3, restitution = 0.5, friction = 0.5;
  Real wall_young = 0, wall_poisson = 0.3;  // grain-wall only; 0: rigid wall
};

struct DemScene {
  bool enabled = false;
  ContactParams grain_grain, grain_wall;
  Real stiffness_overlap = 1e-2;
  Real nodes_per_contact = 1;
  Real dt_factor = 1;       // dt = dt_factor * t_c / 50 (time.dt_fixed overrides)
  Real overlap_max = 0.1;   // guard: overlap above this fraction of the smallest grain diameter
  Real settle_damping = 0;  // [1/s] drag -c m v on every grain while t < settle_until (packing)
  Real settle_until = 0;
  std::vector<GrainShape> shapes;
  std::vector<GrainPack> packs;
  std::vector<GrainBody> bodies;
  std::vector<GrainWall> walls;
  int substeps_max = 1000;  // coupled runs: most DEM sub-steps per fluid step
  // Coupled runs: true = the DEM sub-cycles inside each fluid step; false = one step for both
  // phases (the fluid step is capped at the DEM step).
  bool subcycle = true;
  // Heap measurement at the end of the run (diagnostics/heap.hpp): floor height, slope fit window
  // in x, and the x from which the run-out is measured (the baffle).
  bool heap = false;
  Real heap_floor = 0, heap_x_min = -1e30, heap_x_max = 1e30, heap_origin = 0;
  // Grain-only runs: end the run once the grains are at rest (as LAMMPS' fix halt on ke): at a
  // diagnostics time t >= rest_after, the grains' total kinetic energy below rest_energy [J].
  // The check holds no state of its own, so a restarted run stops where a straight one does.
  bool stop_at_rest = false;
  Real rest_after = 0, rest_energy = 0;
};

// A uniform mean pressure gradient G [Pa/m] added to the computed pressure field. A periodic axis
// makes the computed pressure periodic, so along it nothing carries a weight or drives a flow:
// G does. Fluid particles feel -G / rho0 per unit mass, each grain -G V (its volume; a uniform
// gradient acts at the centroid of a uniform grain). `weight` sets G to carry the whole box's
// weight, G = (fluid mass + grain mass) g / (fluid mass / rho0 + grain volume), so the forces on
// the box sum to zero and its momentum stays at zero: settling in a periodic array of grains.
// Components along non-periodic axes must be 0.
struct PressureGradient {
  bool weight = false;
  Vec3 value;  // Pa/m (weight = false)
  bool enabled() const { return weight || value.x != 0 || value.y != 0 || value.z != 0; }
};

struct Scene {
  std::string source;  // file it came from
  std::string name;
  int dim = 2;
  Vec3 domain_lo, domain_hi;  // particles leaving it are removed and counted
  bool periodic[3] = {false, false, false};
  Vec3 gravity{0, 0, -9.81};
  PressureGradient pressure_gradient;
  SymmetryPlane symmetry;  // core/symmetry.hpp; axis -1 = none
  FluidParams fluid;
  SphParams sph;
  TimeParams time;
  GuardParams guards;
  std::vector<Solid> solids;
  std::vector<FluidBlock> fluid_blocks;
  Diagnostics diagnostics;
  CheckpointParams checkpoint;
  ParallelParams parallel;
  FrameParams frames;
  InSituParams insitu;
  DemScene dem;
  Barrier barrier;
  std::string yaml_text;  // the resolved scene as YAML, stored in outputs and checkpoints

  Real h() const;  // smoothing length
  const Solid* find_solid(const std::string& name) const;
};

}  // namespace sphdem
