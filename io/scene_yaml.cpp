// Scene files: YAML, checked against a strict schema, resolved into a Scene (scene/scene.hpp).
//
// Layout, with the defaults (keys marked "required" must be present; every other key may be left
// out and takes the default shown). Ranges are inclusive "[", exclusive "(". 2D runs are in the x-z
// plane at y = 0: vectors always have three components, and y is ignored where it does not matter.
//
//   name: dam_break_2d           # required; letters, digits, '_', '-', '.'
//   dimension: 2                 # required; 2 or 3
//   domain:                      # required; particles leaving it are removed
//     lo: [x, y, z]              # required
//     hi: [x, y, z]              # required; hi > lo on the used axes (x, z in 2D; 2D: y = 0
//     inside) periodic: [false, false, false]    # per axis; y cannot be periodic in 2D
//   gravity: [0, 0, -9.81]       # m/s^2, each component in [-1000, 1000]; also the body force.
//                                # 2D: the y component must be 0
//   pressure_gradient: [0, 0, 0] # Pa/m, a uniform mean gradient along periodic axes (fluid:
//                                # -G/rho0 per kg, grains: -G V); or `weight`: G carries the
//                                # box's weight (every axis along gravity periodic; needs fluid)
//   symmetry: {axis: y, at: 0.2, keep: above}
//                                # optional symmetry plane x_axis = at (3D; axis x|y|z, not
//                                # periodic; at strictly inside the domain): only the `keep` side
//                                # (above|below) is modelled, the plane is a mirror (free slip);
//                                # one rank, no grains (dem); diagnostics report the mirrored
//                                # full scene, frames and checkpoints hold the modelled side
//   fluid:
//     rho0: 1000                 # (0, 1e5] kg/m^3
//     c0: 0                      # [0, 1e4] m/s; 0 = c0_factor * expected maximum speed
//     c0_factor: 10              # [1, 100]
//     gamma: 7                   # [1, 10], Tait exponent
//     viscosity: {model: laminar, nu: 1e-6, alpha: 0.01}
//                                # model laminar|artificial; nu [0, 1e3] m^2/s (kinematic);
//                                # alpha [0, 10] (Monaghan artificial viscosity)
//     diffusion: {model: fourtakas, delta: 0.1}   # model none|molteni|fourtakas; delta [0, 1]
//     rheology:                  # Herschel-Bulkley-Papanastasiou (seed Eqs. 11-15)
//       model: newtonian         # newtonian|hbp (hbp needs viscosity.model laminar)
//       k: 1e-3                  # [0, 1e6] Pa s^n, consistency (dynamic)
//       n: 1                     # [0.1, 3] flow index
//       m: 100                   # [0, 1e6] s, Papanastasiou exponent
//       cohesion: 0              # [0, 1e7] Pa
//       friction_deg: 0          # [0, 89] degrees; tau_y = cohesion + max(p, 0) tan(phi)
//       mu_max: 1e3              # (0, 1e7] Pa s, cap on mu_eff
//       yield: true              # false drops the yield term (diagnostics)
//     sps: {enabled: false, cs: 0.12, ci: 0.0066}   # Dalrymple & Rogers SPS turbulence
//   sph:                         # required
//     dp: 0.002                  # required; (0, 1] m, initial particle spacing
//     h_factor: 1.2              # [0.5, 3]; h = h_factor * sqrt(dimension) * dp
//     boundary: mdbc             # dbc|mdbc
//     slip: noslip               # noslip|freeslip
//     boundary_layers: 0         # [0, 20]; 0 = enough layers to fill the kernel support (2h)
//   time:                        # required
//     end: 1.0                   # required; (0, 1e6] s
//     cfl: 0.2                   # (0, 1]
//     dt_fixed: 0                # [0, 1] s; > 0 = fixed time step (verification only), >= dt_min
//     dt_min: 1e-9               # [0, 1] s; a step stuck here is a stability fault
//     integrator: verlet         # verlet|symplectic
//     verlet_euler_every: 40     # [1, 1e6]
//   guards:
//     rho_min_ratio: 0.7         # (0, 1)
//     rho_max_ratio: 1.3         # (1, 10]
//     mach_max: 0.1              # (0, 1]
//     check_every: 0             # [0, 1e6] steps; 0 = auto (host 1, device 20)
//     penetration_depth: 0.5     # [0, 10] dp; fluid deeper inside a solid is a fault
//   checkpoint:                  # when to write checkpoints (0 = never by this rule)
//     every_time: 0              # [0, 1e6] simulated s
//     every_steps: 0             # [0, 2e9]
//     every_wall: 0              # [0, 1e7] wall-clock s
//     keep: 3                    # [1, 1000] newest kept
//   parallel:                    # runs on many ranks (mpirun)
//     rebalance_every: 100       # [0, 1e9] steps between imbalance checks (0 = only at the start)
//     imbalance: 1.2             # [1, 100] max/mean owned fluid per rank that triggers a rebalance
//     skin: 0.2                  # [0, 2] h; halo margin: the plan is rebuilt after a skin/2 move
//   frames:                      # ParaView frames (HDF5 + one XDMF index)
//     every: 0                   # [0, 1e6] simulated s; 0 = none
//     fields: [vel, rho, press]  # from: vel, rho, press, acc, drho, mass, id
//     boundary: true             # also write wall boundary particles
//     region: {lo: [..], hi: [..]}   # optional box limiting what is written
//   insitu:                      # ParaView Catalyst extracts (build with SPHDEM_ENABLE_CATALYST)
//     scripts: [catalyst/impact_force.py]   # required; Python files whose first line is
//                                # "# script-version: 2", relative to the scene file's folder
//     every_steps: 10            # [1, 2e9] steps between extract steps (step 0 included)
//   solids:                      # a list; names are unique
//     - name: tank               # required
//       shape: {type: tank, inner_lo: [..], inner_hi: [..], thickness: 0.01}   # required
//       boundary_regions: [{lo: [..], hi: [..]}]   # boundary particles only inside these boxes
//       removed_at: 1e30         # [0, 1e6] s; the solid goes at this time (a gate that opens):
//                                # its boundary particles, its DEM wall and its guard
//   fluid_blocks:                # a list of boxes filled on the dp lattice, minus the solids
//     - lo: [x, y, z]            # required; inside the domain
//       hi: [x, y, z]            # required; hi > lo on the used axes, inside the domain
//       velocity: [0, 0, 0]      # m/s, components in [-1000, 1000]; 2D: y must be 0
//       hydrostatic: true        # initial pressure rho0 g (block top - z)
//       level: none              # m; fill only below this free surface, a plane normal to
//                                # gravity at height `level` along -g (from the origin): the
//                                # block's water at rest; the pressure is rho0 g (level - height)
//   diagnostics:                 # every name below is unique over all diagnostics
//     every: 0.01                # (0, 1e4] s between CSV rows
//     pressure_gauges: [{name: p1, point: [x, y, z]}]           # point inside the domain
//     height_gauges: [{name: h1, x: 0.01, y: 0}]                 # x (required), y inside the
//     domain fronts: [{name: front, origin: [0, 0, 0], direction: [1, 0, 0]}]   # direction not
//     zero profiles: [{name: s, from: [..], to: [..], samples: 100, times: [0.1, 0.2]}]
//                                # from, to required and distinct; samples [2, 1e6];
//                                # times >= 0 and increasing (times after time.end never happen)
//                                # quantity: surface (elevation above each point) | velocity
//                                # (kernel-interpolated fluid velocity at each point)
//     forces: [{name: floor_force, solid: tank}]                 # solid: the name of a solid
//     energy: true
//
// Shapes (key `type`; all keys required unless a default is given; coordinates in [-1e6, 1e6],
// lengths in (0, 1e6]):
//   box        {lo, hi}                                hi > lo; 2D: lo.y < 0 < hi.y
//   plane      {point, normal}                         solid where dot(x - point, normal) < 0
//   slab       {point, normal, thickness}              |dot(x - point, n)| < thickness / 2
//   cylinder   {a, b, radius}                          capped, axis from a to b (a != b)
//   sphere     {center, radius}
//   tank       {inner_lo, inner_hi, thickness, closed_top: false}
//                                                      walls around the inner box; 2D: lo.y < 0 <
//                                                      hi.y
//   union      {parts: [shape, ...]}                   at least one part
//   difference {a: shape, b: shape}                    a minus b
//   transform  {shape, axis: [0, 0, 1], angle_deg: 0, translate: [0, 0, 0]}
//                                                      x_world = R(axis, angle) x_body + translate
//   mesh       {file, spacing: sph.dp}                 STL/OBJ, relative to the scene file's folder
//
// Errors name the file, the line (1-based) and the dotted key: "<file>:<line>: <key>: <what>".
// Overrides ("--set key=value") are applied to the tree before validation; an error inside an
// overridden value names the override instead of the file: "--set <key>=<value>: <key>: <what>".
#include "io/scene_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <utility>

