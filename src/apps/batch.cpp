#include "leeway/apps/batch.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "core/json_io.hpp"
#include "io/mjcf_text.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/check.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/room.hpp"
#include "leeway/core/simulate.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"
#include "leeway/path/planner.hpp"

namespace leeway {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* const kSuiteFormat = "leeway-suite-1";
const char* const kResultsFormat = "leeway-batch-results-1";

// The keys a scenario (and the suite's defaults) may hold; docs/batch.md.
const std::set<std::string> kScenarioKeys = {
    "name",   "cell",      "from",   "to",      "path", "waypoints", "ik_seed", "preset",
    "params", "max_cells", "safety", "checker", "cf",   "plan",      "expect",  "simulate"};
const std::set<std::string> kNestedKeys = {"cf", "plan", "expect", "simulate"};

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Reads the fields of one scenario (or the defaults) for validation; every message starts with
// `where` ("suite.json: scenario 2 'dallara-home-patch'") and names the field.
class Fields {
 public:
  Fields(const json& j, std::string where) : j_(j), where_(std::move(where)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(where_ + ": field '" + field + "' " + what);
  }
  //! A library's message about the field's value (it names the file and the element).
  [[noreturn]] void wrap(const std::string& field, const InputError& e) const {
    throw InputError(where_ + ": field '" + field + "': " + e.what());
  }
  const json* find(const std::string& dotted) const {
    const json* at = &j_;
    std::string rest = dotted;
    for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      if (!at->contains(rest.substr(0, dot))) return nullptr;
      at = &(*at)[rest.substr(0, dot)];
      rest = rest.substr(dot + 1);
    }
    return at->contains(rest) ? &(*at)[rest] : nullptr;
  }
  std::optional<std::string> text(const std::string& field) const {
    const json* v = find(field);
    if (!v) return std::nullopt;
    if (!v->is_string() || v->get<std::string>().empty())
      fail(field, "must be a non-empty string, not " + v->dump());
    return v->get<std::string>();
  }
  std::optional<bool> flag(const std::string& field) const {
    const json* v = find(field);
    if (!v) return std::nullopt;
    if (!v->is_boolean()) fail(field, "must be true or false, not " + v->dump());
    return v->get<bool>();
  }
  std::optional<double> number(const std::string& field, double lo, double hi,
                               const std::string& range) const {
    const json* v = find(field);
    if (!v) return std::nullopt;
    if (!v->is_number() || !std::isfinite(v->get<double>()) || v->get<double>() < lo || v->get<double>() > hi)
      fail(field, v->dump() + " must be " + range);
    return v->get<double>();
  }
  std::optional<long long> whole(const std::string& field, long long lo, long long hi) const {
    const json* v = find(field);
    if (!v) return std::nullopt;
    if (!v->is_number_integer() || v->get<long long>() < lo || v->get<long long>() > hi)
      fail(field,
           v->dump() + " must be a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
    return v->get<long long>();
  }
  void one_of(const std::string& field, const std::set<std::string>& allowed) const {
    if (const auto v = text(field); v && !allowed.count(*v)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(field, "'" + *v + "' must be one of " + list);
    }
  }
  void known_keys(const json& obj, const std::string& prefix, const std::set<std::string>& allowed) const {
    if (!obj.is_object()) fail(prefix, "must be an object, not " + obj.dump());
    for (const auto& [key, value] : obj.items())
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(prefix.empty() ? key : prefix + "." + key, "is not a known key (known: " + list + ")");
      }
  }

 private:
  const json& j_;
  std::string where_;
};

