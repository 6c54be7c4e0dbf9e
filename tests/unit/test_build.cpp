// The scene build's wall filter (many ranks store only the walls near their box): the filtered
// build stores exactly the walls the filter keeps, with the ids and values of the full build, and
// its report counts every wall of the scene.
#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <string>

#include "io/scene_yaml.hpp"
#include "scene/build.hpp"

namespace sphdem {
namespace {

TEST(BuildParticles, WallFilterStoresTheKeptWallsWithTheFullBuildsIds) {
  const Scene scene =
      load_scene(std::string(SPHDEM_SOURCE_DIR) + "/inputs/dam_break_3d.yaml", {"sph.dp=0.02"});
  BuildReport full_rep, cut_rep;
  const ParticleSet<Host> full = build_particles(scene, &full_rep);
  // Keep the walls whose position lies at x < 0.3 m or whose ghost node lies above z = 0.2 m.
  auto keep = [](const Vec3& x, const Vec3& g) { return x.x < Real(0.3) || g.z > Real(0.2); };
  const ParticleSet<Host> cut = build_particles(scene, &cut_rep, keep);

  EXPECT_EQ(cut_rep.wall, full_rep.wall);
  EXPECT_EQ(cut_rep.wall_by_solid, full_rep.wall_by_solid);
  EXPECT_EQ(cut_rep.fluid, full_rep.fluid);
  ASSERT_EQ(cut.n_fluid, full.n_fluid);
  std::map<GlobalId, Index> by_id;
  Index kept = 0;
  for (Index i = full.wall_begin(); i < full.size(); ++i) {
    by_id[full.id[i]] = i;
    if (keep(full.pos[i], full.ghost[i])) ++kept;
  }
  ASSERT_GT(kept, 0);
  ASSERT_LT(kept, full.n_wall);  // the filter drops some walls
  EXPECT_EQ(cut.n_wall, kept);
  for (Index i = cut.wall_begin(); i < cut.size(); ++i) {
    const auto at = by_id.find(cut.id[i]);
    ASSERT_NE(at, by_id.end()) << "wall id " << cut.id[i] << " is not in the full build";
    const Index j = at->second;
    EXPECT_TRUE(keep(cut.pos[i], cut.ghost[i]));
    EXPECT_EQ(cut.pos[i].x, full.pos[j].x);
    EXPECT_EQ(cut.pos[i].y, full.pos[j].y);
    EXPECT_EQ(cut.pos[i].z, full.pos[j].z);
    EXPECT_EQ(cut.ghost[i].z, full.ghost[j].z);
    EXPECT_EQ(cut.ghost_alt[i].x, full.ghost_alt[j].x);
    EXPECT_EQ(cut.normal[i].x, full.normal[j].x);
    EXPECT_EQ(cut.body[i], full.body[j]);
  }
  // The fluid is the same, id for id.
  for (Index i = 0; i < cut.n_fluid; ++i) EXPECT_EQ(cut.id[i], full.id[i]);
}

// Lattice points on a solid's surface: at dp = 0.4 m / 56 the flume's barrier walls are 7 dp wide
// on an 8 dp pitch, so both side faces of every wall lie on lattice rows. Each face holds 2
// columns across the 13 mm thickness (x = 0.596 and 0.604 m) by 13 rows up the 90 mm height (the
// points below the floor belong to the channel, the nearer surface there): 52 per wall. At
// 5 mm no barrier face is on a row. The build names them and `describe_surface_ties` warns.
TEST(BuildParticles, CountsLatticePointsOnASolidsSurface) {
  const std::string flume = std::string(SPHDEM_SOURCE_DIR) + "/inputs/flume/flume.yaml";
  BuildReport fine, five;
  build_particles(load_scene(flume, {"sph.dp=0.00714285714"}), &fine);
  std::map<std::string, Index> ties;
  for (const SurfaceTie& t : fine.ties) ties[t.name] = t.points;
  for (int k = 1; k <= 7; ++k)
    EXPECT_EQ(ties["barrier_" + std::to_string(k)], 52) << "barrier_" << k;
  std::ostringstream os;
  describe_surface_ties(fine, Real(0.00714285714), os);
  EXPECT_EQ(os.str().rfind("warning: ", 0), 0u) << os.str();
  EXPECT_NE(os.str().find("'barrier_1', 'barrier_2'"), std::string::npos) << os.str();
  EXPECT_NE(os.str().find("move the solid by dp/2 or change dp"), std::string::npos) << os.str();

  build_particles(load_scene(flume, {"sph.dp=0.005"}), &five);
  for (const SurfaceTie& t : five.ties)
    EXPECT_EQ(t.name.rfind("barrier_", 0), std::string::npos) << t.name << ": " << t.points;
}

}  // namespace
}  // namespace sphdem
