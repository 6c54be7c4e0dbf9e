// A DEM system: rigid grains of any shape (level sets), fixed and moving walls, contact detection
// and time stepping (seed §2.2, Eqs. 16-20; DESIGN.md §1-2).
//
// Step (DemSystem::step):
//   1. broad phase: pairs of bodies whose bounding spheres overlap, from a sort-based cell list of
//      the body centres (neighbor/cell_list.hpp), cells >= 2 r_max;
//   2. narrow phase, per pair (no atomics: each pair writes its own result slot):
//      - two spheres: one analytic contact point (fast path);
//      - otherwise the master-slave level-set test (Kawamoto et al. 2016) in BOTH orders: every
//      node
//        of A is looked up in phi_B (trilinear value and gradient, B's body frame), and every node
//        of B in phi_A. A penetrating node gives d = -phi, n = grad phi (slave outward normal,
//        rotated to the world frame) and the force of contact_law.hpp (Eqs. 19-20) at the node.
//        The pair force is the MEAN of the two passes (weight 1/2 each), so it does not depend on
//        which body is called A, and the forces on A and B are equal and opposite by construction;
//      - grain against wall: the grain's nodes (or a sphere's centre) against the wall's phi.
//   3. per-body gather of the pair forces and torques (fixed order: walls, then pairs by index);
//   4. integration (dem/rigid_body.hpp) with gravity and external forces; walls move.
// The leapfrog carries velocities at half steps; the contact dashpots and tangential springs are
// fed the velocity predicted to the force time, v + a_prev dt/2 (a_prev: the last step's
// acceleration), which makes the damping second order: the restitution coefficient of a linear
// contact comes out within 1 % of its target at dt = t_c/200 for 0.1 <= e <= 0.99 (about 10 % low
// for e = 0.1 at dt_DEM = t_c/50).
// Tangential springs are stored per (master id, slave id, master node) in a key array sorted
// between steps, and found again by binary search: never by array position, so they survive
// re-ordering, insertion and removal of bodies.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/types.hpp"
#include "dem/contact_law.hpp"
#include "dem/grain_template.hpp"
#include "dem/rigid_body.hpp"
#include "geometry/sdf.hpp"

namespace sphdem::dem {

// Material and law of one kind of contact (grain-grain or grain-wall).
struct ContactModel {
  NormalLaw law = NormalLaw::kLinear;  // kHertz applies to sphere contacts; others use kLinear
  Real kn = 0;           // linear normal stiffness per node [N/m]; 0: from young (contact_law.hpp)
  Real kt = 0;           // linear tangential stiffness [N/m]; 0: kn 2(1-nu)/(2-nu)
  Real restitution = 1;  // sets the normal dashpot (linear) or the Hertz damping alpha
  Real mu = 0;           // Coulomb friction coefficient
  Real young = 0, poisson = 0.3;          // grain material
  Real wall_young = 0, wall_poisson = 0;  // wall material (grain-wall only); young <= 0: rigid
  Real stiffness_overlap = Real(1e-2);    // eps of k_n = (4/3) E* R* sqrt(eps) when kn = 0
  bool tangential_damping = false;        // a dashpot on the sticking tangential spring
};

struct DemParams {
  Vec3 gravity{0, 0, -9.81};
  ContactModel grain_grain, grain_wall;
  Real reference_speed = 1;  // impact speed used by time_step() for Hertz contacts [m/s]
  // Nodes expected to penetrate at once in one level-set contact. Eq. 19 puts k_n on every node,
  // so a face contact of M nodes is M times stiffer (and M times more damped) than a vertex
  // contact; time_step() uses k_n * nodes_per_contact. With 1 (a vertex or sphere contact) a
  // face-to-face contact of many nodes can go unstable at dt_DEM.
  Real nodes_per_contact = 1;
};

// A contact-history key: (master body id, slave body id or wall key, master node).
struct ContactKey {
  GlobalId master = 0, slave = 0;
  std::uint32_t node = 0;
  bool operator<(const ContactKey& o) const {
    if (master != o.master) return master < o.master;
    if (slave != o.slave) return slave < o.slave;
    return node < o.node;
  }
  bool operator==(const ContactKey& o) const {
    return master == o.master && slave == o.slave && node == o.node;
  }
};
constexpr GlobalId kWallKeyBit = GlobalId(1) << 63;  // slave = kWallKeyBit | wall index
constexpr std::uint32_t kCentreNode = 0xFFFFFFFFu;   // the one contact point of the sphere path

// A wall: an analytic plane (phi = (x - point).normal) or a host SDF, translating with velocity.
struct Wall {
  geom::SdfPtr sdf;  // null: plane
  Vec3 point, normal;
  Vec3 offset;         // SDF walls: phi(x) = sdf->phi(x - offset)
  Vec3 velocity;       // translation speed (a baffle lifted at a prescribed speed)
  bool active = true;  // false: touches no grain (a gate that has opened)
  // This wall's own friction coefficient and restitution (DemSystem::set_wall_contact), in place
  // of grain_wall's; negative: grain_wall's. The stiffness stays grain_wall's (it sets the step).
  Real mu = -1, restitution = -1;
  Real zeta = 0, alpha = 0;  // from restitution: linear damping ratio, Hertz damping constant
};

// Everything a bit-identical restart needs beyond what the scene rebuilds (templates, parameters,
// walls' shapes): body states, the integrator's previous rates, moving-wall positions, the
// tangential contact history (keyed by body ids and node) and the time.
struct DemState {
  Real time = 0;
  std::vector<RigidBody> bodies;
  std::vector<Vec3> acc_prev, alpha_prev;
  std::vector<Vec3> wall_point, wall_offset;
  std::vector<ContactKey> keys;
  std::vector<Vec3> springs;
  // The external loads (the fluid's force and torque in a coupled run) of the last step. The next
  // step sets its own before it uses them: a restart needs them only to report them (bodies.csv).
  // Empty in a checkpoint written before they were kept: restored as zero.
  std::vector<Vec3> ext_force, ext_torque;
  // Centroids and motion flags at the last pair-list build: a restart rebuilds the same list
  // (the same broad-phase pairs and rebuild schedule). Empty in older checkpoints: the list is
  // then rebuilt from the restored positions.
  std::vector<Vec3> pairs_built_at;
  std::vector<std::int32_t> pairs_built_motion;
  // The walls' contact impulses since DemSystem::reset_wall_impulse and the time they span (a
  // restart reports the same mean wall force as the run it continues). Empty in checkpoints
  // written before 2026-12-06: restored as zero.
  std::vector<Vec3> wall_impulse;
  Real wall_impulse_time = 0;
};

class DemSystem {
 public:
  explicit DemSystem(const DemParams& params = {});