// Checks every field's type and range (not yet the cell's names). `is_defaults` allows no name.
void check_fields(const Fields& f, const json& s, bool is_defaults) {
  f.known_keys(s, "", kScenarioKeys);
  if (is_defaults && s.contains("name")) f.fail("name", "belongs to each scenario, not to the defaults");
  for (const char* key : {"name", "cell", "from", "to", "path", "ik_seed"}) f.text(key);
  if (s.contains("params") && !s["params"].is_object()) {
    if (!s["params"].is_string())
      f.fail("params",
             "must be a parameter file's name or an object of parameters, not " + s["params"].dump());
    f.text("params");
  }
  f.whole("waypoints", 2, 100000);
  f.one_of("preset", {"leeway", "thesis"});
  f.whole("max_cells", 1, kMaxCellsLimit);
  f.one_of("safety", {"certified", "sampled", "none"});
  f.one_of("checker", {"midphase", "mujoco"});
  if (s.contains("cf")) {
    f.known_keys(s["cf"], "cf", {"windows", "samples", "seed", "self"});
    f.flag("cf.self");
    f.whole("cf.windows", 1, 1000000);
    f.whole("cf.samples", 1, 100000000);
    f.whole("cf.seed", 0, std::numeric_limits<long long>::max());
  }
  if (s.contains("plan")) {
    f.known_keys(s["plan"], "plan", {"seed", "time_limit"});
    f.whole("plan.seed", 0, std::numeric_limits<long long>::max());
    f.number("plan.time_limit", 1e-3, 3600, "a time from 0.001 to 3600 s");
  }
  if (s.contains("simulate")) {
    f.known_keys(s["simulate"], "simulate",
                 {"human", "target", "amplitude", "bandwidth", "seed", "speed", "controller"});
    f.one_of("simulate.human", {"random", "push-toward", "none"});
    f.text("simulate.target");
    f.number("simulate.amplitude", 0, 2000, "a force from 0 to 2000 N");
    f.number("simulate.bandwidth", 1e-6, 20, "a frequency from 0 (excluded) to 20 Hz");
    f.whole("simulate.seed", 0, std::numeric_limits<long long>::max());
    f.number("simulate.speed", 1e-6, 10, "a share of the nominal speed from 0 (excluded) to 10");
    f.one_of("simulate.controller", {"mpc", "projection"});
    if (s["simulate"].value("human", std::string()) == "push-toward" && !s["simulate"].contains("target"))
      f.fail("simulate.target", "is missing: push-toward needs an obstacle's name or \"nearest\"");
  }
  if (s.contains("expect")) {
    f.known_keys(s["expect"], "expect",
                 {"check", "cf_min", "certified", "mean_width_min", "self_collisions_max", "time_max",
                  "simulate", "room"});
    if (s["expect"].contains("room")) {
      f.known_keys(s["expect"]["room"], "expect.room", {"mean_share_min", "tool_translation_min"});
      f.number("expect.room.mean_share_min", 0, 1, "a fraction from 0 to 1");
      f.number("expect.room.tool_translation_min", 0, 100, "a distance from 0 to 100 m");
    }
    if (s["expect"].contains("simulate")) {
      f.known_keys(s["expect"]["simulate"], "expect.simulate", {"contacts", "min_distance"});
      f.whole("expect.simulate.contacts", 0, std::numeric_limits<long long>::max());
      f.number("expect.simulate.min_distance", 0, 100, "a distance from 0 to 100 m");
    }
    f.whole("expect.self_collisions_max", 0, std::numeric_limits<long long>::max());
    f.flag("expect.check");
    f.number("expect.cf_min", 0, 1, "a fraction from 0 to 1");
    f.flag("expect.certified");
    f.number("expect.mean_width_min", 0, 1e3, "a width >= 0 rad");
    f.number("expect.time_max", 0, 1e6, "a time >= 0 s");
  }
}

// The scenario's parameters, as `leeway bounds` builds them: the preset, the cell's own, the
// parameter file or object, the safety mode, MAX_cells, then the CF settings.
Params scenario_params(const Scene& scene, const json& s) {
  ParamLayers layers;
  layers.preset = s.value("preset", std::string("leeway"));
  if (s.contains("params")) {
    if (s["params"].is_object()) {
      layers.object = s["params"];
      layers.object_source = "the scenario's params";
    } else {
      layers.file = s["params"].get<std::string>();
    }
  }
  if (s.contains("safety"))
    layers.safety = parse_safety_mode(s["safety"].get<std::string>(), "the scenario's safety");
  Params p = compose_params(scene, layers);
  if (s.contains("max_cells")) p.height_map.max_cells = s["max_cells"].get<int>();
  if (s.contains("cf")) {
    p.cf.windows = s["cf"].value("windows", p.cf.windows);
    p.cf.samples = s["cf"].value("samples", p.cf.samples);
    p.cf.seed = s["cf"].value("seed", p.cf.seed);
    p.cf.self = s["cf"].value("self", p.cf.self);
  }
  // Against the robot too (bounds.bisect and bounds.half_width name its joints), before any run.
  validate_for_scene(p, scene);
  return p;
}