#include "core/error.hpp"
#include "geometry/sdf.hpp"
#include "scene/barrier.hpp"

namespace sphdem {
namespace {

// Shortest readable form: 0.5, 1000, 1e6, 1e-7 (not 1e+06, 1e-07).
std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  std::string s = os.str();
  std::size_t e = s.find('e');
  if (e != std::string::npos) {
    std::string mant = s.substr(0, e), sign = s[e + 1] == '-' ? "-" : "";
    std::string digits = s.substr(e + 2);
    digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size() - 1));
    s = mant + "e" + sign + digits;
  }
  return s;
}

std::string join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += sep;
    out += items[i];
  }
  return out;
}

struct Range {
  double lo, hi;
  bool lo_open, hi_open;
  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string str() const {
    return std::string(lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) + (hi_open ? ")" : "]");
  }
};
constexpr Range closed(double lo, double hi) {
  return {lo, hi, false, false};
}
constexpr Range left_open(double lo, double hi) {
  return {lo, hi, true, false};
}
constexpr Range open_interval(double lo, double hi) {
  return {lo, hi, true, true};
}

constexpr double kBig = 1e6;
constexpr Range kCoord = closed(-kBig, kBig);      // any coordinate
constexpr Range kLength = left_open(0, kBig);      // a positive length
constexpr Range kDirection = closed(-kBig, kBig);  // a direction (checked non-zero separately)

const char* const kAxis[3] = {"x", "y", "z"};

std::vector<int> used_axes(int dim) {
  return dim == 2 ? std::vector<int>{0, 2} : std::vector<int>{0, 1, 2};
}

// A value in the tree, with the line and dotted key to report.
struct Field {
  YAML::Node node;
  YAML::Mark mark;
  std::string path;
};

std::string key_path(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}
std::string index_path(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// True when dotted key `path` is `base` or lies inside it ("a.b[2].c" lies inside "a.b").
bool path_within(const std::string& path, const std::string& base) {
  if (base.empty() || path.compare(0, base.size(), base) != 0) return false;
  return path.size() == base.size() || path[base.size()] == '.' || path[base.size()] == '[';
}

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Scalar:
      return "'" + n.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "an empty value";
  }
}

// A quoted scalar ('0.5', "true") is a string, never a number or a boolean.
bool is_quoted(const YAML::Node& n) {
  return n.IsScalar() && n.Tag() == "!";
}

struct Override {
  std::string text;  // as given: "sph.dp=0.002"
  std::string path;  // normalised dotted key: "sph.dp"
};

template <class E>
using EnumTable = std::vector<std::pair<std::string, E>>;

const EnumTable<DiffusionModel> kDiffusionModels = {{"none", DiffusionModel::kNone},
                                                    {"molteni", DiffusionModel::kMolteni},
                                                    {"fourtakas", DiffusionModel::kFourtakas}};
const EnumTable<ViscosityModel> kViscosityModels = {{"laminar", ViscosityModel::kLaminar},
                                                    {"artificial", ViscosityModel::kArtificial}};
const EnumTable<RheologyModel> kRheologyModels = {{"newtonian", RheologyModel::kNewtonian},
                                                  {"hbp", RheologyModel::kHbp}};
const EnumTable<BoundaryMethod> kBoundaryMethods = {{"dbc", BoundaryMethod::kDbc},
                                                    {"mdbc", BoundaryMethod::kMdbc}};
const EnumTable<SlipCondition> kSlipConditions = {{"noslip", SlipCondition::kNoSlip},
                                                  {"freeslip", SlipCondition::kFreeSlip}};
const EnumTable<Integrator> kIntegrators = {{"verlet", Integrator::kVerlet},
                                            {"symplectic", Integrator::kSymplectic}};
const EnumTable<GrainShapeType> kGrainShapes = {
    {"sphere", GrainShapeType::kSphere},
    {"box", GrainShapeType::kBox},
    {"ellipsoid", GrainShapeType::kEllipsoid},
    {"trigonal_pyramid", GrainShapeType::kTrigonalPyramid},
    {"polyhedron", GrainShapeType::kPolyhedron},
    {"mesh", GrainShapeType::kMesh}};
const EnumTable<std::string> kContactLaws = {{"linear", "linear"}, {"hertz", "hertz"}};
const EnumTable<std::string> kBarrierPresets = {
    {"P00", "P00"}, {"P30", "P30"}, {"P45", "P45"}, {"V30", "V30"}, {"V45", "V45"}};
const EnumTable<char> kBarrierLayouts = {{"P", 'P'}, {"V", 'V'}};
const EnumTable<bool> kProfileQuantities = {{"surface", false}, {"velocity", true}};
const EnumTable<int> kSymmetryAxes = {{"x", 0}, {"y", 1}, {"z", 2}};
const EnumTable<int> kSymmetrySides = {{"above", 1}, {"below", -1}};
const EnumTable<bool> kBarrierApex = {{"upstream", true}, {"downstream", false}};
const EnumTable<std::string> kPackPlacements = {{"shelf", "shelf"}, {"random", "random"}};

enum class ShapeType {
  kBox,
  kPlane,
  kSlab,
  kCylinder,
  kSphere,
  kTank,
  kUnion,
  kDifference,
  kTransform,
  kMesh
};
const EnumTable<ShapeType> kShapeTypes = {{"box", ShapeType::kBox},
                                          {"plane", ShapeType::kPlane},
                                          {"slab", ShapeType::kSlab},
                                          {"cylinder", ShapeType::kCylinder},
                                          {"sphere", ShapeType::kSphere},
                                          {"tank", ShapeType::kTank},
                                          {"union", ShapeType::kUnion},
                                          {"difference", ShapeType::kDifference},
                                          {"transform", ShapeType::kTransform},
                                          {"mesh", ShapeType::kMesh}};

std::vector<std::string> shape_keys(ShapeType t) {
  switch (t) {
    case ShapeType::kBox:
      return {"type", "lo", "hi"};
    case ShapeType::kPlane:
      return {"type", "point", "normal"};
    case ShapeType::kSlab:
      return {"type", "point", "normal", "thickness"};
    case ShapeType::kCylinder:
      return {"type", "a", "b", "radius"};
    case ShapeType::kSphere:
      return {"type", "center", "radius"};
    case ShapeType::kTank:
      return {"type", "inner_lo", "inner_hi", "thickness", "closed_top"};
    case ShapeType::kUnion:
      return {"type", "parts"};
    case ShapeType::kDifference:
      return {"type", "a", "b"};
    case ShapeType::kTransform:
      return {"type", "shape", "axis", "angle_deg", "translate"};
    case ShapeType::kMesh:
      return {"type", "file", "spacing"};
  }
  return {};
}

class Parser;

// One mapping of the tree: its keys are checked against the allowed set on construction.
class MapReader {
 public:
  MapReader(const Parser& parser, const Field& self, const std::vector<std::string>& allowed);

  const Field& self() const { return self_; }
  std::optional<Field> find(const std::string& key) const {
    for (const auto& e : entries_) {
      if (e.first == key) return e.second;
    }
    return std::nullopt;
  }
  Field require(const std::string& key) const;

  Real number(const std::string& key, const Range& r, Real fallback) const;
  Real number(const std::string& key, const Range& r) const;
  int integer(const std::string& key, int lo, int hi, int fallback) const;
  bool boolean(const std::string& key, bool fallback) const;
  Vec3 vec3(const std::string& key, const Range& r, Vec3 fallback) const;
  Vec3 vec3(const std::string& key, const Range& r) const;
  template <class E>
  E enumeration(const std::string& key, const EnumTable<E>& table, E fallback) const;

 private:
  const Parser* parser_;
  Field self_;
  std::vector<std::pair<std::string, Field>> entries_;
};

class Parser {
 public:
  Parser(std::string file, std::vector<Override> overrides)
      : file_(std::move(file)), overrides_(std::move(overrides)) {}

  Scene parse(const YAML::Node& root);

