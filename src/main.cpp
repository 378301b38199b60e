// The `leeway` command-line program: subcommands over the library. Exit codes: error.hpp.
#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <tuple>

#include "cli_parse.hpp"
#include "leeway/check.hpp"
#include "leeway/error.hpp"
#include "leeway/kinematics.hpp"
#include "leeway/path_check.hpp"
#include "leeway/pipeline.hpp"
#include "leeway/planner.hpp"
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

// Parameters: the preset, then the cell's own (MJCF custom numerics), then the keys present in a
// --params file, then flags (--safety, --max-cells).
leeway::Params load_params(const leeway::Scene& scene, const std::string& preset, const std::string& file,
                           const std::string& safety) {
  leeway::Params p = leeway::preset_params(preset);
  leeway::apply_cell_defaults(scene, p);
  if (!file.empty()) p = leeway::read_params(file, p);
  if (!safety.empty()) {
    if (safety == "none")
      p.safety.mode = leeway::SafetyMode::kNone;
    else if (safety == "sampled")
      p.safety.mode = leeway::SafetyMode::kSampled;
    else if (safety == "certified")
      p.safety.mode = leeway::SafetyMode::kCertified;
    else
      throw InputError("--safety '" + safety + "' must be certified, sampled or none");
  }
  return p;
}

// --preset and --safety on a subcommand that computes bounds.
void add_preset_options(CLI::App* sub, std::string& preset, std::string& safety) {
  sub->add_option("--preset", preset,
                  "Parameter set: leeway (tuned parameters, certified safety) or thesis (section 4.1,\n"
                  "no safety stage: the published method); --params and flags override it")
      ->capture_default_str();
  sub->add_option("--safety", safety,
                  "certified (every interval proven free of the obstacles), sampled (an epsilon-delta\n"
                  "sampling test) or none (the thesis's bounds as they are); default: the preset's");
}

int default_threads() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

std::vector<int> parse_cells_list(const std::string& text) {
  std::vector<int> out;
  const Eigen::VectorXd v = leeway::parse_vector(text, "--max-cells");
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (v[i] != std::floor(v[i]) || v[i] < 1 || v[i] > 1e6)
      throw InputError("--max-cells value '" +
                       (std::abs(v[i]) < 1e15 && v[i] == std::floor(v[i])
                            ? std::to_string(static_cast<long long>(v[i]))
                            : leeway::format_number(v[i])) +
                       "' must be a whole number from 1 to 1000000");
    out.push_back(static_cast<int>(v[i]));
  }
  if (out.empty()) throw InputError("--max-cells lists no value");
  return out;
}

// A path end that needs inverse kinematics (and so a planned path) rather than a keyframe.
bool is_gripper_goal(const std::string& spec) {
  return spec.rfind("site:", 0) == 0 || spec.rfind("xyz:", 0) == 0;
}

// Plans between two path ends (docs/planning.md). On an unreachable goal or no path, prints the
// one-line reason and returns false: the caller exits with kExitFindings and writes nothing.
bool plan_between(const leeway::Scene& scene, const std::string& from, const std::string& to,
                  const std::string& ik_seed_key, const leeway::PlanOptions& options,
                  leeway::PlanResult& result, leeway::Endpoint& a, leeway::Endpoint& b) {
  leeway::EndpointOptions eo;
  eo.ik_seed_key = ik_seed_key;
  std::tie(a, b) = leeway::resolve_endpoints(scene, from, to, eo);
  for (const leeway::Endpoint* e : {&a, &b}) {
    if (e->reachable) continue;
    std::cerr << "leeway: unreachable: " << scene.source() << ": " << (e == &a ? "start" : "goal") << " '"
              << e->spec << "' at (" << leeway::format_number(e->position.x()) << ", "
              << leeway::format_number(e->position.y()) << ", " << leeway::format_number(e->position.z())
              << ") m: no collision-free configuration with the tool pointing down within the joint limits"
              << " (closest: position error " << leeway::format_number(e->ik.position_error)
              << " m, orientation error " << leeway::format_number(e->ik.orientation_error)
              << "); nothing written\n";
    return false;
  }
  result = leeway::plan_path(scene, a.q, b.q, options, "start '" + from + "'", "goal '" + to + "'");
  if (!result.success) {
    std::cerr << "leeway: no path: " << scene.source() << ": " << result.message << "; nothing written\n";
    return false;
  }
  return true;
}