SceneOptions scene_options_of(const json& s) {
  SceneOptions o;
  o.checker = parse_checker(s.value("checker", std::string("midphase")));
  return o;
}

std::string resolve(const fs::path& folder, const std::string& file) {
  const fs::path p(file);
  return p.is_absolute() ? file : (folder / p).lexically_normal().string();
}

// "dallara home -> patch" or "dallara path.json".
std::string label_of(const json& given) {
  const std::string cell = fs::path(given["cell"].get<std::string>()).stem().string();
  if (given.contains("path")) return cell + " " + given["path"].get<std::string>();
  return cell + " " + given["from"].get<std::string>() + " -> " + given["to"].get<std::string>();
}

// A scenario's expectations (its `expect` object, checked by check_fields before).
Expectations expectations_of(const Fields& f, const json& s) {
  Expectations e;
  e.check = f.flag("expect.check");
  e.cf_min = f.number("expect.cf_min", 0, 1, "");
  e.certified = f.flag("expect.certified");
  e.mean_width_min = f.number("expect.mean_width_min", 0, 1e3, "");
  if (s.contains("expect") && s["expect"].contains("self_collisions_max"))
    e.self_collisions_max = s["expect"]["self_collisions_max"].get<long>();
  e.time_max = f.number("expect.time_max", 0, 1e6, "");
  if (const auto c = f.whole("expect.simulate.contacts", 0, std::numeric_limits<long long>::max()))
    e.simulate_contacts_max = static_cast<long>(*c);
  e.simulate_min_distance = f.number("expect.simulate.min_distance", 0, 100, "");
  e.room_mean_share_min = f.number("expect.room.mean_share_min", 0, 1, "");
  e.room_tool_translation_min = f.number("expect.room.tool_translation_min", 0, 100, "");
  return e;
}

}  // namespace

std::string xml_escape(const std::string& text) { return detail::xml_escape(text); }

