#include "io/checkpoint.hpp"

#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <type_traits>

#include "core/error.hpp"
#include "io/h5_util.hpp"

namespace sphdem {

namespace {

std::string label(const std::string& path) {
  return "checkpoint '" + path + "'";
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  h5::fail(label(path), what);
}

// FNV-1a over bytes.
std::uint64_t fnv(const void* p, std::size_t n, std::uint64_t h) {
  const unsigned char* b = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= b[i];
    h *= 1099511628211ull;
  }
  return h;
}

// Order-independent checksum: the sum over particles of a hash of all of the particle's fields.
std::uint64_t local_checksum(const ParticleSet<Host>& ps_const) {
  auto& ps = const_cast<ParticleSet<Host>&>(ps_const);
  std::uint64_t sum = 0;
  for (Index i = 0; i < ps.size(); ++i) {
    if (i >= ps.n_fluid && i < ps.wall_begin()) continue;  // halo copies are not written
    std::uint64_t h = 1469598103934665603ull;
    ps.for_each_field([&](const char*, auto& b) { h = fnv(&b[std::size_t(i)], sizeof(b[0]), h); });
    sum += h;
  }
  return sum;
}

// Copies slots [begin, begin+n) of every field of `src` into a new set.
ParticleSet<Host> slice(const ParticleSet<Host>& src_const, Index begin, Index n) {
  auto& src = const_cast<ParticleSet<Host>&>(src_const);
  ParticleSet<Host> out;
  out.resize(n);
  std::vector<void*> dst;
  out.for_each_field([&](const char*, auto& b) { dst.push_back(&b); });
  std::size_t k = 0;
  src.for_each_field([&](const char*, auto& b) {
    using B = std::decay_t<decltype(b)>;
    auto* d = static_cast<B*>(dst[k++]);
    for (Index i = 0; i < n; ++i) (*d)[std::size_t(i)] = b[std::size_t(begin + i)];
  });
  return out;
}

}  // namespace

namespace h5 {
hid_t create_file(const std::string& path) {
  ensure_mpi();
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL);
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  H5Pclose(fapl);
  return f;
}
hid_t open_file_read(const std::string& path) {
  ensure_mpi();
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL);
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  return f;
}
}  // namespace h5

void ensure_mpi() {
  int init = 0;
  MPI_Initialized(&init);
  if (!init) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    std::atexit([] {
      int fin = 0;
      MPI_Finalized(&fin);
      if (!fin) MPI_Finalize();
    });
  }
}

namespace {

// FNV-1a over raw bytes: the DEM group's checksum.
std::uint64_t fnv(std::uint64_t h, const void* p, std::size_t n) {
  const auto* b = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  return h;
}

// The DEM state as flat arrays, in a fixed order (write, read and checksum share it).
struct DemArrays {
  std::vector<Vec3> x, v, w, inertia, acc_prev, alpha_prev, wall_point, wall_offset, springs;
  // Optional (not in checkpoints before 2026-12-02): the last loads and the pair build.
  std::vector<Vec3> ext_force, ext_torque, pairs_built_at;
  std::vector<std::int32_t> pairs_built_motion;
  // Optional (not before 2026-12-06): the walls' contact impulses and the time they span (1 entry).
  std::vector<Vec3> wall_impulse;
  std::vector<Real> wall_impulse_time;
  std::vector<Real> q, mass;  // q: 4 per body (w, x, y, z)
  std::vector<std::int32_t> motion, shape, node;
  std::vector<std::uint64_t> id, master, slave;

