#include "cli/common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <regex>
#include <thread>
#include <tuple>

#include "core/json_io.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/planner.hpp"

namespace leeway::cli {

SceneOptions scene_options(const std::string& tool, const std::string& checker) {
  SceneOptions o;
  o.tool_site = tool;
  o.checker = parse_checker(checker);
  return o;
}

void add_checker_option(CLI::App* sub, std::string& checker) {
  sub->add_option("--checker", checker,
                  "Collision checker: midphase (leeway's, the default) or mujoco (MuJoCo's full\n"
                  "mj_collision pass, the reference; same answers, slower)")
      ->capture_default_str();
}

nlohmann::json to_array(const Eigen::VectorXd& v) { return detail::to_json_array(v); }

int default_threads() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

void add_tool_option(CLI::App* sub, std::string& tool) {
  sub->add_option("--tool", tool, "Name of the robot's tool site")->capture_default_str();
}

void add_preset_options(CLI::App* sub, std::string& preset, std::string& safety) {
  sub->add_option("--preset", preset,
                  "Parameter set: leeway (tuned parameters, certified safety) or thesis (section 4.1,\n"
                  "no safety stage: the published method); --params and flags override it")
      ->capture_default_str();
  sub->add_option("--safety", safety,
                  "certified (every interval proven free of the obstacles), sampled (an epsilon-delta\n"
                  "sampling test) or none (the thesis's bounds as they are); default: the preset's")
      ->check(non_empty_check("certified, sampled or none"));
}

void add_joint_bounds_options(CLI::App* sub, JointBoundsOptions& options) {
  sub->add_option("--bisect", options.bisect,
                  "Joints Algorithm 3 bisects, e.g. j1,j2,j4 (hinge joints, at most 6, bounded base to\n"
                  "tip); default: the parameters' bounds.bisect, or the first three hinge joints")
      ->check(non_empty_check("joint names, e.g. j1,j2,j4"));
  sub->add_option("--half-width", options.half_width,
                  "Fixed half-widths of joints that are not bisected [rad or m], e.g. j5=0.3,j6=0.1;\n"
                  "default: bounds.wrist_half_width (hinge), bounds.linear_axis_tolerance (slide)")
      ->check(non_empty_check("NAME=VALUE pairs, e.g. j5=0.3,j6=0.1"));
  sub->add_option("--grow", options.grow,
                  "Certified mode: the joints grown beyond the guide toward their free range (on a dense\n"
                  "path by blocks, toward their limits): all, none or names, e.g. j4,j5,j6; default: the\n"
                  "parameters' safety.grow (all)")
      ->check(non_empty_check("all, none or joint names, e.g. j4,j5,j6"));
  sub->add_option("--max-half-width", options.max_half_width,
                  "Certified mode: the largest half-width a joint may keep [rad or m], e.g. j5=0.5,j6=0.3;\n"
                  "default: the parameters' safety.max_half_width (none)")
      ->check(non_empty_check("NAME=VALUE pairs, e.g. j5=0.5,j6=0.3"));
  sub->add_option("--shape", options.shape,
                  "Certified mode: how growth shares the room between joints: greedy (rounds, tip to\n"
                  "base) or lever (cheapest share first); default: the parameters' safety.shape (greedy)")
      ->check(non_empty_check("greedy or lever"));
}

namespace {

// "a,b,c" -> {"a", "b", "c"}; an empty item ("a,,b", "a,") is refused.
std::vector<std::string> split_list(const std::string& text, const std::string& flag) {
  std::vector<std::string> items;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string item =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item.empty())
      throw InputError(flag + " '" + text + "': an empty item (give comma-separated items without spaces)");
    items.push_back(item);
    if (comma == std::string::npos) return items;
    start = comma + 1;
  }
}

// "j5=0.3,j6=0.1" -> {{"j5", 0.3}, {"j6", 0.1}}; `what` names the value in the messages.
std::map<std::string, double> joint_values(const std::string& text, const std::string& flag,
                                           const std::string& what) {
  std::map<std::string, double> values;
  for (const std::string& item : split_list(text, flag)) {
    const size_t eq = item.find('=');
    const std::string name = item.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (eq == std::string::npos || name.empty() || value.empty() || *end != '\0')
      throw InputError(flag + " '" + item + "' must be NAME=VALUE, a joint and its " + what + " [rad or m]");
    if (!values.emplace(name, v).second)
      throw InputError(flag + " " + text + ": joint '" + name + "' is given twice");
  }
  return values;
}

}  // namespace

