// Checkpoint/restart: bit-identical continuation, refusal of bad checkpoints, crash safety
// (kill -9 during writes), and SIGTERM from a scheduler.
#include <gtest/gtest.h>

#include <cmath>
#include <hdf5.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app/simulation.hpp"
#include "core/error.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_yaml.hpp"
#include "validation/run_files.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";

Scene small_scene(std::vector<std::string> extra = {}) {
  std::vector<std::string> ov = {"sph.dp=0.0073", "time.end=10", "checkpoint.every_steps=100",
                                 "checkpoint.keep=10"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return load_scene(kScene, ov);
}

RunResult run(const Scene& s, const std::string& out, std::int64_t steps,
              const std::string& restart = "") {
  return runfiles::run_host(s, out, steps, restart);
}

TEST(Restart, ContinuesBitIdentically) {
  fs::remove_all("restart_straight");
  fs::remove_all("restart_resumed");
  const Scene s = small_scene();
  run(s, "restart_straight", 300);
  fs::create_directories("restart_resumed");
  fs::copy_file("restart_straight/checkpoint_0000000100.h5",
                "restart_resumed/checkpoint_0000000100.h5");
  const RunResult r = run(s, "restart_resumed", 200, "latest");
  EXPECT_EQ(r.steps, 200);
  const CheckpointData a = read_checkpoint("restart_straight/checkpoint_0000000300.h5");
  const CheckpointData b = read_checkpoint("restart_resumed/checkpoint_0000000300.h5");
  EXPECT_EQ(a.counters.step, 300);
  EXPECT_EQ(b.counters.step, 300);
  EXPECT_EQ(a.counters.time, b.counters.time);  // bitwise
  const auto ma = runfiles::state_by_id(a), mb = runfiles::state_by_id(b);
  ASSERT_EQ(ma.size(), mb.size());
  std::size_t differ = 0;
  for (const auto& [id, bytes] : ma) differ += (mb.at(id) != bytes);
  EXPECT_EQ(differ, 0u);
  // The comparison can fail: the state at step 200 differs from the one at 300.
  const CheckpointData c = read_checkpoint("restart_straight/checkpoint_0000000200.h5");
  const auto mc = runfiles::state_by_id(c);
  std::size_t changed = 0;
  for (const auto& [id, bytes] : ma) changed += (mc.at(id) != bytes);
  EXPECT_GT(changed, ma.size() / 2);
  // Diagnostics continue in the same files, one header only.
  std::ifstream f("restart_resumed/front.csv");
  std::string line;
  int headers = 0;
  while (std::getline(f, line)) headers += line.rfind("t,", 0) == 0;
  EXPECT_EQ(headers, 1);
  // guards.csv: the checkpoint holds the open span (the steps since the last row), so every
  // resumed row is the straight run's, digit for digit, the first one included (before, it
  // spanned only the steps since the restart).
  auto lines = [](const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> v;
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  };
  const auto gs = lines("restart_straight/guards.csv"), gr = lines("restart_resumed/guards.csv");
  ASSERT_GE(gr.size(), 3u);
  EXPECT_EQ(gr[0], gs[0]);
  const std::size_t tail = gr.size() - 1;  // every resumed row
  ASSERT_GE(gs.size(), tail + 1);
  for (std::size_t k = 0; k < tail; ++k)
    EXPECT_EQ(gr[gr.size() - 1 - k], gs[gs.size() - 1 - k]) << "row " << k << " from the end";
  // Here every row of the straight run comes after the checkpoint at step 100, so the resumed
  // rows hold all 300 steps: the first one spans the 100 before the checkpoint too.
  double steps = 0;
  for (std::size_t i = 1; i < gr.size(); ++i) steps += std::stod(gr[i].substr(gr[i].find(',') + 1));
  EXPECT_EQ(steps, 300);
}

TEST(Restart, RefusesBadCheckpoints) {
  fs::remove_all("restart_bad");
  const Scene s = small_scene();
  run(s, "restart_bad", 100);
  const std::string good = "restart_bad/checkpoint_0000000100.h5";
  ASSERT_TRUE(fs::exists(good));
  // Missing file.
  try {
    read_checkpoint("restart_bad/nope.h5");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "cannot open checkpoint 'restart_bad/nope.h5': no such file");
  }
  // Truncated file.
  fs::copy_file(good, "restart_bad/truncated.h5");
  fs::resize_file("restart_bad/truncated.h5", fs::file_size(good) / 2);
  try {
    read_checkpoint("restart_bad/truncated.h5");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint 'restart_bad/truncated.h5'"),
              std::string::npos)
        << e.what();
  }
  // Corrupted data: flip bytes in the middle of the particle data.
  fs::copy_file(good, "restart_bad/corrupt.h5");
  {
    std::fstream f("restart_bad/corrupt.h5", std::ios::in | std::ios::out | std::ios::binary);
    const auto n = fs::file_size(good);
    for (std::uintmax_t off = n / 2; off < n / 2 + 64; ++off) {
      f.seekg(std::streamoff(off));
      char c = 0;
      f.read(&c, 1);
      f.seekp(std::streamoff(off));
      c = char(c ^ 0x5a);
      f.write(&c, 1);
    }
  }
  try {
    read_checkpoint("restart_bad/corrupt.h5");
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(m.find("checksum mismatch") != std::string::npos ||
                m.find("cannot read") != std::string::npos)
        << m;
  }
  // A checkpoint of another scene (different dp).
  const Scene other = small_scene({"sph.dp=0.0146"});
  try {
    run(other, "restart_bad", 10, good);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "checkpoint '" + good +
                  "': does not belong to this scene: it has dp = 0.0073 m but "
                  "scene 'dam_break_2d' has sph.dp = 0.0146");
  }
}

