// ParaView Catalyst in situ (io/catalyst_adaptor.cpp, inputs/catalyst/): a short dam-break run
// with the three scripts produces the extracts, and the impact-force table equals the solver's
// own force CSV at the same steps. Built only with SPHDEM_ENABLE_CATALYST=ON.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_2d.yaml";

int sh(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string c;
  while (std::getline(ss, c, ',')) {
    if (c.size() >= 2 && c.front() == '"') c = c.substr(1, c.size() - 2);
    cells.push_back(c);
  }
  return cells;
}

// CSV rows as strings split on ',' (quotes removed); the header row is skipped. With `columns`,
// each row holds those columns in that order, found by the header's names (on many ranks
// ParaView's CSV writer gathers the ranks' tables and orders the columns by name); a missing
// column is a test failure and an empty cell.
std::vector<std::vector<std::string>> csv_rows(const std::string& path,
                                               const std::vector<std::string>& columns = {}) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream f(path);
  std::string line;
  std::vector<int> at;
  bool header = true;
  while (std::getline(f, line)) {
    std::vector<std::string> cells = split_csv_line(line);
    if (header) {
      header = false;
      for (const std::string& c : columns) {
        int k = -1;
        for (std::size_t i = 0; i < cells.size(); ++i)
          if (cells[i] == c) k = int(i);
        EXPECT_GE(k, 0) << path << ": no column " << c;
        at.push_back(k);
      }
      continue;
    }
    if (!columns.empty()) {
      std::vector<std::string> picked;
      for (int k : at)
        picked.push_back(k >= 0 && k < int(cells.size()) ? cells[std::size_t(k)] : "");
      cells = picked;
    }
    rows.push_back(cells);
  }
  return rows;
}

// The extracts' columns, in the order the scripts write them on one rank.
const std::vector<std::string> kImpactColumns = {"solid", "fx",       "fy",       "fz",      "t",
                                                 "step",  "grain_fx", "grain_fy", "grain_fz"};
const std::vector<std::string> kRunupColumns = {"x", "z_surface", "n", "t", "step", "runup"};

std::string step_file(const std::string& dir, const std::string& stem, int step,
                      const std::string& ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%06d", step);
  return dir + "/" + stem + buf + ext;
}

// Equal up to the solver CSV's 10 significant digits.
void expect_same(double catalyst, double solver, const std::string& what) {
  EXPECT_NEAR(catalyst, solver, 1e-9 * std::max(std::fabs(catalyst), std::fabs(solver)) + 1e-12)
      << what;
}

// 800 fluid particles (dp = 2 * 0.00365) moving right at 1.5 m/s, a low barrier 0.024 m in front
// of the column; extracts every 100 steps, solver force rows every step. One test, one run: ctest
// runs tests as separate processes, side by side.
constexpr int kEvery = 100, kSteps = 401, kFluid = 800;

// The run's command: `launcher` is empty for one rank, or an mpiexec prefix.
std::string dam_break_command(const std::string& out, const std::string& launcher) {
  return launcher + std::string(SPHDEM_BINARY) + " run " + kScene + " --out " + out +
         " --quiet --max-steps " + std::to_string(kSteps) +
         " --set sph.dp=0.0073"
         " --set 'solids=[{name: tank, shape: {type: tank, inner_lo: [0, -0.5, 0],"
         " inner_hi: [0.584, 0.5, 0.35], thickness: 0.02}}, {name: barrier,"
         " shape: {type: box, lo: [0.17, -0.5, 0], hi: [0.19, 0.5, 0.04]}}]'"
         " --set 'fluid_blocks[0].velocity=[1.5, 0, 0]'"
         " --set 'insitu={scripts: [catalyst/impact_force.py, catalyst/runup.py,"
         " catalyst/particles.py], every_steps: " +
         std::to_string(kEvery) +
         "}'"
         " --set 'diagnostics={every: 1e-9, energy: false, forces: [{name: tank_force,"
         " solid: tank}, {name: barrier_force, solid: barrier}]}' > " +
         out + ".log 2>&1";
}

