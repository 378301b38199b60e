#include "cli/common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <regex>
#include <thread>
#include <tuple>

#include "json_io.hpp"
#include "leeway/cell_defaults.hpp"
#include "leeway/endpoints.hpp"
#include "leeway/file_io.hpp"
#include "leeway/planner.hpp"

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
  Params p = preset_params(preset);
  apply_cell_defaults(scene, p);
  if (!file.empty()) p = read_params(file, p);
  if (!safety.empty()) {
    if (safety == "none")
      p.safety.mode = SafetyMode::kNone;
    else if (safety == "sampled")
      p.safety.mode = SafetyMode::kSampled;
    else if (safety == "certified")
      p.safety.mode = SafetyMode::kCertified;
    else
      throw InputError("--safety '" + safety + "' must be certified, sampled or none");
  }
  return p;
}

bool is_gripper_goal(const std::string& spec) {
  return spec.rfind("site:", 0) == 0 || spec.rfind("xyz:", 0) == 0;
}

bool plan_between(const Scene& scene, const std::string& from, const std::string& to,
                  const std::string& ik_seed_key, const PlanOptions& options, PlanResult& result, Endpoint& a,
                  Endpoint& b) {
  EndpointOptions eo;
  eo.ik_seed_key = ik_seed_key;
  std::tie(a, b) = resolve_endpoints(scene, from, to, eo);
  for (const Endpoint* e : {&a, &b}) {
    if (e->reachable) continue;
    std::cerr << "leeway: unreachable: " << scene.source() << ": " << (e == &a ? "start" : "goal") << " '"
              << e->spec << "' at (" << format_number(e->position.x()) << ", "
              << format_number(e->position.y()) << ", " << format_number(e->position.z())
              << ") m: no collision-free configuration with the tool pointing down within the joint limits"
              << " (closest: position error " << format_number(e->ik.position_error)
              << " m, orientation error " << format_number(e->ik.orientation_error) << "); nothing written\n";
    return false;
  }
  result = plan_path(scene, a.q, b.q, options, "start '" + from + "'", "goal '" + to + "'");
  if (!result.success) {
    std::cerr << "leeway: no path: " << scene.source() << ": " << result.message << "; nothing written\n";
    return false;
  }
  return true;
}

void require_threads(int threads, const std::string& flag) {
  if (threads < 1 || threads > kMaxThreads)
    throw InputError(flag + " " + std::to_string(threads) + " must be from 1 to " +
                     std::to_string(kMaxThreads));
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