Suite read_suite(const std::string& file) {
  const json j = detail::read_json_file(file, "suite");
  if (!j.is_object()) throw InputError(file + ": a suite is a JSON object with \"format\" and \"scenarios\"");
  Fields top(j, file);
  top.known_keys(j, "", {"format", "name", "defaults", "scenarios"});
  if (j.value("format", json()) != kSuiteFormat)
    top.fail("format",
             "must be \"" + std::string(kSuiteFormat) + "\", not " + j.value("format", json()).dump());
  Suite suite;
  suite.file = file;
  suite.name = top.text("name").value_or(fs::path(file).stem().string());
  const json defaults = j.value("defaults", json::object());
  check_fields(Fields(defaults, file + ": defaults"), defaults, true);
  if (!j.contains("scenarios") || !j["scenarios"].is_array() || j["scenarios"].empty())
    top.fail("scenarios", "must be a non-empty array of scenarios");
  const fs::path folder = fs::path(file).parent_path();
  std::map<std::pair<std::string, std::string>, std::shared_ptr<const Scene>> scenes;  // by (cell, checker)
  std::set<std::string> names;
  for (size_t i = 0; i < j["scenarios"].size(); ++i) {
    const json& given = j["scenarios"][i];
    std::string where = file + ": scenario " + std::to_string(i + 1);
    if (given.is_object() && given.contains("name") && given["name"].is_string())
      where += " '" + given["name"].get<std::string>() + "'";
    if (!given.is_object()) throw InputError(where + ": must be an object, not " + given.dump());
    // The defaults, then the scenario's keys (cf, plan and expect merged key by key).
    json s = defaults;
    for (const auto& [key, value] : given.items()) {
      if (kNestedKeys.count(key) && value.is_object() && s.contains(key) && s[key].is_object())
        s[key].update(value);
      else
        s[key] = value;
    }
    const Fields f(s, where);
    check_fields(f, s, false);
    const auto name = f.text("name");
    if (!name) f.fail("name", "is missing");
    if (!names.insert(*name).second) f.fail("name", "'" + *name + "' is used by an earlier scenario");
    if (!f.text("cell")) f.fail("cell", "is missing");
    const bool by_file = s.contains("path");
    if (by_file && (s.contains("from") || s.contains("to")))
      f.fail("path", "excludes 'from' and 'to': give the path either as a path file or by its two ends");
    if (!by_file && (!s.contains("from") || !s.contains("to")))
      f.fail(s.contains("from") ? "to" : "from",
             "is missing (give 'from' and 'to', or a path file in 'path')");
    const bool linear = !by_file && !is_gripper_goal(s["from"].get<std::string>()) &&
                        !is_gripper_goal(s["to"].get<std::string>());
    if (s.contains("waypoints") && !linear)
      f.fail("waypoints", "applies to the joint-linear path between two keyframes only");

    json run = s;
    run["cell"] = resolve(folder, s["cell"]);
    if (by_file) run["path"] = resolve(folder, s["path"]);
    if (s.contains("params") && s["params"].is_string()) run["params"] = resolve(folder, s["params"]);
    try {
      require_regular_input(run["cell"].get<std::string>(), "cell file");
    } catch (const InputError& e) {
      f.wrap("cell", e);
    }
    const std::string cell_file = run["cell"];
    auto& scene = scenes[{cell_file, s.value("checker", std::string("midphase"))}];
    try {
      if (!scene) scene = std::make_shared<const Scene>(Scene::load(cell_file, scene_options_of(s)));
    } catch (const InputError& e) {
      f.wrap("cell", e);
    }
    // The names the scenario uses exist in its cell.
    const auto check_end = [&](const char* key) {
      const std::string spec = s[key].get<std::string>();
      try {
        if (spec.rfind("site:", 0) == 0)
          site_position(*scene, spec.substr(5));
        else if (spec.rfind("xyz:", 0) == 0) {
          if (parse_vector(spec.substr(4), "the point").size() != 3)
            throw InputError("'" + spec + "' must be xyz:X,Y,Z (three values) [m]");
        } else
          scene->keyframe(spec);
      } catch (const InputError& e) {
        f.wrap(key, e);
      }
    };
    if (!by_file) {
      check_end("from");
      check_end("to");
    }
    if (s.contains("ik_seed")) {
      try {
        scene->keyframe(s["ik_seed"].get<std::string>());
      } catch (const InputError& e) {
        f.wrap("ik_seed", e);
      }
    }
    if (by_file) {
      try {
        read_path(run["path"].get<std::string>(), *scene);
      } catch (const InputError& e) {
        f.wrap("path", e);
      }
    }
    try {
      scenario_params(*scene, run);
    } catch (const InputError& e) {
      f.wrap(s.contains("params") ? "params" : "preset", e);
    }
    Scenario sc;
    sc.name = *name;
    sc.label = label_of(s);
    sc.resolved = {{"name", *name}, {"given", s}, {"run", run}};
    sc.expect = expectations_of(f, s);
    suite.scenarios.push_back(std::move(sc));
  }
  return suite;
}

