// Scene files: the strict schema (every malformed file gives one exact message), overrides,
// defaults, and the scene files shipped in inputs/.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "io/scene_yaml.hpp"
#include "solver/fluid_params.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

std::string bad_scene(const std::string& file) {
  return std::string(SPHDEM_TEST_DATA) + "/bad_scenes/" + file;
}
std::string input_scene(const std::string& file) {
  return std::string(SPHDEM_SOURCE_DIR) + "/inputs/" + file;
}

// Real is double or float (SPHDEM_PRECISION): compare parsed values with a matching tolerance.
double real_tol(double expected) {
  const double rel = std::is_same<Real, float>::value ? 1e-6 : 1e-12;
  return rel * std::max(1.0, std::fabs(expected));
}
#define EXPECT_REAL(a, b) EXPECT_NEAR((a), (b), real_tol(b))

// The InputError message of fn(), or a marker when it throws nothing.
std::string input_error(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no InputError>";
}

// ---- malformed files: one exact message each ------------------------------------------------

struct BadFile {
  const char* file;
  const char* message;  // after "<path>"; @DIR@ stands for the bad_scenes folder
};

const BadFile kBadFiles[] = {
    {"unknown_top_key.yaml",
     ":5: gravty: unknown key; allowed keys: name, dimension, domain, gravity, pressure_gradient, "
     "symmetry, fluid, sph, time, "
     "guards, checkpoint, parallel, frames, insitu, solids, barrier, fluid_blocks, diagnostics, "
     "dem"},
    {"rheology_bad_model.yaml", ":5: fluid.rheology.model: 'bingham' is not one of newtonian, hbp"},
    {"rheology_needs_laminar.yaml",
     ":6: fluid.rheology.model: hbp needs fluid.viscosity.model: laminar (mu_eff drives the "
     "laminar "
     "term)"},
    {"frames_bad_field.yaml",
     ":8: frames.fields[1]: 'pressure' is not one of vel, rho, press, acc, drho, mass, id"},
    {"parallel_imbalance_below_one.yaml",
     ":6: parallel.imbalance: value 0.5 is out of range; allowed [1, 100]"},
    {"checkpoint_negative.yaml",
     ":6: checkpoint.every_steps: value -5 is out of range; allowed [0, 2e9]"},
    {"unknown_nested_key.yaml",
     ":5: sph.dpp: unknown key; allowed keys: dp, h_factor, boundary, slip, boundary_layers, "
     "no_penetration, mdbc_limiter, pairwise"},
    {"unknown_deep_key.yaml",
     ":8: fluid.viscosity.mu: unknown key; allowed keys: model, nu, alpha"},
    {"wrong_type_number.yaml", ":6: time.end: expected a number, got 'soon'"},
    {"wrong_type_vector.yaml", ":4: gravity: expected a list of 3 numbers, got '-9.81'"},
    {"wrong_type_integer.yaml", ":2: dimension: expected an integer, got '2.5'"},
    {"quoted_number.yaml", ":5: time.end: expected a number, got the quoted string '1.0'"},
    {"section_not_mapping.yaml", ":4: sph: expected a mapping, got '0.01'"},
    {"fluid_blocks_not_list.yaml", ":6: fluid_blocks: expected a list, got a mapping"},
    {"bad_list_length.yaml", ":4: domain.lo: expected a list of 3 numbers, got a list of 2"},
    {"periodic_wrong_type.yaml", ":6: domain.periodic[0]: expected true or false, got '0'"},
    {"bad_boolean.yaml", ":8: diagnostics.energy: expected true or false, got 'yes'"},
    {"out_of_range_dp.yaml", ":7: sph.dp: value -0.001 is out of range; allowed (0, 1]"},
    {"out_of_range_h_factor.yaml", ":4: sph.h_factor: value 5 is out of range; allowed [0.5, 3]"},
    {"dimension_out_of_range.yaml", ":2: dimension: value 4 is out of range; allowed [2, 3]"},
    {"nested_shape_out_of_range.yaml",
     ":14: solids[0].shape.parts[1].shape.radius: value 0 is out of range; allowed (0, 1e6]"},
    {"bad_enum_viscosity.yaml",
     ":4: fluid.viscosity.model: 'laminr' is not one of laminar, artificial"},
    {"bad_enum_diffusion.yaml",
     ":4: fluid.diffusion.model: 'delta-sph' is not one of none, molteni, fourtakas"},
    {"bad_enum_shape.yaml",
     ":12: solids[1].shape.type: 'cube' is not one of box, plane, slab, cylinder, sphere, tank, "
     "union, difference, transform, mesh"},
    {"missing_dimension.yaml", ":1: dimension: required key is missing"},
    {"missing_dp.yaml", ":4: sph.dp: required key is missing"},
    {"missing_time.yaml", ":1: time: required key is missing"},
    {"shape_missing_type.yaml", ":8: solids[0].shape.type: required key is missing"},
    {"shape_unknown_key.yaml",
     ":12: solids[0].shape.radius: unknown key; allowed keys: type, lo, hi"},
    {"duplicate_key.yaml", ":7: sph.dp: duplicate key"},
    {"missing_mesh.yaml",
     ":10: solids[0].shape.file: cannot open mesh file '@DIR@/no_such_boulder.stl'"},
    {"yaml_syntax_error.yaml", ":5: YAML syntax error: end of sequence flow not found"},
    {"empty.yaml",
     ":1: the scene is empty; it needs at least name, dimension, domain, sph.dp and time.end"},
    {"top_level_list.yaml", ":1: expected a mapping of scene keys at the top level, got a list"},
    {"two_documents.yaml", ":7: a scene file holds one YAML document"},
    {"invalid_name.yaml",
     ":1: name: 'dam break' is not a valid name; use letters, digits, '_', '-' and '.'"},
    {"domain_hi_not_above_lo.yaml", ":5: domain.hi: hi.z = 0.5 must be greater than lo.z = 1"},
    {"fluid_block_outside_domain.yaml",
     ":8: fluid_blocks[0].hi: hi.x = 1.5 is outside the domain (x from 0 to 1)"},
    {"gauge_outside_domain.yaml",
     ":9: diagnostics.pressure_gauges[1].point: y = 1.5 is outside the domain (y from 0 to 1)"},
    {"gravity_y_in_2d.yaml",
     ":4: gravity: the y component must be 0 in 2D (runs are in the x-z plane)"},
    {"tank_2d_misses_y0.yaml",
     ":8: solids[0].shape.inner_hi: in 2D a tank must span y = 0 (lo.y < 0 < hi.y); runs are in "
     "the x-z plane"},
    {"zero_normal.yaml", ":8: solids[0].shape.normal: must not be the zero vector"},
    {"dt_fixed_below_dt_min.yaml", ":8: time.dt_fixed: 1e-7 is below time.dt_min = 1e-6"},
    {"profile_outside_domain.yaml",
     ":10: diagnostics.profiles[0].to: x = 1.4 is outside the domain (x from 0 to 1)"},
    {"profile_times_not_increasing.yaml",
     ":14: diagnostics.profiles[0].times[2]: times must be increasing; 0.2 follows 0.3"},
    {"probe_missing_solid.yaml",
     ":12: diagnostics.forces[0].solid: no solid named 'tnk'; solids are: tank"},
    {"duplicate_solid_name.yaml",
     ":9: solids[1].name: duplicate solid name 'wall' (also solids[0].name)"},
    {"insitu_missing_script.yaml",
     ":7: insitu.scripts[0]: cannot open Catalyst script '@DIR@/no_such_script.py'"},
    {"insitu_legacy_script.yaml",
     ":7: insitu.scripts[0]: Catalyst script '@DIR@/legacy_catalyst_script.py' must start with the "
     "line '# script-version: 2' (ParaView 5.11 legacy Catalyst runs version-2 scripts only)"},
    {"insitu_every_zero.yaml", ":8: insitu.every_steps: value 0 is out of range; allowed [1, 2e9]"},
    {"insitu_no_scripts.yaml", ":6: insitu.scripts: required key is missing"},
    {"duplicate_diagnostic_name.yaml",
     ":11: diagnostics.fronts[1].name: duplicate diagnostic name 'p1' (also "
     "diagnostics.pressure_gauges[0].name)"},
};