// Runs the sphdem binary; returns its exit status.
int sh(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

TEST(Restart, CheckpointWithoutBoundaryParticles) {
  // A fluid-only set (a periodic box has no walls): the empty boundary datasets are written and
  // read back, and the fluid comes back exactly.
  CheckpointData cp;
  cp.particles.n_fluid = 100;
  cp.particles.resize(100);
  for (Index i = 0; i < 100; ++i) {
    cp.particles.id[std::size_t(i)] = GlobalId(1000 + i);
    cp.particles.pos[std::size_t(i)] = Vec3(Real(i), Real(0.5) * Real(i), 0);
    cp.particles.rho[std::size_t(i)] = Real(1000) + Real(i);
  }
  cp.counters.step = 7;
  cp.dim = 3;
  cp.dp = Real(0.01);
  fs::create_directories("restart_no_boundary");
  const std::string path = "restart_no_boundary/checkpoint.h5";
  EXPECT_GT(write_checkpoint(path, cp), 0u);
  const CheckpointData back = read_checkpoint(path);
  EXPECT_EQ(back.particles.n_fluid, 100);
  EXPECT_EQ(back.particles.n_wall + back.particles.n_grain, 0);
  EXPECT_EQ(back.counters.step, 7);
  EXPECT_EQ(runfiles::state_by_id(back), runfiles::state_by_id(cp));
  // No guards.csv span given: none written, as in an older sphdem's file, and none read back.
  EXPECT_EQ(back.guard_steps, -1);
  // A span (an empty one keeps its infinite bounds) reads back bit for bit.
  cp.guard_steps = 0;
  cp.guard_max_speed = 0;
  cp.guard_rho_min = INFINITY;
  cp.guard_rho_max = -INFINITY;
  cp.guard_dt_min = 1.25e-5;
  EXPECT_GT(write_checkpoint(path, cp), 0u);
  const CheckpointData span = read_checkpoint(path);
  EXPECT_EQ(span.guard_steps, 0);
  EXPECT_EQ(span.guard_rho_min, INFINITY);
  EXPECT_EQ(span.guard_rho_max, -INFINITY);
  EXPECT_EQ(span.guard_dt_min, 1.25e-5);
}

TEST(Restart, KillDuringCheckpointWritesLeavesAUsableCheckpoint) {
  // Checkpoint every step so the kill lands in or near a write; after each kill -9 the newest
  // checkpoint must read back (its checksum verified), and the run must restart from it.
  fs::remove_all("restart_kill");
  const std::string base = std::string(SPHDEM_BINARY) + " run " + kScene +
                           " --out restart_kill --quiet --set sph.dp=0.0073 --set time.end=10"
                           " --set checkpoint.every_steps=1 --set checkpoint.keep=2";
  int kills = 0;
  for (int k = 0; k < 4; ++k) {
    const std::string cmd = "timeout -s KILL " + std::to_string(1.5 + 0.37 * k) + " " + base +
                            (k == 0 ? "" : " --restart latest") + " > /dev/null 2>&1";
    const int rc = sh(cmd);
    kills += rc == 137 || rc == -1;
    const std::string latest = latest_checkpoint("restart_kill");
    ASSERT_FALSE(latest.empty());
    EXPECT_NO_THROW(read_checkpoint(latest)) << latest;
  }
  EXPECT_GE(kills, 3);
}

TEST(Restart, SigtermWritesACheckpointAndStops) {
  fs::remove_all("restart_term");
  const std::string cmd = std::string(SPHDEM_BINARY) + " run " + kScene +
                          " --out restart_term --quiet --set sph.dp=0.0073 --set time.end=10";
  const int rc = sh("(" + cmd + " > /dev/null 2>&1 & pid=$!; sleep 2; kill -TERM $pid; wait $pid)");
  EXPECT_EQ(rc, 4);
  const std::string latest = latest_checkpoint("restart_term");
  ASSERT_FALSE(latest.empty());
  std::ifstream f("restart_term/summary.json");
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_NE(ss.str().find("\"status\": \"interrupted\""), std::string::npos) << ss.str();
  const CheckpointData cp = read_checkpoint(latest);
  EXPECT_GT(cp.counters.step, 0);
  // And the run continues from it.
  EXPECT_EQ(sh(cmd + " --restart latest --max-steps 20 > /dev/null 2>&1"), 0);
}

}  // namespace
}  // namespace sphdem

