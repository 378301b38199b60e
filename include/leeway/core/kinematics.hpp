#pragma once
//! @file kinematics.hpp
//! Forward kinematics, collision queries and inverse kinematics on a Scene. Each object owns one
//! mjData: use one per thread with a shared const Scene.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "leeway/core/scene.hpp"

namespace leeway {

//! A position [m] and rotation (columns = frame axes in world) of a frame.
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
};

//! One robot-link-versus-obstacle contact.
struct Contact {
  int link_geom = -1;
  int obstacle_geom = -1;
  //! Penetration depth [m] (>= 0): exact for box pairs (separating-axis test), MuJoCo's contact
  //! distance otherwise.
  double depth = 0.0;
};

//! Two robot geoms in contact (a Scene::self_pairs() pair).
struct SelfContact {
  int geom1 = -1;  //!< on the part nearer the robot's root (RobotPair::geom1)
  int geom2 = -1;
  double depth = 0.0;  //!< penetration depth [m] (>= 0), as Contact::depth
};

//! The smallest distance between the robot's links and the obstacles.
struct Clearance {
  double distance = INFINITY;  //!< [m]; 0 in contact
  int link_geom = -1;
  int obstacle_geom = -1;
};

//! MuJoCo's mj_kinematics for what moves with the robot joints only (Scene::moving_bodies() and
//! their geoms and sites), with the same arithmetic in the same order, so the poses are bit for bit
//! mj_kinematics's. Everything else in `d` must already hold a full mj_kinematics of the scene
//! (nothing else moves: the robot's joints are the model's only joints). Its cost does not grow
//! with the number of obstacles, mj_kinematics's does (all their geoms).
void update_robot_kinematics(const Scene& scene, mjData& d);

//! Forward kinematics and collision queries for one thread (it owns one mjData). Keeps a pointer to
//! the Scene, which must outlive it.
class RobotState {
 public:
  explicit RobotState(const Scene& scene);

  //! Sets the robot joints and updates the poses (update_robot_kinematics()). @throws InputError on
  //! a bad size or NaN.
  void set(const Eigen::VectorXd& q);
  //! Pose of the tool site at the configuration last passed to set().
  Pose tool_pose() const;
  //! Pose of any site at the configuration last passed to set().
  Pose site_pose(int site) const;
  //! Tool pose at q.
  Pose fk(const Eigen::VectorXd& q) {
    set(q);
    return tool_pose();
  }
  //! True when the robot touches an obstacle or itself at q: obstacle_contact(q), or a self pair
  //! in contact (self_contact()). What every check of a configuration uses.
  bool in_collision(const Eigen::VectorXd& q);
  //! True when a robot link touches or penetrates an obstacle at q: mj_collision's answer, from the
  //! scene's checker (Scene::checker(): the midphase adds no contacts to data(); use contacts()
  //! for them). Self-collision is not looked at.
  bool obstacle_contact(const Eigen::VectorXd& q);
  //! The index in Scene::self_pairs() of the first pair in contact at the configuration last passed
  //! to set(), or -1: MuJoCo's narrowphase on each pair (geoms_touch(), the geoms' margins included).
  int self_contact() const;
  //! All robot-link-versus-obstacle contacts at q (deepest first).
  std::vector<Contact> contacts(const Eigen::VectorXd& q);
  //! All self pairs in contact at q (deepest first).
  std::vector<SelfContact> self_contacts(const Eigen::VectorXd& q);
  //! Clearance between robot links and obstacles at q: the distance of their shapes as MuJoCo
  //! collides them (shape.hpp: exact for boxes, a lower bound within 1e-9 m for the others; a mesh
  //! is its convex hull; planes are skipped).
  Clearance clearance(const Eigen::VectorXd& q);
  //! 6 x dof Jacobian of the tool site (rows: linear, then angular) at the last set() q.
  Eigen::MatrixXd tool_jacobian();

  const Scene& scene() const { return *scene_; }
  const mjData& data() const { return *data_; }

 private:
  void run_collision();
  const Scene* scene_;
  DataPtr data_;
};

//! Options of the numerical inverse kinematics.
struct IkOptions {
  bool tool_down = true;                //!< also require the tool z-axis along world -z (leeway's reading)
  std::vector<bool> locked;             //!< joints kept at the seed value (empty: none)
  int restarts = 24;                    //!< random restarts after the seed itself
  std::uint64_t seed = 1;               //!< RNG seed of the restarts
  double position_tolerance = 1e-5;     //!< [m]
  double orientation_tolerance = 1e-5;  //!< |z_tool - (-e_z)|, dimensionless
  int max_iterations = 400;             //!< per start
  bool require_collision_free = true;   //!< reject solutions in collision with the obstacles
};

//! Result of inverse kinematics.
struct IkResult {
  bool success = false;
  Eigen::VectorXd q;               //!< best configuration found (the solution when success)
  double position_error = 0.0;     //!< [m]
  double orientation_error = 0.0;  //!< |z_tool - (-e_z)| (0 when tool_down is off)
  int solutions_found = 0;         //!< distinct converged starts
};

//! The self pairs that touch at q, for deciding what to exclude (import-urdf, new-cell): the pairs
//! of state.self_contacts(q), and the pairs whose distance (shape.hpp) is at most `tolerance` [m],
//! with depth 0 (boxes meeting face to face at a joint touch or not by rounding; this answers the
//! same either way). Deepest first.
std::vector<SelfContact> self_contacts_within(RobotState& state, const Eigen::VectorXd& q, double tolerance);

//! The IK seed when the caller has none (check_scene's reach test, resolve_endpoints and
//! site_position): the cell's first keyframe, which by convention is its home pose, or, in a cell
//! without keyframes, the joint values nearest zero within the limits (the robot's zero pose).
Eigen::VectorXd default_ik_seed(const Scene& scene);

//! Damped-least-squares inverse kinematics for the tool site within the joint limits, restarted
//! from the seed and from seeded random configurations; returns the converged solution nearest the
//! seed (joint-space distance). Deterministic for a given options.seed.
//! @throws InputError when the target or seed is not finite or the seed has the wrong size.
IkResult solve_ik(RobotState& state, const Eigen::Vector3d& target, const Eigen::VectorXd& seed,
                  const IkOptions& options = {});

}  // namespace leeway