// "  (safety: lower +0.0312)": what the safety stage took off joint i's guide interval.
std::string shrink_note(const leeway::WaypointBounds& w, int i) {
  if (w.guide_lower.size() != w.lower.size() || w.guide_upper.size() != w.upper.size()) return "";
  const double below = w.lower[i] - w.guide_lower[i], above = w.guide_upper[i] - w.upper[i];
  if (!(below > 0) && !(above > 0)) return "";
  std::ostringstream o;
  o << std::fixed << std::setprecision(4) << "  (safety shrank it: lower +" << below << ", upper -" << above
    << ")";
  return o.str();
}

// One line on the safety stage: mode, outcome, work.
void print_safety(const leeway::SafetyReport& r, const leeway::SafetyParams& params) {
  int passed = 0;
  for (const auto& s : r.segments) passed += s.passed ? 1 : 0;
  const auto n = r.segments.size();
  switch (r.mode) {
    case leeway::SafetyMode::kNone:
      std::cout << "safety: none (the thesis's bounds, not checked against the obstacles)\n";
      break;
    case leeway::SafetyMode::kCertified:
      std::cout << "safety: certified, " << passed << " of " << n << " segments proven free (margin "
                << leeway::format_number(params.margin) << " m; " << r.stats.leaves << " leaves, depth "
                << r.stats.max_depth << ")"
                << (r.all_passed ? "" : "; NOT CERTIFIED where the nominal path is too close") << "\n";
      break;
    case leeway::SafetyMode::kSampled:
      std::cout << "safety: sampled, " << passed << " of " << n << " segments passed "
                << r.samples_per_segment << " collision-free samples (epsilon "
                << leeway::format_number(params.epsilon) << ", delta " << leeway::format_number(params.delta)
                << ")\n";
      break;
  }
}

