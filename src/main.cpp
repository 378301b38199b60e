// The `leeway` command-line program: subcommands over the library. Exit codes: error.hpp.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "leeway/check.hpp"
#include "leeway/error.hpp"
#include "leeway/kinematics.hpp"
#include "leeway/scene.hpp"

namespace {

using leeway::InputError;
using nlohmann::json;

json to_array(const Eigen::VectorXd& v) {
  json a = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

json pose_json(const leeway::Pose& p) {
  json rows = json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({p.rotation(r, 0), p.rotation(r, 1), p.rotation(r, 2)});
  return {{"position", {p.position.x(), p.position.y(), p.position.z()}}, {"rotation", rows}};
}

void print_pose(const leeway::Pose& p) {
  std::cout.setf(std::ios::fixed);
  std::cout.precision(6);
  std::cout << "position [m]: " << p.position.x() << " " << p.position.y() << " " << p.position.z() << "\n";
  std::cout << "rotation (rows; columns are the tool axes in world):\n";
  for (int r = 0; r < 3; ++r)
    std::cout << "  " << p.rotation(r, 0) << " " << p.rotation(r, 1) << " " << p.rotation(r, 2) << "\n";
}

// --q or --key to a configuration.
Eigen::VectorXd configuration(const leeway::Scene& scene, const std::string& q, const std::string& key,
                              const std::string& what) {
  if (!q.empty() && !key.empty()) throw InputError(what + ": give either --q or --key, not both");
  if (!key.empty()) return scene.keyframe(key).q;
  if (q.empty())
    throw InputError(what + ": give the joint values with --q \"q1 q2 ...\" or a keyframe with --key");
  Eigen::VectorXd v = leeway::parse_vector(q, what + " --q");
  scene.validate_configuration(v, what + " --q");
  return v;
}

std::string joint_unit(const leeway::RobotJoint& j) { return j.prismatic ? "m" : "rad"; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "leeway: collision-free joint intervals around a nominal robot path (SI units: metres, radians)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "leeway 0.1.0");

  std::string tool = "tool0";
  auto add_tool = [&](CLI::App* sub) {
    sub->add_option("--tool", tool, "Name of the robot's tool site")->capture_default_str();
  };

  // check
  std::string check_file;
  bool check_json = false;
  leeway::CheckOptions check_opts;
  CLI::App* check = app.add_subcommand(
      "check",
      "Check an MJCF cell: keyframe collisions and limits, goal obstacles, reach, overlaps.\n"
      "Exit 0 clean, 1 problems found, 2 the file cannot be used.");
  check->add_option("cell", check_file, "MJCF file of the workcell")->required();
  check->add_flag("--json", check_json, "Print one JSON object instead of text");
  check->add_option("--dz", check_opts.goal_dz, "Algorithm 1 descent step [m]")->capture_default_str();
  check->add_option("--seed", check_opts.seed, "Seed of the inverse-kinematics restarts")
      ->capture_default_str();
  add_tool(check);

  // fk
  std::string fk_file, fk_q, fk_key;
  bool fk_json = false;
  CLI::App* fk = app.add_subcommand("fk", "Forward kinematics: the tool site's position [m] and orientation");
  fk->add_option("cell", fk_file, "MJCF file of the workcell")->required();
  fk->add_option("--q", fk_q, "Joint values in the robot's joint order [rad or m], e.g. \"0 0 0 0 0 0\"");
  fk->add_option("--key", fk_key, "Use a keyframe's joint values instead of --q");
  fk->add_flag("--json", fk_json, "Print JSON: position [x, y, z] and rotation (3x3 rows)");
  add_tool(fk);

  // ik
  std::string ik_file, ik_site, ik_seed_q, ik_seed_key, ik_lock;
  std::vector<double> ik_xyz;
  bool ik_json = false, ik_free = false;
  leeway::IkOptions ik_opts;
  CLI::App* ik = app.add_subcommand(
      "ik",
      "Inverse kinematics: joint values that put the tool site at a goal, tool pointing down,\n"
      "within limits and collision-free, nearest the seed. Exit 1 when no solution is found.");
  ik->add_option("cell", ik_file, "MJCF file of the workcell")->required();
  auto* site_opt = ik->add_option("--site", ik_site, "Goal site name");
  ik->add_option("--xyz", ik_xyz, "Goal position x y z [m]")->expected(3)->excludes(site_opt);
  ik->add_option("--seed-q", ik_seed_q, "Seed configuration [rad or m] (default: first keyframe)");
  ik->add_option("--seed-key", ik_seed_key, "Seed from a keyframe");
  ik->add_option("--lock", ik_lock, "Comma-separated joints kept at the seed value (e.g. the linear axis)");
  ik->add_flag("--free-orientation", ik_free, "Position only: do not require the tool to point down");
  ik->add_option("--restarts", ik_opts.restarts, "Random restarts after the seed")->capture_default_str();
  ik->add_option("--seed", ik_opts.seed, "Seed of the random restarts")->capture_default_str();
  ik->add_flag("--json", ik_json, "Print JSON");
  add_tool(ik);

  try {
    // CLI11 would only say "A subcommand is required" for a mistyped one: name it.
    const std::string first = argc > 1 ? argv[1] : "";
    if (!first.empty() && first[0] != '-' && first != "check" && first != "fk" && first != "ik") {
      std::cerr << "leeway: error: unknown subcommand '" << first << "'; subcommands: check, fk, ik "
                << "(see leeway --help)\n";
      return leeway::kExitBadInput;
    }
    try {
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
      return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
      return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
      return app.exit(e);
    } catch (const CLI::ParseError& e) {
      app.exit(e);
      return leeway::kExitBadInput;
    }
    leeway::SceneOptions scene_opts;
    scene_opts.tool_site = tool;

    if (*check) {
      const auto scene = leeway::Scene::load(check_file, scene_opts);
      const auto report = leeway::check_scene(scene, check_opts);
      if (check_json)
        std::cout << leeway::to_json(scene, report).dump(2) << "\n";
      else
        std::cout << leeway::to_text(scene, report);
      return report.ok() ? leeway::kExitOk : leeway::kExitFindings;
    }

    if (*fk) {
      const auto scene = leeway::Scene::load(fk_file, scene_opts);
      const Eigen::VectorXd q = configuration(scene, fk_q, fk_key, fk_file);
      leeway::RobotState state(scene);
      const leeway::Pose p = state.fk(q);
      if (fk_json) {
        json out = pose_json(p);
        out["q"] = to_array(q);
        out["units"] = "SI: metres, radians";
        std::cout << out.dump(2) << "\n";
      } else {
        print_pose(p);
      }
      return leeway::kExitOk;
    }

    if (*ik) {
      const auto scene = leeway::Scene::load(ik_file, scene_opts);
      Eigen::Vector3d target;
      if (!ik_site.empty()) {
        leeway::RobotState probe(scene);
        probe.set(scene.lower_limits().cwiseMax(0).cwiseMin(scene.upper_limits()));
        target = probe.site_pose(scene.goal_site(ik_site)).position;
      } else if (ik_xyz.size() == 3) {
        target = Eigen::Vector3d(ik_xyz[0], ik_xyz[1], ik_xyz[2]);
        if (!target.allFinite()) throw InputError(ik_file + ": --xyz values must be finite numbers");
      } else {
        throw InputError(ik_file + ": give the goal with --site NAME or --xyz X Y Z");
      }
      Eigen::VectorXd seed;
      if (!ik_seed_q.empty() || !ik_seed_key.empty())
        seed = configuration(scene, ik_seed_q, ik_seed_key, ik_file + " seed");
      else if (!scene.keyframes().empty())
        seed = scene.keyframes().front().q;
      else
        seed =
            Eigen::VectorXd::Zero(scene.dof()).cwiseMax(scene.lower_limits()).cwiseMin(scene.upper_limits());
      ik_opts.tool_down = !ik_free;
      ik_opts.locked.assign(static_cast<size_t>(scene.dof()), false);
      if (!ik_lock.empty()) {
        std::string name;
        auto lock = [&](const std::string& n) {
          const auto names = scene.joint_names();
          for (size_t i = 0; i < names.size(); ++i)
            if (names[i] == n) {
              ik_opts.locked[i] = true;
              return;
            }
          throw InputError(ik_file + ": --lock names unknown joint '" + n + "'");
        };
        for (char c : ik_lock + ",") {
          if (c == ',') {
            if (!name.empty()) lock(name);
            name.clear();
          } else {
            name += c;
          }
        }
      }
      leeway::RobotState state(scene);
      const auto result = leeway::solve_ik(state, target, seed, ik_opts);
      if (ik_json) {
        json out = {{"success", result.success},
                    {"target", {target.x(), target.y(), target.z()}},
                    {"joints", scene.joint_names()},
                    {"q", to_array(result.q)},
                    {"position_error", result.position_error},
                    {"orientation_error", result.orientation_error},
                    {"units", "SI: metres, radians"}};
        std::cout << out.dump(2) << "\n";
      } else {
        std::cout << (result.success ? "solution" : "NO SOLUTION; closest configuration")
                  << " (units: rad, m):\n";
        for (int i = 0; i < scene.dof(); ++i) {
          const auto& j = scene.joints()[static_cast<size_t>(i)];
          std::cout << "  " << j.name << " = " << result.q[i] << " " << joint_unit(j) << "\n";
        }
        std::cout << "position error " << result.position_error << " m, orientation error "
                  << result.orientation_error << "\n";
      }
      return result.success ? leeway::kExitOk : leeway::kExitFindings;
    }
  } catch (const InputError& e) {
    std::cerr << "leeway: error: " << e.what() << "\n";
    return leeway::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "leeway: internal error (please report): " << e.what() << "\n";
    return leeway::kExitInternal;
  }
  return leeway::kExitOk;
}