  template <class F>
  void each(F&& f) {
    f("x", x), f("v", v), f("w", w), f("inertia", inertia), f("acc_prev", acc_prev);
    f("alpha_prev", alpha_prev), f("wall_point", wall_point), f("wall_offset", wall_offset);
    f("springs", springs), f("q", q), f("mass", mass), f("motion", motion), f("shape", shape);
    f("node", node), f("id", id), f("master", master), f("slave", slave);
    f("ext_force", ext_force), f("ext_torque", ext_torque), f("pairs_built_at", pairs_built_at);
    f("pairs_built_motion", pairs_built_motion);
    f("wall_impulse", wall_impulse), f("wall_impulse_time", wall_impulse_time);
  }
  static bool optional(const std::string& name) {
    return name == "ext_force" || name == "ext_torque" || name == "pairs_built_at" ||
           name == "pairs_built_motion" || name == "wall_impulse" || name == "wall_impulse_time";
  }
  std::uint64_t checksum() {
    std::uint64_t h = 1469598103934665603ULL;
    each([&](const char*, auto& v) { h = fnv(h, v.data(), v.size() * sizeof(v[0])); });
    return h;
  }
};

DemArrays flatten(const dem::DemState& s) {
  DemArrays a;
  for (const dem::RigidBody& b : s.bodies) {
    a.x.push_back(b.x);
    a.v.push_back(b.v);
    a.w.push_back(b.w);
    a.inertia.push_back(b.inertia);
    a.q.insert(a.q.end(), {b.q.w, b.q.x, b.q.y, b.q.z});
    a.mass.push_back(b.mass);
    a.motion.push_back(std::int32_t(b.motion));
    a.shape.push_back(b.shape);
    a.id.push_back(b.id);
  }
  a.acc_prev = s.acc_prev;
  a.alpha_prev = s.alpha_prev;
  a.wall_point = s.wall_point;
  a.wall_offset = s.wall_offset;
  a.springs = s.springs;
  a.ext_force = s.ext_force;
  a.ext_torque = s.ext_torque;
  a.pairs_built_at = s.pairs_built_at;
  a.pairs_built_motion = s.pairs_built_motion;
  a.wall_impulse = s.wall_impulse;
  if (!s.wall_impulse.empty()) a.wall_impulse_time = {s.wall_impulse_time};
  for (const dem::ContactKey& k : s.keys) {
    a.master.push_back(k.master);
    a.slave.push_back(k.slave);
    a.node.push_back(std::int32_t(k.node));
  }
  return a;
}

dem::DemState unflatten(const DemArrays& a, Real time) {
  dem::DemState s;
  s.time = time;
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    dem::RigidBody b;
    b.x = a.x[i];
    b.v = a.v[i];
    b.w = a.w[i];
    b.inertia = a.inertia[i];
    b.q = Quat{a.q[4 * i], a.q[4 * i + 1], a.q[4 * i + 2], a.q[4 * i + 3]};
    b.mass = a.mass[i];
    b.motion = dem::Motion(a.motion[i]);
    b.shape = a.shape[i];
    b.id = a.id[i];
    s.bodies.push_back(b);
  }
  s.acc_prev = a.acc_prev;
  s.alpha_prev = a.alpha_prev;
  s.wall_point = a.wall_point;
  s.wall_offset = a.wall_offset;
  s.springs = a.springs;
  s.ext_force = a.ext_force;
  s.ext_torque = a.ext_torque;
  s.pairs_built_at = a.pairs_built_at;
  s.pairs_built_motion = a.pairs_built_motion;
  s.wall_impulse = a.wall_impulse;
  s.wall_impulse_time = a.wall_impulse_time.empty() ? Real(0) : a.wall_impulse_time.front();
  for (std::size_t i = 0; i < a.master.size(); ++i)
    s.keys.push_back(dem::ContactKey{a.master[i], a.slave[i], std::uint32_t(a.node[i])});
  return s;
}

