#pragma once
//! @file scene.hpp
//! A workcell loaded from MJCF, with the robot, its links, the obstacles, goal sites and keyframes
//! recognised by the rules of docs/mjcf-conventions.md.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "leeway/core/collision.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/numbers.hpp"

namespace leeway {

//! One robot joint (1-dof hinge or slide), in the model's order.
struct RobotJoint {
  std::string name;
  int id = -1;             //!< MuJoCo joint id
  bool prismatic = false;  //!< slide joint [m] rather than hinge [rad]
  double lower = 0.0;      //!< lower limit [rad or m]
  double upper = 0.0;      //!< upper limit [rad or m]
  double max_speed = 0.0;  //!< nominal max speed from joint user[0] [rad/s or m/s]; 0 if absent
};

//! What a geom is to leeway.
enum class GeomRole {
  kIgnored,    //!< not collidable in the file (contype = conaffinity = 0): visual only
  kLink,       //!< collidable geom on a robot body that moves with a joint
  kRobotBase,  //!< collidable geom on a robot body fixed to the world (base, rail): only against links
  kObstacle,   //!< any other collidable geom
};

//! Two robot geoms that leeway checks against each other (self-collision): on rigid parts of the
//! robot (MuJoCo's weld bodies) that are neither the same nor parent and child, and not excluded
//! by the cell. geom1 is on the part with the smaller body id (MuJoCo numbers parents first, so on
//! one chain it is the part nearer the root).
struct RobotPair {
  int geom1 = -1;
  int geom2 = -1;
};

//! A pair that would be a RobotPair but the cell excludes it.
struct ExcludedPair {
  int geom1 = -1;
  int geom2 = -1;
  //! true: MuJoCo's <contact><exclude body1 body2/>; false: a leeway_exclude custom text naming
  //! the two geoms (docs/mjcf-conventions.md).
  bool by_body = false;
};

//! A named keyframe's joint values (robot joints in order).
struct Keyframe {
  std::string name;
  Eigen::VectorXd q;
};

//! Options for recognising the scene.
struct SceneOptions {
  std::string tool_site = "tool0";  //!< the site at the robot's flange
  //! Which pipeline answers every collision check against this scene and its volume: the midphase
  //! (default) or MuJoCo's full mj_collision pass (the reference; collision.hpp).
  CollisionChecker checker = CollisionChecker::kMidphase;
};

//! A loaded, recognised workcell. Owns its mjModel, whose collision bitmasks are normalised so that
//! MuJoCo reports only robot-link-versus-obstacle contacts (bit 0 of link contype against bit 0 of
//! obstacle conaffinity); the robot's pairs with itself are leeway's own list (self_pairs()).
class Scene {
 public:
  //! Loads and recognises an MJCF file.
  //! @throws InputError naming the file, element and value when the file cannot be used.
  static Scene load(const std::string& path, const SceneOptions& options = {});

  //! Recognises an already compiled model; `source` names it in messages.
  //! @throws InputError as load().
  static Scene from_model(ModelPtr model, std::string source, const SceneOptions& options = {});

  const std::string& source() const { return source_; }
  const mjModel& model() const { return *model_; }
  int dof() const { return static_cast<int>(joints_.size()); }
  const std::vector<RobotJoint>& joints() const { return joints_; }
  std::vector<std::string> joint_names() const;
  Eigen::VectorXd lower_limits() const;
  Eigen::VectorXd upper_limits() const;
  int robot_root_body() const { return robot_root_; }
  //! The bodies that move with the robot joints (a joint on them or on an ancestor), parents first,
  //! and the geoms and sites on them: all that update_robot_kinematics() recomputes.
  const std::vector<int>& moving_bodies() const { return moving_bodies_; }
  const std::vector<int>& moving_geoms() const { return moving_geoms_; }
  const std::vector<int>& moving_sites() const { return moving_sites_; }

  const std::vector<int>& link_geoms() const { return link_geoms_; }
  const std::vector<int>& base_geoms() const { return base_geoms_; }
  const std::vector<int>& obstacle_geoms() const { return obstacle_geoms_; }
  //! The robot geom pairs checked for self-collision (RobotPair), and those the cell excludes.
  const std::vector<RobotPair>& self_pairs() const { return self_pairs_; }
  const std::vector<ExcludedPair>& excluded_pairs() const { return excluded_pairs_; }
  //! The cell's `<option>` settings leeway overrode for its checks, one sentence each (contacts or
  //! constraints disabled, an override margin, predefined pairs only): every check (check, the
  //! path check, the planner, IK, CF, the sampled mode, simulate) sees the geoms' own contacts.
  const std::vector<std::string>& overridden_options() const { return overridden_options_; }
  GeomRole role(int geom) const { return roles_.at(static_cast<size_t>(geom)); }
  //! The geom's name, or "unnamed geom #id on body 'b'" when it has none.
  std::string geom_label(int geom) const;

  int tool_site() const { return tool_site_; }
  //! The collision checker: SceneOptions::checker, or kMujoco when the model needs mj_collision
  //! (emulates_mj_collision() is false for it).
  CollisionChecker checker() const { return checker_; }
  //! Every geom that is not a link, indexed for the midphase at its (fixed) pose.
  const StaticGeoms& statics() const { return statics_; }
  const std::vector<int>& goal_sites() const { return goal_sites_; }
  //! Site id of a goal site. @throws InputError listing the goal sites when unknown.
  int goal_site(const std::string& name) const;

  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  //! A keyframe by name. @throws InputError listing the keyframes when unknown.
  const Keyframe& keyframe(const std::string& name) const;

  //! Checks a configuration's size and finiteness. @throws InputError naming `what`, the joint and
  //! the value.
  void validate_configuration(const Eigen::VectorXd& q, const std::string& what) const;

  //! Indices of the joints whose value lies outside their limits.
  std::vector<int> joints_outside_limits(const Eigen::VectorXd& q) const;

  //! Copies a robot configuration into qpos (other entries untouched).
  void set_qpos(mjData& d, const Eigen::VectorXd& q) const;

 private:
  Scene() = default;
  void recognise(const SceneOptions& options);
  void find_self_pairs();
  void override_blinding_options(mjModel& m);

  std::string source_;
  ModelPtr model_;
  std::vector<RobotJoint> joints_;
  int robot_root_ = -1;
  std::vector<int> moving_bodies_, moving_geoms_, moving_sites_;
  std::vector<GeomRole> roles_;
  std::vector<int> link_geoms_, base_geoms_, obstacle_geoms_;
  std::vector<RobotPair> self_pairs_;
  std::vector<ExcludedPair> excluded_pairs_;
  std::vector<std::string> overridden_options_;
  int tool_site_ = -1;
  CollisionChecker checker_ = CollisionChecker::kMidphase;
  StaticGeoms statics_;
  std::vector<int> goal_sites_;
  std::vector<Keyframe> keyframes_;
};

//! Parses "q1 q2 ..." (spaces or commas) into a vector. @throws InputError naming `what` and the
//! offending token when a token is not a finite number.
Eigen::VectorXd parse_vector(const std::string& text, const std::string& what);

}  // namespace leeway