void apply_joint_bounds_options(const Scene& scene, const JointBoundsOptions& options, Params& p) {
  if (options.bisect.empty() && options.half_width.empty() && options.grow.empty() &&
      options.max_half_width.empty() && options.shape.empty())
    return;
  // The preset, the cell's and the file's parameters alone first, so that what is refused below
  // comes from the flags.
  validate_for_scene(p, scene);
  std::string given;
  if (!options.bisect.empty()) {
    p.bounds.bisect = split_list(options.bisect, "--bisect");
    given = "--bisect " + options.bisect;
  }
  if (!options.half_width.empty()) {
    p.bounds.half_width = joint_values(options.half_width, "--half-width", "half-width");
    given += (given.empty() ? "" : " / ") + std::string("--half-width ") + options.half_width;
  }
  if (!options.grow.empty()) {
    split_list(options.grow, "--grow");  // refuses empty items
    p.safety.grow = options.grow;
    given += (given.empty() ? "" : " / ") + std::string("--grow ") + options.grow;
  }
  if (!options.max_half_width.empty()) {
    p.safety.max_half_width = joint_values(options.max_half_width, "--max-half-width", "largest half-width");
    given += (given.empty() ? "" : " / ") + std::string("--max-half-width ") + options.max_half_width;
  }
  if (!options.shape.empty()) {
    p.safety.shape = options.shape;
    given += (given.empty() ? "" : " / ") + std::string("--shape ") + options.shape;
  }
  try {
    validate_for_scene(p, scene);
  } catch (const InputError& e) {
    throw InputError(given + ": " + e.what());
  }
}

Eigen::VectorXd configuration(const Scene& scene, const std::string& q, const std::string& key,
                              const std::string& what) {
  if (!q.empty() && !key.empty()) throw InputError(what + ": give either --q or --key, not both");
  if (!key.empty()) return scene.keyframe(key).q;
  if (q.empty())
    throw InputError(what + ": give the joint values with --q \"q1 q2 ...\" or a keyframe with --key");
  Eigen::VectorXd v = parse_vector(q, what + " --q");
  scene.validate_configuration(v, what + " --q");
  return v;
}

Params load_params(const Scene& scene, const std::string& preset, const std::string& file,
                   const std::string& safety) {
  ParamLayers layers;
  layers.preset = preset;
  layers.file = file;
  if (!safety.empty()) layers.safety = parse_safety_mode(safety, "--safety");
  return compose_params(scene, layers);
}

bool report_refusal(const NominalPath& path) {
  if (path.ok()) return true;
  std::cerr << "leeway: " << refusal_name(path.refusal) << ": " << path.message << "; nothing written\n";
  return false;
}

bool plan_between(const Scene& scene, const std::string& from, const std::string& to,
                  const std::string& ik_seed_key, const PlanOptions& options, PlanResult& result, Endpoint& a,
                  Endpoint& b) {
  EndpointOptions eo;
  eo.ik_seed_key = ik_seed_key;
  std::tie(a, b) = resolve_endpoints(scene, from, to, eo);
  for (const Endpoint* e : {&a, &b}) {
    if (e->reachable) continue;
    std::cerr << "leeway: unreachable: " << scene.source() << ": " << describe_unreachable(*e, e == &a)
              << "; nothing written\n";
    return false;
  }
  result = plan_path(scene, a.q, b.q, options, "start '" + from + "'", "goal '" + to + "'");
  if (!result.success) {
    std::cerr << "leeway: no path: " << scene.source() << ": " << result.message << "; nothing written\n";
    return false;
  }
  return true;
}

std::pair<int, int> parse_size(const std::string& text, const std::string& flag) {
  static const std::regex re("([0-9]{1,5})[xX]([0-9]{1,5})");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw InputError(flag + " '" + text + "' must be WIDTHxHEIGHT in pixels, e.g. 1280x960");
  const int w = std::stoi(m[1]), h = std::stoi(m[2]);
  if (w < 16 || w > 8192 || h < 16 || h > 8192)
    throw InputError(flag + " '" + text + "': width and height must be from 16 to 8192 pixels");
  return {w, h};
}

}  // namespace leeway::cli