// Rank 0 writes the replicated state; the other ranks take part with empty selections.
void write_dem(hid_t f, const dem::DemState& s, int rank, const std::string& lab) {
  DemArrays a = flatten(s);
  hid_t grp = H5Gcreate2(f, "dem", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  h5::write_attr<double>(grp, "time", H5T_NATIVE_DOUBLE, s.time);
  h5::write_attr<std::uint64_t>(grp, "checksum", H5T_NATIVE_UINT64, a.checksum());
  a.each([&](const char* name, auto& v) {
    const Index n = Index(v.size());
    h5::write_field(grp, name, v.data(), rank == 0 ? n : 0, 0, n, lab);
  });
  H5Gclose(grp);
}

dem::DemState read_dem(hid_t f, const std::string& path, const std::string& lab) {
  if (H5Lexists(f, "dem", H5P_DEFAULT) <= 0) return {};
  hid_t grp = H5Gopen2(f, "dem", H5P_DEFAULT);
  DemArrays a;
  double time = 0;
  std::uint64_t sum = 0;
  try {
    time = h5::read_attr<double>(grp, "time", H5T_NATIVE_DOUBLE, lab);
    sum = h5::read_attr<std::uint64_t>(grp, "checksum", H5T_NATIVE_UINT64, lab);
    a.each([&](const char* name, auto& v) {
      if (H5Lexists(grp, name, H5P_DEFAULT) <= 0) {
        if (DemArrays::optional(name)) return;
        h5::fail(lab, std::string("dem/") + name + " is missing");
      }
      hid_t ds = H5Dopen2(grp, name, H5P_DEFAULT);
      hid_t sp = H5Dget_space(ds);
      hsize_t dims[2] = {0, 0};
      H5Sget_simple_extent_dims(sp, dims, nullptr);
      H5Sclose(sp);
      H5Dclose(ds);
      v.resize(std::size_t(dims[0]));
      h5::read_field(grp, name, v.data(), Index(dims[0]), 0, lab);
    });
  } catch (...) {
    H5Gclose(grp);
    throw;
  }
  H5Gclose(grp);
  if (a.checksum() != sum)
    throw InputError(path + ": DEM state checksum mismatch: the file is corrupted");
  return unflatten(a, Real(time));
}

}  // namespace