namespace {

// The nominal path a scenario names (as `leeway bounds`: a file, gripper goals, or keyframes planned
// around when the straight path collides), with its planner settings.
PathRequest path_request_of(const json& s) {
  PathRequest request;
  request.file = s.value("path", std::string());
  request.from = s.value("from", std::string());
  request.to = s.value("to", std::string());
  request.waypoints = s.value("waypoints", 2);
  request.ik_seed = s.value("ik_seed", std::string());
  if (s.contains("plan")) {
    request.plan.seed = s["plan"].value("seed", request.plan.seed);
    request.plan.time_limit = s["plan"].value("time_limit", request.plan.time_limit);
  }
  return request;
}

// The scenario's closed loop (docs/simulate.md): its `simulate` object's settings, the outcome into
// `measured` and its time into `timing`.
void simulate_scenario(const Scene& scene, const std::vector<WaypointBounds>& bounds, const json& sim,
                       json& measured, json& timing) {
  SimulateOptions so;
  const std::string human = sim.value("human", std::string("random"));
  so.human.kind = human == "none"          ? HumanKind::kNone
                  : human == "push-toward" ? HumanKind::kPushToward
                                           : HumanKind::kRandom;
  so.human.target = sim.value("target", std::string());
  so.human.amplitude = sim.value("amplitude", so.human.amplitude);
  so.human.bandwidth = sim.value("bandwidth", so.human.bandwidth);
  so.seed = sim.value("seed", so.seed);
  so.speed = sim.value("speed", so.speed);
  so.controller = sim.value("controller", std::string("mpc")) == "projection" ? ControllerKind::kProjection
                                                                              : ControllerKind::kMpc;
  const auto s0 = Clock::now();
  const SimulationReport sr = simulate(scene, BoundsTrajectory(scene, bounds), so);
  timing["simulate_s"] = seconds_since(s0);
  measured["simulate_contacts"] = sr.contact_steps;
  measured["simulate_min_distance"] = sr.min_distance;
  measured["simulate_left_bounds"] = sr.left_bounds;
  measured["simulate_reached_end"] = sr.reached_end;
  json freedom = json::array();
  for (Eigen::Index j = 0; j < sr.freedom_used.size(); ++j) freedom.push_back(sr.freedom_used[j]);
  measured["simulate_freedom_used"] = freedom;
  if (sr.first_contact)
    measured["simulate_first_contact"] = {{"t", sr.first_contact->t},
                                          {"geom1", sr.first_contact->geom1},
                                          {"geom2", sr.first_contact->geom2},
                                          {"depth", sr.first_contact->depth}};
}

}  // namespace

json run_scenario(const json& resolved, int threads) {
  const auto t0 = Clock::now();
  const json& given = resolved.at("given");
  json r = {{"name", resolved.at("name")}, {"cell", given.at("cell")}};
  if (given.contains("path")) {
    r["path"] = given["path"];
  } else {
    r["from"] = given["from"];
    r["to"] = given["to"];
  }
  json timing = json::object();
  try {
    const json& s = resolved.at("run");
    const Scene scene = Scene::load(s.at("cell").get<std::string>(), scene_options_of(s));
    const Params p = scenario_params(scene, s);
    json measured = json::object();
    if (s.contains("expect") && s["expect"].contains("check")) {
      const auto c0 = Clock::now();
      const CheckReport report = check_scene(scene);
      measured["check_passed"] = report.ok();
      measured["check_problems"] = report.problems;
      timing["check_s"] = seconds_since(c0);
    }
    const NominalPath nominal = resolve_nominal_path(scene, path_request_of(s));
    if (!nominal.ok()) throw InputError(std::string(refusal_name(nominal.refusal)) + ": " + nominal.message);
    const std::vector<Eigen::VectorXd>& path = nominal.waypoints;
    const bool planned = nominal.planned;
    measured["waypoints"] = path.size();
    measured["planned"] = planned;

    VolumeModel world(scene, VolumeModel::capacity_for(scene, p.height_map.max_cells));
    const BoundsRun run = compute_bounds(scene, world, path, p, threads);
    const auto c0 = Clock::now();
    const CfResult cf = confidence_factor(scene, run.bounds, p.cf, threads);
    timing["cf_s"] = seconds_since(c0);
    CaseEval widths;
    width_stats(scene, p.bounds, run.bounds, 0.0, widths);
    int passed = 0;
    for (const auto& seg : run.safety.segments) passed += seg.passed ? 1 : 0;
    measured["max_cells"] = p.height_map.max_cells;
    measured["boxes"] = run.volume.boxes.size();
    measured["collision_checks"] = run.checks;
    measured["safety"] = safety_mode_name(run.safety.mode);
    measured["certified"] = run.safety.mode == SafetyMode::kCertified && run.safety.all_passed;
    measured["segments_passed"] = passed;
    measured["segments"] = run.safety.segments.size();
    measured["cf"] = cf.cf;
    measured["cf_ci_low"] = cf.ci_low;
    measured["cf_ci_high"] = cf.ci_high;
    measured["cf_samples"] = cf.samples;
    measured["cf_collisions"] = cf.collisions;
    measured["cf_obstacle_collisions"] = cf.obstacle_collisions;
    measured["cf_self_collisions"] = cf.self_collisions;
    measured["mean_width"] = widths.mean_width;
    measured["bisected"] = widths.bisected;
    measured["collapsed"] = widths.collapsed;
    // The room the bounds keep (docs/algorithm.md, "Room").
    const RoomReport room = measure_room(scene, run.bounds, RoomOptions{}, threads);
    measured["room_mean_share"] = std::isnan(room.mean_share) ? json(nullptr) : json(room.mean_share);
    measured["room_goal_tool_translation"] = room.waypoints.back().tool_translation;
    measured["room_goal_tool_rotation"] = room.waypoints.back().tool_rotation;
    // The closed loop (docs/simulate.md), when the scenario asks for it or expects its outcome.
    if (s.contains("simulate") || (s.contains("expect") && s["expect"].contains("simulate")))
      simulate_scenario(scene, run.bounds, s.value("simulate", json::object()), measured, timing);
    r["status"] = "ok";
    r["measured"] = measured;
    timing["method_s"] = run.ms_total() / 1000;
    timing["stages_ms"] = {{"categorize", run.ms_categorize},
                           {"volume", run.ms_volume},
                           {"inject", run.ms_inject},
                           {"bounds", run.ms_bounds},
                           {"safety", run.ms_safety}};
  } catch (const std::exception& e) {
    r["status"] = "error";
    r["error"] = e.what();
  }
  timing["seconds"] = seconds_since(t0);
  r["timing"] = timing;
  return r;
}