class SceneYamlBadFile : public ::testing::TestWithParam<BadFile> {};

TEST_P(SceneYamlBadFile, GivesExactMessage) {
  const std::string path = bad_scene(GetParam().file);
  std::string expected = path + GetParam().message;
  const std::string dir = std::string(SPHDEM_TEST_DATA) + "/bad_scenes";
  for (std::size_t at; (at = expected.find("@DIR@")) != std::string::npos;) {
    expected.replace(at, 5, dir);
  }
  EXPECT_EQ(input_error([&] { load_scene(path); }), expected);
}

std::string case_name(const ::testing::TestParamInfo<BadFile>& info) {
  std::string n = fs::path(info.param.file).stem().string();
  std::replace_if(
      n.begin(), n.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
  return n;
}

INSTANTIATE_TEST_SUITE_P(SceneYaml, SceneYamlBadFile, ::testing::ValuesIn(kBadFiles), case_name);

// Every file in bad_scenes/ has its expected message above (no file silently untested).
TEST(SceneYamlBadFiles, EveryFileIsInTheTable) {
  std::set<std::string> listed;
  for (const BadFile& c : kBadFiles) listed.insert(c.file);
  int n = 0;
  for (const auto& e : fs::directory_iterator(std::string(SPHDEM_TEST_DATA) + "/bad_scenes")) {
    if (e.path().extension() != ".yaml") continue;
    ++n;
    EXPECT_TRUE(listed.count(e.path().filename().string())) << e.path();
  }
  EXPECT_EQ(n, int(listed.size()));
  EXPECT_GE(n, 24);
}

TEST(SceneYamlBadFiles, MissingSceneFile) {
  const std::string path = bad_scene("does_not_exist.yaml");
  EXPECT_EQ(input_error([&] { load_scene(path); }), "cannot open scene file '" + path + "'");
}

TEST(SceneYamlBadFiles, ParseSceneReportsTheSourceName) {
  EXPECT_EQ(input_error([] { parse_scene("name: x\n", "inline.yaml"); }),
            "inline.yaml:1: dimension: required key is missing");
  EXPECT_EQ(input_error([] { parse_scene("name: [x\n", "inline.yaml"); }),
            "inline.yaml:2: YAML syntax error: end of sequence flow not found");
}

// ---- bad overrides: the message names the override ------------------------------------------

struct BadOverride {
  std::vector<std::string> overrides;
  std::string message;
};

TEST(SceneYamlBadOverride, GivesExactMessage) {
  const std::string path = input_scene("hydrostatic_tank_2d.yaml");
  const std::vector<BadOverride> cases = {
      {{"sph.dpp=0.1"}, "--set sph.dpp=0.1: unknown key 'sph.dpp'"},
      {{"sph.boundary=dbc", "sph.no_penetration=true"},
       "--set sph.no_penetration=true: sph.no_penetration: the penetration control is part of "
       "mDBC (boundary: mdbc); DBC walls resist approach through their own density"},
      {{"sph.boundary=dbc", "sph.mdbc_limiter=true"},
       "--set sph.mdbc_limiter=true: sph.mdbc_limiter: the limiter bounds mDBC's extrapolated "
       "wall density (boundary: mdbc); DBC walls have no extrapolation"},
      {{"sph.mdbc_limiter=sometimes"},
       "--set sph.mdbc_limiter=sometimes: sph.mdbc_limiter: expected true or false, got "
       "'sometimes'"},
      {{"foo.bar=1"}, "--set foo.bar=1: unknown key 'foo.bar'"},
      {{"solids[0].shape.radius=1"},
       "--set solids[0].shape.radius=1: unknown key 'solids[0].shape.radius'"},
      {{"sph.dp=-1"}, "--set sph.dp=-1: sph.dp: value -1 is out of range; allowed (0, 1]"},
      {{"time.end=soon"}, "--set time.end=soon: time.end: expected a number, got 'soon'"},
      {{"sph.dp=0.005", "fluid.viscosity={model: laminr}"},
       "--set fluid.viscosity={model: laminr}: fluid.viscosity.model: 'laminr' is not one of "
       "laminar, artificial"},
      {{"sph={dpp: 1}"},
       "--set sph={dpp: 1}: sph.dpp: unknown key; allowed keys: dp, h_factor, boundary, slip, "
       "boundary_layers, no_penetration, mdbc_limiter, pairwise"},
      {{"domain={lo: [0, 0, 0]}"},
       "--set domain={lo: [0, 0, 0]}: domain.hi: required key is missing"},
      {{"diagnostics.forces[0].solid=tnk"},
       "--set diagnostics.forces[0].solid=tnk: diagnostics.forces[0].solid: no solid named 'tnk'; "
       "solids are: tank"},
      {{"sph.dp"}, "--set sph.dp: expected key=value"},
      {{"gravity=[0,0"}, "--set gravity=[0,0: YAML syntax error: end of sequence flow not found"},
      {{"sph..dp=1"},
       "--set sph..dp=1: malformed key 'sph..dp'; expected e.g. sph.dp or solids[0].name"},
      {{"time.end.x=1"}, "--set time.end.x=1: 'time.end' is not a mapping"},
      {{"solids[3].name=x"}, "--set solids[3].name=x: 'solids' has no entry [3]"},
      {{"dimension[0]=2"}, "--set dimension[0]=2: 'dimension' is not a list"},
  };
  for (const BadOverride& c : cases) {
    SCOPED_TRACE(c.overrides.back());
    EXPECT_EQ(input_error([&] { load_scene(path, c.overrides); }), c.message);
  }
}

// A mean pressure gradient only along periodic axes; `weight` only in a box periodic along gravity.
TEST(SceneYamlPressureGradient, RefusedWhereAWallCarriesThePressure) {
  const std::string tank = input_scene("hydrostatic_tank_2d.yaml");
  EXPECT_EQ(input_error([&] { load_scene(tank, {"pressure_gradient=weight"}); }),
            "--set pressure_gradient=weight: pressure_gradient: 'weight' needs a box periodic "
            "along gravity; gravity.z = -9.81 but domain.periodic.z is false (a wall carries the "
            "weight there)");
  EXPECT_EQ(input_error([&] { load_scene(tank, {"pressure_gradient=[5, 0, 0]"}); }),
            "--set pressure_gradient=[5, 0, 0]: pressure_gradient: component x = 5 is along a "
            "non-periodic axis (domain.periodic.x is false); there the computed pressure carries "
            "the gradient");
  EXPECT_EQ(input_error([&] { load_scene(tank, {"pressure_gradient=up"}); }),
            "--set pressure_gradient=up: pressure_gradient: expected 'weight' or a list of 3 "
            "numbers [Pa/m], got 'up'");
  const std::string settling = input_scene("sphere_settling.yaml");
  EXPECT_EQ(input_error([&] { load_scene(settling, {"gravity=[0, 0, 0]"}); }),
            settling + ":18: pressure_gradient: 'weight' needs gravity; gravity is zero");
  const Scene s = load_scene(settling);
  EXPECT_TRUE(s.pressure_gradient.weight);
  EXPECT_TRUE(s.pressure_gradient.enabled());
  const Scene v = load_scene(settling, {"pressure_gradient=[0, 0, -9810]"});
  EXPECT_FALSE(v.pressure_gradient.weight);
  EXPECT_REAL(v.pressure_gradient.value.z, -9810);
}

// ---- the scene files in inputs/ -------------------------------------------------------------

TEST(SceneYamlInputs, EveryInputParsesAndRoundTrips) {
  int n = 0;
  for (const auto& e :
       fs::recursive_directory_iterator(std::string(SPHDEM_SOURCE_DIR) + "/inputs")) {
    if (e.path().extension() != ".yaml") continue;
    ++n;
    const std::string path = e.path().string();
    SCOPED_TRACE(path);
    Scene s;
    ASSERT_NO_THROW(s = load_scene(path)) << input_error([&] { load_scene(path); });
    EXPECT_EQ(s.name, e.path().stem().string());  // the convention: name = file name
    EXPECT_EQ(s.source, path);
    for (const Solid& solid : s.solids) EXPECT_TRUE(solid.sdf) << solid.name;
    // The resolved YAML is itself a valid scene with the same content.
    Scene again;
    ASSERT_NO_THROW(again = parse_scene(s.yaml_text, path));
    EXPECT_EQ(again.name, s.name);
    EXPECT_EQ(again.sph.dp, s.sph.dp);
    EXPECT_EQ(again.time.end, s.time.end);
    EXPECT_EQ(again.yaml_text, s.yaml_text);
  }
  EXPECT_GE(n, 4);
}

TEST(SceneYamlInputs, HydrostaticTank2d) {
  Scene s = load_scene(input_scene("hydrostatic_tank_2d.yaml"));
  EXPECT_EQ(s.dim, 2);
  ASSERT_EQ(s.fluid_blocks.size(), 1u);
  const FluidBlock& b = s.fluid_blocks[0];
  const double n_fluid = (b.hi.x - b.lo.x) / s.sph.dp * ((b.hi.z - b.lo.z) / s.sph.dp);
  EXPECT_GE(n_fluid, 5000);
  EXPECT_LE(n_fluid, 10000);
  EXPECT_REAL(b.hi.x - b.lo.x, 1.0);
  EXPECT_REAL(b.hi.z - b.lo.z, 0.5);
  EXPECT_TRUE(b.hydrostatic);
  ASSERT_EQ(s.diagnostics.pressure_gauges.size(), 1u);
  EXPECT_REAL(s.diagnostics.pressure_gauges[0].point.z, 0.25);  // mid-depth
  ASSERT_EQ(s.diagnostics.forces.size(), 1u);
  EXPECT_EQ(s.diagnostics.forces[0].name, "floor_force");
  EXPECT_EQ(s.diagnostics.forces[0].solid, "tank");
  const Solid* tank = s.find_solid("tank");
  ASSERT_NE(tank, nullptr);
  EXPECT_LT(tank->sdf->phi(Vec3(0.5, 0, -0.02)), 0);  // inside the floor
  EXPECT_GT(tank->sdf->phi(Vec3(0.5, 0, 0.25)), 0);   // in the water
  // The walls are deeper than the kernel support, 2h.
  EXPECT_GT(0.05, 2 * s.h());
}

TEST(SceneYamlInputs, DamBreak2d) {
  Scene s = load_scene(input_scene("dam_break_2d.yaml"));
  EXPECT_EQ(s.dim, 2);
  EXPECT_REAL(s.sph.dp, 0.146 / 40);
  EXPECT_REAL(s.h(), 1.2 * std::sqrt(2.0) * s.sph.dp);
  EXPECT_REAL(s.time.end, 0.6);
  ASSERT_EQ(s.fluid_blocks.size(), 1u);
  EXPECT_REAL(s.fluid_blocks[0].lo.x, 0);
  EXPECT_REAL(s.fluid_blocks[0].hi.x, 0.146);
  EXPECT_REAL(s.fluid_blocks[0].hi.z, 0.292);
  ASSERT_EQ(s.diagnostics.fronts.size(), 1u);
  EXPECT_EQ(s.diagnostics.fronts[0].name, "front");
  ASSERT_EQ(s.diagnostics.height_gauges.size(), 1u);
  EXPECT_EQ(s.diagnostics.height_gauges[0].name, "column_height");
  EXPECT_REAL(s.diagnostics.height_gauges[0].x, 0.01);
  const Solid* tank = s.find_solid("tank");
  ASSERT_NE(tank, nullptr);
  EXPECT_LT(tank->sdf->phi(Vec3(-0.01, 0, 0.1)), 0);  // the left wall; x = 0 is its inner face
  EXPECT_GT(tank->sdf->phi(Vec3(0.01, 0, 0.1)), 0);
  EXPECT_LT(tank->sdf->phi(Vec3(0.594, 0, 0.1)), 0);  // the right wall at x = 0.584
}

TEST(SceneYamlInputs, DamBreak3d) {
  Scene s = load_scene(input_scene("dam_break_3d.yaml"));
  EXPECT_EQ(s.dim, 3);
  EXPECT_REAL(s.sph.dp, 0.002);
  ASSERT_EQ(s.fluid_blocks.size(), 1u);
  EXPECT_REAL(s.fluid_blocks[0].hi.y - s.fluid_blocks[0].lo.y, 0.2);
  EXPECT_EQ(s.diagnostics.fronts.at(0).name, "front");
  EXPECT_EQ(s.diagnostics.height_gauges.at(0).name, "column_height");
  EXPECT_GT(0.01, 2 * s.h());  // wall thickness covers the kernel support
}

TEST(SceneYamlInputs, Poiseuille2d) {
  Scene s = load_scene(input_scene("poiseuille_2d.yaml"));
  EXPECT_TRUE(s.periodic[0]);
  EXPECT_FALSE(s.periodic[1]);
  EXPECT_FALSE(s.periodic[2]);
  EXPECT_REAL(s.gravity.x, 2e-4);
  EXPECT_REAL(s.gravity.z, 0);
  EXPECT_EQ(s.fluid.viscosity, ViscosityModel::kLaminar);
  EXPECT_REAL(s.fluid.nu, 1e-6);
  EXPECT_EQ(s.fluid.diffusion, DiffusionModel::kMolteni);
  EXPECT_REAL(1e-3 / s.sph.dp, 40);  // 40 particles across the gap
  // Steady u_max = F L^2 / (8 nu) = 2.5e-5 m/s: Mach well under the guard.
  EXPECT_LT(2.5e-5 / s.fluid.c0, s.guards.mach_max);
  EXPECT_EQ(s.solids.size(), 2u);
  ASSERT_NE(s.find_solid("bottom_plate"), nullptr);
  ASSERT_NE(s.find_solid("top_plate"), nullptr);
  EXPECT_LT(s.find_solid("bottom_plate")->sdf->phi(Vec3(5e-4, 0, -1e-5)), 0);
  EXPECT_GT(s.find_solid("bottom_plate")->sdf->phi(Vec3(5e-4, 0, 1e-5)), 0);
  EXPECT_LT(s.find_solid("top_plate")->sdf->phi(Vec3(5e-4, 0, 1.01e-3)), 0);
  ASSERT_EQ(s.diagnostics.profiles.size(), 1u);
  EXPECT_EQ(s.diagnostics.profiles[0].samples, 41);
  EXPECT_EQ(s.diagnostics.profiles[0].times.size(), 5u);
}

// ---- overrides ------------------------------------------------------------------------------

TEST(SceneYamlOverrides, ChangeValues) {
  const std::string path = input_scene("dam_break_2d.yaml");
  Scene s = load_scene(
      path, {"sph.dp=0.002", "time.end=0.5", "gravity=[0,0,-9.8]", "fluid.viscosity.model=laminar",
             "sph.boundary=dbc", "diagnostics.height_gauges[0].x=0.02",
             "fluid_blocks[0].velocity=[0.5, 0, 0]"});
  EXPECT_REAL(s.sph.dp, 0.002);
  EXPECT_REAL(s.time.end, 0.5);
  EXPECT_REAL(s.gravity.z, -9.8);
  EXPECT_EQ(s.fluid.viscosity, ViscosityModel::kLaminar);
  EXPECT_EQ(s.sph.boundary, BoundaryMethod::kDbc);
  EXPECT_REAL(s.diagnostics.height_gauges.at(0).x, 0.02);
  EXPECT_REAL(s.fluid_blocks.at(0).velocity.x, 0.5);
  // Untouched keys keep the file's values.
  EXPECT_REAL(s.fluid.alpha, 0.01);
  EXPECT_REAL(s.fluid_blocks.at(0).hi.x, 0.146);

  // The resolved YAML carries the overrides.
  Scene again = parse_scene(s.yaml_text, path);
  EXPECT_REAL(again.sph.dp, 0.002);
  EXPECT_REAL(again.time.end, 0.5);
  EXPECT_REAL(again.gravity.z, -9.8);
  EXPECT_EQ(again.fluid.viscosity, ViscosityModel::kLaminar);
  EXPECT_REAL(again.diagnostics.height_gauges.at(0).x, 0.02);
}

TEST(SceneYamlOverrides, AddKeysAndSectionsTheFileLacks) {
  Scene s = load_scene(input_scene("dam_break_2d.yaml"),
                       {"guards.mach_max=0.05", "guards.check_every=10", "time.dt_fixed=1e-5",
                        "time.dt_max=2e-4", "domain.periodic=[true, false, false]"});
  EXPECT_REAL(s.guards.mach_max, 0.05);
  EXPECT_EQ(s.guards.check_every, 10);
  EXPECT_REAL(s.guards.rho_min_ratio, GuardParams().rho_min_ratio);
  EXPECT_REAL(s.time.dt_fixed, 1e-5);
  EXPECT_REAL(s.time.dt_max, 2e-4);
  EXPECT_REAL(TimeParams().dt_max, 0);  // no cap unless asked
  EXPECT_TRUE(s.periodic[0]);
}

TEST(SceneYamlOverrides, LaterOverrideWins) {
  Scene s = load_scene(input_scene("dam_break_2d.yaml"), {"sph.dp=0.004", "sph.dp=0.003"});
  EXPECT_REAL(s.sph.dp, 0.003);
}

// ---- defaults -------------------------------------------------------------------------------

TEST(SceneYamlDefaults, MinimalSceneGetsTheStructDefaults) {
  const char* text =
      "name: minimal\n"
      "dimension: 3\n"
      "domain: {lo: [0, 0, 0], hi: [1, 2, 3]}\n"
      "sph: {dp: 0.05}\n"
      "time: {end: 0.25}\n";
  Scene s = parse_scene(text, "minimal.yaml");
  const Scene d;
  EXPECT_EQ(s.source, "minimal.yaml");
  EXPECT_EQ(s.name, "minimal");
  EXPECT_EQ(s.dim, 3);
  EXPECT_REAL(s.domain_hi.y, 2);
  EXPECT_REAL(s.domain_hi.z, 3);
  EXPECT_REAL(s.sph.dp, 0.05);
  EXPECT_REAL(s.time.end, 0.25);
  for (int a = 0; a < 3; ++a) EXPECT_FALSE(s.periodic[a]);
  EXPECT_EQ(s.gravity.x, d.gravity.x);
  EXPECT_EQ(s.gravity.y, d.gravity.y);
  EXPECT_EQ(s.gravity.z, d.gravity.z);
  EXPECT_EQ(s.fluid.rho0, d.fluid.rho0);
  EXPECT_EQ(s.fluid.c0, d.fluid.c0);
  EXPECT_EQ(s.fluid.c0_factor, d.fluid.c0_factor);
  EXPECT_EQ(s.fluid.gamma, d.fluid.gamma);
  EXPECT_EQ(s.fluid.viscosity, d.fluid.viscosity);
  EXPECT_EQ(s.fluid.nu, d.fluid.nu);
  EXPECT_EQ(s.fluid.alpha, d.fluid.alpha);
  EXPECT_EQ(s.fluid.diffusion, d.fluid.diffusion);
  EXPECT_EQ(s.fluid.delta, d.fluid.delta);
  EXPECT_EQ(s.sph.h_factor, d.sph.h_factor);
  EXPECT_EQ(s.sph.boundary, d.sph.boundary);
  EXPECT_EQ(s.sph.slip, d.sph.slip);
  EXPECT_EQ(s.sph.boundary_layers, d.sph.boundary_layers);
  EXPECT_EQ(s.time.cfl, d.time.cfl);
  EXPECT_EQ(s.time.dt_fixed, d.time.dt_fixed);
  EXPECT_EQ(s.time.dt_min, d.time.dt_min);
  EXPECT_EQ(s.time.integrator, d.time.integrator);
  EXPECT_EQ(s.time.verlet_euler_every, d.time.verlet_euler_every);
  EXPECT_EQ(s.guards.rho_min_ratio, d.guards.rho_min_ratio);
  EXPECT_EQ(s.guards.rho_max_ratio, d.guards.rho_max_ratio);
  EXPECT_EQ(s.guards.mach_max, d.guards.mach_max);
  EXPECT_EQ(s.guards.check_every, d.guards.check_every);
  EXPECT_TRUE(s.solids.empty());
  EXPECT_TRUE(s.fluid_blocks.empty());
  EXPECT_EQ(s.diagnostics.every, d.diagnostics.every);
  EXPECT_EQ(s.diagnostics.energy, d.diagnostics.energy);
  EXPECT_TRUE(s.diagnostics.pressure_gauges.empty());
  EXPECT_TRUE(s.diagnostics.forces.empty());
  EXPECT_REAL(s.h(), 1.2 * std::sqrt(3.0) * 0.05);
  EXPECT_FALSE(s.yaml_text.empty());
}

TEST(SceneYamlDefaults, ListItemDefaults) {
  const char* text =
      "name: items\n"
      "dimension: 2\n"
      "domain: {lo: [0, -1, 0], hi: [1, 1, 1]}\n"
      "sph: {dp: 0.01}\n"
      "time: {end: 1}\n"
      "fluid_blocks: [{lo: [0, 0, 0], hi: [0.5, 0, 0.5]}]\n"
      "diagnostics:\n"
      "  height_gauges: [{name: h, x: 0.2}]\n"
      "  fronts: [{name: f}]\n"
      "  profiles: [{name: p, from: [0, 0, 0.1], to: [1, 0, 0.1]}]\n";
  Scene s = parse_scene(text, "items.yaml");
  ASSERT_EQ(s.fluid_blocks.size(), 1u);
  EXPECT_TRUE(s.fluid_blocks[0].hydrostatic);
  EXPECT_EQ(s.fluid_blocks[0].velocity.x, 0);
  EXPECT_EQ(s.diagnostics.height_gauges.at(0).y, 0);
  EXPECT_EQ(s.diagnostics.fronts.at(0).direction.x, 1);
  EXPECT_EQ(s.diagnostics.fronts.at(0).origin.x, 0);
  EXPECT_EQ(s.diagnostics.profiles.at(0).samples, 100);
  EXPECT_TRUE(s.diagnostics.profiles.at(0).times.empty());
}

// ---- shapes ---------------------------------------------------------------------------------

// An ASCII STL of the axis-aligned cube [lo, hi]^3, outward-facing triangles.
void write_cube_stl(const std::string& path, double lo, double hi) {
  std::ofstream out(path);
  out << "solid cube\n";
  auto corner = [&](int i, int j, int k) { return Vec3(i ? hi : lo, j ? hi : lo, k ? hi : lo); };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Vec3 n;
      n[axis] = side ? 1 : -1;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      Vec3 q[4];
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int c = 0; c < 4; ++c) {
        int ijk[3];
        ijk[axis] = side;
        ijk[u] = uv[c][0];
        ijk[v] = uv[c][1];
        q[c] = corner(ijk[0], ijk[1], ijk[2]);
      }
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        Vec3 a = q[t[0]], b = q[t[1]], c = q[t[2]];
        if (dot(cross(b - a, c - a), n) < 0) std::swap(b, c);
        out << " facet normal " << n.x << " " << n.y << " " << n.z << "\n  outer loop\n";
        for (const Vec3& p : {a, b, c}) {
          out << "   vertex " << p.x << " " << p.y << " " << p.z << "\n";
        }
        out << "  endloop\n endfacet\n";
      }
    }
  }
  out << "endsolid cube\n";
}