  void set_params(const DemParams& params);
  const DemParams& params() const { return params_; }

  // Adds a shape; grains of one shape share it. Returns its index.
  int add_template(GrainTemplate t);
  const GrainTemplate& shape(int k) const { return *templates_[std::size_t(k)]; }

  // Adds a grain of shape `shape` and density rho at centroid x with orientation q (body ->
  // world), velocity v and world-frame angular velocity w. Returns its slot. Ids default to the
  // insertion count.
  std::size_t add_body(int shape, Real rho, Vec3 x, Quat q = {}, Vec3 v = {}, Vec3 w_world = {},
                       Motion motion = Motion::kFree);
  int add_plane_wall(Vec3 point, Vec3 outward_normal, Vec3 velocity = {});
  int add_sdf_wall(geom::SdfPtr sdf, Vec3 velocity = {});
  // Gives wall w its own friction coefficient (mu >= 0) and restitution (0 < e <= 1) for grain
  // contacts; a negative value keeps grain_wall's. LAMMPS' fix wall/gran takes them per wall.
  void set_wall_contact(int w, Real mu, Real restitution);

  std::vector<RigidBody>& bodies() { return bodies_; }
  const std::vector<RigidBody>& bodies() const { return bodies_; }
  std::vector<Wall>& walls() { return walls_; }

  // External force and torque (world frame, about the centroid) added at every step until reset.
  void set_external(std::size_t body, Vec3 force, Vec3 torque);
  Vec3 external_force(std::size_t body) const { return ext_force_.at(body); }
  Vec3 external_torque(std::size_t body) const { return ext_torque_.at(body); }

  // Contact forces and torques at the current state; advances the tangential springs by dt.
  void compute_forces(Real dt);
  // compute_forces, then integrates every body and moves the walls.
  void step(Real dt);
  // dt_DEM = t_c / 50, t_c = pi sqrt(m*/(k_n nodes_per_contact)) for the lightest free grain
  // against a grain and a wall (Hertz: the Hertz contact time at reference_speed).
  Real time_step() const;

  // The grains' contact force ON wall w (minus the sum of its contacts' forces on the grains) at
  // the last compute_forces: a barrier wall's load from boulders [N].
  const Vec3& wall_force(int w) const { return wall_force_.at(std::size_t(w)); }
  // The time mean of wall_force over the steps since reset_wall_impulse() (zero before a step):
  // a coupled run resets it at each fluid step, so it is the load over that step's sub-steps.
  Vec3 wall_mean_force(int w) const;
  void reset_wall_impulse();
  const Vec3& force(std::size_t body) const { return force_[body]; }    // contacts only
  const Vec3& torque(std::size_t body) const { return torque_[body]; }  // contacts only
  Real time() const { return time_; }
  std::size_t contact_count() const;  // active contact points
  // Broad-phase pairs: bounding spheres within reach plus the skin (a Verlet list, rebuilt when a
  // grain has moved more than half the skin since the last build).
  std::size_t pair_count() const { return pairs_.size(); }
  std::size_t pair_builds() const { return pair_builds_; }
  Real max_overlap() const { return max_overlap_; }  // of the last compute_forces
  // Per-pair node lists (on by default): each grain pair keeps, for each of its two level-set
  // passes, the nodes of one grain that lay within a band of the other's surface when the list
  // was made, and tests only those while the pair's relative pose has not moved any node by more
  // than the skin (see compute_forces). The forces are bit-identical either way; off, every
  // step scans all nodes (tests compare the two).
  void set_node_lists(bool on) { node_lists_on_ = on; }
  // phi lookups in the level-set passes of the last compute_forces, and node lists remade.
  std::size_t phi_lookups() const { return phi_lookups_; }
  std::size_t node_list_builds() const { return node_list_builds_; }
  // The contact history (tangential springs) sorted by key, sphere pairs included.
  std::vector<ContactKey> history_keys() const;
  std::vector<Vec3> history_springs() const;
  Real kinetic_energy() const;