namespace sphdem {
namespace {

// Three spheres on a rough plane pushed sideways by a tilted gravity, the first one sliding and
// the third dropping onto the other two: the tangential springs are loaded at the checkpoint.
dem::DemSystem grains_in_contact() {
  dem::DemParams p;
  p.gravity = Vec3(2.0, 0, -9.81);
  p.grain_wall.kn = 1e6;
  p.grain_wall.restitution = 0.5;
  p.grain_wall.mu = 0.4;
  p.grain_wall.poisson = 0.3;
  p.grain_wall.tangential_damping = true;
  p.grain_grain = p.grain_wall;
  dem::DemSystem sys(p);
  sys.add_plane_wall(Vec3(0, 0, 0), Vec3(0, 0, 1));
  const Real r = 0.02;
  const int s = sys.add_template(dem::GrainTemplate::sphere(r));
  sys.add_body(s, 2500, Vec3(0, 0, r), Quat{}, Vec3(0.3, 0, 0));
  sys.add_body(s, 2500, Vec3(2 * r, 0.001, r));
  sys.add_body(s, 2500, Vec3(r, 0, r * Real(2.75)), Quat{}, Vec3(0, 0.05, 0));
  return sys;
}

std::string body_state(const dem::DemSystem& sys) {
  std::ostringstream os;
  os << std::hexfloat;
  for (const dem::RigidBody& b : sys.bodies())
    os << b.id << ' ' << b.x.x << ' ' << b.x.y << ' ' << b.x.z << ' ' << b.v.x << ' ' << b.v.y
       << ' ' << b.v.z << ' ' << b.q.w << ' ' << b.q.x << ' ' << b.q.y << ' ' << b.q.z << ' '
       << b.w.x << ' ' << b.w.y << ' ' << b.w.z << '\n';
  return os.str();
}

TEST(Restart, GrainsInContactContinueBitIdentically) {
  const Real dt = 1e-5;  // below the contact limit t_c/50 = 1.29e-5 s
  const int half = 2000;
  dem::DemSystem straight = grains_in_contact();
  for (int i = 0; i < 2 * half; ++i) straight.step(dt);

  dem::DemSystem first = grains_in_contact();
  for (int i = 0; i < half; ++i) first.step(dt);
  ASSERT_GE(first.contact_count(), 2u) << "the grains must be in contact at the checkpoint";
  double spring = 0;
  for (const Vec3& s : first.history_springs()) spring = std::max(spring, double(norm(s)));
  ASSERT_GT(spring, 0) << "the tangential springs must be loaded at the checkpoint";

  CheckpointData cp;
  cp.dim = 3;
  cp.dp = Real(0.01);
  cp.dem = first.state();
  fs::create_directories("restart_dem");
  const std::string path = "restart_dem/checkpoint.h5";
  ASSERT_GT(write_checkpoint(path, cp), 0u);
  const CheckpointData back = read_checkpoint(path);
  dem::DemSystem resumed = grains_in_contact();
  resumed.restore(back.dem);
  EXPECT_EQ(resumed.time(), first.time());
  // The floor's load (accumulated since the start: never reset here) comes back bit for bit,
  // and goes on as in the straight run.
  const Vec3 f_first = first.wall_mean_force(0), f_back = resumed.wall_mean_force(0);
  ASSERT_GT(norm(f_first), 0);
  EXPECT_EQ(std::memcmp(&f_first, &f_back, sizeof(Vec3)), 0);
  for (int i = 0; i < half; ++i) resumed.step(dt);
  EXPECT_EQ(body_state(resumed), body_state(straight));
  const Vec3 f_straight = straight.wall_mean_force(0), f_resumed = resumed.wall_mean_force(0);
  EXPECT_EQ(std::memcmp(&f_straight, &f_resumed, sizeof(Vec3)), 0);

  // Control: the same restart without the contact history ends elsewhere.
  dem::DemState no_history = back.dem;
  no_history.keys.clear();
  no_history.springs.clear();
  dem::DemSystem forgetful = grains_in_contact();
  forgetful.restore(no_history);
  for (int i = 0; i < half; ++i) forgetful.step(dt);
  EXPECT_NE(body_state(forgetful), body_state(straight));
}

TEST(Restart, CorruptedDemStateIsRefused) {
  dem::DemSystem sys = grains_in_contact();
  for (int i = 0; i < 200; ++i) sys.step(Real(1e-5));
  CheckpointData cp;
  cp.dim = 3;
  cp.dp = Real(0.01);
  cp.dem = sys.state();
  fs::create_directories("restart_dem");
  const std::string path = "restart_dem/corrupt.h5";
  ASSERT_GT(write_checkpoint(path, cp), 0u);
  // Change one body velocity in the file.
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  hid_t ds = H5Dopen2(f, "dem/v", H5P_DEFAULT);
  std::vector<double> v(9);
  H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  v[0] += 1e-3;
  H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Dclose(ds);
  H5Fclose(f);
  try {
    read_checkpoint(path);
    FAIL() << "a corrupted DEM state was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("DEM state checksum mismatch"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sphdem
