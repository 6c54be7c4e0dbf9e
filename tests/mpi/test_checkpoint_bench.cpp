// Checkpoint I/O bandwidth for about 1 M particles (docs/BENCHMARKS.md, "Checkpoint I/O").
// Disabled by default; run with
//   mpiexec --oversubscribe -n N mpi_tests --gtest_also_run_disabled_tests
//           --gtest_filter='*CheckpointIo*'
// SPHDEM_BENCH_PARTICLES (default 1000000 fluid particles), SPHDEM_BENCH_REPS (default 3) and
// SPHDEM_BENCH_DIR (default: the working folder) change the set-up.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "mpi_test_util.hpp"

namespace sphdem {
namespace {

using namespace mpitest;

double slowest(double v) {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, comm());
  return v;
}

template <class F>
double timed(F&& f) {
  MPI_Barrier(comm());
  const double t0 = MPI_Wtime();
  f();
  return slowest(MPI_Wtime() - t0);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

long env_or(const char* name, long fallback) {
  const char* s = std::getenv(name);
  return s ? std::max(1L, std::atol(s)) : fallback;
}

TEST(Bench, DISABLED_CheckpointIo) {
  const std::int64_t n = env_or("SPHDEM_BENCH_PARTICLES", 1000000);
  const int reps = int(env_or("SPHDEM_BENCH_REPS", 3));
  const char* dir_env = std::getenv("SPHDEM_BENCH_DIR");
  const std::string dir = dir_env ? dir_env : ".";
  // This rank's contiguous block of a lattice of fluid particles, every field set.
  const std::int64_t first = n * rank() / size(), last = n * (rank() + 1) / size();
  const Real dp = Real(0.002);
  CheckpointData cp;
  ParticleSet<Host>& ps = cp.particles;
  ps.n_fluid = Index(last - first);
  ps.resize(ps.size());
  for (std::int64_t id = first; id < last; ++id) {
    const std::size_t s = std::size_t(id - first);
    const Real x = Real(id % 100), y = Real((id / 100) % 100), z = Real(id / 10000);
    ps.id[s] = GlobalId(id);
    ps.pos[s] = Vec3(x * dp, y * dp, z * dp);
    ps.vel[s] = ps.vel_prev[s] = Vec3(Real(1e-3) * x, 0, -Real(1e-3) * z);
    ps.rho[s] = ps.rho_prev[s] = Real(1000) + Real(1e-3) * z;
    ps.mass[s] = Real(1000) * dp * dp * dp;
    ps.press[s] = Real(9.81e3) * z * dp;
    ps.body[s] = -1;
  }
  cp.counters.step = 1234;
  cp.counters.time = 0.5;
  cp.dim = 3;
  cp.dp = dp;
  cp.scene_yaml = "name: bench\n";
  const std::string path = dir + "/bench_checkpoint_np" + std::to_string(size()) + ".h5";

  std::vector<double> write, sync, read_warm, read_cold;
  std::uint64_t bytes = 0;
  for (int r = 0; r < reps; ++r) {
    write.push_back(timed([&] { bytes = write_checkpoint(path, cp); }));
    // The write above may end in the page cache; fsync shows what reaching the disk costs, and
    // dropping the file's cached pages makes the second read come from the disk.
    sync.push_back(timed([&] {
      if (rank() == 0) {
        const int fd = ::open(path.c_str(), O_RDONLY);
        ASSERT_GE(fd, 0);
        ::fsync(fd);
        ::close(fd);
      }
    }));
    CheckpointData back;
    read_warm.push_back(timed([&] { back = read_checkpoint(path); }));
    EXPECT_EQ(sum_ranks(back.particles.n_fluid), n);
    if (rank() == 0) {
      const int fd = ::open(path.c_str(), O_RDONLY);
      ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
      ::close(fd);
    }
    read_cold.push_back(timed([&] { back = read_checkpoint(path); }));
    EXPECT_EQ(back.counters.step, 1234);
  }
  if (rank() == 0) {
    const double mb = double(bytes) / 1e6;
    std::printf(
        "BENCH checkpoint ranks %d particles %lld file %.1f MB (%.1f bytes/particle), median of "
        "%d\n",
        size(), (long long)n, mb, double(bytes) / double(n), reps);
    std::printf(
        "BENCH checkpoint seconds: write %.3f (%.0f MB/s), fsync %.3f (write+fsync %.0f MB/s), "
        "read (cached) %.3f (%.0f MB/s), read (file dropped from the page cache) %.3f (%.0f "
        "MB/s)\n",
        median(write), mb / median(write), median(sync), mb / (median(write) + median(sync)),
        median(read_warm), mb / median(read_warm), median(read_cold), mb / median(read_cold));
  }
  MPI_Barrier(comm());
  if (rank() == 0) std::filesystem::remove(path);
}

}  // namespace
}  // namespace sphdem