void check_impact_force(const std::string& out) {
  const std::string dir = out + "/catalyst";
  // Solver rows: one per step (diagnostics.every < dt), row i = the state after step i.
  std::map<std::string, std::vector<std::vector<std::string>>> solver = {
      {"tank", csv_rows(out + "/tank_force.csv")},
      {"barrier", csv_rows(out + "/barrier_force.csv")}};
  ASSERT_EQ(solver["tank"].size(), std::size_t(kSteps + 1));
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir))
    files += e.path().filename().string().rfind("impact_force_", 0) == 0;
  EXPECT_EQ(files, 5);  // steps 0, 100, ..., 400
  EXPECT_FALSE(fs::exists(step_file(dir, "impact_force", 50, ".csv")));
  double barrier_fx_last = 0;
  for (int step = 0; step < kSteps; step += kEvery) {
    const auto rows = csv_rows(step_file(dir, "impact_force", step, ".csv"), kImpactColumns);
    ASSERT_EQ(rows.size(), 2u) << "step " << step;
    for (const auto& r : rows) {
      ASSERT_EQ(r.size(), 9u);
      const std::string what = r[0] + " at step " + std::to_string(step);
      ASSERT_TRUE(solver.count(r[0])) << what;
      const auto& s = solver[r[0]][std::size_t(step)];
      EXPECT_EQ(std::stod(r[5]), step) << what;
      expect_same(std::stod(r[4]), std::stod(s[0]), what + ": t");
      for (int k = 0; k < 3; ++k)
        expect_same(std::stod(r[1 + k]), std::stod(s[1 + k]), what + ": f" + "xyz"[k]);
      for (int k = 0; k < 3; ++k)  // no grains: no contact load
        EXPECT_EQ(std::stod(r[6 + k]), 0.0) << what + ": grain_f" + "xyz"[k];
      if (r[0] == "barrier") barrier_fx_last = std::stod(r[1]);
    }
  }
  // The comparison is not one of zeros: the flow pushes on the barrier by step 400.
  EXPECT_GT(barrier_fx_last, 100.0);
}

void check_runup(const std::string& dir) {
  // Step 0: the column, 0.146 m wide (20 bins of dp) and 0.292 m high, all particles counted.
  auto rows = csv_rows(step_file(dir, "runup", 0, ".csv"), kRunupColumns);
  ASSERT_EQ(rows.size(), 20u);
  double n = 0;
  for (const auto& r : rows) {
    EXPECT_NEAR(std::stod(r[1]), 0.292, 1e-9);  // z_surface
    EXPECT_NEAR(std::stod(r[5]), 0.292, 1e-9);  // runup
    n += std::stod(r[2]);
  }
  EXPECT_EQ(n, kFluid);
  // Step 400 (t = 0.013 s): the column has moved right up to the barrier's face (x = 0.17), not
  // into it, and, launched at 1.5 m/s away from the back wall, its trailing edge has dropped by
  // more than a particle. Its highest point (the run-up column) is still the column's top: at
  // most the free-fall distance g t^2 / 2 = 0.8 mm lower, and at most dp/4 higher (SPH noise; it
  // reads 0.09 mm above 0.292 since the mDBC corner fix, a hair below it before).
  rows = csv_rows(step_file(dir, "runup", 400, ".csv"), kRunupColumns);
  ASSERT_FALSE(rows.empty());
  double x_max = 0;
  n = 0;
  for (const auto& r : rows) {
    x_max = std::max(x_max, std::stod(r[0]));
    n += std::stod(r[2]);
  }
  EXPECT_EQ(n, kFluid);
  EXPECT_GT(x_max, 0.16);
  EXPECT_LT(x_max, 0.17);
  EXPECT_LT(std::stod(rows[0][1]), 0.292 - 0.0073);  // trailing edge, first bin
  EXPECT_GT(std::stod(rows[0][5]), 0.292 - 0.5 * 9.81 * 0.0131 * 0.0131);
  EXPECT_LT(std::stod(rows[0][5]), 0.292 + 0.25 * 0.0073);
}