  // ---- errors ----
  // Where a problem is: the override that produced the value, or the file and line.
  std::string where(const YAML::Mark& mark, const std::string& path) const {
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
      if (path_within(path, it->path)) return "--set " + it->text;
    }
    if (mark.line >= 0) return file_ + ":" + std::to_string(mark.line + 1);
    // A mapping that an override created on its way to its key has no line.
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
      if (path_within(it->path, path)) return "--set " + it->text;
    }
    return file_;
  }
  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& path,
                         const std::string& what) const {
    std::string msg = where(mark, path) + ": ";
    if (!path.empty()) msg += path + ": ";
    throw InputError(msg + what);
  }
  [[noreturn]] void fail(const Field& f, const std::string& what) const {
    fail(f.mark, f.path, what);
  }
  [[noreturn]] void unknown_key(const YAML::Mark& mark, const std::string& path,
                                const std::vector<std::string>& allowed) const {
    // An override that put the unknown key there (or something below it) is reported as such.
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
      if (path_within(it->path, path)) {
        throw InputError("--set " + it->text + ": unknown key '" + it->path + "'");
      }
    }
    fail(mark, path, "unknown key; allowed keys: " + join(allowed));
  }

  // ---- scalar conversions ----
  double parse_double(const Field& f, const char* expected) const {
    if (!f.node.IsScalar()) {
      fail(f, std::string("expected ") + expected + ", got " + describe(f.node));
    }
    const std::string& s = f.node.Scalar();
    if (is_quoted(f.node)) {
      fail(f, std::string("expected ") + expected + ", got the quoted string '" + s + "'");
    }
    bool ok = !s.empty() && s.find_first_not_of("0123456789+-.eE") == std::string::npos;
    double v = 0;
    if (ok) {
      char* end = nullptr;
      v = std::strtod(s.c_str(), &end);
      ok = end == s.c_str() + s.size() && std::isfinite(v);
    }
    if (!ok) fail(f, std::string("expected ") + expected + ", got '" + s + "'");
    return v;
  }
  Real number(const Field& f, const Range& r) const {
    double v = parse_double(f, "a number");
    if (!r.contains(v)) {
      fail(f, "value " + f.node.Scalar() + " is out of range; allowed " + r.str());
    }
    return Real(v);
  }
  int integer(const Field& f, int lo, int hi) const {
    double v = parse_double(f, "an integer");
    if (v != std::floor(v)) fail(f, "expected an integer, got '" + f.node.Scalar() + "'");
    if (v < lo || v > hi) {
      fail(f, "value " + f.node.Scalar() + " is out of range; allowed " + closed(lo, hi).str());
    }
    return int(v);
  }
  bool boolean(const Field& f) const {
    if (f.node.IsScalar() && !is_quoted(f.node)) {
      const std::string& s = f.node.Scalar();
      if (s == "true" || s == "True" || s == "TRUE") return true;
      if (s == "false" || s == "False" || s == "FALSE") return false;
    }
    fail(f, "expected true or false, got " + describe(f.node));
  }
  std::string string(const Field& f) const {
    if (!f.node.IsScalar()) fail(f, "expected a string, got " + describe(f.node));
    return f.node.Scalar();
  }
  std::string name(const Field& f) const {
    std::string s = string(f);
    bool ok = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    });
    if (!ok) fail(f, "'" + s + "' is not a valid name; use letters, digits, '_', '-' and '.'");
    return s;
  }
  template <class E>
  E enumeration(const Field& f, const EnumTable<E>& table) const {
    std::vector<std::string> names;
    for (const auto& e : table) names.push_back(e.first);
    if (!f.node.IsScalar()) {
      fail(f, "expected one of " + join(names) + ", got " + describe(f.node));
    }
    for (const auto& e : table) {
      if (e.first == f.node.Scalar()) return e.second;
    }
    fail(f, "'" + f.node.Scalar() + "' is not one of " + join(names));
  }

  // ---- lists ----
  std::vector<Field> list(const Field& f) const {
    if (!f.node.IsSequence()) fail(f, "expected a list, got " + describe(f.node));
    std::vector<Field> out;
    for (std::size_t i = 0; i < f.node.size(); ++i) {
      YAML::Node e = f.node[i];
      YAML::Mark m = e.Mark();
      if (m.line < 0 || e.IsNull()) m = f.mark;
      out.push_back(Field{e, m, index_path(f.path, i)});
    }
    return out;
  }
  std::vector<Field> fixed_list(const Field& f, std::size_t n, const char* what) const {
    if (!f.node.IsSequence()) {
      fail(f, "expected a list of " + std::to_string(n) + " " + what + ", got " + describe(f.node));
    }
    if (f.node.size() != n) {
      fail(f, "expected a list of " + std::to_string(n) + " " + what + ", got a list of " +
                  std::to_string(f.node.size()));
    }
    return list(f);
  }
  Vec3 vec3(const Field& f, const Range& r) const {
    std::vector<Field> items = fixed_list(f, 3, "numbers");
    return Vec3(number(items[0], r), number(items[1], r), number(items[2], r));
  }
  MapReader map(const Field& f, const std::vector<std::string>& allowed) const {
    return MapReader(*this, f, allowed);
  }

 private:
  // ---- checks shared by several sections ----
  void check_planar(const Field& f, const Vec3& v) const {
    if (dim_ == 2 && v.y != 0) {
      fail(f, "the y component must be 0 in 2D (runs are in the x-z plane)");
    }
  }
  void check_above(const Field& f_hi, const Vec3& lo, const Vec3& hi,
                   const std::vector<int>& axes) const {
    for (int a : axes) {
      if (!(hi[a] > lo[a])) {
        fail(f_hi, std::string("hi.") + kAxis[a] + " = " + fmt(hi[a]) +
                       " must be greater than lo." + kAxis[a] + " = " + fmt(lo[a]));
      }
    }
  }
  void check_spans_y0(const Field& f, const Vec3& lo, const Vec3& hi, const char* what) const {
    if (dim_ == 2 && !(lo.y < 0 && 0 < hi.y)) {
      fail(f, std::string("in 2D ") + what +
                  " must span y = 0 (lo.y < 0 < hi.y); runs are in the x-z plane");
    }
  }
  void check_in_domain(const Field& f, Real v, int axis, const std::string& label) const {
    if (v < scene_->domain_lo[axis] || v > scene_->domain_hi[axis]) {
      fail(f, label + kAxis[axis] + " = " + fmt(v) + " is outside the domain (" + kAxis[axis] +
                  " from " + fmt(scene_->domain_lo[axis]) + " to " + fmt(scene_->domain_hi[axis]) +
                  ")");
    }
  }
  void check_in_domain(const Field& f, const Vec3& p, const std::string& label) const {
    for (int a : used_axes(dim_)) check_in_domain(f, p[a], a, label);
  }
  void check_nonzero(const Field& f, const Vec3& v) const {
    if (norm2(v) == 0) fail(f, "must not be the zero vector");
  }

  // ---- sections ----
  void parse_domain(const Field& f);
  void parse_pressure_gradient(const Field& f, bool has_fluid);
  void parse_symmetry(const Field& f);
  void parse_fluid(const Field& f);
  void parse_sph(const Field& f);
  void parse_time(const Field& f);
  void parse_guards(const Field& f);
  void parse_checkpoint(const Field& f);
  void parse_parallel(const Field& f);
  void parse_frames(const Field& f);
  void parse_insitu(const Field& f);
  void parse_solids(const Field& f);
  void parse_barrier(const Field& f);
  void parse_dem(const Field& f);
  ContactParams parse_contact(const Field& f, bool wall) const;
  void parse_fluid_blocks(const Field& f);
  void parse_diagnostics(const Field& f);
  geom::SdfPtr parse_shape(const Field& f) const;
  std::string diagnostic_name(const MapReader& m);

  std::string file_;
  std::vector<Override> overrides_;
  Scene* scene_ = nullptr;
  int dim_ = 2;
  std::map<std::string, std::string> diagnostic_names_;  // name -> where it was first used
};

// ---- MapReader ------------------------------------------------------------------------------

MapReader::MapReader(const Parser& parser, const Field& self,
                     const std::vector<std::string>& allowed)
    : parser_(&parser), self_(self) {
  if (!self.node.IsMap()) parser.fail(self, "expected a mapping, got " + describe(self.node));
  for (auto it = self.node.begin(); it != self.node.end(); ++it) {
    const YAML::Node& k = it->first;
    if (!k.IsScalar()) {
      parser.fail(k.Mark(), self.path, "keys must be plain names, got " + describe(k));
    }
    const std::string key = k.Scalar();
    const std::string path = key_path(self.path, key);
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      parser.unknown_key(k.Mark(), path, allowed);
    }
    if (find(key)) parser.fail(k.Mark(), path, "duplicate key");
    // Values are reported at their key's line (a null value's own mark is the next token's).
    YAML::Mark mark = k.Mark().line >= 0 ? k.Mark() : it->second.Mark();
    entries_.emplace_back(key, Field{it->second, mark, path});
  }
}

Field MapReader::require(const std::string& key) const {
  auto f = find(key);
  if (!f) parser_->fail(self_.mark, key_path(self_.path, key), "required key is missing");
  return *f;
}
Real MapReader::number(const std::string& key, const Range& r, Real fallback) const {
  auto f = find(key);
  return f ? parser_->number(*f, r) : fallback;
}
Real MapReader::number(const std::string& key, const Range& r) const {
  return parser_->number(require(key), r);
}
int MapReader::integer(const std::string& key, int lo, int hi, int fallback) const {
  auto f = find(key);
  return f ? parser_->integer(*f, lo, hi) : fallback;
}
bool MapReader::boolean(const std::string& key, bool fallback) const {
  auto f = find(key);
  return f ? parser_->boolean(*f) : fallback;
}
Vec3 MapReader::vec3(const std::string& key, const Range& r, Vec3 fallback) const {
  auto f = find(key);
  return f ? parser_->vec3(*f, r) : fallback;
}
Vec3 MapReader::vec3(const std::string& key, const Range& r) const {
  return parser_->vec3(require(key), r);
}
template <class E>
E MapReader::enumeration(const std::string& key, const EnumTable<E>& table, E fallback) const {
  auto f = find(key);
  return f ? parser_->enumeration(*f, table) : fallback;
}

