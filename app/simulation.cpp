#include "simulation.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <mpi.h>

#include "core/error.hpp"
#include "cuda/device.hpp"
#include "decomposition/distributed.hpp"
#include "diagnostics/guards.hpp"
#include "diagnostics/mirror.hpp"
#include "diagnostics/probes.hpp"
#include "io/checkpoint.hpp"
#include "io/csv_series.hpp"
#include "io/frames.hpp"
#include "io/insitu.hpp"
#include "coupling/grain_boundary.hpp"
#include "granular.hpp"
#include "scene/barrier.hpp"
#include "scene/build_dem.hpp"
#include "solver/mirror_exchange.hpp"
#include "run_common.hpp"

namespace sphdem {

Backend parse_backend(const std::string& s) {
  if (s == "auto") return Backend::kAuto;
  if (s == "host" || s == "cpu") return Backend::kHost;
  if (s == "device" || s == "gpu") return Backend::kDevice;
  throw InputError("--backend: '" + s + "' is not one of auto, host, device");
}

int world_size() {
  int init = 0;
  MPI_Initialized(&init);
  int size = 1;
  if (init) MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

int world_rank() {
  int init = 0;
  MPI_Initialized(&init);
  int rank = 0;
  if (init) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

std::array<int, 3> parse_procs(const std::string& s) {
  std::array<int, 3> p{0, 0, 0};
  if (s.empty()) return p;
  int k = 0;
  std::size_t at = 0;
  while (k < 3) {
    const std::size_t next = s.find_first_of("x,", at);
    const std::string part = s.substr(at, next == std::string::npos ? next : next - at);
    try {
      std::size_t used = 0;
      p[std::size_t(k)] = std::stoi(part, &used);
      if (used != part.size() || p[std::size_t(k)] < 0) throw std::invalid_argument(part);
    } catch (const std::exception&) {
      throw InputError("--procs: '" + s + "' is not three counts such as 2x1x1 (0 = any)");
    }
    ++k;
    if (next == std::string::npos) break;
    at = next + 1;
  }
  const auto seps = std::count_if(s.begin(), s.end(), [](char c) { return c == 'x' || c == ','; });
  if (k != 3 || seps != 2)
    throw InputError("--procs: '" + s + "' is not three counts such as 2x1x1 (0 = any)");
  return p;
}

namespace {
// Many ranks: how many of the scene's fixed-wall particles each rank holds (its box plus halo).
void log_walls_held(const MpiExchange& ex, SolverBase& solver, Index total, std::ostream& log) {
  long long mine = solver.host_particles().n_wall, most = 0, sum = 0;
  MPI_Allreduce(&mine, &most, 1, MPI_LONG_LONG, MPI_MAX, ex.comm());
  MPI_Allreduce(&mine, &sum, 1, MPI_LONG_LONG, MPI_SUM, ex.comm());
  log << "fixed-wall particles per rank (box plus halo): largest share " << most << " of " << total
      << ", " << sum << " on all ranks with the copies\n";
}

// Puts the wall slots of `built` (a build: fluid, then walls) into `ps`, which holds none,
// between its fluid and its grain particles.
void insert_walls(ParticleSet<Host>& ps, ParticleSet<Host>& built) {
  if (ps.n_wall != 0 || ps.n_halo != 0)
    throw std::logic_error("insert_walls: the set already holds walls or a halo");
  const Index nf = ps.n_fluid, wb = built.wall_begin(), nw = built.n_wall;
  std::vector<void*> from;
  built.for_each_field([&](const char*, auto& b) { from.push_back(&b); });
  std::size_t k = 0;
  ps.for_each_field([&](const char*, auto& f) {
    const auto& b = static_cast<std::decay_t<decltype(f)>*>(from[k++])->vec();
    auto& v = f.vec();
    v.insert(v.begin() + nf, b.begin() + wb, b.begin() + wb + nw);
  });
  ps.n_wall = nw;
}
}  // namespace

std::unique_ptr<SolverBase> make_solver(
    const Scene& scene, Backend backend, std::ostream& log, BuildReport* report,
    std::shared_ptr<MpiExchange>* exchange, std::array<int, 3> procs,
    const std::function<void(ParticleSet<Host>&, BuildReport&)>& prepare) {
  BuildReport rep;
  // Many ranks: no wall is stored until the boxes are known (they come from the fluid).
  const bool many = world_size() > 1;
  ParticleSet<Host> ps = build_particles(
      scene, &rep,
      many ? WallFilter([](const Vec3&, const Vec3&) { return false; }) : WallFilter{});
  if (world_rank() == 0) {
    describe_thin_solids(rep, scene.sph.dp, log);
    describe_surface_ties(rep, scene.sph.dp, log);
  }
  if (prepare) prepare(ps, rep);
  if (report) *report = rep;
  const Real c0 = resolve_sound_speed(scene, rep);
  if (rep.fluid == 0)
    throw InputError(scene.source + ": fluid_blocks: the scene holds no fluid particles");
  const int nranks = world_size();
  // A process grid asking for more ranks than this run has is refused (0 = any, counts as 1).
  const int asked = std::max(procs[0], 1) * std::max(procs[1], 1) * std::max(procs[2], 1);
  if (nranks == 1 && asked > 1)
    throw InputError("--procs: " + std::to_string(procs[0]) + "x" + std::to_string(procs[1]) + "x" +
                     std::to_string(procs[2]) + " asks for " + std::to_string(asked) +
                     " ranks, but this run has 1 (start it with mpirun -n " +
                     std::to_string(asked) + ")");
  if (nranks > 1 && scene.symmetry.enabled())
    throw InputError(scene.source +
                     ": symmetry: a symmetry plane runs on one rank only for now "
                     "(this run has " +
                     std::to_string(nranks) + " ranks)");
  std::shared_ptr<Exchange> mirror;
  if (scene.symmetry.enabled()) {
    const StepParams p = make_step_params(scene, c0);
    const SymmetryPlane& sym = scene.symmetry;
    mirror = std::make_shared<MirrorExchange>(sym, (Real(2.02) + scene.parallel.skin) * p.h,
                                              Real(2.02) * p.h);
    log << "symmetry plane "
        << "xyz"[sym.axis] << " = " << sym.at << ", modelling "
        << "xyz"[sym.axis] << (sym.keep > 0 ? " > " : " < ") << sym.at << ": "
        << rep.symmetry_fluid_dropped << " fluid and " << rep.symmetry_walls_dropped
        << " wall particles of the full scene not built; diagnostics report the mirrored full "
           "scene\n";
    std::vector<std::string> unpaired;
    mirror_solids(scene, &unpaired);
    for (const std::string& w : unpaired)
      log << "warning: symmetry: " << w
          << " has no mirror image among the barrier walls; impact_force.csv gives it its "
             "modelled part plus that part's mirror image\n";
    describe_symmetry_mismatch(rep, log);
  }
  if (nranks > 1) {
    const StepParams p = make_step_params(scene, c0);
    for (int k = 0; k < 3; ++k)
      if (p.grid.periodic[k])
        throw InputError(scene.source +
                         ": domain.periodic: a periodic axis runs on one rank only "
                         "for now (this run has " +
                         std::to_string(nranks) + " ranks)");
    // The halo: the kernel's reach plus the skin, and with mDBC the largest distance between a
    // wall particle's two ghost nodes. The rank owning the first ghost node gathers at both (the
    // fit takes the one that sees more fluid); a halo short of the second gave the V30 barrier
    // a 2e-5 difference from one rank within 8 steps (DistributedRun.ThinBarrierWalls...).
    const Real spread = p.mdbc ? rep.ghost_spread : Real(0);
    auto ex = std::make_shared<MpiExchange>(MPI_COMM_WORLD, p.grid, procs,
                                            (Real(2.02) + scene.parallel.skin) * p.h + spread,
                                            scene.parallel.imbalance);
    keep_owned_fluid(*ex, ps);
    ex->rebalance(ps);  // boxes from the initial histogram (DMSwarm moves the fluid)
    {
      // The walls: the scene's lattice again, each rank storing only the walls near its box.
      const int me = ex->rank();
      const bool by_ghost = p.mdbc;
      ParticleSet<Host> built = build_particles(scene, nullptr, [&](const Vec3& x, const Vec3& g) {
        return ex->keeps_wall(me, x, g, by_ghost);
      });
      insert_walls(ps, built);
    }
    const auto pr = ex->decomposition().procs();
    // One GPU per rank: the node-local rank modulo the GPUs this node has.
    std::string why;
    const auto gpus =
        backend == Backend::kHost ? std::vector<cuda::GpuInfo>{} : cuda::list_gpus(&why);
    if (backend == Backend::kDevice && gpus.empty())
      throw InputError("--backend device: no usable GPU (" + why + ")");
    if (!gpus.empty()) {
      MPI_Comm node;
      int local = 0;
      MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
      MPI_Comm_rank(node, &local);
      MPI_Comm_free(&node);
      const int dev = local % int(gpus.size());
      cuda::select_device(dev);
      log << "backend: device on every rank (rank 0: GPU " << dev << ", "
          << gpus[std::size_t(dev)].name << "), " << nranks << " ranks as " << pr[0] << " x "
          << pr[1] << " x " << pr[2] << " boxes, owned-fluid imbalance (max/mean) "
          << ex->last_imbalance() << "\n";
      if (exchange) *exchange = ex;
      auto solver = make_device_solver(scene, std::move(ps), c0, ex);
      log_walls_held(*ex, *solver, rep.wall, log);
      return solver;
    }
    {
      std::ostringstream cuts;
      for (int k = 0; k < 3; ++k) {
        const auto& st = ex->decomposition().cell_starts(k);
        if (st.size() <= 2) continue;
        cuts << " "
             << "xyz"[k] << " cuts at";
        for (std::size_t i = 1; i + 1 < st.size(); ++i)
          cuts << " " << p.grid.lo[k] + Real(st[i]) * p.grid.cell[k];
      }
      log << "boxes:" << cuts.str() << " m; halo " << ex->width() << " m";
      if (spread > 0) log << " (" << spread << " m of it for the mDBC walls' second ghost nodes)";
      log << "\n";
    }
    log << "backend: host, " << host_thread_count() << " OpenMP threads per rank, " << nranks
        << " ranks as " << pr[0] << " x " << pr[1] << " x " << pr[2]
        << " boxes, owned-fluid imbalance (max/mean) " << ex->last_imbalance() << "\n";
    if (exchange) *exchange = ex;
    auto solver = make_host_solver(scene, std::move(ps), c0, ex);
    log_walls_held(*ex, *solver, rep.wall, log);
    return solver;
  }
  bool device = false;
  if (backend != Backend::kHost) {
    std::string why;
    const auto gpus = cuda::list_gpus(&why);
    if (!gpus.empty()) {
      device = true;
      log << "backend: device (" << gpus[0].name << ")\n";
    } else if (backend == Backend::kDevice) {
      throw InputError("--backend device: no usable GPU (" + why + ")");
    } else {
      log << "backend: host, " << host_thread_count() << " OpenMP threads (no GPU: " << why
          << ")\n";
    }
  } else {
    log << "backend: host, " << host_thread_count() << " OpenMP threads\n";
  }
  std::unique_ptr<SolverBase> solver = device ? make_device_solver(scene, std::move(ps), c0, mirror)
                                              : make_host_solver(scene, std::move(ps), c0, mirror);
  // The mirror halo's width is known once the solver has kept its walls (their ghost nodes
  // across the plane can widen it).
  if (mirror)
    log << "symmetry: mirror halo " << static_cast<const MirrorExchange&>(*mirror).width()
        << " m of fluid on the modelled side\n";
  return solver;
}

namespace {

// Writes every particle as CSV: the emergency state dump when a guard fires. Roles: fluid (owned),
// halo (on many ranks, a copy of another rank's fluid particle as last refreshed: its owner's
// file holds the current state), wall, grain.
void write_state_csv(const ParticleSet<Host>& ps, const std::string& path) {
  std::ofstream f(path);
  f << "id,role,x,y,z,vx,vy,vz,rho,p\n" << std::setprecision(12);
  const Index grain_begin = ps.wall_begin() + ps.n_wall;
  for (Index i = 0; i < ps.size(); ++i) {
    const char* role = i < ps.n_fluid        ? "fluid"
                       : i < ps.wall_begin() ? "halo"
                       : i < grain_begin     ? "wall"
                                             : "grain";
    f << ps.id[i] << ',' << role << ',' << ps.pos[i].x << ',' << ps.pos[i].y << ',' << ps.pos[i].z
      << ',' << ps.vel[i].x << ',' << ps.vel[i].y << ',' << ps.vel[i].z << ',' << ps.rho[i] << ','
      << ps.press[i] << '\n';
  }
}

std::vector<std::string> profile_columns(const ProfileSpec& p) {
  if (p.velocity) return {"t", "s", "x", "y", "z", "u", "v", "w"};
  return {"t", "s", "x", "y", "z_surface"};
}

// Diagnostics of a run: one CSV per named diagnostic.
class DiagnosticWriter {
 public:
  // append: a restart continues the series already in `dir`, from keep_before (the checkpoint's
  // time; rows from then on were written after the checkpoint and are dropped).
  // enabled = false (ranks other than 0): no files; write() must not be called.
  DiagnosticWriter(const Scene& s, const std::string& dir, bool append, bool enabled = true,
                   double keep_before = INFINITY)
      : scene_(s), dir_(dir) {
    const Diagnostics& d = s.diagnostics;
    for (std::size_t i = 0; i < d.profiles.size(); ++i) profile_next_.push_back(0);
    if (!enabled) return;
    using Cols = std::vector<std::string>;
    auto path = [&](const std::string& name) { return dir + "/" + name + ".csv"; };
    for (const auto& g : d.pressure_gauges)
      pressure_.emplace_back(path(g.name), Cols{"t", "p"}, append, keep_before);
    for (const auto& g : d.height_gauges)
      height_.emplace_back(path(g.name), Cols{"t", "h"}, append, keep_before);
    for (const auto& g : d.fronts)
      front_.emplace_back(path(g.name), Cols{"t", "x_front"}, append, keep_before);
    if (!d.velocity_gauges.empty()) {
      Cols c{"t"};
      for (const auto& g : d.velocity_gauges)
        for (const char* q : {"_u", "_depth", "_froude"}) c.push_back(g.name + q);
      velocity_.open(path("velocity_gauges"), c, append, keep_before);
    }
    for (const auto& g : d.forces)
      force_.emplace_back(path(g.name), Cols{"t", "fx", "fy", "fz"}, append, keep_before);
    for (const auto& g : d.profiles) {
      profile_.emplace_back(path(g.name), profile_columns(g), append, keep_before);
    }
    if (limiter_stats(s))
      mdbc_.open(path("mdbc_limiter"),
                 {"t", "clipped", "rho_fit_max", "rho_cut_max", "clip_x_lo", "clip_x_hi", "cut_x",
                  "cut_y", "cut_z"},
                 append, keep_before);
    // Always: how near the run comes to its stability guards (docs/SCENES.md, outputs).
    guards_.open(path("guards"),
                 {"t", "steps", "max_speed", "mach", "rho_min", "rho_max", "dt_min"}, append,
                 keep_before);
    guards_on_ = true;
    if (d.energy)
      energy_.open(path("energy"), {"t", "kinetic", "potential", "total", "px", "py", "pz"}, append,
                   keep_before);
    if (s.barrier.enabled) {
      Cols c{"t"};
      for (int k = 1; k <= s.barrier.walls; ++k) {
        c.push_back("barrier_" + std::to_string(k) + "_fx");
        c.push_back("barrier_" + std::to_string(k) + "_f");
      }
      c.push_back("total_fx");
      c.push_back("total_f");
      // Barrier walls that are also DEM walls: the grains' contact force on each, after the
      // fluid's (a file of an earlier run keeps its own columns: see CsvSeries::open).
      for (int k = 1; k <= s.barrier.walls; ++k)
        if (grain_wall(s, k)) {
          c.push_back("barrier_" + std::to_string(k) + "_grain_fx");
          c.push_back("barrier_" + std::to_string(k) + "_grain_f");
          grain_cols_ = true;
        }
      if (grain_cols_) {
        c.push_back("total_grain_fx");
        c.push_back("total_grain_f");
      }
      impact_.open(path("impact_force"), c, append, keep_before);
      runup_.open(path("runup"), {"t", "runup", "x", "y"}, append, keep_before);
      trap_.open(path("trap"),
                 {"t", "fluid_mass_upstream", "fluid_mass_downstream", "grains_upstream",
                  "grains_downstream"},
                 append, keep_before);
    }
  }
  // mdbc_limiter.csv: what the mDBC density limiter does (clips, or would clip with it off) at
  // each diagnostic time; written where the wall loads are measured or the limiter is on: mDBC
  // walls with a barrier, a force probe (diagnostics.forces) or the limiter. With it off the
  // file says where the limiter would act (docs/VALIDATION.md compares the two on a thin plate).
  static bool limiter_stats(const Scene& s) {
    return s.sph.boundary == BoundaryMethod::kMdbc &&
           (s.barrier.enabled || s.sph.mdbc_limiter || !s.diagnostics.forces.empty());
  }
  // The limiter's effect for the next write (collective: every rank computes it).
  void set_mdbc_limiter(const MdbcLimiterStats& st) { mdbc_stats_ = st; }

  // Barrier wall k (1-based) is a DEM wall: grains press on it.
  static bool grain_wall(const Scene& s, int k) {
    for (const GrainWall& w : s.dem.walls)
      if (w.solid == "barrier_" + std::to_string(k)) return true;
    return false;
  }
  // The grains' contact force on each barrier wall (index k - 1) for the next write: the mean over
  // the last fluid step's DEM sub-steps.
  void set_barrier_grain_force(std::vector<Vec3> f) { barrier_grain_ = std::move(f); }

  std::vector<std::int64_t> profile_state() const {
    return std::vector<std::int64_t>(profile_next_.begin(), profile_next_.end());
  }
  void set_profile_state(const std::vector<std::int64_t>& v) {
    for (std::size_t i = 0; i < v.size() && i < profile_next_.size(); ++i)
      profile_next_[i] = std::size_t(v[i]);
  }

  // guards.csv: every step's reductions join the span of the next row (all ranks call this; the
  // reductions agree).
  void add_step(const StepStats& st) { span_.add(st); }
  // The row for the steps since the previous one (none before the first step), at time t; the
  // run's last row when a guard fires, whose span ends with the step the guard judged.
  // Every rank resets its span here, so the spans agree across ranks (a checkpoint holds it).
  void write_guards(Real t, Real c0) {
    if (span_.steps == 0) return;
    if (guards_on_)
      guards_.row({t, double(span_.steps), span_.max_speed, span_.max_speed / c0, span_.rho_min,
                   span_.rho_max, span_.dt_min});
    span_ = GuardSpan{};
  }
  const GuardSpan& guard_span() const { return span_; }
  void set_guard_span(const GuardSpan& s) { span_ = s; }

  void write(Real t, const ParticleSet<Host>& ps, const StepParams& p) {
    write_guards(t, p.eos.c0);
    // A symmetry plane: every diagnostic reads the mirrored full scene.
    if (scene_.symmetry.enabled()) {
      if (mirror_.empty()) mirror_ = mirror_solids(scene_);
      write_full(t, mirror_full(ps, scene_.symmetry, mirror_), p);
    } else {
      write_full(t, ps, p);
    }
  }

  void write_full(Real t, const ParticleSet<Host>& ps, const StepParams& p) {
    const Diagnostics& d = scene_.diagnostics;
    for (std::size_t i = 0; i < d.pressure_gauges.size(); ++i)
      pressure_[i].row({t, probe_pressure(ps, p, d.pressure_gauges[i].point)});
    for (std::size_t i = 0; i < d.height_gauges.size(); ++i) {
      const Real h = probe_surface_height(ps, p, d.height_gauges[i].x, d.height_gauges[i].y);
      height_[i].row({t, std::isfinite(h) ? h : 0.0});
    }
    for (std::size_t i = 0; i < d.fronts.size(); ++i)
      front_[i].row({t, probe_front(ps, d.fronts[i].origin, d.fronts[i].direction)});
    if (!d.velocity_gauges.empty()) {
      std::vector<double> row{t};
      for (const auto& g : d.velocity_gauges) {
        const ChannelFlow c = probe_channel_flow(ps, p, scene_.gravity, g.x, g.y);
        row.insert(row.end(), {c.u, c.depth, c.froude});
      }
      velocity_.row(row);
    }
    for (std::size_t i = 0; i < d.forces.size(); ++i) {
      int idx = -1;
      for (std::size_t s = 0; s < scene_.solids.size(); ++s)
        if (scene_.solids[s].name == d.forces[i].solid) idx = int(s);
      const Vec3 f = probe_solid_force(ps, idx);
      force_[i].row({t, f.x, f.y, f.z});
    }
    for (std::size_t i = 0; i < d.profiles.size(); ++i) {
      const ProfileSpec& pr = d.profiles[i];
      while (profile_next_[i] < pr.times.size() && t >= pr.times[profile_next_[i]]) {
        const int n = std::max(2, pr.samples);
        // One file per requested time as well (<name>_<time>.csv, the time as in the scene),
        // which is what a plot of the profile at 0.7 s wants to open.
        char tag[32];
        std::snprintf(tag, sizeof tag, "%g", double(pr.times[profile_next_[i]]));
        CsvSeries at(dir_ + "/" + pr.name + "_" + tag + ".csv", profile_columns(pr));
        for (int k = 0; k < n; ++k) {
          const Real s = Real(k) / Real(n - 1);
          const Vec3 x = pr.from + (pr.to - pr.from) * s;
          std::vector<double> row{t, s * norm(pr.to - pr.from), x.x, x.y};
          if (pr.velocity) {
            const Vec3 u = probe_velocity(ps, p, x);
            row.insert(row.end(), {x.z, u.x, u.y, u.z});
          } else {
            const Real z = probe_surface_height(ps, p, x.x, x.y);
            row.push_back(std::isfinite(z) ? z : 0.0);
          }
          profile_[i].row(row);
          at.row(row);
        }
        ++profile_next_[i];
      }
    }
    if (d.energy) {
      const Energy e = probe_energy(ps, scene_.gravity);
      energy_.row({t, e.kinetic, e.potential, e.kinetic + e.potential, e.momentum.x, e.momentum.y,
                   e.momentum.z});
    }
    if (scene_.barrier.enabled) write_barrier(t, ps, p);
    // No row before the run's (or restart's) first step: the solver has no cell lists yet.
    if (limiter_stats(scene_) && !std::isnan(mdbc_stats_.clipped))
      mdbc_.row({t, mdbc_stats_.clipped, mdbc_stats_.rho_fit_max, mdbc_stats_.rho_cut_max,
                 mdbc_stats_.clip_x_lo, mdbc_stats_.clip_x_hi, mdbc_stats_.cut_at.x,
                 mdbc_stats_.cut_at.y, mdbc_stats_.cut_at.z});
  }

  // impact_force.csv: the fluid force on each barrier wall, its component along the channel (x)
  // and its magnitude, and the row's total; runup.csv: the run-up at the barrier.
  void write_barrier(Real t, const ParticleSet<Host>& ps, const StepParams& p) {
    std::vector<double> row{t};
    Vec3 total;
    for (int k = 1; k <= scene_.barrier.walls; ++k) {
      const std::string name = "barrier_" + std::to_string(k);
      int idx = -1;
      for (std::size_t s = 0; s < scene_.solids.size(); ++s)
        if (scene_.solids[s].name == name) idx = int(s);
      const Vec3 f = probe_solid_force(ps, idx);
      total += f;
      row.push_back(f.x);
      row.push_back(norm(f));
    }
    row.push_back(total.x);
    row.push_back(norm(total));
    if (grain_cols_) {
      Vec3 grains;
      for (int k = 1; k <= scene_.barrier.walls; ++k) {
        if (!grain_wall(scene_, k)) continue;
        const std::size_t i = std::size_t(k - 1);
        const Vec3 f = i < barrier_grain_.size() ? barrier_grain_[i] : Vec3();
        grains += f;
        row.push_back(f.x);
        row.push_back(norm(f));
      }
      row.push_back(grains.x);
      row.push_back(norm(grains));
    }
    impact_.row(row);
    const Runup r = barrier_runup(scene_.barrier, ps, p.radius2, p.dp);
    runup_.row({t, r.height, r.where.x, r.where.y});
    const Trap tr = barrier_trap(scene_.barrier, ps);
    trap_.row({t, tr.fluid_upstream, tr.fluid_downstream, double(tr.grains_upstream),
               double(tr.grains_downstream)});
  }

 private:
  const Scene& scene_;
  std::string dir_;
  std::vector<CsvSeries> pressure_, height_, front_, force_, profile_;
  std::vector<std::size_t> profile_next_;
  std::vector<std::int32_t> mirror_;  // symmetry plane: each solid's mirror image
  CsvSeries energy_, impact_, runup_, trap_, velocity_, mdbc_, guards_;
  bool guards_on_ = false;           // rank 0 writes guards.csv
  GuardSpan span_;                   // add_step
  MdbcLimiterStats mdbc_stats_;      // set_mdbc_limiter
  bool grain_cols_ = false;          // impact_force.csv has the grains' columns
  std::vector<Vec3> barrier_grain_;  // set_barrier_grain_force
};

// Both to the terminal and to run.log.
}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& opt) {
  if (is_granular(scene)) return run_granular(scene, opt);
  const std::string restart_file = prepare_output(opt);
  const bool restarting = !restart_file.empty();
  const int rank = world_rank();
  const bool root = rank == 0;

  Log log(opt.out_dir + "/run.log", opt.quiet, restarting, root);
  if (root) {
    std::ofstream y(opt.out_dir + "/scene.yaml");
    y << scene.yaml_text;
  }
  log << "sphdem " << SPHDEM_VERSION << " (" << SPHDEM_PRECISION_NAME << ") scene '" << scene.name
      << "' from " << scene.source << "\n";
  std::ostringstream slog;
  BuildReport rep;
  std::shared_ptr<MpiExchange> ex;
  // ---- coupled runs (scene.dem with fluid): grains, their boundary particles, fluid loads ----
  DemBuild dem;
  std::unique_ptr<GrainCoupling> coupling;
  std::function<void(ParticleSet<Host>&, BuildReport&)> prepare;
  if (scene.dem.enabled) {
    // Keys of grain-only runs that a coupled run does not honour are refused, not ignored.
    if (scene.dem.settle_until > 0)
      throw InputError(scene.source +
                       ": dem.settle: the packing drag applies to grain-only runs (no "
                       "fluid_blocks); grains in a fluid settle through the fluid");
    if (scene.dem.heap)
      throw InputError(scene.source +
                       ": dem.heap: the heap measurement applies to grain-only runs");
    if (scene.dem.stop_at_rest)
      throw InputError(scene.source +
                       ": dem.stop_at_rest: stopping at rest applies to grain-only runs (no "
                       "fluid_blocks)");
    dem = build_dem(scene, slog);
    coupling = std::make_unique<GrainCoupling>(*dem.system, scene.sph.dp, boundary_depth(scene),
                                               scene.fluid.rho0, scene.dim);
    prepare = [&](ParticleSet<Host>& ps, BuildReport& br) {
      // Ids after the scene's fluid and walls (on many ranks the set holds no walls yet).
      br.fluid -= coupling->append(ps, *dem.system, GlobalId(br.fluid + br.wall));
      br.grain = coupling->particle_count();
    };
  }
  // dem.subcycle: false runs both phases on one step: the fluid step is capped at the DEM step.
  Scene capped;
  const bool one_step = coupling && !scene.dem.subcycle;
  if (one_step) {
    capped = scene;
    capped.time.dt_max = scene.time.dt_max > 0 ? std::min(scene.time.dt_max, dem.dt) : Real(dem.dt);
  }
  auto solver =
      make_solver(one_step ? capped : scene, opt.backend, slog, &rep, &ex, opt.procs, prepare);
  std::vector<Vec3> grain_force, grain_torque;
  if (coupling && ex)  // many ranks: each rank holds the grain particles near its box
    solver->set_grain_source(
        [&](const Vec3& lo, const Vec3& hi) { return coupling->generate(*dem.system, lo, hi); },
        coupling->particle_count());
  if (coupling) {
    slog << "grains: " << dem.system->bodies().size() << " in the fluid, "
         << coupling->particle_count() << " grain boundary particles; DEM step " << dem.dt
         << (one_step ? " s, one step for both phases (dem.subcycle: false)\n"
                      : " s, sub-cycled within each fluid step\n");
  }
  // ---- a mean pressure gradient (scene.hpp PressureGradient): the fluid's body acceleration
  // becomes g - G / rho0 and each grain feels -G V. Periodic axes only, so one rank. ----
  std::vector<Vec3> gradient_force;  // -G V per grain
  if (scene.pressure_gradient.enabled()) {
    const ParticleSet<Host>& hp = solver->host_particles();
    double fluid_mass = 0, grain_mass = 0, grain_volume = 0;
    for (Index i = 0; i < hp.n_fluid; ++i) fluid_mass += double(hp.mass[i]);
    if (coupling) {
      for (const dem::RigidBody& b : dem.system->bodies()) {
        grain_mass += double(b.mass);
        grain_volume += double(dem.system->shape(b.shape).volume());
      }
    }
    const double rho0 = double(scene.fluid.rho0);
    const Vec3 G =
        scene.pressure_gradient.weight
            ? scene.gravity * Real((fluid_mass + grain_mass) / (fluid_mass / rho0 + grain_volume))
            : scene.pressure_gradient.value;
    solver->set_body_acceleration(scene.gravity - G / scene.fluid.rho0);
    if (coupling)
      for (const dem::RigidBody& b : dem.system->bodies())
        gradient_force.push_back(-G * dem.system->shape(b.shape).volume());
    const Vec3 a = solver->params().gravity;
    slog << "pressure gradient: G = (" << G.x << ", " << G.y << ", " << G.z << ") Pa/m"
         << (scene.pressure_gradient.weight ? " carries the weight of fluid and grains" : "")
         << "; fluid body acceleration (" << a.x << ", " << a.y << ", " << a.z << ") m/s^2\n";
  }
  MPI_Comm comm = ex ? ex->comm() : MPI_COMM_SELF;
  // What this rank writes (checkpoints, frames), and what rank 0 evaluates diagnostics on.
  // Calls f with this rank's share (one rank: the solver's particles, without a copy).
  auto with_share = [&](auto&& f) {
    if (ex) {
      f(output_share(solver->host_particles(), solver->wall_mine()));
    } else {
      f(solver->host_particles());
    }
  };
  auto gathered = [&]() {
    return ex ? gather_on_root(comm, solver->host_particles(), solver->wall_mine())
              : solver->host_particles();
  };
  log << slog.str();
  const StepParams& p = solver->params();
  log << "particles: " << rep.fluid << " fluid, " << rep.wall << " wall boundary, " << rep.grain
      << " grain boundary; dp = " << p.dp << " m, h = " << p.h << " m, c0 = " << p.eos.c0
      << " m/s\n";

  Real next_diag = 0;
  std::vector<std::int64_t> profile_state;
  std::optional<GuardSpan> guard_span;  // the checkpoint's, when it has one
  if (restarting) {
    CheckpointData cp = read_checkpoint(restart_file);
    // A gate removed before the checkpoint left it without the gate's boundary particles.
    Index boundary = rep.wall + rep.grain;
    for (std::size_t s = 0; s < scene.solids.size(); ++s)
      if (!scene.solids[s].removed_by(0) && scene.solids[s].removed_by(cp.counters.time))
        boundary -= rep.wall_by_solid[s];
    check_checkpoint_matches(cp, scene, boundary, restart_file);
    if (coupling) {
      if (cp.dem.bodies.empty())
        throw InputError(restart_file + ": holds no grains; it is not a checkpoint of '" +
                         scene.name + "'");
      try {
        dem.system->restore(cp.dem);
      } catch (const InputError& e) {
        throw InputError(restart_file + ": " + e.what());
      }
      // The fluid's loads of the checkpoint's step, for the first bodies.csv row.
      for (std::size_t i = 0; i < dem.system->bodies().size(); ++i) {
        grain_force.push_back(dem.system->external_force(i));
        grain_torque.push_back(dem.system->external_torque(i));
      }
    }
    if (ex) distribute_after_read(*ex, cp.particles, solver->params().mdbc);
    next_diag = cp.next_output_time;
    profile_state = cp.profile_next;
    if (cp.guard_steps >= 0) {
      GuardSpan g;
      g.steps = cp.guard_steps;
      g.max_speed = Real(cp.guard_max_speed);
      g.rho_min = Real(cp.guard_rho_min);
      g.rho_max = Real(cp.guard_rho_max);
      g.dt_min = Real(cp.guard_dt_min);
      guard_span = g;
    }
    solver->restore(std::move(cp.particles), cp.counters);
    log << "restarted from " << restart_file << " at t = " << solver->time() << " s, step "
        << solver->step_count() << "\n";
  }

  RunResult r;
  r.fluid = rep.fluid;
  r.wall = rep.wall;
  r.grain = rep.grain;
  r.space = solver->space_name();
  // Rows at or after the checkpoint's time were written after it: a restart drops them. (Not
  // next_diag: with diagnostics.every below the step it lags the time.)
  const double keep_before = restarting ? double(solver->time()) : INFINITY;
  DiagnosticWriter diag(scene, opt.out_dir, restarting, root, keep_before);
  diag.set_profile_state(profile_state);
  if (guard_span) diag.set_guard_span(*guard_span);
  std::unique_ptr<std::ofstream> bodies_csv;
  if (coupling && root) {  // the DEM is replicated on every rank: rank 0 writes it
    // A restart drops the rows written after its checkpoint (a killed run's last rows) first.
    if (restarting) CsvSeries::trim(opt.out_dir + "/bodies.csv", keep_before);
    bodies_csv = std::make_unique<std::ofstream>(opt.out_dir + "/bodies.csv",
                                                 restarting ? std::ios::app : std::ios::trunc);
    *bodies_csv << std::setprecision(10);
    if (!restarting) *bodies_csv << "t,id,x,y,z,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz\n";
  }
  // The grains' contact load on each scene solid (by body index; zero for a solid that is no
  // DEM wall): the mean over the last fluid step (DemSystem::wall_mean_force).
  auto solid_grain_force = [&]() {
    std::vector<Vec3> f(scene.solids.size());
    if (coupling)
      for (std::size_t j = 0; j < dem.wall_solid.size(); ++j)
        for (std::size_t s = 0; s < scene.solids.size(); ++s)
          if (scene.solids[s].name == dem.wall_solid[j]->name)
            f[s] += dem.system->wall_mean_force(dem.wall_index[j]);
    return f;
  };
  auto write_diagnostics = [&]() {
    if (DiagnosticWriter::limiter_stats(scene)) diag.set_mdbc_limiter(solver->mdbc_limiter_stats());
    if (coupling && scene.barrier.enabled) {  // the grains' load on each barrier wall
      const std::vector<Vec3> by_solid = solid_grain_force();
      std::vector<Vec3> f(std::size_t(std::max(scene.barrier.walls, 0)));
      for (std::size_t s = 0; s < scene.solids.size(); ++s)
        for (int k = 1; k <= scene.barrier.walls; ++k)
          if (scene.solids[s].name == "barrier_" + std::to_string(k))
            f[std::size_t(k - 1)] += by_solid[s];
      diag.set_barrier_grain_force(std::move(f));
    }
    if (bodies_csv) {  // each grain's state and the fluid's force and torque on it
      const auto& bodies = dem.system->bodies();
      for (std::size_t i = 0; i < bodies.size(); ++i) {
        const dem::RigidBody& b = bodies[i];
        const Vec3 w = dem::world_omega(b);
        const Vec3 f = i < grain_force.size() ? grain_force[i] : Vec3();
        const Vec3 t = i < grain_torque.size() ? grain_torque[i] : Vec3();
        *bodies_csv << solver->time() << "," << b.id << "," << b.x.x << "," << b.x.y << "," << b.x.z
                    << "," << b.v.x << "," << b.v.y << "," << b.v.z << "," << w.x << "," << w.y
                    << "," << w.z << "," << f.x << "," << f.y << "," << f.z << "," << t.x << ","
                    << t.y << "," << t.z << "\n";
      }
    }
    if (!ex) {
      diag.write(solver->time(), solver->host_particles(), p);
      return;
    }
    const ParticleSet<Host> all = gathered();
    if (root)
      diag.write(solver->time(), all, p);
    else
      diag.write_guards(solver->time(), p.eos.c0);  // no row here, but the span is reset with
                                                    // rank 0's, so a checkpoint's attributes agree
  };
  // The particle the Mach or the density guard names: the fastest, densest or lightest fluid
  // particle over all ranks (every rank calls this together, since the step's reductions agree).
  auto locate_extreme = [&](Extreme e) -> std::string {
    ExtremeFluid f = extreme_fluid(solver->host_particles(), e);
    if (ex) {
      struct {
        double key;
        int rank;
      } mine{f.key, rank}, top{};
      MPI_Allreduce(&mine, &top, 1, MPI_DOUBLE_INT, MPI_MAXLOC, comm);
      double buf[8] = {f.key,           double(f.pos.x), double(f.pos.y), double(f.pos.z),
                       double(f.vel.x), double(f.vel.y), double(f.vel.z), double(f.rho)};
      std::uint64_t id = f.id;
      MPI_Bcast(buf, 8, MPI_DOUBLE, top.rank, comm);
      MPI_Bcast(&id, 1, MPI_UINT64_T, top.rank, comm);
      f = ExtremeFluid{buf[0], GlobalId(id), Vec3(Real(buf[1]), Real(buf[2]), Real(buf[3])),
                       Vec3(Real(buf[4]), Real(buf[5]), Real(buf[6])), Real(buf[7])};
    }
    return fluid_particle_text(f) + near_solid_text(scene, solver->time(), f.pos,
                                                    rep.boundary_depth, rep.thin,
                                                    rep.boundary_depth);
  };
  std::unique_ptr<FrameWriter> frames;
  Real next_frame = 0;
  if (scene.frames.every > 0) {
    frames = std::make_unique<FrameWriter>(opt.out_dir, scene.frames, scene.dim);
    if (restarting) {
      frames->adopt_existing(solver->time());
      next_frame = scene.frames.every * Real(frames->count());
    }
  }

  auto save = [&](const std::string& path) {
    CheckpointData cp;
    with_share([&](const ParticleSet<Host>& sh) { cp.particles = sh; });  // a copy
    cp.counters = solver->counters();
    cp.next_output_time = next_diag;
    cp.profile_next = diag.profile_state();
    const GuardSpan& gs = diag.guard_span();
    cp.guard_steps = gs.steps;
    cp.guard_max_speed = double(gs.max_speed);
    cp.guard_rho_min = double(gs.rho_min);
    cp.guard_rho_max = double(gs.rho_max);
    cp.guard_dt_min = double(gs.dt_min);
    if (ex) {  // rank 0 evaluates the profiles; the file's attributes must agree on all ranks
      MPI_Bcast(cp.profile_next.data(), int(cp.profile_next.size()), MPI_INT64_T, 0, comm);
      // The guard span is each rank's own (reset at every diagnostics time on all ranks).
      std::int64_t span[2] = {cp.guard_steps, -cp.guard_steps};
      MPI_Allreduce(MPI_IN_PLACE, span, 2, MPI_INT64_T, MPI_MAX, comm);
      if (span[0] != -span[1])
        throw RuntimeFault("checkpoint: the guards.csv span holds " + std::to_string(-span[1]) +
                           " to " + std::to_string(span[0]) +
                           " steps across the ranks; they must agree");
    }
    cp.scene_yaml = scene.yaml_text;
    cp.dim = scene.dim;
    cp.dp = scene.sph.dp;
    if (coupling) cp.dem = dem.system->state();
    if (bodies_csv) bodies_csv->flush();
    const auto t0 = std::chrono::steady_clock::now();
    const std::uint64_t bytes = write_checkpoint(path, cp);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++r.checkpoints;
    r.last_checkpoint = path;
    log << "checkpoint " << path << " (" << bytes / 1048576.0 << " MiB, " << s
        << " s) at t = " << solver->time() << " s\n";
  };

  // ---- in situ (io/insitu.hpp): Catalyst extracts at insitu.every_steps; a no-op without
  // insitu.scripts. Destroyed when run_scene returns, before MPI_Finalize. ----
  std::unique_ptr<InSituAdaptor> insitu = make_insitu_adaptor(scene, opt.out_dir);
  if (!scene.insitu.scripts.empty())
    log << "in situ: " << insitu->name() << ", " << scene.insitu.scripts.size()
        << " script(s) every " << scene.insitu.every_steps << " steps, extracts in " << opt.out_dir
        << "/catalyst\n";
  // ---- end in situ ----

  // ---- gates (Solid::removed_at): a solid removed by the current time takes its boundary
  // particles out of the run and its DEM wall out of the contacts, right after the step that
  // reaches removed_at (so no later checkpoint holds them). ----
  std::vector<char> opened(scene.solids.size(), 0);
  auto open_gates = [&]() {
    for (std::size_t s = 0; s < scene.solids.size(); ++s) {
      const Solid& so = scene.solids[s];
      if (opened[s] || !so.removed_by(solver->time())) continue;
      opened[s] = 1;
      const Index n = so.removed_by(0) ? 0 : solver->remove_solid(std::int32_t(s));
      if (so.removed_at > 0 && (n > 0 || !restarting))
        log << "t = " << solver->time() << " s: solid '" << so.name
            << "' removed (removed_at = " << so.removed_at << " s), " << n
            << " boundary particles\n";
    }
    if (coupling) update_walls(scene, dem, dem.system->time());
  };
  open_gates();

  SignalGuard signals(opt.handle_signals);
  const bool tty = root && !opt.quiet && isatty(STDOUT_FILENO);  // rank 0 prints progress
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last_progress = start, last_checkpoint_wall = start;
  const CheckpointParams& ck = scene.checkpoint;
  Real next_checkpoint_time =
      ck.every_time > 0
          ? ck.every_time * (std::floor(solver->time() / ck.every_time + Real(1e-9)) + 1)
          : Real(0);
  const Real end = scene.time.end;
  double particle_steps = 0;
  std::int64_t steps = 0;
  const int guard_every = scene.guards.check_every > 0                    ? scene.guards.check_every
                          : std::string(solver->space_name()) == "device" ? 20
                                                                          : 1;
  LoopTimes lt;  // the loop's own phases (bench: opt.time_after_steps)
  TimingMark mark;
  try {
    while (solver->time() < end - Real(1e-12) * end &&
           (opt.max_steps < 0 || steps < opt.max_steps)) {
      if (steps == opt.time_after_steps) mark = {clock::now(), solver->phase_times(), lt};
      timed(lt.io, [&] {
        if (solver->time() >= next_diag - Real(1e-12)) {
          write_diagnostics();
          next_diag += scene.diagnostics.every;
        }
        if (frames && solver->time() >= next_frame - Real(1e-12)) {
          with_share([&](const ParticleSet<Host>& sh) { frames->write(solver->time(), sh); });
          next_frame += scene.frames.every;
        }
        if (insitu->due(solver->step_count()))  // in situ (see above)
          with_share([&](const ParticleSet<Host>& sh) {
            insitu->execute(solver->step_count(), solver->time(), sh, p, solid_grain_force());
          });
      });
      if (coupling)  // the grain boundary particles take the grains' poses at t^n
        timed(lt.coupling, [&] { solver->pose_grains(coupling->table(), dem.system->bodies()); });
      const StepStats st = solver->step();
      diag.add_step(st);  // guards.csv, before any guard can fire on this step
      if (coupling) {
        // The fluid's force on each grain at t^n drives the DEM from t^n to t^n + dt, in
        // sub-steps no longer than the DEM step (contacts between grains and with walls).
        dem::DemSystem& sys = *dem.system;
        timed(lt.coupling, [&] {
          // Many ranks: this rank's owned grain slots, then one sum over ranks (DESIGN.md §5).
          const std::vector<std::uint8_t> mine = solver->grain_mine();
          coupling->loads(solver->grain_particles(), sys, grain_force, grain_torque,
                          ex ? mine.data() : nullptr);
          if (ex) {
            std::vector<Real> ft(6 * grain_force.size());
            for (std::size_t i = 0; i < grain_force.size(); ++i)
              for (int a = 0; a < 3; ++a) {
                ft[6 * i + std::size_t(a)] = grain_force[i][a];
                ft[6 * i + 3 + std::size_t(a)] = grain_torque[i][a];
              }
            ex->sum(ft.data(), Index(ft.size()));
            for (std::size_t i = 0; i < grain_force.size(); ++i)
              for (int a = 0; a < 3; ++a) {
                grain_force[i][a] = ft[6 * i + std::size_t(a)];
                grain_torque[i][a] = ft[6 * i + 3 + std::size_t(a)];
              }
          }
          for (std::size_t i = 0; i < gradient_force.size(); ++i)
            grain_force[i] += gradient_force[i];
          for (std::size_t i = 0; i < sys.bodies().size(); ++i)
            sys.set_external(i, grain_force[i], grain_torque[i]);
        });
        const double want = std::ceil(double(st.dt) / double(dem.dt) - 1e-9);
        if (want > double(scene.dem.substeps_max))
          throw StabilityError(
              "DEM: the fluid step " + std::to_string(st.dt) + " s needs " + std::to_string(want) +
              " DEM sub-steps of " + std::to_string(dem.dt) +
              " s, more than dem.substeps_max = " + std::to_string(scene.dem.substeps_max));
        const int nsub = std::max(1, int(want));
        const Real h = st.dt / Real(nsub);
        timed(lt.dem, [&] {
          sys.reset_wall_impulse();  // the walls' mean load over this fluid step
          for (int k = 0; k < nsub; ++k) {
            update_walls(scene, dem, sys.time());
            sys.step(h);
          }
        });
        timed(lt.guards, [&] { check_grain_guards(scene, sys, dem.min_diameter); });
      }
      open_gates();
      ++steps;
      particle_steps += double(solver->fluid_count());  // no device download
      if (st.removed > 0)
        log << "t = " << solver->time() << " s: " << st.removed
            << " fluid particles left the domain\n";
      const auto guards_from = clock::now();
      check_step_guards(scene, p, st, solver->time(), solver->step_count(), locate_extreme);
      if (solver->fluid_count() == 0) {
        log << "t = " << solver->time() << " s: all fluid has left the domain; stopping\n";
        break;
      }
      if (steps % guard_every == 0) {
        if (!ex) {
          check_particle_guards(scene, p, solver->host_particles(), solver->time(),
                                solver->step_count());
        } else {
          // Collective: every rank stops if any rank's particles fail.
          std::string why;
          try {
            check_particle_guards(scene, p, solver->host_particles(), solver->time(),
                                  solver->step_count());
          } catch (const StabilityError& e) {
            why = e.what();
          }
          int bad = why.empty() ? 0 : 1, any = 0, first = 0;
          MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm);
          if (any) {
            const int me = bad ? rank : 1 << 30;
            MPI_Allreduce(&me, &first, 1, MPI_INT, MPI_MIN, comm);
            int len = int(why.size());
            MPI_Bcast(&len, 1, MPI_INT, first, comm);
            why.resize(std::size_t(len));
            MPI_Bcast(why.data(), len, MPI_CHAR, first, comm);
            throw StabilityError(why + " (rank " + std::to_string(first) + ")");
          }
        }
      }
      const auto now = clock::now();
      lt.guards += std::chrono::duration<double>(now - guards_from).count();
      // Checkpoints: by steps, simulated time, wall time, or on a signal.
      int sig = g_signal;
      const bool by_steps = ck.every_steps > 0 && solver->step_count() % ck.every_steps == 0;
      const bool by_time =
          ck.every_time > 0 && solver->time() >= next_checkpoint_time - Real(1e-12);
      bool by_wall =
          ck.every_wall > 0 &&
          std::chrono::duration<double>(now - last_checkpoint_wall).count() >= ck.every_wall;
      if (ex) {  // a signal or the wall clock on any rank checkpoints on all of them
        int f[2] = {sig, by_wall ? 1 : 0};
        MPI_Allreduce(MPI_IN_PLACE, f, 2, MPI_INT, MPI_MAX, comm);
        sig = f[0];
        by_wall = f[1] != 0;
      }
      if (by_steps || by_time || by_wall || sig != 0) {
        if (sig != 0) log << "signal " << (sig == SIGTERM ? "SIGTERM" : "SIGUSR1") << " received\n";
        timed(lt.io, [&] {
          save(checkpoint_path(opt.out_dir, solver->step_count()));
          prune_checkpoints(opt.out_dir, ck.keep);
        });
        last_checkpoint_wall = now;
        while (ck.every_time > 0 && next_checkpoint_time <= solver->time() + Real(1e-12))
          next_checkpoint_time += ck.every_time;
        g_signal = 0;
        if (sig == SIGTERM) {
          r.interrupted = true;
          log << "stopping on SIGTERM; continue with --restart latest\n";
          break;
        }
      }
      const double since = std::chrono::duration<double>(now - last_progress).count();
      if (root && !opt.quiet && (since > (tty ? 0.25 : opt.progress_every_s))) {
        last_progress = now;
        const double wall = std::chrono::duration<double>(now - start).count();
        const double rate = steps / wall;
        const double eta = (end - solver->time()) / st.dt / rate;
        std::ostringstream line;
        line << "t = " << std::setprecision(4) << solver->time()
             << " s, dt = " << std::setprecision(3) << st.dt << " s, step " << solver->step_count()
             << ", " << std::setprecision(3) << rate << " steps/s, " << particle_steps / wall
             << " particle-steps/s, ETA " << fmt_duration(eta);
        if (tty) {
          std::cout << "\r" << line.str() << "   " << std::flush;
        } else {
          std::cout << line.str() << "\n";
        }
        log.file() << line.str() << std::endl;  // flushed: tail -f run.log shows progress
      }
    }
    if (opt.time_after_steps >= 0 && steps > opt.time_after_steps) {
      r.timing = timing_since(mark, steps - opt.time_after_steps, solver->phase_times(), lt);
      r.timing.pairs = solver->last_pair_count();
      r.timing.fluid = solver->fluid_count();
      r.timing.boundary = r.wall + r.grain;  // all ranks' (the build report)
      if (coupling) {
        r.timing.grains = Index(dem.system->bodies().size());
        r.timing.contacts = double(dem.system->contact_count());
      }
    }
    if (!r.interrupted) {
      write_diagnostics();
      if (frames)
        with_share([&](const ParticleSet<Host>& sh) { frames->write(solver->time(), sh); });
    }
  } catch (const StabilityError& e) {
    r.unstable = true;
    r.failure = e.what();
    if (tty) std::cout << "\n";
    log << "ERROR: " << e.what() << "\n";
    diag.write_guards(solver->time(), p.eos.c0);  // the span that ends with the judged step
    const std::string dump = opt.out_dir + "/emergency_step" + std::to_string(solver->step_count());
    const std::string csv = dump + (ex ? "_rank" + std::to_string(rank) : std::string()) + ".csv";
    write_state_csv(solver->host_particles(), csv);
    save(dump + ".h5");
    log << "emergency state written to " << (ex ? dump + "_rank*.csv" : csv) << " and " << dump
        << ".h5\n";
  }
  if (tty && !r.unstable) std::cout << "\n";
  r.steps = steps;
  r.sim_time = solver->time();
  r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  r.removed = solver->removed_count();
  r.removed_mass = solver->removed_mass();
  r.particle_steps_per_second = r.wall_seconds > 0 ? particle_steps / r.wall_seconds : 0;
  if (ex)
    log << "ranks: " << ex->size() << ", halo rebuilt at " << solver->halo_rebuilds() << " of "
        << r.steps << " steps, rebalanced " << ex->rebalance_count()
        << " times, owned-fluid imbalance at the last check " << ex->last_imbalance() << "\n";
  if (ex && coupling) {  // DESIGN.md §5: each rank holds only the grain particles near its box
    const Real n = Real(solver->host_particles().n_grain);
    Real held[2] = {n, -n};
    ex->max(held, 2);
    log << "grain boundary particles held per rank (owned + copies): " << -held[1] << " to "
        << held[0] << " of " << coupling->particle_count() << "\n";
  }
  if (r.removed > 0)
    log << "removed (open ends): " << r.removed << " particles, " << r.removed_mass << " kg\n";
  log << "done: " << r.steps << " steps, t = " << r.sim_time << " s, " << r.wall_seconds
      << " s wall, " << r.particle_steps_per_second << " particle-steps/s\n";
  if (root) write_summary(opt.out_dir + "/summary.json", scene, r);
  log.flush();
  return r;
}

void check_scene(const Scene& scene, std::ostream& os) {
  if (is_granular(scene)) {
    check_granular(scene, os);
    return;
  }
  BuildReport rep;
  ParticleSet<Host> ps = build_particles(scene, &rep);
  std::ostringstream grains;
  if (scene.dem.enabled) {  // grains in the fluid: their boundary particles replace fluid
    std::ostringstream blog;
    DemBuild dem = build_dem(scene, blog);
    GrainCoupling coupling(*dem.system, scene.sph.dp, boundary_depth(scene), scene.fluid.rho0,
                           scene.dim);
    rep.fluid -= coupling.append(ps, *dem.system);
    rep.grain = coupling.particle_count();
    grains << blog.str() << "grains: " << dem.system->bodies().size() << ", DEM step " << dem.dt
           << " s\n";
  }
  const Real c0 = resolve_sound_speed(scene, rep);
  const StepParams p = make_step_params(scene, c0);
  // Estimated dt: acoustic limit at rest, force limit from gravity, viscous limit.
  const Real g = std::max(p.g_mag, Real(1e-12));
  const Real dt_f = std::sqrt(p.h / g);
  const Real dt_cv = p.h / c0;
  Real dt_v = p.laminar && p.nu > 0 ? Real(0.125) * p.h * p.h / p.nu : Real(1e30);
  // HBP: the viscous limit follows the largest mu_eff; mu_max bounds it (a pessimistic estimate).
  if (p.hbp) dt_v = Real(0.125) * p.h * p.h / (p.hbp_params.mu_max / p.eos.rho0);
  Real dt = std::min(scene.time.cfl * std::min(dt_f, dt_cv), dt_v);
  if (scene.time.dt_fixed > 0) dt = scene.time.dt_fixed;
  const double steps = std::ceil(scene.time.end / dt);
  // Memory: every field of every particle, plus the cell lists.
  std::size_t bytes_per = 0;
  ps.for_each_field([&](const char*, auto& b) { bytes_per += sizeof(*b.data()); });
  const double mem = double(bytes_per) * double(ps.size()) + 8.0 * double(p.grid.cell_count()) * 2;
  // Rough cost from the CPU figures in docs/BENCHMARKS.md: in 3D, double precision, a thread
  // does about 2e7 (fluid particle x neighbour)-steps/s for the whole step, the neighbours being
  // the lattice sites within 2h (1.3e7 before the pairwise fluid pass, which made the 3D dam
  // break's step 1.5-1.75x and the flume's 1.5-1.65x faster); 2D runs go faster. mDBC adds a
  // ghost-node gather per boundary particle, near fluid or not: about 1 us per particle-step in 3D
  // (0.7-1.2 us measured: the 3D dam break at 25k, and the flume's half scene at dp = 5 mm, 107k
  // walls, where it was a quarter of the step).
  const double kh = double(2 * p.h / p.dp);
  const double per_thread = scene.dim == 3 ? 2e7 / (4.18879 * kh * kh * kh) : 2.5e5;
  const double gathers = scene.sph.boundary == BoundaryMethod::kMdbc && scene.dim == 3
                             ? double(rep.wall + rep.grain) * 1e-6
                             : 0.0;
  const double cost =
      (double(rep.fluid) / per_thread + gathers) * steps / double(host_thread_count());
  os << "scene '" << scene.name << "' (" << scene.source << "), " << scene.dim << "D\n"
     << grains.str() << "particles: fluid " << rep.fluid << ", wall boundary " << rep.wall
     << ", grain boundary " << rep.grain << ", total " << ps.size() << "\n";
  describe_thin_solids(rep, scene.sph.dp, os);
  describe_surface_ties(rep, scene.sph.dp, os);
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    const Solid& so = scene.solids[s];
    if (so.removed_by(0)) {
      os << "solid '" << so.name << "': removed at t = 0 (removed_at), no boundary particles\n";
    } else if (so.removed_at < Real(1e29)) {
      os << "solid '" << so.name << "': " << rep.wall_by_solid[s]
         << " boundary particles, removed at t = " << so.removed_at << " s (removed_at)\n";
    }
  }
  if (scene.pressure_gradient.weight)
    os << "pressure gradient: carries the weight of fluid and grains (periodic box)\n";
  else if (scene.pressure_gradient.enabled())
    os << "pressure gradient: (" << scene.pressure_gradient.value.x << ", "
       << scene.pressure_gradient.value.y << ", " << scene.pressure_gradient.value.z << ") Pa/m\n";
  if (scene.symmetry.enabled()) {
    const SymmetryPlane& sym = scene.symmetry;
    os << "symmetry plane: "
       << "xyz"[sym.axis] << " = " << sym.at << ", modelling "
       << "xyz"[sym.axis] << (sym.keep > 0 ? " > " : " < ") << sym.at << " (the full scene has "
       << rep.fluid + rep.symmetry_fluid_dropped << " fluid particles; "
       << rep.symmetry_walls_dropped << " wall particles across the plane not built)\n";
    describe_symmetry_mismatch(rep, os);
    std::vector<std::string> unpaired;
    mirror_solids(scene, &unpaired);
    for (const std::string& w : unpaired)
      os << "warning: symmetry: " << w << " has no mirror image among the barrier walls\n";
  }
  os << "dp = " << p.dp << " m, h = " << p.h << " m, c0 = " << c0 << " m/s, cells " << p.grid.n[0]
     << " x " << p.grid.n[1] << " x " << p.grid.n[2] << "\n"
     << "memory estimate: " << std::setprecision(3) << mem / 1048576.0 << " MiB\n"
     << "time step estimate: " << dt << " s (force " << dt_f << ", acoustic " << dt_cv
     << ", viscous " << dt_v << "; CFL " << scene.time.cfl << ")\n"
     << "steps to t = " << scene.time.end << " s: about " << std::setprecision(6) << steps << "\n"
     << "rough cost on " << host_thread_count() << " CPU threads: " << fmt_duration(cost) << "\n";
  if (scene.barrier.enabled) {
    const Barrier& b = scene.barrier;
    // Boundary particles of the barrier walls (by body = solid index).
    std::vector<Index> per_wall(std::size_t(b.walls), 0);
    std::vector<int> wall_of_solid(scene.solids.size(), -1);
    for (int k = 0; k < b.walls; ++k)
      for (std::size_t s = 0; s < scene.solids.size(); ++s)
        if (scene.solids[s].name == "barrier_" + std::to_string(k + 1)) wall_of_solid[s] = k;
    for (Index i = ps.wall_begin(); i < ps.size(); ++i) {
      const std::int32_t body = ps.body[i];
      if (body >= 0 && wall_of_solid[std::size_t(body)] >= 0)
        ++per_wall[std::size_t(wall_of_solid[std::size_t(body)])];
    }
    Index walls = 0;
    for (Index n : per_wall) walls += n;
    os << "barrier: " << (b.preset.empty() ? std::string(1, b.layout) : b.preset) << ", " << b.walls
       << " walls " << b.width * 1000 << " x " << b.thickness * 1000 << " x " << b.height * 1000
       << " mm turned " << b.angle_deg << " deg, row at x = " << b.x
       << " m; effective opening ratio " << std::setprecision(4) << barrier_opening_ratio(b)
       << " (projected on the cross-channel axis); " << walls << " boundary particles\n";
    if (scene.dim == 3) {
      std::vector<bool> is_wall(scene.solids.size());
      for (std::size_t s = 0; s < scene.solids.size(); ++s) is_wall[s] = wall_of_solid[s] >= 0;
      const LatticeOpening lo = barrier_lattice_opening(b, ps, is_wall, scene.sph.dp);
      // The column count is a fair opening only for walls square to the lattice: a turned wall's
      // thin ends miss lattice points (its columns there are free of particles, not of the wall).
      bool square = true;
      for (const BarrierWall& w : barrier_walls(b)) square = square && w.angle == 0;
      if (square)
        os << "barrier on the lattice: " << lo.open << " of " << lo.columns
           << " columns across the channel hold no barrier wall particle (opening "
           << std::setprecision(4) << lo.ratio() << ")\n";
      if (lo.closed_gaps > 0)
        os << "warning: barrier: " << lo.closed_gaps << " of the " << lo.gaps
           << " gaps between the walls (and beside the channel's sides) hold no lattice column "
              "free of wall particles at dp = "
           << scene.sph.dp * 1000 << " mm, so no fluid passes there: refine dp\n";
    }
  }
}

}  // namespace sphdem