// The decimated cloud: every 4th fluid particle of each rank, one piece per rank.
void check_particles(const std::string& dir, int ranks) {
  for (int step = 0; step < kSteps; step += kEvery) {
    const std::string piece = step_file(dir, "particles", step, "");
    int points = 0;
    for (int r = 0; r < ranks; ++r) {
      const std::string f =
          piece + "/" + fs::path(piece).filename().string() + "_" + std::to_string(r) + ".vtp";
      const std::string xml = slurp(f);
      ASSERT_FALSE(xml.empty()) << f;
      const auto at = xml.find("NumberOfPoints=\"");
      ASSERT_NE(at, std::string::npos) << f;
      const int n = std::stoi(xml.substr(at + 16));
      EXPECT_GT(n, 0) << f;
      points += n;
      for (const char* a : {"vel", "rho", "press", "id"})
        EXPECT_NE(xml.find(std::string("Name=\"") + a + "\""), std::string::npos) << f << ": " << a;
    }
    // Each rank keeps ceil(n_rank / 4) of its n_rank particles.
    EXPECT_GE(points, kFluid / 4) << piece;
    EXPECT_LE(points, kFluid / 4 + ranks - 1) << piece;
  }
}

void check_dam_break(const std::string& out, int ranks) {
  EXPECT_NE(slurp(out + "/run.log").find("in situ: catalyst, 3 script(s) every 100 steps"),
            std::string::npos);
  const std::string timing = slurp(out + "/catalyst/timing.json");
  EXPECT_NE(timing.find("\"extract_steps\": 5,"), std::string::npos) << timing;
  {
    SCOPED_TRACE("impact force");
    check_impact_force(out);
  }
  {
    SCOPED_TRACE("run-up");
    check_runup(out + "/catalyst");
  }
  {
    SCOPED_TRACE("decimated particles");
    check_particles(out + "/catalyst", ranks);
  }
}

TEST(Catalyst, DamBreakExtractsMatchTheSolver) {
  const std::string out = "catalyst_dam_break";
  fs::remove_all(out);
  // Exit 0: the processor was finalized before MPI_Finalize (otherwise Open MPI aborts).
  ASSERT_EQ(sh(dam_break_command(out, "")), 0) << slurp(out + ".log");
  check_dam_break(out, 1);
}

// The same run on 2 ranks: each rank hands Catalyst its own fluid and walls, and the scripts
// reduce over the ranks, so the tables are whole (one row per solid, one per x bin) and equal
// the solver's gathered force CSVs; the cloud is one piece per rank. Before the reductions the
// table had each solid twice, with each rank's share of its force.
TEST(Catalyst, ExtractsAreWholeOnTwoRanks) {
  const std::string out = "catalyst_dam_break_np2";
  fs::remove_all(out);
  const std::string mpiexec = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " +
                              std::string(SPHDEM_MPIEXEC) + " --oversubscribe -n 2 ";
  ASSERT_EQ(sh(dam_break_command(out, mpiexec)), 0) << slurp(out + ".log");
  EXPECT_NE(slurp(out + "/run.log").find("2 ranks"), std::string::npos) << slurp(out + "/run.log");
  check_dam_break(out, 2);
}