// ---- sections -------------------------------------------------------------------------------

Scene Parser::parse(const YAML::Node& root) {
  Scene s;
  s.source = file_;  // also the base folder of mesh paths
  scene_ = &s;
  MapReader top = map(Field{root, root.Mark(), ""},
                      {"name", "dimension", "domain", "gravity", "pressure_gradient", "symmetry",
                       "fluid", "sph", "time", "guards", "checkpoint", "parallel", "frames",
                       "insitu", "solids", "barrier", "fluid_blocks", "diagnostics", "dem"});
  s.name = name(top.require("name"));
  s.dim = dim_ = integer(top.require("dimension"), 2, 3);
  parse_domain(top.require("domain"));
  if (auto f = top.find("gravity")) {
    s.gravity = vec3(*f, closed(-1e3, 1e3));
    check_planar(*f, s.gravity);
  }
  if (auto f = top.find("pressure_gradient"))
    parse_pressure_gradient(*f, bool(top.find("fluid_blocks")));
  if (auto f = top.find("fluid")) parse_fluid(*f);
  // A scene of grains only (a `dem` section and no fluid_blocks) needs no `sph` section.
  const bool grains_only = top.find("dem") && !top.find("fluid_blocks");
  if (auto f = top.find("sph"); f || !grains_only) parse_sph(top.require("sph"));
  parse_time(top.require("time"));
  if (auto f = top.find("guards")) parse_guards(*f);
  if (auto f = top.find("checkpoint")) parse_checkpoint(*f);
  if (auto f = top.find("parallel")) parse_parallel(*f);
  if (auto f = top.find("frames")) parse_frames(*f);
  if (auto f = top.find("insitu")) parse_insitu(*f);
  if (auto f = top.find("solids")) parse_solids(*f);
  if (auto f = top.find("barrier")) parse_barrier(*f);
  if (auto f = top.find("fluid_blocks")) parse_fluid_blocks(*f);
  if (auto f = top.find("diagnostics")) parse_diagnostics(*f);
  if (auto f = top.find("dem")) parse_dem(*f);
  if (auto f = top.find("symmetry")) {
    parse_symmetry(*f);
    if (top.find("dem"))
      fail(*f, "a symmetry plane needs a scene without grains (dem): grains are not mirrored");
    if (s.sph.boundary == BoundaryMethod::kDbc)
      fail(*f,
           "a symmetry plane needs sph.boundary: mdbc (a DBC wall's density sums the fluid on "
           "both sides of the plane, and the mirror copies are not summed into walls)");
  }
  scene_ = nullptr;
  return s;
}

void Parser::parse_pressure_gradient(const Field& f, bool has_fluid) {
  PressureGradient& g = scene_->pressure_gradient;
  if (f.node.IsScalar() && !is_quoted(f.node) && f.node.Scalar() == "weight") {
    g.weight = true;
    if (!has_fluid) fail(f, "'weight' needs fluid (fluid_blocks); this scene has none");
    const Vec3 w = scene_->gravity;
    if (w.x == 0 && w.y == 0 && w.z == 0) fail(f, "'weight' needs gravity; gravity is zero");
    for (int a = 0; a < 3; ++a) {
      if (w[a] != 0 && !scene_->periodic[a]) {
        fail(f, std::string("'weight' needs a box periodic along gravity; gravity.") + kAxis[a] +
                    " = " + fmt(w[a]) + " but domain.periodic." + kAxis[a] +
                    " is false (a wall carries the weight there)");
      }
    }
    return;
  }
  if (f.node.IsScalar()) {
    fail(f, "expected 'weight' or a list of 3 numbers [Pa/m], got '" + f.node.Scalar() + "'");
  }
  g.value = vec3(f, closed(-1e9, 1e9));
  check_planar(f, g.value);
  if (g.enabled() && !has_fluid) fail(f, "a pressure gradient needs fluid (fluid_blocks)");
  for (int a = 0; a < 3; ++a) {
    if (g.value[a] != 0 && !scene_->periodic[a]) {
      fail(f, std::string("component ") + kAxis[a] + " = " + fmt(g.value[a]) +
                  " is along a non-periodic axis (domain.periodic." + kAxis[a] +
                  " is false); there the computed pressure carries the gradient");
    }
  }
}

void Parser::parse_symmetry(const Field& f) {
  if (dim_ != 3) fail(f, "a symmetry plane needs dimension 3");
  MapReader m = map(f, {"axis", "at", "keep"});
  SymmetryPlane& s = scene_->symmetry;
  s.axis = enumeration(m.require("axis"), kSymmetryAxes);
  const Field fa = m.require("at");
  s.at = number(fa, kCoord);
  s.keep = m.enumeration("keep", kSymmetrySides, 1);
  const int a = s.axis;
  if (scene_->periodic[a])
    fail(fa, std::string("the plane is normal to a periodic axis (domain.periodic.") + kAxis[a] +
                 " is true)");
  if (!(s.at > scene_->domain_lo[a] && s.at < scene_->domain_hi[a]))
    fail(fa, "value " + fmt(s.at) + " is not strictly inside the domain along " + kAxis[a] + " (" +
                 fmt(scene_->domain_lo[a]) + ", " + fmt(scene_->domain_hi[a]) + ")");
}

void Parser::parse_domain(const Field& f) {
  MapReader m = map(f, {"lo", "hi", "periodic"});
  Field f_lo = m.require("lo");
  Field f_hi = m.require("hi");
  scene_->domain_lo = vec3(f_lo, kCoord);
  scene_->domain_hi = vec3(f_hi, kCoord);
  if (auto p = m.find("periodic")) {
    std::vector<Field> items = fixed_list(*p, 3, "booleans");
    for (int a = 0; a < 3; ++a) scene_->periodic[a] = boolean(items[a]);
    if (dim_ == 2 && scene_->periodic[1]) fail(items[1], "y cannot be periodic in 2D");
  }
  check_above(f_hi, scene_->domain_lo, scene_->domain_hi, used_axes(dim_));
  if (dim_ == 2 && !(scene_->domain_lo.y <= 0 && 0 <= scene_->domain_hi.y)) {
    fail(f_hi, "in 2D the domain must contain y = 0 (lo.y <= 0 <= hi.y)");
  }
}

void Parser::parse_fluid(const Field& f) {
  FluidParams& p = scene_->fluid;
  MapReader m = map(f, {"rho0", "c0", "c0_factor", "gamma", "p_min", "viscosity", "diffusion",
                        "rheology", "sps"});
  p.rho0 = m.number("rho0", left_open(0, 1e5), p.rho0);
  p.c0 = m.number("c0", closed(0, 1e4), p.c0);
  p.c0_factor = m.number("c0_factor", closed(1, 100), p.c0_factor);
  p.gamma = m.number("gamma", closed(1, 10), p.gamma);
  p.p_min = m.number("p_min", closed(-1e30, 0), p.p_min);
  if (auto v = m.find("viscosity")) {
    MapReader vm = map(*v, {"model", "nu", "alpha"});
    p.viscosity = vm.enumeration("model", kViscosityModels, p.viscosity);
    p.nu = vm.number("nu", closed(0, 1e3), p.nu);
    p.alpha = vm.number("alpha", closed(0, 10), p.alpha);
  }
  if (auto d = m.find("diffusion")) {
    MapReader dm = map(*d, {"model", "delta"});
    p.diffusion = dm.enumeration("model", kDiffusionModels, p.diffusion);
    p.delta = dm.number("delta", closed(0, 1), p.delta);
  }
  if (auto r = m.find("rheology")) {
    RheologyParams& q = p.rheology;
    MapReader rm = map(*r, {"model", "k", "n", "m", "cohesion", "friction_deg", "mu_max", "yield"});
    q.model = rm.enumeration("model", kRheologyModels, q.model);
    q.k = rm.number("k", closed(0, 1e6), q.k);
    q.n = rm.number("n", closed(0.1, 3), q.n);
    q.m = rm.number("m", closed(0, 1e6), q.m);
    q.cohesion = rm.number("cohesion", closed(0, 1e7), q.cohesion);
    q.friction_deg = rm.number("friction_deg", closed(0, 89), q.friction_deg);
    q.mu_max = rm.number("mu_max", left_open(0, 1e7), q.mu_max);
    q.yield = rm.boolean("yield", q.yield);
    if (q.model == RheologyModel::kHbp && p.viscosity != ViscosityModel::kLaminar) {
      fail(*rm.find("model"),
           "hbp needs fluid.viscosity.model: laminar (mu_eff drives the laminar term)");
    }
  }
  if (auto sp = m.find("sps")) {
    MapReader sm = map(*sp, {"enabled", "cs", "ci"});
    p.sps.enabled = sm.boolean("enabled", p.sps.enabled);
    p.sps.cs = sm.number("cs", closed(0, 1), p.sps.cs);
    p.sps.ci = sm.number("ci", closed(0, 1), p.sps.ci);
  }
}