// The thesis's 20 MAX_cells values (section 4.1).
const char* kThesisCells =
    "100,150,200,500,750,1000,1500,2000,3000,5000,7500,10000,12000,15000,20000,25000,30000,40000,50000,"
    "100000";

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

  // plan
  std::string pl_file, pl_from, pl_to, pl_out, pl_ik_seed;
  bool pl_json = false, pl_no_simplify = false, pl_no_direct = false;
  leeway::PlanOptions pl_opts;
  CLI::App* plan = app.add_subcommand(
      "plan",
      "Plan a collision-free path (OMPL RRT-Connect in joint space, then simplified) between two\n"
      "keyframes or gripper goals (site:NAME, xyz:X,Y,Z: inverse kinematics first); see docs/planning.md.\n"
      "Exit 0 path found, 1 unreachable goal or no path within the time limit, 2 bad input\n"
      "(also a start or goal in collision).");
  plan->add_option("cell", pl_file, "MJCF file of the workcell")->required();
  plan->add_option("--from", pl_from, "Start: a keyframe, site:NAME or xyz:X,Y,Z [m]")->required();
  plan->add_option("--to", pl_to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z [m]")->required();
  plan->add_option("--seed", pl_opts.seed, "Random seed (same seed, same path)")->capture_default_str();
  plan->add_option("--time-limit", pl_opts.time_limit, "RRT-Connect's time budget [s]")
      ->capture_default_str();
  plan->add_option("--resolution", pl_opts.resolution, "Motion resolution of hinge joints [rad]")
      ->capture_default_str();
  plan->add_option("--slide-resolution", pl_opts.slide_resolution, "Motion resolution of slide joints [m]")
      ->capture_default_str();
  plan->add_option("--range", pl_opts.range, "RRT-Connect's longest extension [rad]; 0 = OMPL's default")
      ->capture_default_str();
  plan->add_option("--clearance", pl_opts.clearance, "Clearance margin to the obstacles [m]")
      ->capture_default_str();
  plan->add_flag("--no-simplify", pl_no_simplify, "Keep RRT-Connect's raw path");
  plan->add_flag("--no-direct", pl_no_direct,
                 "Run RRT-Connect even when the joint-linear edge from start to goal is free");
  plan->add_option("--ik-seed", pl_ik_seed, "Keyframe seeding the inverse kinematics of gripper goals");
  plan->add_option("--out", pl_out, "Write the path file here (JSON)");
  plan->add_flag("--json", pl_json, "Print the path file to standard output");
  add_tool(plan);

  // bounds
  std::string b_file, b_from, b_to, b_params, b_out, b_path, b_ik_seed;
  int b_cells = 0, b_waypoints = 2, b_threads = default_threads();
  bool b_json = false;
  leeway::PlanOptions b_plan;
  CLI::App* bounds = app.add_subcommand(
      "bounds",
      "Joint bounds along a path (thesis chapter 3): the joint-linear path between two keyframes, a\n"
      "planned path when --from/--to name a gripper goal (site:NAME, xyz:X,Y,Z), or every waypoint of\n"
      "a path file (--path). The path is checked densely first; a colliding straight path between two\n"
      "keyframes is planned around (RRT-Connect). Exit 0 on success, 1 a colliding path, an unreachable\n"
      "goal or no path, 2 bad input.");
  bounds->add_option("cell", b_file, "MJCF file of the workcell")->required();
  auto* b_path_opt =
      bounds->add_option("--path", b_path, "Path file written by leeway plan --out (instead of --from/--to)");
  bounds->add_option("--from", b_from, "Start: a keyframe, site:NAME or xyz:X,Y,Z")->excludes(b_path_opt);
  bounds->add_option("--to", b_to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z")->excludes(b_path_opt);
  bounds
      ->add_option("--waypoints", b_waypoints,
                   "Waypoints along the joint-linear path between two keyframes (>= 2; the thesis: 2)")
      ->capture_default_str();
  bounds->add_option("--seed", b_plan.seed, "Planner seed (gripper goals)")->capture_default_str();
  bounds->add_option("--time-limit", b_plan.time_limit, "Planner time budget [s] (gripper goals)")
      ->capture_default_str();
  bounds->add_option("--ik-seed", b_ik_seed, "Keyframe seeding the inverse kinematics of gripper goals");
  bounds->add_option("--max-cells", b_cells, "MAX_cells of the height-map (default: from --params, 20000)");
  bounds->add_option("--params", b_params, "Parameter file (JSON; see leeway params)");
  std::string b_preset = "leeway", b_safety;
  add_preset_options(bounds, b_preset, b_safety);
  bounds->add_option("--out", b_out, "Write the bounds file here (JSON)");
  bounds->add_option("--threads", b_threads, "Worker threads")->capture_default_str();
  bounds->add_flag("--json", b_json, "Print the bounds file to standard output");
  bool b_no_plan = false;
  bounds->add_flag(
      "--no-plan", b_no_plan,
      "Exit 1 when the straight path between two keyframes collides instead of planning around it");

  // cf
  std::string c_file, c_bounds;
  bool c_json = false;
  int c_threads = default_threads();
  leeway::CfParams c_params;
  CLI::App* cf =
      app.add_subcommand("cf", "Confidence Factor of a bounds file against the real obstacles (section 4.1)");
  cf->add_option("cell", c_file, "MJCF file of the workcell")->required();
  cf->add_option("bounds", c_bounds, "Bounds file written by leeway bounds --out")->required();
  cf->add_option("--windows", c_params.windows, "Windows along the path")->capture_default_str();
  cf->add_option("--samples", c_params.samples, "Random configurations per window")->capture_default_str();
  cf->add_option("--seed", c_params.seed, "Random seed")->capture_default_str();
  cf->add_option("--threads", c_threads, "Worker threads")->capture_default_str();
  cf->add_flag("--json", c_json, "Print JSON");

  // sweep
  std::string s_file, s_from, s_to, s_params, s_cells = kThesisCells, s_csv;
  int s_threads = default_threads(), s_waypoints = 2;
  leeway::CfParams s_cf;
  CLI::App* sweep = app.add_subcommand(
      "sweep", "The thesis's table: for each MAX_cells, boxes, time [ms] and CF [%], as Markdown (and CSV)");
  sweep->add_option("cell", s_file, "MJCF file of the workcell")->required();
  sweep->add_option("--from", s_from, "Keyframe the path starts at")->required();
  sweep->add_option("--to", s_to, "Keyframe the path ends at")->required();
  sweep->add_option("--waypoints", s_waypoints, "Waypoints along the joint-linear path")
      ->capture_default_str();
  sweep->add_option("--max-cells", s_cells, "Comma-separated MAX_cells values (default: the thesis's 20)");
  sweep->add_option("--params", s_params, "Parameter file (JSON)");
  std::string s_preset = "leeway", s_safety;
  add_preset_options(sweep, s_preset, s_safety);
  sweep->add_option("--csv", s_csv, "Also write the table as CSV here");
  sweep->add_option("--windows", s_cf.windows, "CF windows")->capture_default_str();
  sweep->add_option("--samples", s_cf.samples, "CF samples per window")->capture_default_str();
  sweep->add_option("--seed", s_cf.seed, "CF random seed")->capture_default_str();
  sweep->add_option("--threads", s_threads, "Worker threads")->capture_default_str();

  // params
  std::string p_file;
  CLI::App* params_cmd =
      app.add_subcommand("params", "Print the default parameters as JSON (SI units), or a cell's");
  params_cmd->add_option("cell", p_file, "Also apply this cell's own defaults (MJCF custom numerics)");
  std::string p_preset = "leeway";
  params_cmd->add_option("--preset", p_preset, "Parameter set to print: leeway or thesis")
      ->capture_default_str();

  return leeway::detail::run_reporting_errors("leeway", [&]() -> int {
    // CLI11 would only say "A subcommand is required" for a mistyped one: name it.
    const std::string first = argc > 1 ? argv[1] : "";
    if (!first.empty() && first[0] != '-' && first != "check" && first != "fk" && first != "ik" &&
        first != "plan" && first != "bounds" && first != "cf" && first != "sweep" && first != "params") {
      std::cerr << "leeway: error: unknown subcommand '" << first
                << "'; subcommands: check, fk, ik, plan, bounds, cf, sweep, params "
                << "(see leeway --help)\n";
      return leeway::kExitBadInput;
    }
    if (const auto code = leeway::detail::parse_cli(app, argc, argv)) return *code;
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
    if (*plan) {
      const auto scene = leeway::Scene::load(pl_file, scene_opts);
      pl_opts.simplify = !pl_no_simplify;
      pl_opts.try_direct = !pl_no_direct;
      leeway::PlanResult result;
      leeway::Endpoint a, b;
      if (!plan_between(scene, pl_from, pl_to, pl_ik_seed, pl_opts, result, a, b))
        return leeway::kExitFindings;
      const json out = leeway::path_json(scene, result, pl_opts, a, b);
      if (!pl_out.empty()) leeway::write_file_atomic(pl_out, out.dump(2) + "\n");
      if (pl_json) {
        std::cout << out.dump(2) << "\n";
      } else {
        std::cout << scene.source() << " " << pl_from << " -> " << pl_to << " (units: rad, m, s)\n";
        std::cout << result.waypoints.size() << " waypoints, " << result.method
                  << (result.method == "direct" ? " (the joint-linear edge is free)" : "") << ", length "
                  << leeway::format_number(result.length) << " rad (weighted), " << result.checks
                  << " collision checks, "
                  << leeway::format_number(result.plan_seconds + result.simplify_seconds) << " s, seed "
                  << pl_opts.seed << "\n";
        std::cout << "joints:";
        for (const auto& n : scene.joint_names()) std::cout << " " << n;
        std::cout << "\n" << std::fixed << std::setprecision(6);
        for (size_t w = 0; w < result.waypoints.size(); ++w) {
          std::cout << "  " << std::setw(3) << w << ":";
          for (Eigen::Index i = 0; i < result.waypoints[w].size(); ++i)
            std::cout << " " << result.waypoints[w][i];
          std::cout << "\n";
        }
        if (!pl_out.empty()) std::cout << "wrote " << pl_out << "\n";
      }
      return leeway::kExitOk;
    }

    if (*bounds) {
      const auto scene = leeway::Scene::load(b_file, scene_opts);
      leeway::Params p = load_params(scene, b_preset, b_params, b_safety);
      if (bounds->count("--max-cells") > 0) p.height_map.max_cells = b_cells;
      p.validate();
      if (b_threads < 1) throw InputError("--threads " + std::to_string(b_threads) + " must be >= 1");
      std::vector<Eigen::VectorXd> path;
      std::string label = b_from + " -> " + b_to;
      const bool linear = b_path.empty() && !is_gripper_goal(b_from) && !is_gripper_goal(b_to);
      if (!linear && bounds->count("--waypoints") > 0)
        throw InputError("--waypoints applies to the joint-linear path between two keyframes only, not to " +
                         std::string(b_path.empty() ? "a planned path" : "--path"));
      if (!b_path.empty()) {
        path = leeway::read_path(b_path, scene);
        label = b_path;
      } else if (b_from.empty() || b_to.empty()) {
        throw InputError(b_file +
                         ": give the path with --from and --to (keyframes, site:NAME or xyz:X,Y,Z)"
                         " or with --path FILE");
      } else if (linear) {
        path = leeway::keyframe_path(scene, b_from, b_to, b_waypoints);
      } else {
        leeway::PlanResult planned;
        leeway::Endpoint a, b;
        if (!plan_between(scene, b_from, b_to, b_ik_seed, b_plan, planned, a, b))
          return leeway::kExitFindings;
        path = planned.waypoints;
      }
      // Issue #9: the nominal path is checked first, densely, whatever its source: the thesis's
      // method (chapter 3) assumes it collision-free.
      const leeway::PathCheckOptions b_check;
      leeway::PathCheckResult checked = leeway::check_path(scene, path, b_check);
      json nominal = {{"checked", true},
                      {"resolution", b_check.resolution},
                      {"slide_resolution", b_check.slide_resolution},
                      {"planned", !linear && b_path.empty()}};
      if (linear && !checked.free()) {
        const leeway::PathCollision hit = *checked.collision;
        const std::string what =
            "the straight path from " + b_from + " to " + b_to +
            (path.size() > 2 ? " (" + std::to_string(path.size()) + " waypoints)" : std::string()) + " " +
            leeway::describe_collision(scene, hit, true);
        // A keyframe that is not free itself cannot be planned around.
        std::string stuck;
        for (const auto& [key, q] : {std::pair{b_from, path.front()}, std::pair{b_to, path.back()}})
          if (stuck.empty() && !leeway::check_path(scene, {q}, b_check).free()) stuck = key;
        if (b_no_plan || !stuck.empty()) {
          std::cerr << "leeway: collision: " << scene.source() << ": " << what
                    << (stuck.empty() ? ""
                                      : "; keyframe '" + stuck + "' itself is not free, so no path avoids it")
                    << "; nothing written\n";
          return leeway::kExitFindings;
        }
        leeway::PlanOptions around = b_plan;
        around.try_direct = false;  // the straight edge may pass the planner's coarser check
        const leeway::PlanResult planned = leeway::plan_path(scene, path.front(), path.back(), around,
                                                             "start '" + b_from + "'", "goal '" + b_to + "'");
        if (!planned.success) {
          std::cerr << "leeway: no path: " << scene.source() << ": " << what << "; " << planned.message
                    << "; nothing written\n";
          return leeway::kExitFindings;
        }
        // Standard output stays one JSON object with --json.
        (b_json ? std::cerr : std::cout)
            << what << "; planned a path with " << planned.waypoints.size()
            << " waypoints (RRT-Connect, seed " << around.seed << ")"
            << (path.size() > 2
                    ? ", which replaces the " + std::to_string(path.size()) + " straight waypoints"
                    : std::string())
            << "\n";
        nominal["planned"] = true;
        nominal["replaced_straight_path"] = {
            {"from", b_from},
            {"to", b_to},
            {"waypoints", path.size()},
            {"obstacle", hit.obstacle_geom >= 0 ? json(hit.obstacle) : json(nullptr)},
            {"link", hit.link_geom >= 0 ? json(hit.link) : json(nullptr)},
            {"s", hit.path_fraction},
            {"depth", hit.depth},
            {"q", to_array(hit.q)},
            {"checks", checked.checks},
            {"planner",
             {{"name", "RRTConnect"},
              {"seed", around.seed},
              {"time_limit", around.time_limit},
              {"resolution", around.resolution},
              {"slide_resolution", around.slide_resolution},
              {"waypoints", planned.waypoints.size()}}}};
        path = planned.waypoints;
        label += " (planned around '" + hit.obstacle + "')";
        checked = leeway::check_path(scene, path, b_check);
      }
      if (!checked.free()) {
        // A path file, or a planned path that passed the planner's coarser edge check.
        const bool planned = nominal["planned"].get<bool>();
        std::cerr << "leeway: collision: " << (b_path.empty() ? scene.source() : b_path) << ": "
                  << (b_path.empty() ? "the path planned from " + b_from + " to " + b_to
                                     : std::string("the path"))
                  << " " << leeway::describe_collision(scene, *checked.collision)
                  << (planned ? " when checked at " + leeway::format_number(b_check.resolution) +
                                    " rad (the planner checks at " +
                                    leeway::format_number(b_plan.resolution) + " rad)"
                              : std::string())
                  << "; nothing written\n";
        return leeway::kExitFindings;
      }
      nominal["checks"] = checked.checks;
      leeway::VolumeModel world(scene,
                                p.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
      const auto run = leeway::compute_bounds(scene, world, path, p, b_threads);
      json out = leeway::bounds_json(scene, run, p);
      out["nominal_path"] = nominal;
      if (!b_out.empty()) leeway::write_file_atomic(b_out, out.dump(2) + "\n");
      if (b_json) {
        std::cout << out.dump(2) << "\n";
      } else {
        std::cout << scene.source() << " " << label << " (units: rad, m, ms)\n";
        std::cout << "MAX_cells " << p.height_map.max_cells << ", boxes " << run.volume.boxes.size()
                  << ", goal obstacle " << out["goal_obstacle"].dump() << ", collision checks " << run.checks
                  << "\n";
        std::cout << std::fixed << std::setprecision(4);
        for (size_t w = 0; w < run.bounds.size(); ++w) {
          std::cout << "waypoint " << w << ":\n";
          for (int i = 0; i < scene.dof(); ++i)
            std::cout << "  " << std::setw(8) << scene.joints()[static_cast<size_t>(i)].name << "  ["
                      << run.bounds[w].lower[i] << ", " << run.bounds[w].upper[i] << "]  nominal "
                      << run.bounds[w].q[i]
                      << (run.bounds[w].collapsed[static_cast<size_t>(i)] ? "  (collapsed, widened)" : "")
                      << shrink_note(run.bounds[w], i) << "\n";
        }
        print_safety(run.safety, p.safety);
        std::cout << std::setprecision(1) << "time [ms]: categorize " << run.ms_categorize << ", volume "
                  << run.ms_volume << ", inject " << run.ms_inject << ", bounds " << run.ms_bounds
                  << ", safety " << run.ms_safety << ", total " << run.ms_total() << "\n";
        if (!b_out.empty()) std::cout << "wrote " << b_out << "\n";
      }
      return leeway::kExitOk;
    }

    if (*cf) {
      const auto scene = leeway::Scene::load(c_file, scene_opts);
      if (c_threads < 1) throw InputError("--threads " + std::to_string(c_threads) + " must be >= 1");
      const auto wb = leeway::read_bounds(c_bounds, scene);
      const auto r = leeway::confidence_factor(scene, wb, c_params, c_threads);
      if (c_json) {
        json out = {{"cf", r.cf},
                    {"ci95", {r.ci_low, r.ci_high}},
                    {"worst_window", {{"index", r.worst_window}, {"cf", r.worst_window_cf}}},
                    {"window_cf", r.window_cf},
                    {"samples", r.samples},
                    {"collisions", r.collisions},
                    {"windows", c_params.windows},
                    {"seed", c_params.seed},
                    {"units", "cf and ci95 are fractions (1 = 100 %)"}};
        std::cout << out.dump(2) << "\n";
      } else {
        std::cout << std::fixed << std::setprecision(4) << "CF " << 100 * r.cf << " % (95 % CI "
                  << 100 * r.ci_low << " .. " << 100 * r.ci_high << " %), " << r.collisions << " of "
                  << r.samples << " samples collide; worst window " << r.worst_window << " of "
                  << c_params.windows << ": " << 100 * r.worst_window_cf << " %\n";
      }
      return leeway::kExitOk;
    }

    if (*sweep) {
      const auto scene = leeway::Scene::load(s_file, scene_opts);
      const leeway::Params base = load_params(scene, s_preset, s_params, s_safety);
      // CF settings: the parameter file's cf section unless given on the command line.
      if (sweep->count("--windows") == 0) s_cf.windows = base.cf.windows;
      if (sweep->count("--samples") == 0) s_cf.samples = base.cf.samples;
      if (sweep->count("--seed") == 0) s_cf.seed = base.cf.seed;
      const std::vector<int> cells = parse_cells_list(s_cells);
      if (s_threads < 1) throw InputError("--threads " + std::to_string(s_threads) + " must be >= 1");
      const auto path = leeway::keyframe_path(scene, s_from, s_to, s_waypoints);
      // Issue #9: the nominal path is checked first; a sweep bounds the straight path only.
      if (const auto checked = leeway::check_path(scene, path); !checked.free()) {
        std::cerr << "leeway: collision: " << scene.source() << ": the straight path from " << s_from
                  << " to " << s_to
                  << (path.size() > 2 ? " (" + std::to_string(path.size()) + " waypoints)" : std::string())
                  << " " << leeway::describe_collision(scene, *checked.collision, true)
                  << "; nothing written\n";
        return leeway::kExitFindings;
      }
      for (int c : cells) {
        leeway::Params p = base;
        p.height_map.max_cells = c;
        p.validate();
      }
      leeway::VolumeModel world(scene, *std::max_element(cells.begin(), cells.end()) +
                                           static_cast<int>(scene.obstacle_geoms().size()));
      std::ostringstream md, csv;
      md << "| Max CBox | CBox | Computational Time [ms] | Confidence Factor [%] | 95 % CI [%] |"
            " worst window [%] | collapsed | mean width j1-j3 [rad] |\n"
         << "|---:|---:|---:|---:|---|---:|---:|---:|\n";
      csv << "max_cells,boxes,time_ms,volume_ms,bounds_ms,checks,cf,ci_low,ci_high,worst_window_cf,collapsed,"
             "mean_width\n";
      const auto kinds = leeway::bound_kinds(scene);
      for (int c : cells) {
        leeway::Params p = base;
        p.height_map.max_cells = c;
        const auto run = leeway::compute_bounds(scene, world, path, p, s_threads);
        const auto r = leeway::confidence_factor(scene, run.bounds, s_cf, s_threads);
        // Collapsed intervals and the mean width of the bisected joints' intervals.
        int collapsed = 0, bisected = 0;
        double width = 0;
        for (const auto& w : run.bounds)
          for (size_t i = 0; i < kinds.size(); ++i)
            if (kinds[i] == leeway::BoundKind::kBisected) {
              const auto k = static_cast<Eigen::Index>(i);
              collapsed += w.collapsed[i] ? 1 : 0;
              width += w.upper[k] - w.lower[k];
              ++bisected;
            }
        width /= std::max(1, bisected);
        md << std::fixed << "| " << c << " | " << run.volume.boxes.size() << " | " << std::setprecision(1)
           << run.ms_total() << " | " << std::setprecision(4) << 100 * r.cf << " | " << 100 * r.ci_low
           << " .. " << 100 * r.ci_high << " | " << 100 * r.worst_window_cf << " | " << collapsed << "/"
           << bisected << " | " << std::setprecision(3) << width << " |\n";
        csv << c << "," << run.volume.boxes.size() << "," << std::setprecision(3) << run.ms_total() << ","
            << run.ms_volume << "," << run.ms_bounds << "," << run.checks << "," << std::setprecision(6)
            << r.cf << "," << r.ci_low << "," << r.ci_high << "," << r.worst_window_cf << "," << collapsed
            << "," << width << "\n";
        std::cerr << "max_cells " << c << " done\n";
      }
      std::cout << md.str();
      if (!s_csv.empty()) leeway::write_file_atomic(s_csv, csv.str());
      return leeway::kExitOk;
    }

    if (*params_cmd) {
      leeway::Params p = leeway::preset_params(p_preset);
      if (!p_file.empty()) leeway::apply_cell_defaults(leeway::Scene::load(p_file, scene_opts), p);
      std::cout << leeway::to_json(p).dump(2) << "\n";
      return leeway::kExitOk;
    }
    return leeway::kExitOk;
  });
}