// Boulders (tests/data/scenes/catalyst_boulders.yaml): the extract's grain columns are the
// grains' contact load on each solid, the same numbers as impact_force.csv's barrier_k_grain_fx
// and _f, and at rest one bead's weight on barrier_2 and one on the channel floor.
TEST(Catalyst, BoulderLoadsReachTheExtract) {
  const std::string out = "catalyst_boulders", dir = out + "/catalyst";
  fs::remove_all(out);
  const std::string scene =
      std::string(SPHDEM_SOURCE_DIR) + "/tests/data/scenes/catalyst_boulders.yaml";
  ASSERT_EQ(sh(std::string(SPHDEM_BINARY) + " run " + scene + " --out " + out + " --quiet > " +
               out + ".log 2>&1"),
            0)
      << slurp(out + ".log");
  // impact_force.csv: t, barrier_k_fx, barrier_k_f (k = 1..3), total_fx, total_f, then the same
  // for the grains; one row per step (diagnostics.every < dt), row i = the state after step i.
  const auto solver = csv_rows(out + "/impact_force.csv");
  ASSERT_GT(solver.size(), 200u);
  ASSERT_EQ(solver[0].size(), 17u);
  const double weight = 2500 * (4.0 / 3.0) * M_PI * std::pow(0.008, 3) * 9.81;
  int files = 0, settled = 0;
  for (int step = 0; step < int(solver.size()); step += 20) {
    const std::string file = step_file(dir, "impact_force", step, ".csv");
    if (!fs::exists(file)) continue;
    ++files;
    const auto rows = csv_rows(file);
    ASSERT_EQ(rows.size(), 4u) << file;  // channel, barrier_1 .. barrier_3
    const auto& s = solver[std::size_t(step)];
    std::map<std::string, std::vector<double>> g;
    for (const auto& r : rows) {
      ASSERT_EQ(r.size(), 9u) << file;
      const std::string what = r[0] + " at step " + std::to_string(step);
      expect_same(std::stod(r[4]), std::stod(s[0]), what + ": t");
      g[r[0]] = {std::stod(r[6]), std::stod(r[7]), std::stod(r[8])};
      if (r[0] == "channel") continue;
      const int k = r[0].back() - '1';  // barrier_1 -> 0
      ASSERT_TRUE(k >= 0 && k < 3) << what;
      // The fluid's force along x, and the grains' (x and magnitude), as in the solver's row.
      expect_same(std::stod(r[1]), std::stod(s[std::size_t(1 + 2 * k)]), what + ": fx");
      expect_same(g[r[0]][0], std::stod(s[std::size_t(9 + 2 * k)]), what + ": grain_fx");
      expect_same(std::hypot(g[r[0]][0], g[r[0]][1], g[r[0]][2]),
                  std::stod(s[std::size_t(10 + 2 * k)]), what + ": grain_f");
    }
    ASSERT_EQ(g.size(), 4u) << file;
    for (const char* w : {"barrier_1", "barrier_3"})
      for (int a = 0; a < 3; ++a) EXPECT_EQ(g[w][std::size_t(a)], 0.0) << w << " step " << step;
    if (std::stod(s[0]) < 0.04) continue;  // settling (contact time 2.3 ms)
    ++settled;
    for (const char* w : {"barrier_2", "channel"}) {
      EXPECT_NEAR(g[w][2], -weight, 0.01 * weight) << w << " step " << step;
      EXPECT_LT(std::hypot(g[w][0], g[w][1]), 0.01 * weight) << w << " step " << step;
    }
  }
  EXPECT_GE(files, 10);
  EXPECT_GE(settled, 5);
}

TEST(Catalyst, AFailingScriptStopsTheRunWithAMessage) {
  fs::remove_all("catalyst_broken");
  fs::create_directories("catalyst_broken");
  const std::string script = fs::absolute("catalyst_broken/broken.py").string();
  std::ofstream(script) << "# script-version: 2\nraise RuntimeError('broken on purpose')\n";
  const int rc = sh(std::string(SPHDEM_BINARY) + " run " + kScene +
                    " --out catalyst_broken/out --quiet --max-steps 5 --set sph.dp=0.0146"
                    " --set 'insitu={scripts: [" +
                    script + "]}' > catalyst_broken/log 2>&1");
  EXPECT_EQ(rc, 1);
  const std::string log = slurp("catalyst_broken/log");
  EXPECT_NE(log.find("broken on purpose"), std::string::npos) << log;
  EXPECT_NE(log.find("error: insitu: a Catalyst script failed at step 0"), std::string::npos)
      << log;
}

}  // namespace