void Parser::parse_sph(const Field& f) {
  SphParams& p = scene_->sph;
  MapReader m = map(f, {"dp", "h_factor", "boundary", "slip", "boundary_layers", "no_penetration",
                        "mdbc_limiter", "pairwise"});
  p.dp = m.number("dp", left_open(0, 1));
  p.h_factor = m.number("h_factor", closed(0.5, 3), p.h_factor);
  p.boundary = m.enumeration("boundary", kBoundaryMethods, p.boundary);
  p.slip = m.enumeration("slip", kSlipConditions, p.slip);
  p.no_penetration = m.boolean("no_penetration", p.no_penetration);
  if (p.no_penetration && p.boundary != BoundaryMethod::kMdbc)
    fail(*m.find("no_penetration"),
         "the penetration control is part of mDBC (boundary: mdbc); DBC walls resist approach "
         "through their own density");
  p.mdbc_limiter = m.boolean("mdbc_limiter", p.mdbc_limiter);
  if (p.mdbc_limiter && p.boundary != BoundaryMethod::kMdbc)
    fail(*m.find("mdbc_limiter"),
         "the limiter bounds mDBC's extrapolated wall density (boundary: mdbc); DBC walls have "
         "no extrapolation");
  p.boundary_layers = m.integer("boundary_layers", 0, 20, p.boundary_layers);
  p.pairwise = m.boolean("pairwise", p.pairwise);
}

void Parser::parse_time(const Field& f) {
  TimeParams& p = scene_->time;
  MapReader m =
      map(f, {"end", "cfl", "dt_fixed", "dt_min", "dt_max", "integrator", "verlet_euler_every"});
  p.end = m.number("end", left_open(0, 1e6));
  p.cfl = m.number("cfl", left_open(0, 1), p.cfl);
  p.dt_fixed = m.number("dt_fixed", closed(0, 1), p.dt_fixed);
  p.dt_min = m.number("dt_min", closed(0, 1), p.dt_min);
  p.dt_max = m.number("dt_max", closed(0, 1), p.dt_max);
  p.integrator = m.enumeration("integrator", kIntegrators, p.integrator);
  p.verlet_euler_every = m.integer("verlet_euler_every", 1, 1000000, p.verlet_euler_every);
  if (p.dt_fixed > 0 && p.dt_fixed < p.dt_min) {
    fail(*m.find("dt_fixed"), fmt(p.dt_fixed) + " is below time.dt_min = " + fmt(p.dt_min));
  }
}

void Parser::parse_guards(const Field& f) {
  GuardParams& p = scene_->guards;
  MapReader m =
      map(f, {"rho_min_ratio", "rho_max_ratio", "mach_max", "check_every", "penetration_depth"});
  p.rho_min_ratio = m.number("rho_min_ratio", open_interval(0, 1), p.rho_min_ratio);
  p.rho_max_ratio = m.number("rho_max_ratio", left_open(1, 10), p.rho_max_ratio);
  p.mach_max = m.number("mach_max", left_open(0, 1), p.mach_max);
  p.check_every = m.integer("check_every", 0, 1000000, p.check_every);
  p.penetration_depth = m.number("penetration_depth", closed(0, 10), p.penetration_depth);
}

void Parser::parse_checkpoint(const Field& f) {
  CheckpointParams& p = scene_->checkpoint;
  MapReader m = map(f, {"every_time", "every_steps", "every_wall", "keep"});
  p.every_time = m.number("every_time", closed(0, 1e6), p.every_time);
  p.every_steps = m.integer("every_steps", 0, 2000000000, int(p.every_steps));
  p.every_wall = m.number("every_wall", closed(0, 1e7), p.every_wall);
  p.keep = int(m.integer("keep", 1, 1000, p.keep));
}

void Parser::parse_parallel(const Field& f) {
  ParallelParams& p = scene_->parallel;
  MapReader m = map(f, {"rebalance_every", "imbalance", "skin"});
  p.rebalance_every = m.integer("rebalance_every", 0, 1000000000, p.rebalance_every);
  p.imbalance = m.number("imbalance", closed(1, 100), p.imbalance);
  p.skin = m.number("skin", closed(0, 2), p.skin);
}

void Parser::parse_frames(const Field& f) {
  FrameParams& p = scene_->frames;
  MapReader m = map(f, {"every", "fields", "boundary", "region"});
  p.every = m.number("every", closed(0, 1e6), p.every);
  p.boundary = m.boolean("boundary", p.boundary);
  if (auto fl = m.find("fields")) {
    if (!fl->node.IsSequence()) fail(*fl, "expected a list of field names");
    static const char* kAllowed[] = {"vel", "rho", "press", "acc", "drho", "mass", "id"};
    p.fields.clear();
    for (std::size_t i = 0; i < fl->node.size(); ++i) {
      const Field item{fl->node[i], fl->node[i].Mark(), fl->path + "[" + std::to_string(i) + "]"};
      if (!item.node.IsScalar()) fail(item, "expected a field name");
      const std::string v = item.node.Scalar();
      bool ok = false;
      for (const char* a : kAllowed) ok = ok || v == a;
      if (!ok) fail(item, "'" + v + "' is not one of vel, rho, press, acc, drho, mass, id");
      p.fields.push_back(v);
    }
  }
  if (auto r = m.find("region")) {
    MapReader rm = map(*r, {"lo", "hi"});
    p.region = true;
    p.region_lo = vec3(rm.require("lo"), kCoord);
    p.region_hi = vec3(rm.require("hi"), kCoord);
    for (int k = 0; k < 3; ++k) {
      if (dim_ == 2 && k == 1) continue;
      if (!(p.region_hi[k] > p.region_lo[k])) fail(*r, "hi must exceed lo on every axis");
    }
  }
}

void Parser::parse_insitu(const Field& f) {
  InSituParams& p = scene_->insitu;
  MapReader m = map(f, {"scripts", "every_steps"});
  Field f_list = m.require("scripts");
  std::vector<Field> items = list(f_list);
  if (items.empty()) fail(f_list, "expected at least one Catalyst script");
  namespace fs = std::filesystem;
  for (const Field& item : items) {
    const std::string file = string(item);
    if (file.empty()) fail(item, "expected a file name, got an empty string");
    fs::path path(file);
    if (path.is_relative()) path = fs::path(scene_->source).parent_path() / path;
    const std::string resolved = path.string();
    std::ifstream in(resolved);
    if (!in) fail(item, "cannot open Catalyst script '" + resolved + "'");
    // ParaView 5.11's vtkCPPythonScriptV2Pipeline runs only version-2 scripts; a legacy
    // (version 1) script would fail much later, inside Catalyst, with a Python traceback.
    std::string first;
    std::getline(in, first);
    if (first.rfind("# script-version: 2", 0) != 0) {
      fail(item, "Catalyst script '" + resolved +
                     "' must start with the line '# script-version: 2' (ParaView 5.11 legacy "
                     "Catalyst runs version-2 scripts only)");
    }
    p.scripts.push_back(resolved);
  }
  p.every_steps = m.integer("every_steps", 1, 2000000000, int(p.every_steps));
}

void Parser::parse_solids(const Field& f) {
  std::map<std::string, std::string> seen;
  for (const Field& item : list(f)) {
    MapReader m = map(item, {"name", "shape", "boundary_regions", "removed_at"});
    Field f_name = m.require("name");
    Solid solid;
    solid.name = name(f_name);
    auto [it, fresh] = seen.emplace(solid.name, f_name.path);
    if (!fresh) fail(f_name, "duplicate solid name '" + solid.name + "' (also " + it->second + ")");
    solid.sdf = parse_shape(m.require("shape"));
    if (auto fr = m.find("boundary_regions")) {
      for (const Field& r : list(*fr)) {
        MapReader rm = map(r, {"lo", "hi"});
        Field f_lo = rm.require("lo");
        Field f_hi = rm.require("hi");
        const Vec3 lo = vec3(f_lo, kCoord), hi = vec3(f_hi, kCoord);
        check_above(f_hi, lo, hi, used_axes(dim_));
        solid.boundary_regions.emplace_back(lo, hi);
      }
      if (solid.boundary_regions.empty())
        fail(*fr, "an empty list would leave the solid without boundary particles; omit the key");
    }
    solid.removed_at = m.number("removed_at", closed(0, 1e6), solid.removed_at);
    scene_->solids.push_back(std::move(solid));
  }
}

