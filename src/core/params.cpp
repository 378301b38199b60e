#include "leeway/core/params.hpp"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "json_io.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {
namespace {

using nlohmann::json;

//! Calls f(section, key, field) for every parameter, in the order of params.hpp. The one list that
//! to_json, params_from_json and validate() share, so that a new field cannot be forgotten in one.
template <class P, class F>
void for_each_field(P& p, F&& f) {
  f("height_map", "auto_extent", p.height_map.auto_extent);
  f("height_map", "origin_x", p.height_map.origin_x);
  f("height_map", "origin_y", p.height_map.origin_y);
  f("height_map", "x_dim", p.height_map.x_dim);
  f("height_map", "y_dim", p.height_map.y_dim);
  f("height_map", "max_cells", p.height_map.max_cells);
  f("volume", "d_t_lb", p.volume.d_t_lb);
  f("volume", "d_t_ub", p.volume.d_t_ub);
  f("volume", "d_g_lb", p.volume.d_g_lb);
  f("volume", "d_g_ub", p.volume.d_g_ub);
  f("volume", "d_ng_ub", p.volume.d_ng_ub);
  f("volume", "h_max", p.volume.h_max);
  f("volume", "alpha_t", p.volume.alpha_t);
  f("volume", "alpha_g", p.volume.alpha_g);
  f("volume", "alpha_ng", p.volume.alpha_ng);
  f("volume", "goal_constant_term", p.volume.goal_constant_term);
  f("volume", "reach_radius", p.volume.reach_radius);
  f("volume", "trail_margin", p.volume.trail_margin);
  f("volume", "add_obstacle_boxes", p.volume.add_obstacle_boxes);
  f("volume", "distance", p.volume.distance);
  f("categorize", "goal_dz", p.categorize.goal_dz);
  f("categorize", "trail_densify", p.categorize.trail_densify);
  f("bounds", "resolution", p.bounds.resolution);
  f("bounds", "min_half_width", p.bounds.min_half_width);
  f("bounds", "wrist_half_width", p.bounds.wrist_half_width);
  f("bounds", "linear_axis_tolerance", p.bounds.linear_axis_tolerance);
  f("bounds", "self_collision", p.bounds.self_collision);
  f("bounds", "bisect", p.bounds.bisect);
  f("bounds", "half_width", p.bounds.half_width);
  f("cf", "windows", p.cf.windows);
  f("cf", "samples", p.cf.samples);
  f("cf", "seed", p.cf.seed);
  f("safety", "mode", p.safety.mode);
  f("safety", "margin", p.safety.margin);
  f("safety", "max_leaves", p.safety.max_leaves);
  f("safety", "epsilon", p.safety.epsilon);
  f("safety", "delta", p.safety.delta);
  f("safety", "seed", p.safety.seed);
  f("safety", "grow", p.safety.grow);
  f("safety", "max_half_width", p.safety.max_half_width);
  f("safety", "shape", p.safety.shape);
  f("safety", "grow_leaves", p.safety.grow_leaves);
  f("safety", "turn", p.safety.turn);
  f("safety", "runs", p.safety.runs);
}

const char* distance_name(DistanceMode m) { return m == DistanceMode::k3d ? "3d" : "plane"; }

std::string value_text(double v) { return format_number(v); }
std::string value_text(int v) { return std::to_string(v); }

//! "parameter 'volume.d_t_lb' = 2"
template <class T>
std::string describe(const char* key, T value) {
  return std::string("parameter '") + key + "' = " + value_text(value);
}

void require_positive(const char* key, double v) {
  if (!(v > 0)) throw InputError(describe(key, v) + " must be > 0");
}
void require_non_negative(const char* key, double v) {
  if (!(v >= 0)) throw InputError(describe(key, v) + " must be >= 0");
}
template <class T>
void require_between(const char* key, T v, T lo, T hi) {
  if (!(v >= lo && v <= hi))
    throw InputError(describe(key, v) + " must be between " + value_text(lo) + " and " + value_text(hi));
}
void require_smaller(const char* lb_key, double lb, const char* ub_key, double ub) {
  if (!(lb < ub))
    throw InputError(describe(lb_key, lb) + " must be smaller than '" + ub_key + "' = " + value_text(ub));
}

//! A JSON value for an error message, shortened when long.
std::string shown(const json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

[[noreturn]] void wrong_type(const std::string& source, const std::string& key, const char* expected,
                             const json& v) {
  throw InputError(source + ": parameter '" + key + "' must be " + expected + ", got " + v.type_name() + " " +
                   shown(v));
}

void read_value(const json& v, const std::string& key, const std::string& source, bool& out) {
  if (!v.is_boolean()) wrong_type(source, key, "true or false", v);
  out = v.get<bool>();
}

void read_value(const json& v, const std::string& key, const std::string& source, double& out) {
  if (!v.is_number()) wrong_type(source, key, "a number", v);
  out = v.get<double>();
}

void read_value(const json& v, const std::string& key, const std::string& source, int& out) {
  // JSON integers only: 2.5 or 2.0 for a count is more likely a mistake than intended.
  if (!v.is_number_integer()) wrong_type(source, key, "an integer", v);
  constexpr auto kMax = std::numeric_limits<int>::max();
  constexpr auto kMin = std::numeric_limits<int>::min();
  if (v.is_number_unsigned() ? v.get<std::uint64_t>() > static_cast<std::uint64_t>(kMax)
                             : (v.get<std::int64_t>() > kMax || v.get<std::int64_t>() < kMin))
    throw InputError(source + ": parameter '" + key + "' = " + shown(v) + " is out of the integer range");
  out = v.get<int>();
}

void read_value(const json& v, const std::string& key, const std::string& source, std::uint64_t& out) {
  if (!v.is_number_unsigned()) wrong_type(source, key, "an integer >= 0", v);
  out = v.get<std::uint64_t>();
}

void read_value(const json& v, const std::string& key, const std::string& source, DistanceMode& out) {
  if (v.is_string() && v.get<std::string>() == "plane")
    out = DistanceMode::kPlane;
  else if (v.is_string() && v.get<std::string>() == "3d")
    out = DistanceMode::k3d;
  else
    wrong_type(source, key, "\"plane\" or \"3d\"", v);
}

void read_value(const json& v, const std::string& key, const std::string& source, SafetyMode& out) {
  for (SafetyMode m : {SafetyMode::kNone, SafetyMode::kSampled, SafetyMode::kCertified})
    if (v.is_string() && v.get<std::string>() == safety_mode_name(m)) {
      out = m;
      return;
    }
  wrong_type(source, key, "\"none\", \"sampled\" or \"certified\"", v);
}

void read_value(const json& v, const std::string& key, const std::string& source, std::string& out) {
  if (!v.is_string()) wrong_type(source, key, "a string", v);
  out = v.get<std::string>();
}

void read_value(const json& v, const std::string& key, const std::string& source,
                std::vector<std::string>& out) {
  if (!v.is_array()) wrong_type(source, key, "a list of joint names", v);
  std::vector<std::string> names;
  for (const json& name : v) {
    if (!name.is_string()) wrong_type(source, key, "a list of joint names", v);
    names.push_back(name.get<std::string>());
  }
  out = std::move(names);
}

void read_value(const json& v, const std::string& key, const std::string& source,
                std::map<std::string, double>& out) {
  if (!v.is_object()) wrong_type(source, key, "an object of joint names and half-widths", v);
  std::map<std::string, double> widths;
  for (const auto& [name, width] : v.items()) read_value(width, key + "." + name, source, widths[name]);
  out = std::move(widths);
}

// Per-joint half-widths [rad or m]: named, finite, from 0 to kMaxLength.
void require_joint_widths(const std::string& key, const std::map<std::string, double>& widths) {
  for (const auto& [name, width] : widths) {
    if (name.empty()) throw InputError("parameter '" + key + "' holds an empty joint name");
    const std::string named = key + "." + name;
    if (!std::isfinite(width)) throw InputError(describe(named.c_str(), width) + " must be a finite number");
    require_between(named.c_str(), width, 0.0, kMaxLength);
  }
}

std::string join(const std::set<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

void Params::validate() const {
  for_each_field(*this, [](const char* section, const char* key, const auto& field) {
    if constexpr (std::is_same_v<std::decay_t<decltype(field)>, double>) {
      if (!std::isfinite(field))
        throw InputError(describe((std::string(section) + "." + key).c_str(), field) +
                         " must be a finite number");
    }
  });
  // Physical bounds: a workcell is metres across; lengths beyond kMaxLength [m] or steps below the
  // lower bounds would only produce unusable bounds or run for ever.
  const HeightMapParams& hm = height_map;
  require_between("height_map.max_cells", hm.max_cells, 1, kMaxCellsLimit);
  require_between("height_map.origin_x", hm.origin_x, -kMaxLength, kMaxLength);
  require_between("height_map.origin_y", hm.origin_y, -kMaxLength, kMaxLength);
  if (!hm.auto_extent) {
    // Explicit extents only matter (and are only checked) when auto_extent is off.
    for (const auto& [key, dim] : {std::pair{"height_map.x_dim", hm.x_dim}, {"height_map.y_dim", hm.y_dim}})
      if (!(dim >= kMinMapSide && dim <= kMaxLength))
        throw InputError(describe(key, dim) + " must be between " + value_text(kMinMapSide) + " and " +
                         value_text(kMaxLength) + " m when 'height_map.auto_extent' is false");
  }
  const VolumeParams& v = volume;
  require_non_negative("volume.d_t_lb", v.d_t_lb);
  require_smaller("volume.d_t_lb", v.d_t_lb, "volume.d_t_ub", v.d_t_ub);
  require_non_negative("volume.d_g_lb", v.d_g_lb);
  require_smaller("volume.d_g_lb", v.d_g_lb, "volume.d_g_ub", v.d_g_ub);
  require_positive("volume.d_ng_ub", v.d_ng_ub);
  require_positive("volume.h_max", v.h_max);
  require_non_negative("volume.trail_margin", v.trail_margin);
  require_positive("volume.alpha_t", v.alpha_t);
  require_positive("volume.alpha_g", v.alpha_g);
  require_positive("volume.alpha_ng", v.alpha_ng);
  require_positive("volume.reach_radius", v.reach_radius);
  require_between("volume.reach_radius", v.reach_radius, kMinMapSide, kMaxLength);
  for (const auto& [key, value] : {std::pair{"volume.d_t_ub", v.d_t_ub},
                                   {"volume.d_g_ub", v.d_g_ub},
                                   {"volume.d_ng_ub", v.d_ng_ub},
                                   {"volume.h_max", v.h_max},
                                   {"volume.trail_margin", v.trail_margin},
                                   {"volume.alpha_t", v.alpha_t},
                                   {"volume.alpha_g", v.alpha_g},
                                   {"volume.alpha_ng", v.alpha_ng}})
    if (!(value <= kMaxLength))
      throw InputError(describe(key, value) + " must be <= " + value_text(kMaxLength));
  if (v.distance != DistanceMode::kPlane && v.distance != DistanceMode::k3d)
    throw InputError("parameter 'volume.distance' = " + std::to_string(static_cast<int>(v.distance)) +
                     " must be plane or 3d");
  require_between("categorize.goal_dz", categorize.goal_dz, kMinGoalDz, 10.0);
  require_between("categorize.trail_densify", categorize.trail_densify, 0, 1000);
  require_between("bounds.resolution", bounds.resolution, kMinResolution, 1.0);
  require_between("bounds.min_half_width", bounds.min_half_width, 0.0, kMaxLength);
  require_between("bounds.wrist_half_width", bounds.wrist_half_width, 0.0, kMaxLength);
  require_between("bounds.linear_axis_tolerance", bounds.linear_axis_tolerance, 0.0, 1.0);
  // The joint names are checked against the robot by validate_for_scene; here what needs no robot.
  if (static_cast<int>(bounds.bisect.size()) > kMaxBisected)
    throw InputError("parameter 'bounds.bisect' names " + std::to_string(bounds.bisect.size()) +
                     " joints; at most " + std::to_string(kMaxBisected) +
                     " can be bisected (the sixth takes 64 Algorithm-2 runs per waypoint, each further one "
                     "doubles them)");
  for (size_t i = 0; i < bounds.bisect.size(); ++i) {
    const std::string& name = bounds.bisect[i];
    if (name.empty()) throw InputError("parameter 'bounds.bisect' holds an empty joint name");
    for (size_t k = 0; k < i; ++k)
      if (bounds.bisect[k] == name)
        throw InputError("parameter 'bounds.bisect' names joint '" + name + "' twice");
  }
  require_joint_widths("bounds.half_width", bounds.half_width);
  require_between("cf.windows", cf.windows, 1, std::numeric_limits<int>::max());
  require_between("cf.samples", cf.samples, 1, std::numeric_limits<int>::max());
  if (safety.mode != SafetyMode::kNone && safety.mode != SafetyMode::kSampled &&
      safety.mode != SafetyMode::kCertified)
    throw InputError("parameter 'safety.mode' = " + std::to_string(static_cast<int>(safety.mode)) +
                     " must be none, sampled or certified");
  require_between("safety.margin", safety.margin, 0.0, 1.0);
  require_between("safety.max_leaves", safety.max_leaves, 1, 100000000);
  require_between("safety.grow_leaves", safety.grow_leaves, 0.01, 1000.0);
  require_between("safety.epsilon", safety.epsilon, 1e-9, 0.5);
  require_between("safety.delta", safety.delta, 1e-12, 0.5);
  if (safety.grow.empty())
    throw InputError("parameter 'safety.grow' is empty: give all, none or joint names");
  require_joint_widths("safety.max_half_width", safety.max_half_width);
  if (safety.shape != "greedy" && safety.shape != "lever")
    throw InputError("parameter 'safety.shape' = '" + safety.shape + "' must be greedy or lever");
}

const char* safety_mode_name(SafetyMode mode) {
  switch (mode) {
    case SafetyMode::kNone:
      return "none";
    case SafetyMode::kSampled:
      return "sampled";
    case SafetyMode::kCertified:
      return "certified";
  }
  return "?";
}

SafetyMode parse_safety_mode(const std::string& name, const std::string& what) {
  for (SafetyMode m : {SafetyMode::kNone, SafetyMode::kSampled, SafetyMode::kCertified})
    if (name == safety_mode_name(m)) return m;
  throw InputError(what + " '" + name + "' must be certified, sampled or none");
}

Params preset_params(const std::string& name) {
  Params p;
  if (name == "thesis") {
    // Section 4.1 as published (Params' defaults), without any check against the real obstacles.
    p.safety.mode = SafetyMode::kNone;
    return p;
  }
  if (name == "leeway") {
    // docs/data/tuning/preset.json: leeway-tune's run of 2026-11-22 on the nine thesis paths
    // (MAX_cells up to 20,000, MuJoCo's full collision pass). Later runs (docs/tuning.md,
    // docs/data/tuning/tuned.json) are reported, not adopted: changing the preset changes every
    // default output, and is a decision of its own.
    p.height_map.max_cells = 1725;
    p.volume.d_t_lb = 0.3756895344528792;
    p.volume.d_t_ub = 1.77736013400714;
    p.volume.d_g_lb = 0.9956428788490507;
    p.volume.d_g_ub = 1.690378256532044;
    p.volume.d_ng_ub = 0.3042948618621293;
    p.volume.h_max = 1.7002108396343036;
    p.volume.alpha_t = 1.7607431532670978;
    p.volume.alpha_g = 3.9620660871306113;
    p.volume.alpha_ng = 3.568484783491677;
    p.volume.trail_margin = 0.05451587373395741;
    p.bounds.self_collision = true;
    p.safety.mode = SafetyMode::kCertified;
    return p;
  }
  throw InputError("unknown preset '" + name + "' (presets: leeway, thesis)");
}

nlohmann::json to_json(const Params& p) {
  json j = json::object();
  for_each_field(p, [&](const char* section, const char* key, const auto& field) {
    if constexpr (std::is_same_v<std::decay_t<decltype(field)>, DistanceMode>)
      j[section][key] = distance_name(field);
    else if constexpr (std::is_same_v<std::decay_t<decltype(field)>, SafetyMode>)
      j[section][key] = safety_mode_name(field);
    else
      j[section][key] = field;
  });
  return j;
}

Params params_from_json(const nlohmann::json& j, const std::string& source, const Params& base) {
  Params p = base;
  if (!j.is_object())
    throw InputError(source + ": the parameters must be a JSON object, got " + j.type_name() + " " +
                     shown(j));

  // Unknown keys first, at both levels: a misspelt key would otherwise silently keep its default.
  std::map<std::string, std::set<std::string>> known;
  for_each_field(p, [&](const char* section, const char* key, const auto&) { known[section].insert(key); });
  std::set<std::string> sections;
  for (const auto& entry : known) sections.insert(entry.first);
  for (const auto& [section, body] : j.items()) {
    const auto it = known.find(section);
    if (it == known.end())
      throw InputError(source + ": unknown parameter '" + section + "' (known sections: " + join(sections) +
                       ")");
    if (!body.is_object())
      throw InputError(source + ": parameter '" + section + "' must be an object, got " + body.type_name() +
                       " " + shown(body));
    for (const auto& item : body.items())
      if (it->second.count(item.key()) == 0)
        throw InputError(source + ": unknown parameter '" + section + "." + item.key() + "' (known in '" +
                         section + "': " + join(it->second) + ")");
  }

  for_each_field(p, [&](const char* section, const char* key, auto& field) {
    const auto s = j.find(section);
    if (s == j.end()) return;
    const auto k = s->find(key);
    if (k == s->end()) return;
    read_value(*k, std::string(section) + "." + key, source, field);
  });

  try {
    p.validate();
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
  return p;
}

Params read_params(const std::string& path, const Params& base) {
  return params_from_json(detail::read_json_file(path, "parameter file"), path, base);
}

}  // namespace leeway