void judge(const Scenario& scenario, json& result) {
  const bool ok = result.value("status", std::string()) == "ok";
  const json measured = result.value("measured", json::object());
  json list = json::array();
  bool all = ok;
  // cmp: +1 measured >= expected, 0 equal, -1 measured <= expected.
  const auto add = [&](const char* name, const std::string& title, const json& expected, const char* key,
                       int cmp) {
    json e = {{"name", name}, {"title", title}, {"expected", expected}};
    if (!ok || !measured.contains(key)) {
      e["measured"] = nullptr;
      e["passed"] = false;
    } else {
      e["measured"] = measured[key];
      const bool passed = cmp > 0   ? measured[key].get<double>() >= expected.get<double>()
                          : cmp < 0 ? measured[key].get<double>() <= expected.get<double>()
                                    : measured[key] == expected;
      e["passed"] = passed;
    }
    all = all && e["passed"].get<bool>();
    list.push_back(e);
  };
  const Expectations& x = scenario.expect;
  if (x.check) add("check", *x.check ? "check passes" : "check fails", *x.check, "check_passed", 0);
  if (x.cf_min) add("cf_min", "CF >= " + format_number(*x.cf_min), *x.cf_min, "cf", 1);
  if (x.certified)
    add("certified", *x.certified ? "certified" : "not certified", *x.certified, "certified", 0);
  if (x.mean_width_min)
    add("mean_width_min", "mean width >= " + format_number(*x.mean_width_min) + " rad", *x.mean_width_min,
        "mean_width", 1);
  if (x.self_collisions_max)
    add("self_collisions_max", "CF samples in self-collision <= " + std::to_string(*x.self_collisions_max),
        *x.self_collisions_max, "cf_self_collisions", -1);
  if (x.simulate_contacts_max)
    add("simulate_contacts", "simulated steps with a contact <= " + std::to_string(*x.simulate_contacts_max),
        *x.simulate_contacts_max, "simulate_contacts", -1);
  if (x.simulate_min_distance)
    add("simulate_min_distance",
        "simulated min distance >= " + format_number(*x.simulate_min_distance) + " m",
        *x.simulate_min_distance, "simulate_min_distance", 1);
  if (x.room_mean_share_min)
    add("room_mean_share_min", "room: mean kept share >= " + format_number(*x.room_mean_share_min),
        *x.room_mean_share_min, "room_mean_share", 1);
  if (x.room_tool_translation_min)
    add("room_tool_translation_min",
        "room: the tool's translation at the goal >= " + format_number(*x.room_tool_translation_min) + " m",
        *x.room_tool_translation_min, "room_goal_tool_translation", 1);
  result["expectations"] = list;
  result["passed"] = all;
  if (x.time_max) {
    json t = {{"title", "time <= " + format_number(*x.time_max) + " s (soft)"}, {"expected", *x.time_max}};
    if (ok && result["timing"].contains("method_s")) {
      t["measured"] = result["timing"]["method_s"];
      t["warning"] = t["measured"].get<double>() > *x.time_max;
    } else {
      t["measured"] = nullptr;
      t["warning"] = false;
    }
    result["timing"]["time_max"] = t;
  }
}