void Parser::parse_barrier(const Field& f) {
  Barrier& b = scene_->barrier;
  if (dim_ != 3) fail(f, "a barrier needs dimension: 3");
  MapReader m = map(f, {"preset", "layout", "angle_deg", "walls", "width", "thickness", "height",
                        "x", "y", "floor_z", "apex", "runup_band"});
  b.enabled = true;
  if (auto p = m.find("preset")) {
    for (const char* k : {"layout", "angle_deg"})
      if (auto c = m.find(k))
        fail(*c, std::string("give either preset or ") + k + ", not both (preset " + string(*p) +
                     " sets layout and angle)");
    apply_barrier_preset(b, m.enumeration("preset", kBarrierPresets, std::string("P00")));
  } else {
    b.layout = m.enumeration("layout", kBarrierLayouts, b.layout);
    b.angle_deg = m.number("angle_deg", closed(-80, 80), b.angle_deg);
  }
  b.walls = m.integer("walls", 1, 1000, b.walls);
  b.width = m.number("width", kLength, b.width);
  b.thickness = m.number("thickness", kLength, b.thickness);
  b.height = m.number("height", kLength, b.height);
  b.x = m.number("x", kCoord, b.x);
  if (auto fy = m.find("y")) {
    std::vector<Field> items = fixed_list(*fy, 2, "numbers");
    b.y_lo = number(items[0], kCoord);
    b.y_hi = number(items[1], kCoord);
    if (!(b.y_hi > b.y_lo)) fail(items[1], "must be above y[0] = " + fmt(b.y_lo));
  }
  b.floor_z = m.number("floor_z", kCoord, b.floor_z);
  b.apex_upstream = m.enumeration("apex", kBarrierApex, b.apex_upstream);
  b.runup_band = m.number("runup_band", closed(0, kBig), b.runup_band);
  for (Solid& s : barrier_solids(b)) {
    if (scene_->find_solid(s.name))
      fail(f, "the barrier's wall solids are named barrier_1 .. barrier_" +
                  std::to_string(b.walls) + "; a solid called '" + s.name + "' already exists");
    scene_->solids.push_back(std::move(s));
  }
}

ContactParams Parser::parse_contact(const Field& f, bool wall) const {
  ContactParams c;
  std::vector<std::string> keys{"law", "kn", "young", "poisson", "restitution", "friction"};
  if (wall) {
    keys.push_back("wall_young");
    keys.push_back("wall_poisson");
  }
  MapReader m = map(f, keys);
  c.law = m.enumeration("law", kContactLaws, c.law);
  c.kn = m.number("kn", closed(0, 1e12), c.kn);
  c.young = m.number("young", closed(0, 1e13), c.young);
  c.poisson = m.number("poisson", closed(0, 0.5), c.poisson);
  c.restitution = m.number("restitution", left_open(0, 1), c.restitution);
  c.friction = m.number("friction", closed(0, 10), c.friction);
  if (wall) {
    c.wall_young = m.number("wall_young", closed(0, 1e13), c.wall_young);
    c.wall_poisson = m.number("wall_poisson", closed(0, 0.5), c.wall_poisson);
  }
  if (c.kn == 0 && c.young == 0)
    fail(f, "give either kn (normal stiffness per node, N/m) or young (Young's modulus, Pa)");
  return c;
}

void Parser::parse_dem(const Field& f) {
  DemScene& d = scene_->dem;
  d.enabled = true;
  if (dim_ != 3) fail(f, "DEM grains need dimension: 3");
  MapReader m = map(f, {"grain_grain", "grain_wall", "stiffness_overlap", "nodes_per_contact",
                        "dt_factor", "overlap_max", "settle", "shapes", "packs", "bodies", "walls",
                        "heap", "stop_at_rest", "substeps_max", "subcycle"});
  d.grain_grain = parse_contact(m.require("grain_grain"), false);
  d.grain_wall = parse_contact(m.require("grain_wall"), true);
  d.stiffness_overlap = m.number("stiffness_overlap", left_open(0, 1), d.stiffness_overlap);
  d.nodes_per_contact = m.number("nodes_per_contact", closed(1, 1e4), d.nodes_per_contact);
  d.dt_factor = m.number("dt_factor", left_open(0, 100), d.dt_factor);
  d.overlap_max = m.number("overlap_max", left_open(0, 1), d.overlap_max);
  if (auto f_sub = m.find("substeps_max")) d.substeps_max = integer(*f_sub, 1, 1000000);
  d.subcycle = m.boolean("subcycle", d.subcycle);
  if (auto s = m.find("settle")) {
    MapReader sm = map(*s, {"until", "damping"});
    d.settle_until = sm.number("until", closed(0, 1e6));
    d.settle_damping = sm.number("damping", closed(0, 1e6), d.settle_damping);
  }
  if (auto h = m.find("heap")) {
    MapReader hm = map(*h, {"floor", "x_min", "x_max", "origin"});
    d.heap = true;
    d.heap_floor = hm.number("floor", kCoord, d.heap_floor);
    d.heap_x_min = hm.number("x_min", kCoord, -1e6);
    d.heap_x_max = hm.number("x_max", kCoord, 1e6);
    d.heap_origin = hm.number("origin", kCoord, d.heap_origin);
  }
  if (auto r = m.find("stop_at_rest")) {
    MapReader rm = map(*r, {"after", "kinetic_energy"});
    d.stop_at_rest = true;
    d.rest_after = rm.number("after", closed(0, 1e6), d.rest_after);
    d.rest_energy = rm.number("kinetic_energy", left_open(0, 1e6));
  }
  std::map<std::string, std::string> shape_names;
  for (const Field& item : list(m.require("shapes"))) {
    Field f_type = MapReader(*this, item,
                             {"name", "type", "diameter", "size", "perturbation", "planes",
                              "variants", "seed", "file", "scale", "grid_spacing", "node_spacing"})
                       .require("type");
    GrainShape g;
    g.type = enumeration(f_type, kGrainShapes);
    std::vector<std::string> keys{"name", "type",         "variants",
                                  "seed", "grid_spacing", "node_spacing"};
    switch (g.type) {
      case GrainShapeType::kSphere:
        keys.push_back("diameter");
        break;
      case GrainShapeType::kBox:
      case GrainShapeType::kEllipsoid:
        keys.push_back("size");
        break;
      case GrainShapeType::kTrigonalPyramid:
        keys.insert(keys.end(), {"diameter", "perturbation"});
        break;
      case GrainShapeType::kPolyhedron:
        keys.insert(keys.end(), {"diameter", "planes"});
        break;
      case GrainShapeType::kMesh:
        keys.insert(keys.end(), {"file", "scale"});
        break;
    }
    MapReader sm = map(item, keys);
    Field f_name = sm.require("name");
    g.name = name(f_name);
    auto [it, fresh] = shape_names.emplace(g.name, f_name.path);
    if (!fresh) fail(f_name, "duplicate shape name '" + g.name + "' (also " + it->second + ")");
    if (sm.find("diameter"))
      g.diameter = sm.number("diameter", kLength);
    else if (g.type == GrainShapeType::kSphere || g.type == GrainShapeType::kTrigonalPyramid ||
             g.type == GrainShapeType::kPolyhedron)
      sm.require("diameter");
    if (g.type == GrainShapeType::kBox || g.type == GrainShapeType::kEllipsoid) {
      g.size = sm.vec3("size", kLength);
    }
    g.perturbation = sm.number("perturbation", closed(0, 0.3), g.perturbation);
    g.planes = sm.integer("planes", 6, 200, g.planes);
    g.variants = sm.integer("variants", 1, 1000, g.variants);
    g.seed = std::uint32_t(sm.integer("seed", 0, 2000000000, int(g.seed)));
    g.grid_spacing = sm.number("grid_spacing", closed(0, 1), g.grid_spacing);
    g.node_spacing = sm.number("node_spacing", closed(0, 1), g.node_spacing);
    if (g.type == GrainShapeType::kMesh) {
      namespace fs = std::filesystem;
      fs::path path = string(sm.require("file"));
      if (path.is_relative()) path = fs::path(scene_->source).parent_path() / path;
      g.file = path.string();
      g.scale = sm.number("scale", kLength, g.scale);
    }
    d.shapes.push_back(std::move(g));
  }
  auto check_shape = [&](const Field& f_shape, const std::string& shape) {
    if (!shape_names.count(shape)) {
      std::vector<std::string> names;
      for (const auto& [n, where] : shape_names) names.push_back(n);
      fail(f_shape, "no shape named '" + shape + "'; shapes are: " + join(names));
    }
  };
  if (auto bl = m.find("bodies")) {
    for (const Field& item : list(*bl)) {
      MapReader bm =
          map(item, {"shape", "density", "position", "velocity", "axis", "angle_deg", "fixed"});
      GrainBody b;
      Field f_shape = bm.require("shape");
      b.shape = string(f_shape);
      check_shape(f_shape, b.shape);
      b.density = bm.number("density", left_open(0, 1e5), b.density);
      b.position = bm.vec3("position", kCoord);
      b.velocity = bm.vec3("velocity", closed(-1e3, 1e3), b.velocity);
      if (auto fa = bm.find("axis")) {
        b.axis = vec3(*fa, kDirection);
        check_nonzero(*fa, b.axis);
      }
      b.angle_deg = bm.number("angle_deg", closed(-360, 360), b.angle_deg);
      b.fixed = bm.boolean("fixed", b.fixed);
      d.bodies.push_back(b);
    }
  }
  if (!m.find("packs") && !m.find("bodies")) m.require("packs");
  std::vector<Field> pack_items;
  if (auto pl = m.find("packs")) pack_items = list(*pl);
  for (const Field& item : pack_items) {
    MapReader pm = map(item, {"shape", "count", "fraction", "placement", "density", "lo", "hi",
                              "velocity", "random_orientation", "seed"});
    GrainPack p;
    Field f_shape = pm.require("shape");
    p.shape = string(f_shape);
    check_shape(f_shape, p.shape);
    if (auto fc = pm.find("count")) {
      if (auto ff = pm.find("fraction"))
        fail(*ff, "give either count or fraction (solid volume fraction of the box), not both");
      p.count = integer(*fc, 1, 100000000);
    } else if (pm.find("fraction")) {
      p.fraction = pm.number("fraction", left_open(0, 0.3));
    } else {
      pm.require("count");
    }
    p.placement = pm.enumeration("placement", kPackPlacements, p.placement);
    p.density = pm.number("density", left_open(0, 1e5), p.density);
    p.lo = pm.vec3("lo", kCoord);
    Field f_hi = pm.require("hi");
    p.hi = vec3(f_hi, kCoord);
    check_above(f_hi, p.lo, p.hi, {0, 1, 2});
    p.velocity = pm.vec3("velocity", closed(-1e3, 1e3), p.velocity);
    p.random_orientation = pm.boolean("random_orientation", p.random_orientation);
    p.seed = std::uint32_t(pm.integer("seed", 0, 2000000000, int(p.seed)));
    d.packs.push_back(p);
  }
  if (auto w = m.find("walls")) {
    for (const Field& item : list(*w)) {
      MapReader wm = map(item, {"solid", "velocity", "start", "stop", "friction", "restitution"});
      GrainWall gw;
      Field f_s = wm.require("solid");
      gw.solid = string(f_s);
      if (!scene_->find_solid(gw.solid)) {
        std::vector<std::string> names;
        for (const Solid& s : scene_->solids) names.push_back(s.name);
        fail(f_s, "no solid named '" + gw.solid + "'; " +
                      (names.empty() ? std::string("the scene has no solids")
                                     : "solids are: " + join(names)));
      }
      gw.velocity = wm.vec3("velocity", closed(-1e3, 1e3), gw.velocity);
      gw.start = wm.number("start", closed(0, 1e6), gw.start);
      Field f_stop = wm.find("stop") ? *wm.find("stop") : item;
      gw.stop = wm.number("stop", closed(0, 1e30), gw.stop);
      if (gw.stop <= gw.start) fail(f_stop, "stop must be after start (" + fmt(gw.start) + ")");
      // Per-wall contact material, in place of grain_wall's (its stiffness stays: it sets dt).
      gw.friction = wm.number("friction", closed(0, 10), gw.friction);
      gw.restitution = wm.number("restitution", left_open(0, 1), gw.restitution);
      d.walls.push_back(gw);
    }
  }
}