TEST(SceneYamlShapes, EveryShapeTypeBuilds) {
  const fs::path dir = fs::temp_directory_path() / "sphdem_test_scene_yaml";
  fs::create_directories(dir / "meshes");
  write_cube_stl((dir / "meshes" / "cube.stl").string(), 0.4, 0.6);
  const std::string scene_path = (dir / "shapes.yaml").string();
  {
    std::ofstream out(scene_path);
    out << "name: shapes\n"
           "dimension: 3\n"
           "domain: {lo: [0, 0, 0], hi: [1, 1, 1]}\n"
           "sph: {dp: 0.02}\n"
           "time: {end: 0.1}\n"
           "solids:\n"
           "  - {name: box, shape: {type: box, lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}}\n"
           "  - {name: plane, shape: {type: plane, point: [0, 0, 0.1], normal: [0, 0, 1]}}\n"
           "  - {name: slab, shape: {type: slab, point: [0, 0, 0.5], normal: [0, 0, 2], "
           "thickness: 0.1}}\n"
           "  - {name: cyl, shape: {type: cylinder, a: [0.5, 0.5, 0], b: [0.5, 0.5, 1], "
           "radius: 0.1}}\n"
           "  - {name: ball, shape: {type: sphere, center: [0.5, 0.5, 0.5], radius: 0.2}}\n"
           "  - {name: tank, shape: {type: tank, inner_lo: [0, 0, 0], inner_hi: [1, 1, 1], "
           "thickness: 0.05, closed_top: true}}\n"
           "  - name: both\n"
           "    shape:\n"
           "      type: union\n"
           "      parts:\n"
           "        - {type: sphere, center: [0.2, 0.5, 0.5], radius: 0.05}\n"
           "        - {type: sphere, center: [0.8, 0.5, 0.5], radius: 0.05}\n"
           "  - name: hollow\n"
           "    shape:\n"
           "      type: difference\n"
           "      a: {type: sphere, center: [0.5, 0.5, 0.5], radius: 0.3}\n"
           "      b: {type: sphere, center: [0.5, 0.5, 0.5], radius: 0.2}\n"
           "  - name: moved\n"
           "    shape:\n"
           "      type: transform\n"
           "      shape: {type: box, lo: [-0.1, -0.05, -0.05], hi: [0.1, 0.05, 0.05]}\n"
           "      axis: [0, 0, 1]\n"
           "      angle_deg: 90\n"
           "      translate: [0.5, 0.5, 0.5]\n"
           "  - {name: mesh, shape: {type: mesh, file: meshes/cube.stl, spacing: 0.01}}\n";
  }
  Scene s;
  ASSERT_NO_THROW(s = load_scene(scene_path)) << input_error([&] { load_scene(scene_path); });
  ASSERT_EQ(s.solids.size(), 10u);
  auto phi = [&](const char* name, Vec3 x) {
    const Solid* solid = s.find_solid(name);
    EXPECT_NE(solid, nullptr) << name;
    return solid ? solid->sdf->phi(x) : Real(0);
  };
  EXPECT_LT(phi("box", Vec3(0.05, 0.05, 0.05)), 0);
  EXPECT_GT(phi("box", Vec3(0.5, 0.5, 0.5)), 0);
  EXPECT_LT(phi("plane", Vec3(0.5, 0.5, 0.05)), 0);
  EXPECT_GT(phi("plane", Vec3(0.5, 0.5, 0.15)), 0);
  EXPECT_REAL(phi("slab", Vec3(0.3, 0.3, 0.5)), -0.05);
  EXPECT_REAL(phi("cyl", Vec3(0.5, 0.7, 0.5)), 0.1);
  EXPECT_REAL(phi("ball", Vec3(0.5, 0.5, 0.9)), 0.2);
  EXPECT_LT(phi("tank", Vec3(0.5, 0.5, 1.02)), 0);  // closed top
  EXPECT_GT(phi("tank", Vec3(0.5, 0.5, 0.5)), 0);
  EXPECT_LT(phi("both", Vec3(0.8, 0.5, 0.5)), 0);
  EXPECT_GT(phi("both", Vec3(0.5, 0.5, 0.5)), 0);
  EXPECT_GT(phi("hollow", Vec3(0.5, 0.5, 0.5)), 0);
  EXPECT_LT(phi("hollow", Vec3(0.5, 0.5, 0.75)), 0);
  // The box is long in x before the 90-degree turn about z: long in y after it.
  EXPECT_LT(phi("moved", Vec3(0.5, 0.58, 0.5)), 0);
  EXPECT_GT(phi("moved", Vec3(0.58, 0.5, 0.5)), 0);
  EXPECT_LT(phi("mesh", Vec3(0.5, 0.5, 0.5)), 0);
  EXPECT_GT(phi("mesh", Vec3(0.8, 0.5, 0.5)), 0);
  fs::remove_all(dir);
}

