#include "leeway/path/endpoints.hpp"

#include <algorithm>

#include "leeway/core/error.hpp"

namespace leeway {

Eigen::VectorXd place_slides(const Scene& scene, const Eigen::Vector3d& goal, const Eigen::VectorXd& q) {
  scene.validate_configuration(q, "linear-axis policy configuration");
  if (!goal.allFinite()) throw InputError("linear-axis policy: the goal position is not finite");
  int base_joint = -1;
  for (const auto& j : scene.joints())
    if (!j.prismatic) {
      base_joint = j.id;
      break;
    }
  RobotState state(scene);
  Eigen::VectorXd out = q;
  for (int i = 0; i < scene.dof(); ++i) {
    const RobotJoint& joint = scene.joints()[static_cast<size_t>(i)];
    if (!joint.prismatic) continue;
    out[i] = 0.0;
    state.set(out);
    const mjData& d = state.data();
    const Eigen::Vector3d base =
        base_joint >= 0 ? Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(d.xanchor + 3 * base_joint))
                        : state.tool_pose().position;
    const Eigen::Vector3d axis = Eigen::Map<const Eigen::Vector3d>(d.xaxis + 3 * joint.id).normalized();
    out[i] = std::clamp(axis.dot(goal - base), joint.lower, joint.upper);
  }
  return out;
}

IkResult gripper_ik(RobotState& state, const Eigen::Vector3d& goal, const Eigen::VectorXd& seed,
                    IkOptions options) {
  const Scene& scene = state.scene();
  scene.validate_configuration(seed, "IK seed");
  if (!goal.allFinite()) throw InputError("IK target position is not finite");
  options.locked.resize(static_cast<size_t>(scene.dof()), false);
  for (int i = 0; i < scene.dof(); ++i)
    if (scene.joints()[static_cast<size_t>(i)].prismatic) options.locked[static_cast<size_t>(i)] = true;
  return solve_ik(state, goal, place_slides(scene, goal, seed), options);
}

Eigen::Vector3d site_position(const Scene& scene, const std::string& name) {
  const int site = scene.goal_site(name);
  // Goal sites are outside the robot: any configuration gives their position.
  RobotState state(scene);
  state.set(default_ik_seed(scene));
  return state.site_pose(site).position;
}

std::string describe_unreachable(const Endpoint& end, bool start) {
  return std::string(start ? "start" : "goal") + " '" + end.spec + "' at (" +
         format_number(end.position.x()) + ", " + format_number(end.position.y()) + ", " +
         format_number(end.position.z()) +
         ") m: no collision-free configuration with the tool pointing down within the joint limits (closest: "
         "position error " +
         format_number(end.ik.position_error) + " m, orientation error " +
         format_number(end.ik.orientation_error) + ")";
}

bool is_gripper_goal(const std::string& spec) {
  return spec.rfind("site:", 0) == 0 || spec.rfind("xyz:", 0) == 0;
}

std::pair<Endpoint, Endpoint> resolve_endpoints(const Scene& scene, const std::string& from,
                                                const std::string& to, const EndpointOptions& options) {
  auto parse = [&](const std::string& spec) {
    Endpoint e;
    e.spec = spec;
    if (spec.rfind("site:", 0) == 0) {
      e.site = spec.substr(5);
      if (e.site.empty()) throw InputError(scene.source() + ": '" + spec + "' names no site (site:NAME)");
      e.position = site_position(scene, e.site);
    } else if (spec.rfind("xyz:", 0) == 0) {
      const Eigen::VectorXd v = parse_vector(spec.substr(4), "'" + spec + "'");
      if (v.size() != 3)
        throw InputError("'" + spec + "' must give three coordinates x,y,z [m], got " +
                         std::to_string(v.size()));
      e.position = v;
    } else {
      if (spec.empty())
        throw InputError(scene.source() + ": an empty path end (give a keyframe or site:NAME)");
      e.keyframe = spec;
      e.q = scene.keyframe(spec).q;
    }
    return e;
  };
  Endpoint a = parse(from), b = parse(to);
  Eigen::VectorXd fixed_seed;
  if (!options.ik_seed_key.empty()) fixed_seed = scene.keyframe(options.ik_seed_key).q;
  RobotState state(scene);
  auto solve = [&](Endpoint& e, const Eigen::VectorXd& seed) {
    e.ik = gripper_ik(state, e.position, fixed_seed.size() > 0 ? fixed_seed : seed, options.ik);
    e.reachable = e.ik.success;
    e.q = e.ik.q;
  };
  if (a.keyframe.empty()) solve(a, b.keyframe.empty() ? default_ik_seed(scene) : b.q);
  if (b.keyframe.empty()) solve(b, a.q);
  return {a, b};
}

}  // namespace leeway