json suite_results_json(const Suite& suite, const std::vector<json>& results) {
  LEEWAY_DEMAND(results.size() == suite.scenarios.size());
  int passed = 0, failed = 0, errors = 0;
  double seconds = 0;
  for (const auto& r : results) {
    if (r["status"] == "error")
      ++errors;
    else if (r["passed"].get<bool>())
      ++passed;
    else
      ++failed;
    seconds += r["timing"].value("seconds", 0.0);
  }
  return {
      {"format", kResultsFormat},
      {"suite", suite.name},
      {"units", "SI: m, rad, s; CF a fraction"},
      {"scenarios", results},
      {"counts", {{"scenarios", results.size()}, {"passed", passed}, {"failed", failed}, {"errors", errors}}},
      {"timing", {{"scenario_seconds_sum", seconds}}}};
}

std::string junit_xml(const Suite& suite, const std::vector<json>& results) {
  LEEWAY_DEMAND(results.size() == suite.scenarios.size());
  std::ostringstream cases;
  int tests = 0, failures = 0, errors = 0, skipped = 0;
  double total = 0;
  const std::string suite_name = xml_escape(suite.name);
  for (size_t i = 0; i < results.size(); ++i) {
    const json& r = results[i];
    const std::string cls = suite_name + "." + xml_escape(suite.scenarios[i].name);
    const double seconds = r["timing"].value("seconds", 0.0);
    total += seconds;
    const bool ok = r["status"] == "ok";
    ++tests;
    cases << "    <testcase classname=\"" << cls << "\" name=\"run\" time=\"" << seconds << "\"";
    if (ok) {
      cases << "/>\n";
    } else {
      ++errors;
      const std::string message = xml_escape(r.value("error", std::string("failed")));
      cases << ">\n      <error message=\"" << message << "\" type=\"error\">" << message << "</error>\n"
            << "    </testcase>\n";
    }
    for (const auto& e : r["expectations"]) {
      ++tests;
      cases << "    <testcase classname=\"" << cls << "\" name=\"" << xml_escape(e["title"])
            << "\" time=\"0\"";
      if (!ok) {
        ++skipped;
        cases << ">\n      <skipped message=\"the scenario did not run to the end\"/>\n    </testcase>\n";
      } else if (e["passed"].get<bool>()) {
        cases << "/>\n";
      } else {
        ++failures;
        const std::string measured =
            e["measured"].is_number() ? format_number(e["measured"].get<double>()) : e["measured"].dump();
        const std::string message =
            xml_escape("measured " + measured + ", expected " + e["title"].get<std::string>());
        cases << ">\n      <failure message=\"" << message << "\" type=\"expectation\">" << message
              << "</failure>\n    </testcase>\n";
      }
    }
    if (r["timing"].contains("time_max")) {
      const json& t = r["timing"]["time_max"];
      ++tests;
      cases << "    <testcase classname=\"" << cls << "\" name=\"" << xml_escape(t["title"])
            << "\" time=\"0\"";
      if (!ok) {
        ++skipped;
        cases << ">\n      <skipped message=\"the scenario did not run to the end\"/>\n    </testcase>\n";
      } else if (t["warning"].get<bool>()) {
        cases << ">\n      <system-out>"
              << xml_escape("warning: the method took " + format_number(t["measured"].get<double>()) +
                            " s, over " + format_number(t["expected"].get<double>()) +
                            " s (soft: times are noisy)")
              << "</system-out>\n    </testcase>\n";
      } else {
        cases << "/>\n";
      }
    }
  }
  std::ostringstream out;
  const std::string counts = " tests=\"" + std::to_string(tests) + "\" failures=\"" +
                             std::to_string(failures) + "\" errors=\"" + std::to_string(errors) +
                             "\" skipped=\"" + std::to_string(skipped) + "\" time=\"";
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<testsuites name=\"" << suite_name << "\"" << counts << total << "\">\n"
      << "  <testsuite name=\"" << suite_name << "\"" << counts << total << "\">\n"
      << cases.str() << "  </testsuite>\n</testsuites>\n";
  return out.str();
}

}  // namespace leeway