std::uint64_t write_checkpoint(const std::string& path, const CheckpointData& d) {
  ensure_mpi();
  const MPI_Comm comm = MPI_COMM_WORLD;
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const ParticleSet<Host>& ps = d.particles;
  const Index nb = ps.n_wall + ps.n_grain;
  Index local[2] = {ps.n_fluid, nb}, total[2] = {0, 0}, offset[2] = {0, 0};
  MPI_Allreduce(local, total, 2, MPI_INT64_T, MPI_SUM, comm);
  MPI_Exscan(local, offset, 2, MPI_INT64_T, MPI_SUM, comm);
  if (rank == 0) offset[0] = offset[1] = 0;
  std::uint64_t sum_local = local_checksum(ps), sum = 0;
  MPI_Allreduce(&sum_local, &sum, 1, MPI_UINT64_T, MPI_SUM, comm);

  const std::string tmp = path + ".tmp";
  hid_t f = h5::create_file(tmp);
  if (f < 0) throw InputError("cannot create checkpoint file '" + tmp + "'");
  h5::write_attr<std::int64_t>(f, "format_version", H5T_NATIVE_INT64, kCheckpointFormatVersion);
  h5::write_attr<double>(f, "time", H5T_NATIVE_DOUBLE, d.counters.time);
  h5::write_attr<std::int64_t>(f, "step", H5T_NATIVE_INT64, d.counters.step);
  h5::write_attr<std::int64_t>(f, "verlet_count", H5T_NATIVE_INT64, d.counters.verlet_count);
  h5::write_attr<std::int64_t>(f, "removed", H5T_NATIVE_INT64, d.counters.removed);
  h5::write_attr<double>(f, "removed_mass", H5T_NATIVE_DOUBLE, d.counters.removed_mass);
  h5::write_attr<std::int64_t>(f, "dim", H5T_NATIVE_INT64, d.dim);
  h5::write_attr<double>(f, "dp", H5T_NATIVE_DOUBLE, d.dp);
  h5::write_attr<std::int64_t>(f, "real_bytes", H5T_NATIVE_INT64, sizeof(Real));
  h5::write_attr<double>(f, "next_output_time", H5T_NATIVE_DOUBLE, d.next_output_time);
  h5::write_attr<std::int64_t>(f, "n_fluid", H5T_NATIVE_INT64, total[0]);
  h5::write_attr<std::int64_t>(f, "n_boundary", H5T_NATIVE_INT64, total[1]);
  h5::write_attr<std::uint64_t>(f, "checksum", H5T_NATIVE_UINT64, sum);
  if (d.guard_steps >= 0) {
    h5::write_attr<std::int64_t>(f, "guard_steps", H5T_NATIVE_INT64, d.guard_steps);
    h5::write_attr<double>(f, "guard_max_speed", H5T_NATIVE_DOUBLE, d.guard_max_speed);
    h5::write_attr<double>(f, "guard_rho_min", H5T_NATIVE_DOUBLE, d.guard_rho_min);
    h5::write_attr<double>(f, "guard_rho_max", H5T_NATIVE_DOUBLE, d.guard_rho_max);
    h5::write_attr<double>(f, "guard_dt_min", H5T_NATIVE_DOUBLE, d.guard_dt_min);
  }
  {
    const hsize_t n = d.profile_next.size();
    hid_t sp = H5Screate_simple(1, &n, nullptr);
    hid_t ds =
        H5Dcreate2(f, "profile_next", H5T_NATIVE_INT64, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hid_t ms = H5Screate_simple(1, &n, nullptr);
    if (rank != 0) {
      H5Sselect_none(sp);
      H5Sselect_none(ms);
    }
    H5Dwrite(ds, H5T_NATIVE_INT64, ms, sp, H5P_DEFAULT, d.profile_next.data());
    H5Sclose(ms);
    H5Dclose(ds);
    H5Sclose(sp);
  }
  {
    const hsize_t n = d.scene_yaml.size();
    hid_t sp = H5Screate_simple(1, &n, nullptr);
    hid_t ds =
        H5Dcreate2(f, "scene_yaml", H5T_NATIVE_CHAR, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hid_t ms = H5Screate_simple(1, &n, nullptr);
    if (rank != 0 || n == 0) {
      H5Sselect_none(sp);
      H5Sselect_none(ms);
    }
    H5Dwrite(ds, H5T_NATIVE_CHAR, ms, sp, H5P_DEFAULT, d.scene_yaml.data());
    H5Sclose(ms);
    H5Dclose(ds);
    H5Sclose(sp);
  }
  const ParticleSet<Host> fluid = slice(ps, 0, ps.n_fluid);
  const ParticleSet<Host> bound = slice(ps, ps.wall_begin(), nb);
  for (int g = 0; g < 2; ++g) {
    hid_t grp = H5Gcreate2(f, g == 0 ? "fluid" : "boundary", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    auto& set = const_cast<ParticleSet<Host>&>(g == 0 ? fluid : bound);
    set.for_each_field([&](const char* name, auto& b) {
      h5::write_field(grp, name, b.data(), local[g], offset[g], total[g], label(path));
    });
    if (g == 1) {
      h5::write_attr<std::int64_t>(grp, "n_wall", H5T_NATIVE_INT64, ps.n_wall);
      h5::write_attr<std::int64_t>(grp, "n_grain", H5T_NATIVE_INT64, ps.n_grain);
    }
    H5Gclose(grp);
  }
  if (!d.dem.bodies.empty()) write_dem(f, d.dem, rank, label(path));
  if (H5Fclose(f) < 0) throw InputError("cannot close checkpoint file '" + tmp + "'");
  MPI_Barrier(comm);
  if (rank == 0) {
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw InputError("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
  }
  MPI_Barrier(comm);
  std::uint64_t bytes = 0;
  if (rank == 0) bytes = std::filesystem::file_size(path);
  MPI_Bcast(&bytes, 1, MPI_UINT64_T, 0, comm);
  return bytes;
}

CheckpointData read_checkpoint(const std::string& path) {
  ensure_mpi();
  const MPI_Comm comm = MPI_COMM_WORLD;
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (!std::filesystem::exists(path))
    throw InputError("cannot open checkpoint '" + path + "': no such file");
  // Silence HDF5's own error stack printing; we report our own message.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  hid_t f = h5::open_file_read(path);
  if (f < 0) fail(path, "not a readable HDF5 file (truncated or corrupted?)");
  CheckpointData d;
  try {
    const auto version =
        h5::read_attr<std::int64_t>(f, "format_version", H5T_NATIVE_INT64, label(path));
    if (version != kCheckpointFormatVersion) {
      std::ostringstream os;
      os << "format version " << version << " is not the supported " << kCheckpointFormatVersion;
      fail(path, os.str());
    }
    const auto real_bytes =
        h5::read_attr<std::int64_t>(f, "real_bytes", H5T_NATIVE_INT64, label(path));
    if (real_bytes != std::int64_t(sizeof(Real)))
      fail(path, "written by a build with a different precision (SPHDEM_PRECISION)");
    d.counters.time = h5::read_attr<double>(f, "time", H5T_NATIVE_DOUBLE, label(path));
    d.counters.step = h5::read_attr<std::int64_t>(f, "step", H5T_NATIVE_INT64, label(path));
    d.counters.verlet_count =
        h5::read_attr<std::int64_t>(f, "verlet_count", H5T_NATIVE_INT64, label(path));
    d.counters.removed = h5::read_attr<std::int64_t>(f, "removed", H5T_NATIVE_INT64, label(path));
    d.counters.removed_mass =
        h5::read_attr<double>(f, "removed_mass", H5T_NATIVE_DOUBLE, label(path));
    d.dim = int(h5::read_attr<std::int64_t>(f, "dim", H5T_NATIVE_INT64, path));
    d.dp = h5::read_attr<double>(f, "dp", H5T_NATIVE_DOUBLE, label(path));
    d.next_output_time =
        h5::read_attr<double>(f, "next_output_time", H5T_NATIVE_DOUBLE, label(path));
    d.total_fluid = h5::read_attr<std::int64_t>(f, "n_fluid", H5T_NATIVE_INT64, label(path));
    d.total_boundary = h5::read_attr<std::int64_t>(f, "n_boundary", H5T_NATIVE_INT64, label(path));
    const auto checksum =
        h5::read_attr<std::uint64_t>(f, "checksum", H5T_NATIVE_UINT64, label(path));
    if (H5Aexists(f, "guard_steps") > 0) {
      d.guard_steps = h5::read_attr<std::int64_t>(f, "guard_steps", H5T_NATIVE_INT64, label(path));
      d.guard_max_speed =
          h5::read_attr<double>(f, "guard_max_speed", H5T_NATIVE_DOUBLE, label(path));
      d.guard_rho_min = h5::read_attr<double>(f, "guard_rho_min", H5T_NATIVE_DOUBLE, label(path));
      d.guard_rho_max = h5::read_attr<double>(f, "guard_rho_max", H5T_NATIVE_DOUBLE, label(path));
      d.guard_dt_min = h5::read_attr<double>(f, "guard_dt_min", H5T_NATIVE_DOUBLE, label(path));
    }
    for (const char* name : {"profile_next", "scene_yaml"}) {
      if (H5Lexists(f, name, H5P_DEFAULT) <= 0)
        fail(path, std::string("'") + name + "' is missing");
      hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
      hid_t sp = H5Dget_space(ds);
      const hssize_t n = H5Sget_simple_extent_npoints(sp);
      herr_t e = 0;
      if (std::strcmp(name, "profile_next") == 0) {
        d.profile_next.resize(std::size_t(n));
        if (n > 0)
          e = H5Dread(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.profile_next.data());
      } else {
        d.scene_yaml.resize(std::size_t(n));
        if (n > 0)
          e = H5Dread(ds, H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.scene_yaml.data());
      }
      H5Sclose(sp);
      H5Dclose(ds);
      if (e < 0) fail(path, std::string("cannot read '") + name + "'");
    }
    // Each rank reads a contiguous block of each group; DMSwarm redistributes afterwards.
    const Index totals[2] = {d.total_fluid, d.total_boundary};
    Index counts[2], offs[2];
    for (int g = 0; g < 2; ++g) {
      offs[g] = totals[g] * rank / size;
      counts[g] = totals[g] * (rank + 1) / size - offs[g];
    }
    ParticleSet<Host>& ps = d.particles;
    ps.n_fluid = counts[0];
    hid_t bg = H5Gopen2(f, "boundary", H5P_DEFAULT);
    if (bg < 0) fail(path, "group 'boundary' is missing");
    const auto n_wall_total =
        h5::read_attr<std::int64_t>(bg, "n_wall", H5T_NATIVE_INT64, label(path));
    H5Gclose(bg);
    ps.n_wall = counts[1];
    ps.n_grain = 0;
    (void)n_wall_total;
    ps.resize(ps.size());
    for (int g = 0; g < 2; ++g) {
      hid_t grp = H5Gopen2(f, g == 0 ? "fluid" : "boundary", H5P_DEFAULT);
      if (grp < 0)
        fail(path, std::string("group '") + (g == 0 ? "fluid" : "boundary") + "' is missing");
      ParticleSet<Host> part = [&] {
        ParticleSet<Host> p;
        p.resize(counts[g]);
        return p;
      }();
      part.for_each_field([&](const char* name, auto& b) {
        h5::read_field(grp, name, b.data(), counts[g], offs[g], label(path));
      });
      H5Gclose(grp);
      // Place the group's slots into the rank's set.
      const Index base = g == 0 ? 0 : ps.wall_begin();
      std::vector<void*> dst;
      ps.for_each_field([&](const char*, auto& b) { dst.push_back(&b); });
      std::size_t k = 0;
      part.for_each_field([&](const char*, auto& b) {
        using B = std::decay_t<decltype(b)>;
        auto* out = static_cast<B*>(dst[k++]);
        for (Index i = 0; i < counts[g]; ++i) (*out)[std::size_t(base + i)] = b[std::size_t(i)];
      });
    }
    std::uint64_t sum_local = local_checksum(ps), sum = 0;
    MPI_Allreduce(&sum_local, &sum, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (sum != checksum) fail(path, "checksum mismatch: the file is corrupted");
    // Walls and grain particles share the boundary block (sorted together by cell): count the
    // grains of this rank's share by their body field.
    Index grains = 0;
    for (Index i = ps.wall_begin(); i < ps.size(); ++i)
      if (is_grain_body(ps.body[std::size_t(i)])) ++grains;
    ps.n_wall -= grains;
    ps.n_grain = grains;
    d.dem = read_dem(f, path, label(path));
  } catch (...) {
    H5Fclose(f);
    throw;
  }
  H5Fclose(f);
  return d;
}

void check_checkpoint_matches(const CheckpointData& cp, const Scene& scene,
                              Index scene_boundary_count, const std::string& path) {
  std::ostringstream os;
  if (cp.dim != scene.dim) {
    os << "it is " << cp.dim << "D but scene '" << scene.name << "' is " << scene.dim << "D";
  } else if (std::abs(cp.dp - scene.sph.dp) > Real(1e-12) * scene.sph.dp) {
    os << "it has dp = " << cp.dp << " m but scene '" << scene.name
       << "' has sph.dp = " << scene.sph.dp;
  } else if (cp.total_boundary != scene_boundary_count) {
    os << "it holds " << cp.total_boundary << " boundary particles but scene '" << scene.name
       << "' builds " << scene_boundary_count;
  } else {
    return;
  }
  fail(path, "does not belong to this scene: " + os.str());
}

std::string checkpoint_path(const std::string& dir, std::int64_t step) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "checkpoint_%010lld.h5", static_cast<long long>(step));
  return dir + "/" + buf;
}

namespace {
std::vector<std::string> list_checkpoints(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("checkpoint_", 0) == 0 && n.size() > 3 && n.substr(n.size() - 3) == ".h5")
      out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());  // zero-padded step numbers sort in time order
  return out;
}
}  // namespace

std::string latest_checkpoint(const std::string& dir) {
  const auto all = list_checkpoints(dir);
  return all.empty() ? std::string() : all.back();
}

void prune_checkpoints(const std::string& dir, int keep) {
  auto all = list_checkpoints(dir);
  if (keep <= 0 || int(all.size()) <= keep) return;
  for (std::size_t i = 0; i + std::size_t(keep) < all.size(); ++i) std::filesystem::remove(all[i]);
}

}  // namespace sphdem