TEST(SceneYaml, FindSolidAndH) {
  Scene s;
  s.dim = 2;
  s.sph.dp = 0.01;
  s.sph.h_factor = 1.5;
  EXPECT_REAL(s.h(), 1.5 * std::sqrt(2.0) * 0.01);
  s.dim = 3;
  EXPECT_REAL(s.h(), 1.5 * std::sqrt(3.0) * 0.01);
  s.solids.push_back(Solid{"a", nullptr, {}});
  s.solids.push_back(Solid{"b", nullptr, {}});
  ASSERT_NE(s.find_solid("b"), nullptr);
  EXPECT_EQ(s.find_solid("b")->name, "b");
  EXPECT_EQ(s.find_solid("c"), nullptr);
}

// sph.mdbc_limiter reaches the solver's step parameters (update_mdbc reads p.mdbc_limit), and
// only with mDBC walls.
TEST(SceneYaml, MdbcLimiterReachesTheStepParameters) {
  const std::string base =
      "name: t\ndimension: 2\ndomain: {lo: [0, 0, 0], hi: [1, 0, 1]}\ntime: {end: 0.1}\n";
  EXPECT_FALSE(make_step_params(parse_scene(base + "sph: {dp: 0.01}\n", "a.yaml"), 10).mdbc_limit);
  EXPECT_TRUE(
      make_step_params(parse_scene(base + "sph: {dp: 0.01, mdbc_limiter: true}\n", "b.yaml"), 10)
          .mdbc_limit);
}

}  // namespace
}  // namespace sphdem