geom::SdfPtr Parser::parse_shape(const Field& f) const {
  if (!f.node.IsMap()) fail(f, "expected a mapping with a 'type' key, got " + describe(f.node));
  // The allowed keys depend on the type, so read it first.
  std::optional<Field> f_type;
  for (auto it = f.node.begin(); it != f.node.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == "type") {
      f_type = Field{it->second, it->first.Mark(), key_path(f.path, "type")};
      break;
    }
  }
  if (!f_type) fail(f.mark, key_path(f.path, "type"), "required key is missing");
  const ShapeType type = enumeration(*f_type, kShapeTypes);
  MapReader m = map(f, shape_keys(type));

  switch (type) {
    case ShapeType::kBox: {
      Vec3 lo = m.vec3("lo", kCoord);
      Field f_hi = m.require("hi");
      Vec3 hi = vec3(f_hi, kCoord);
      check_above(f_hi, lo, hi, {0, 1, 2});
      check_spans_y0(f_hi, lo, hi, "a box");
      return geom::make_box(lo, hi);
    }
    case ShapeType::kPlane: {
      Vec3 point = m.vec3("point", kCoord);
      Field f_n = m.require("normal");
      Vec3 n = vec3(f_n, kDirection);
      check_nonzero(f_n, n);
      return geom::make_plane(point, n);
    }
    case ShapeType::kSlab: {
      Vec3 point = m.vec3("point", kCoord);
      Field f_n = m.require("normal");
      Vec3 n = vec3(f_n, kDirection);
      check_nonzero(f_n, n);
      return geom::make_slab(point, n, m.number("thickness", kLength));
    }
    case ShapeType::kCylinder: {
      Vec3 a = m.vec3("a", kCoord);
      Field f_b = m.require("b");
      Vec3 b = vec3(f_b, kCoord);
      if (norm2(b - a) == 0) fail(f_b, "must differ from a (the axis has zero length)");
      return geom::make_cylinder(a, b, m.number("radius", kLength));
    }
    case ShapeType::kSphere: {
      Vec3 c = m.vec3("center", kCoord);
      return geom::make_sphere(c, m.number("radius", kLength));
    }
    case ShapeType::kTank: {
      Vec3 lo = m.vec3("inner_lo", kCoord);
      Field f_hi = m.require("inner_hi");
      Vec3 hi = vec3(f_hi, kCoord);
      check_above(f_hi, lo, hi, {0, 1, 2});
      check_spans_y0(f_hi, lo, hi, "a tank");
      Real t = m.number("thickness", kLength);
      return geom::make_tank(lo, hi, t, m.boolean("closed_top", false));
    }
    case ShapeType::kUnion: {
      Field f_parts = m.require("parts");
      std::vector<Field> items = list(f_parts);
      if (items.empty()) fail(f_parts, "expected at least one part");
      std::vector<geom::SdfPtr> parts;
      for (const Field& item : items) parts.push_back(parse_shape(item));
      return geom::make_union(std::move(parts));
    }
    case ShapeType::kDifference: {
      geom::SdfPtr a = parse_shape(m.require("a"));
      geom::SdfPtr b = parse_shape(m.require("b"));
      return geom::make_difference(std::move(a), std::move(b));
    }
    case ShapeType::kTransform: {
      geom::SdfPtr body = parse_shape(m.require("shape"));
      Vec3 axis(0, 0, 1);
      if (auto f_axis = m.find("axis")) {
        axis = vec3(*f_axis, kDirection);
        check_nonzero(*f_axis, axis);
      }
      Real angle = m.number("angle_deg", closed(-360, 360), 0);
      Vec3 t = m.vec3("translate", kCoord, Vec3());
      return geom::make_transform(std::move(body), axis, angle * kPi / 180, t);
    }
    case ShapeType::kMesh: {
      Field f_file = m.require("file");
      std::string file = string(f_file);
      if (file.empty()) fail(f_file, "expected a file name, got an empty string");
      Real spacing = m.number("spacing", kLength, scene_->sph.dp);
      namespace fs = std::filesystem;
      fs::path path(file);
      if (path.is_relative()) path = fs::path(scene_->source).parent_path() / path;
      const std::string resolved = path.string();
      if (!std::ifstream(resolved)) fail(f_file, "cannot open mesh file '" + resolved + "'");
      try {
        return geom::make_mesh_sdf(geom::load_mesh(resolved), spacing);
      } catch (const std::exception& e) {
        fail(f_file, e.what());
      }
    }
  }
  fail(f, "unhandled shape type");  // not reached: the enumeration covers every type
}

void Parser::parse_fluid_blocks(const Field& f) {
  for (const Field& item : list(f)) {
    MapReader m = map(item, {"lo", "hi", "velocity", "hydrostatic", "level"});
    FluidBlock b;
    Field f_lo = m.require("lo");
    Field f_hi = m.require("hi");
    b.lo = vec3(f_lo, kCoord);
    b.hi = vec3(f_hi, kCoord);
    check_above(f_hi, b.lo, b.hi, used_axes(dim_));
    check_in_domain(f_lo, b.lo, "lo.");
    check_in_domain(f_hi, b.hi, "hi.");
    if (auto f_v = m.find("velocity")) {
      b.velocity = vec3(*f_v, closed(-1e3, 1e3));
      check_planar(*f_v, b.velocity);
    }
    b.hydrostatic = m.boolean("hydrostatic", b.hydrostatic);
    if (auto f_l = m.find("level")) {
      b.level = number(*f_l, kCoord);
      b.has_level = true;
      if (norm2(scene_->gravity) == 0) fail(*f_l, "a level surface needs gravity; gravity is zero");
    }
    scene_->fluid_blocks.push_back(b);
  }
}