  DemState state() const;
  // Replaces the dynamic state with one taken from an identically built system. Throws
  // InputError when the body or wall counts differ.
  void restore(const DemState& s);

 private:
  struct PairOut;
  // The nodes of grain m that may touch grain s in one pass of a pair, and the relative pose
  // (s's frame) they were found at.
  struct NodeList {
    Quat q0;  // conj(q_s) q_m
    Vec3 t0;  // conj(q_s) (x_m - x_s)
    bool valid = false;
    GlobalId m_id = 0, s_id = 0;  // the bodies it was made for (body indices may be reused)
    int m_shape = -1, s_shape = -1;
    std::vector<std::uint32_t> nodes;  // in the order a full scan visits them
  };
  void find_pairs();
  void build_pair_list();
  bool pairs_stale() const;
  PairLaw pair_law(const RigidBody& a, const RigidBody& b, bool wall) const;
  // A grain-wall law `base` (pair_law(b, b, true)) with wall w's own friction and restitution.
  PairLaw wall_law(const PairLaw& base, const Wall& w) const;
  const Vec3* find_spring(const ContactKey& k) const;
  // hist_keys_ and the sphere pairs' springs merged, sorted by key.
  void merged_history(std::vector<ContactKey>& keys, std::vector<Vec3>& springs) const;

  DemParams params_;
  Real alpha_gg_ = 0, alpha_gw_ = 0;  // Hertz damping constants
  Real zeta_gg_ = 0, zeta_gw_ = 0;    // linear dashpots' damping ratios
  std::vector<std::shared_ptr<const GrainTemplate>> templates_;
  std::vector<RigidBody> bodies_;
  std::vector<Wall> walls_;
  std::vector<RigidBody> eval_;  // bodies with velocities predicted to the force time
  std::vector<Vec3> force_, torque_, ext_force_, ext_torque_;
  std::vector<Vec3> wall_force_, wall_impulse_;  // per wall (wall_force, wall_mean_force)
  Real wall_impulse_time_ = 0;
  std::vector<Vec3> acc_prev_, alpha_prev_;  // last step's dv/dt (world) and dw/dt (body)
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
  std::vector<Vec3> pairs_built_at_;        // centroids at the last pair build
  std::vector<Motion> pairs_built_motion_;  // motion flags at the last pair build
  // Each body's pairs in pair order (CSR): entry 2 pi + 0 when the body is the pair's first,
  // 2 pi + 1 when its second. Built with the pair list.
  std::vector<std::uint32_t> by_body_off_, by_body_;
  Real skin_ = 0;  // of the last build
  std::size_t pair_builds_ = 0;
  std::vector<std::size_t> node_begin_;  // body i's nodes: world_nodes_[node_begin_[i] ...]
  std::vector<Vec3> world_nodes_;        // surface nodes in the world frame, this step
  std::vector<Vec3> box_lo_, box_hi_;    // world bounding box of each grain, this step
  // Contact history. Sphere-sphere pairs keep their spring in the pair list while it lives
  // (pair_spring_[pi], valid where pair_touch_[pi] is 1: in contact at the last step), so the
  // common case needs no search; a rebuild carries them to the new list by key. Every other
  // contact point (grain nodes, walls) is in hist_keys_/hist_springs_, sorted by key, rebuilt
  // each step. After a restore, hist_keys_ holds everything until the next pair build.
  std::vector<std::array<NodeList, 2>> node_lists_;  // per pair: pass (a on b), pass (b on a)
  bool node_lists_on_ = true;
  std::size_t phi_lookups_ = 0, node_list_builds_ = 0;
  std::vector<Vec3> pair_spring_;
  std::vector<std::uint8_t> pair_touch_;
  std::vector<ContactKey> hist_keys_;  // sorted
  std::vector<Vec3> hist_springs_;
  Real time_ = 0, max_overlap_ = 0;
  GlobalId next_id_ = 0;
};

}  // namespace sphdem::dem