std::string Parser::diagnostic_name(const MapReader& m) {
  Field f = m.require("name");
  std::string n = name(f);
  auto [it, fresh] = diagnostic_names_.emplace(n, f.path);
  if (!fresh) fail(f, "duplicate diagnostic name '" + n + "' (also " + it->second + ")");
  return n;
}

void Parser::parse_diagnostics(const Field& f) {
  Diagnostics& d = scene_->diagnostics;
  MapReader m = map(f, {"every", "pressure_gauges", "height_gauges", "fronts", "profiles", "forces",
                        "velocity_gauges", "energy"});
  d.every = m.number("every", left_open(0, 1e4), d.every);
  if (auto l = m.find("pressure_gauges")) {
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "point"});
      PressureGauge pg;
      pg.name = diagnostic_name(g);
      Field f_p = g.require("point");
      pg.point = vec3(f_p, kCoord);
      check_in_domain(f_p, pg.point, "");
      d.pressure_gauges.push_back(pg);
    }
  }
  if (auto l = m.find("height_gauges")) {
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "x", "y"});
      HeightGauge hg;
      hg.name = diagnostic_name(g);
      Field f_x = g.require("x");
      hg.x = number(f_x, kCoord);
      check_in_domain(f_x, hg.x, 0, "");
      if (auto f_y = g.find("y")) {
        hg.y = number(*f_y, kCoord);
        if (dim_ == 3) check_in_domain(*f_y, hg.y, 1, "");
      }
      d.height_gauges.push_back(hg);
    }
  }
  if (auto l = m.find("fronts")) {
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "origin", "direction"});
      FrontTracker ft;
      ft.name = diagnostic_name(g);
      ft.origin = g.vec3("origin", kCoord, ft.origin);
      if (auto f_d = g.find("direction")) {
        ft.direction = vec3(*f_d, kDirection);
        check_nonzero(*f_d, ft.direction);
      }
      d.fronts.push_back(ft);
    }
  }
  if (auto l = m.find("profiles")) {
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "from", "to", "samples", "times", "quantity"});
      ProfileSpec ps;
      ps.name = diagnostic_name(g);
      Field f_from = g.require("from");
      ps.from = vec3(f_from, kCoord);
      Field f_to = g.require("to");
      ps.to = vec3(f_to, kCoord);
      // A sample outside the domain would read an empty column (elevation 0), not the flow.
      check_in_domain(f_from, ps.from, "");
      check_in_domain(f_to, ps.to, "");
      if (norm2(ps.to - ps.from) == 0) fail(f_to, "must differ from 'from'");
      ps.samples = g.integer("samples", 2, 1000000, ps.samples);
      ps.velocity = g.enumeration("quantity", kProfileQuantities, false);
      if (auto f_t = g.find("times")) {
        for (const Field& t : list(*f_t)) {
          Real v = number(t, closed(0, 1e6));
          if (!ps.times.empty() && !(v > ps.times.back())) {
            fail(t, "times must be increasing; " + t.node.Scalar() + " follows " +
                        fmt(ps.times.back()));
          }
          ps.times.push_back(v);
        }
      }
      d.profiles.push_back(ps);
    }
  }
  if (auto l = m.find("forces")) {
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "solid"});
      ForceProbe fp;
      fp.name = diagnostic_name(g);
      Field f_s = g.require("solid");
      fp.solid = string(f_s);
      if (!scene_->find_solid(fp.solid)) {
        std::vector<std::string> names;
        for (const Solid& s : scene_->solids) names.push_back(s.name);
        fail(f_s, "no solid named '" + fp.solid + "'; " +
                      (names.empty() ? std::string("the scene has no solids")
                                     : "solids are: " + join(names)));
      }
      d.forces.push_back(fp);
    }
  }
  if (auto l = m.find("velocity_gauges")) {
    if (dim_ != 3) fail(*l, "velocity gauges need dimension: 3 (a channel along x)");
    for (const Field& item : list(*l)) {
      MapReader g = map(item, {"name", "x", "y"});
      VelocityGauge vg;
      vg.name = diagnostic_name(g);
      Field f_x = g.require("x");
      vg.x = number(f_x, kCoord);
      check_in_domain(f_x, vg.x, 0, "");
      Field f_y = g.require("y");
      vg.y = number(f_y, kCoord);
      check_in_domain(f_y, vg.y, 1, "");
      d.velocity_gauges.push_back(vg);
    }
  }
  d.energy = m.boolean("energy", d.energy);
}

// ---- overrides ------------------------------------------------------------------------------

struct KeySegment {
  std::string key;  // a mapping key, or
  long index = -1;  // a list index (>= 0)
};

// "solids[0].shape.thickness" -> solids, [0], shape, thickness. Empty on a malformed key.
std::vector<KeySegment> split_key(const std::string& key) {
  std::vector<KeySegment> out;
  std::size_t i = 0;
  auto is_name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  };
  while (true) {
    std::size_t start = i;
    while (i < key.size() && is_name_char(key[i])) ++i;
    if (i == start) return {};
    out.push_back({key.substr(start, i - start), -1});
    while (i < key.size() && key[i] == '[') {
      std::size_t close = key.find(']', i);
      if (close == std::string::npos || close == i + 1) return {};
      std::string digits = key.substr(i + 1, close - i - 1);
      if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) {
        return {};
      }
      out.push_back({"", std::stol(digits)});
      i = close + 1;
    }
    if (i == key.size()) return out;
    if (key[i] != '.') return {};
    ++i;
  }
}

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n";
  std::size_t a = s.find_first_not_of(ws);
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(ws) - a + 1);
}

// Applies "key=value" to the tree; returns the normalised key.
Override apply_override(YAML::Node& root, const std::string& text) {
  const std::string where = "--set " + text + ": ";
  std::size_t eq = text.find('=');
  if (eq == std::string::npos) throw InputError(where + "expected key=value");
  const std::string key = trim(text.substr(0, eq));
  std::vector<KeySegment> segs = split_key(key);
  if (segs.empty()) {
    throw InputError(where + "malformed key '" + key + "'; expected e.g. sph.dp or solids[0].name");
  }
  YAML::Node value;
  try {
    value = YAML::Load(text.substr(eq + 1));
  } catch (const YAML::ParserException& e) {
    throw InputError(where + "YAML syntax error: " + e.msg);
  }

  YAML::Node cur = root;
  std::string so_far;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const KeySegment& s = segs[i];
    const bool last = i + 1 == segs.size();
    if (s.index < 0) {
      if (!cur.IsMap() && !cur.IsNull())
        throw InputError(where + "'" + so_far + "' is not a mapping");
      so_far = key_path(so_far, s.key);
      if (last) {
        cur[s.key] = value;
      } else {
        YAML::Node next = cur[s.key];
        if (!next.IsDefined()) next = YAML::Node(YAML::NodeType::Map);
        cur.reset(next);
      }
    } else {
      const std::size_t idx = static_cast<std::size_t>(s.index);
      if (!cur.IsSequence()) throw InputError(where + "'" + so_far + "' is not a list");
      if (idx >= cur.size()) {
        throw InputError(where + "'" + so_far + "' has no entry [" + std::to_string(idx) + "]");
      }
      so_far = index_path(so_far, idx);
      if (last) {
        cur[idx] = value;
      } else {
        cur.reset(cur[idx]);
      }
    }
  }
  return Override{text, so_far};
}

}  // namespace

Scene parse_scene(const std::string& yaml_text, const std::string& source_name,
                  const std::vector<std::string>& overrides) {
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(yaml_text);
  } catch (const YAML::ParserException& e) {
    std::string line = e.mark.line >= 0 ? ":" + std::to_string(e.mark.line + 1) : "";
    throw InputError(source_name + line + ": YAML syntax error: " + e.msg);
  }
  if (docs.size() > 1) {
    std::string line = docs[1].Mark().line >= 0 ? std::to_string(docs[1].Mark().line + 1) : "1";
    throw InputError(source_name + ":" + line + ": a scene file holds one YAML document");
  }
  YAML::Node root = docs.empty() ? YAML::Node() : docs[0];
  if (root.IsNull() || !root.IsDefined()) {
    throw InputError(source_name +
                     ":1: the scene is empty; it needs at least name, dimension, domain, sph.dp "
                     "and time.end");
  }
  if (!root.IsMap()) {
    throw InputError(source_name + ":" + std::to_string(root.Mark().line + 1) +
                     ": expected a mapping of scene keys at the top level, got " + describe(root));
  }

  std::vector<Override> applied;
  for (const std::string& o : overrides) applied.push_back(apply_override(root, o));

  Parser parser(source_name, applied);
  Scene parsed = parser.parse(root);
  YAML::Emitter emitter;
  emitter << root;
  parsed.yaml_text = std::string(emitter.c_str()) + "\n";
  return parsed;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open scene file '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path, overrides);
}

}  // namespace sphdem
