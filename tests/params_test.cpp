#include "leeway/core/params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using nlohmann::json;

//! The message of the InputError that f throws, or "" (and a test failure) when it does not throw.
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return "";
}

TEST(ParamsTest, DefaultsAreTheThesisValuesInSi) {
  // Section 4.1: d_t 350..1500 mm, d_g 100..2000 mm, d_ng,UB 500 mm, h_max 1500 mm, all exponents 1,
  // reach 2800 mm (Dallara, Baltico); 30 windows of 10000 samples for the CF.
  const Params p;
  EXPECT_EQ(p.volume.d_t_lb, 0.35);
  EXPECT_EQ(p.volume.d_t_ub, 1.5);
  EXPECT_EQ(p.volume.d_g_lb, 0.1);
  EXPECT_EQ(p.volume.d_g_ub, 2.0);
  EXPECT_EQ(p.volume.d_ng_ub, 0.5);
  EXPECT_EQ(p.volume.h_max, 1.5);
  EXPECT_EQ(p.volume.alpha_t, 1.0);
  EXPECT_EQ(p.volume.alpha_g, 1.0);
  EXPECT_EQ(p.volume.alpha_ng, 1.0);
  EXPECT_TRUE(p.volume.goal_constant_term);  // eq. 4.1
  EXPECT_EQ(p.volume.reach_radius, 2.8);
  EXPECT_EQ(p.volume.distance, DistanceMode::kPlane);
  EXPECT_EQ(p.cf.windows, 30);
  EXPECT_EQ(p.cf.samples, 10000);
  EXPECT_NO_THROW(p.validate());
}

//! Every field set to a non-default value.
Params unusual() {
  Params p;
  p.height_map.auto_extent = false;
  p.height_map.origin_x = -1.25;
  p.height_map.origin_y = 0.5;
  p.height_map.x_dim = 7.5;
  p.height_map.y_dim = 3.25;
  p.height_map.max_cells = 1234;
  p.volume.d_t_lb = 0.3;
  p.volume.d_t_ub = 1.7;
  p.volume.d_g_lb = 0.2;
  p.volume.d_g_ub = 2.2;
  p.volume.d_ng_ub = 0.6;
  p.volume.h_max = 1.1;
  p.volume.alpha_t = 2.0;
  p.volume.alpha_g = 0.5;
  p.volume.alpha_ng = 3.0;
  p.volume.goal_constant_term = false;
  p.volume.reach_radius = 3.0;
  p.volume.add_obstacle_boxes = true;
  p.volume.distance = DistanceMode::k3d;
  p.categorize.goal_dz = 0.02;
  p.categorize.trail_densify = 4;
  p.bounds.resolution = 0.005;
  p.bounds.min_half_width = 0.02;
  p.bounds.wrist_half_width = 0.3;
  p.bounds.linear_axis_tolerance = 0.05;
  p.bounds.bisect = {"j4", "j1", "j2"};  // any order: bounded in model order
  p.bounds.half_width = {{"j5", 0.35}, {"rail_x", 0.5}};
  p.safety.grow = "j4,j6";
  p.safety.max_half_width = {{"j6", 0.25}};
  p.safety.shape = "lever";
  p.safety.grow_leaves = 2.5;
  p.safety.runs = false;
  p.safety.turn = false;
  p.cf.windows = 12;
  p.cf.samples = 500;
  p.cf.seed = 18446744073709551615ull;  // the largest seed: JSON must carry all 64 bits
  return p;
}

void expect_equal(const Params& a, const Params& b) {
  EXPECT_EQ(a.height_map.auto_extent, b.height_map.auto_extent);
  EXPECT_EQ(a.height_map.origin_x, b.height_map.origin_x);
  EXPECT_EQ(a.height_map.origin_y, b.height_map.origin_y);
  EXPECT_EQ(a.height_map.x_dim, b.height_map.x_dim);
  EXPECT_EQ(a.height_map.y_dim, b.height_map.y_dim);
  EXPECT_EQ(a.height_map.max_cells, b.height_map.max_cells);
  EXPECT_EQ(a.volume.d_t_lb, b.volume.d_t_lb);
  EXPECT_EQ(a.volume.d_t_ub, b.volume.d_t_ub);
  EXPECT_EQ(a.volume.d_g_lb, b.volume.d_g_lb);
  EXPECT_EQ(a.volume.d_g_ub, b.volume.d_g_ub);
  EXPECT_EQ(a.volume.d_ng_ub, b.volume.d_ng_ub);
  EXPECT_EQ(a.volume.h_max, b.volume.h_max);
  EXPECT_EQ(a.volume.alpha_t, b.volume.alpha_t);
  EXPECT_EQ(a.volume.alpha_g, b.volume.alpha_g);
  EXPECT_EQ(a.volume.alpha_ng, b.volume.alpha_ng);
  EXPECT_EQ(a.volume.goal_constant_term, b.volume.goal_constant_term);
  EXPECT_EQ(a.volume.reach_radius, b.volume.reach_radius);
  EXPECT_EQ(a.volume.add_obstacle_boxes, b.volume.add_obstacle_boxes);
  EXPECT_EQ(a.volume.distance, b.volume.distance);
  EXPECT_EQ(a.categorize.goal_dz, b.categorize.goal_dz);
  EXPECT_EQ(a.categorize.trail_densify, b.categorize.trail_densify);
  EXPECT_EQ(a.bounds.resolution, b.bounds.resolution);
  EXPECT_EQ(a.bounds.min_half_width, b.bounds.min_half_width);
  EXPECT_EQ(a.bounds.wrist_half_width, b.bounds.wrist_half_width);
  EXPECT_EQ(a.bounds.linear_axis_tolerance, b.bounds.linear_axis_tolerance);
  EXPECT_EQ(a.bounds.bisect, b.bounds.bisect);
  EXPECT_EQ(a.bounds.half_width, b.bounds.half_width);
  EXPECT_EQ(a.safety.grow, b.safety.grow);
  EXPECT_EQ(a.safety.max_half_width, b.safety.max_half_width);
  EXPECT_EQ(a.safety.shape, b.safety.shape);
  EXPECT_EQ(a.safety.grow_leaves, b.safety.grow_leaves);
  EXPECT_EQ(a.safety.runs, b.safety.runs);
  EXPECT_EQ(a.safety.turn, b.safety.turn);
  EXPECT_EQ(a.cf.windows, b.cf.windows);
  EXPECT_EQ(a.cf.samples, b.cf.samples);
  EXPECT_EQ(a.cf.seed, b.cf.seed);
}

TEST(ParamsJsonTest, RoundTripKeepsEveryField) {
  const Params p = unusual();
  ASSERT_NO_THROW(p.validate());
  expect_equal(params_from_json(to_json(p), "mem"), p);
  // Through text too: the printed doubles read back bit for bit.
  expect_equal(params_from_json(json::parse(to_json(p).dump()), "text"), p);
}

TEST(ParamsJsonTest, KeysAreTheFieldNames) {
  const json j = to_json(unusual());
  EXPECT_EQ(j.at("height_map").at("max_cells"), 1234);
  EXPECT_EQ(j.at("height_map").at("auto_extent"), false);
  EXPECT_EQ(j.at("volume").at("d_ng_ub"), 0.6);
  EXPECT_EQ(j.at("volume").at("distance"), "3d");
  EXPECT_EQ(to_json(Params{}).at("volume").at("distance"), "plane");
  EXPECT_EQ(j.at("categorize").at("trail_densify"), 4);
  EXPECT_EQ(j.at("bounds").at("linear_axis_tolerance"), 0.05);
  EXPECT_EQ(j.at("cf").at("seed"), 18446744073709551615ull);
  EXPECT_EQ(j.size(), 6u);
  EXPECT_EQ(j.at("safety").size(), 12u);
  EXPECT_EQ(j.at("safety").at("grow_leaves"), 2.5);
  EXPECT_EQ(to_json(Params{}).at("safety").at("grow_leaves"), 1.0);
  EXPECT_EQ(j.at("safety").at("runs"), false);
  EXPECT_EQ(to_json(Params{}).at("safety").at("runs"), true);
  EXPECT_EQ(j.at("safety").at("turn"), false);
  EXPECT_EQ(to_json(Params{}).at("safety").at("turn"), true);
  EXPECT_EQ(j.at("safety").at("mode"), "certified");
  EXPECT_EQ(j.at("safety").at("shape"), "lever");
  EXPECT_EQ(to_json(Params{}).at("safety").at("shape"), "greedy");
  EXPECT_EQ(j.at("height_map").size(), 6u);
  EXPECT_EQ(j.at("volume").size(), 14u);  // 13 of section 4.1 and 3.2 plus trail_margin
  EXPECT_EQ(j.at("categorize").size(), 2u);
  // Four of sections 3.3 and 4.2.3, self_collision, bisect and half_width.
  EXPECT_EQ(j.at("bounds").size(), 7u);
  EXPECT_EQ(j.at("bounds").at("bisect"), json::parse(R"(["j4", "j1", "j2"])"));
  EXPECT_EQ(j.at("bounds").at("half_width"), json::parse(R"({"j5": 0.35, "rail_x": 0.5})"));
  // The defaults: the thesis's rule and no per-joint half-width, as [] and {}.
  EXPECT_EQ(to_json(Params{}).at("bounds").at("bisect"), json::array());
  EXPECT_EQ(to_json(Params{}).at("bounds").at("half_width"), json::object());
  EXPECT_EQ(to_json(Params{}).at("bounds").at("self_collision"), false);
  EXPECT_EQ(to_json(preset_params("leeway")).at("bounds").at("self_collision"), true);
  EXPECT_EQ(to_json(preset_params("thesis")).at("bounds").at("self_collision"), false);
  EXPECT_EQ(j.at("cf").size(), 3u);
}

TEST(ParamsJsonTest, MissingKeysKeepDefaults) {
  const Params p = params_from_json(json::parse(R"({"volume": {"h_max": 1.2}, "cf": {}})"), "p.json");
  EXPECT_EQ(p.volume.h_max, 1.2);
  EXPECT_EQ(p.volume.d_t_lb, 0.35);
  EXPECT_EQ(p.height_map.max_cells, 20000);
  EXPECT_EQ(p.cf.windows, 30);
  expect_equal(params_from_json(json::object(), "empty"), Params{});
}

TEST(ParamsJsonTest, UnknownKeysAreErrors) {
  std::string m = error_of([] { params_from_json(json::parse(R"({"volume": {"h_maxx": 1}})"), "p.json"); });
  EXPECT_NE(m.find("p.json"), std::string::npos) << m;
  EXPECT_NE(m.find("'volume.h_maxx'"), std::string::npos) << m;
  m = error_of([] { params_from_json(json::parse(R"({"volumes": {}})"), "p.json"); });
  EXPECT_NE(m.find("'volumes'"), std::string::npos) << m;
}

TEST(ParamsJsonTest, WrongTypesAreErrors) {
  const std::string cases[][2] = {
      {R"({"volume": {"h_max": "1.5"}})", "'volume.h_max'"},  // a string is not a number
      {R"({"volume": {"h_max": null}})", "'volume.h_max'"},
      {R"({"volume": {"goal_constant_term": 1}})", "'volume.goal_constant_term'"},
      {R"({"volume": {"distance": "euclid"}})", "'volume.distance'"},
      {R"({"volume": 3})", "'volume'"},
      {R"({"height_map": {"max_cells": 2.5}})", "'height_map.max_cells'"},
      {R"({"height_map": {"max_cells": 1e12}})", "'height_map.max_cells'"},
      {R"({"height_map": {"max_cells": 99999999999}})", "'height_map.max_cells'"},  // beyond int
      {R"({"cf": {"seed": -1}})", "'cf.seed'"},
      {R"({"cf": {"windows": [30]}})", "'cf.windows'"},
      {R"({"bounds": {"bisect": "j1,j2"}})", "'bounds.bisect' must be a list of joint names"},
      {R"({"bounds": {"bisect": ["j1", 2]}})", "'bounds.bisect' must be a list of joint names"},
      {R"({"bounds": {"half_width": [0.3]}})", "'bounds.half_width' must be an object of joint names"},
      {R"({"bounds": {"half_width": {"j5": "0.3"}}})", "'bounds.half_width.j5' must be a number"},
  };
  for (const auto& c : cases) {
    const std::string m = error_of([&] { params_from_json(json::parse(c[0]), "p.json"); });
    EXPECT_EQ(m.rfind("p.json: ", 0), 0u) << c[0] << " -> " << m;
    EXPECT_NE(m.find(c[1]), std::string::npos) << c[0] << " -> " << m;
  }
  const std::string m = error_of([] { params_from_json(json::array(), "p.json"); });
  EXPECT_NE(m.find("p.json"), std::string::npos) << m;
}

TEST(ParamsJsonTest, JointListsReplaceTheBase) {
  // A file's 'bounds.bisect' and 'bounds.half_width' replace the base's whole list and map.
  Params base;
  base.bounds.bisect = {"j1", "j2", "j3"};
  base.bounds.half_width = {{"j5", 0.3}, {"j6", 0.1}};
  const Params p = params_from_json(
      json::parse(R"({"bounds": {"bisect": ["j1", "j2", "j4"], "half_width": {"j3": 0.25}}})"), "p.json",
      base);
  EXPECT_EQ(p.bounds.bisect, (std::vector<std::string>{"j1", "j2", "j4"}));
  EXPECT_EQ(p.bounds.half_width, (std::map<std::string, double>{{"j3", 0.25}}));
  // Empty values give back the defaults: the thesis's rule, no per-joint widths.
  const Params q =
      params_from_json(json::parse(R"({"bounds": {"bisect": [], "half_width": {}}})"), "p.json", base);
  EXPECT_TRUE(q.bounds.bisect.empty());
  EXPECT_TRUE(q.bounds.half_width.empty());
}

TEST(ParamsValidateTest, JointListsAreRefusedWithTheJointAndTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    std::function<void(Params&)> set;
    std::string message;
  };
  const Case cases[] = {
      {[](Params& p) {
         p.bounds.bisect = {"j1", "j2", "j1"};
       },
       "parameter 'bounds.bisect' names joint 'j1' twice"},
      {[](Params& p) {
         p.bounds.bisect = {"j1", ""};
       },
       "parameter 'bounds.bisect' holds an empty joint name"},
      {[](Params& p) { p.bounds.bisect = {"a", "b", "c", "d", "e", "f", "g"}; },
       "parameter 'bounds.bisect' names 7 joints; at most 6 can be bisected (the sixth takes 64 Algorithm-2 "
       "runs per waypoint, each further one doubles them)"},
      {[](Params& p) {
         p.bounds.half_width = {{"j5", -0.1}};
       },
       "parameter 'bounds.half_width.j5' = -0.1 must be between 0 and 1000"},
      {[](Params& p) {
         p.bounds.half_width = {{"j5", 1001}};
       },
       "parameter 'bounds.half_width.j5' = 1001 must be between 0 and 1000"},
      {[=](Params& p) {
         p.bounds.half_width = {{"j6", nan}};
       },
       "parameter 'bounds.half_width.j6' = nan must be a finite number"},
      {[](Params& p) {
         p.bounds.half_width = {{"", 0.1}};
       },
       "parameter 'bounds.half_width' holds an empty joint name"},
  };
  for (const auto& c : cases) {
    Params p;
    c.set(p);
    EXPECT_EQ(error_of([&] { p.validate(); }), c.message);
  }
  // Six joints and the bounds of the range are accepted.
  Params p;
  p.bounds.bisect = {"a", "b", "c", "d", "e", "f"};
  p.bounds.half_width = {{"g", 0.0}, {"h", 1000.0}};
  EXPECT_NO_THROW(p.validate());
  // From a file, the file is named first.
  EXPECT_EQ(
      error_of([] { params_from_json(json::parse(R"({"bounds": {"half_width": {"j5": -1}}})"), "p.json"); }),
      "p.json: parameter 'bounds.half_width.j5' = -1 must be between 0 and 1000");
}

TEST(ParamsJsonTest, OutOfRangeValuesAreValidated) {
  const std::string m =
      error_of([] { params_from_json(json::parse(R"({"volume": {"h_max": -1}})"), "p.json"); });
  EXPECT_EQ(m, "p.json: parameter 'volume.h_max' = -1 must be > 0");
}

struct InvalidCase {
  const char* key;
  std::function<void(Params&)> set;
};

TEST(ParamsValidateTest, EachInvalidValueNamesItsKey) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const InvalidCase cases[] = {
      {"'volume.d_t_lb'", [](Params& p) { p.volume.d_t_lb = 2.0; }},  // >= d_t_ub = 1.5
      {"'volume.d_t_lb'", [](Params& p) { p.volume.d_t_lb = 1.5; }},  // == d_t_ub
      {"'volume.d_t_lb'", [](Params& p) { p.volume.d_t_lb = -0.1; }},
      {"'volume.d_t_ub'", [=](Params& p) { p.volume.d_t_ub = nan; }},
      {"'volume.d_g_lb'", [](Params& p) { p.volume.d_g_lb = 3.0; }},  // >= d_g_ub = 2
      {"'volume.d_g_lb'", [](Params& p) { p.volume.d_g_lb = -0.1; }},
      {"'volume.d_g_ub'", [=](Params& p) { p.volume.d_g_ub = inf; }},
      {"'volume.d_ng_ub'", [](Params& p) { p.volume.d_ng_ub = 0.0; }},
      {"'volume.h_max'", [](Params& p) { p.volume.h_max = 0.0; }},
      {"'volume.h_max'", [=](Params& p) { p.volume.h_max = nan; }},
      {"'volume.alpha_t'", [](Params& p) { p.volume.alpha_t = 0.0; }},
      {"'volume.alpha_g'", [](Params& p) { p.volume.alpha_g = -1.0; }},
      {"'volume.alpha_ng'", [](Params& p) { p.volume.alpha_ng = 0.0; }},
      {"'volume.reach_radius'", [](Params& p) { p.volume.reach_radius = 0.0; }},
      {"'volume.reach_radius'", [=](Params& p) { p.volume.reach_radius = -inf; }},
      {"'height_map.max_cells'", [](Params& p) { p.height_map.max_cells = 0; }},
      {"'height_map.max_cells'", [](Params& p) { p.height_map.max_cells = 1000001; }},
      {"'height_map.origin_x'", [=](Params& p) { p.height_map.origin_x = nan; }},
      {"'height_map.x_dim'",
       [](Params& p) {
         p.height_map.auto_extent = false;
         p.height_map.x_dim = 0.0;
         p.height_map.y_dim = 1.0;
       }},
      {"'height_map.y_dim'",
       [](Params& p) {
         p.height_map.auto_extent = false;
         p.height_map.x_dim = 1.0;
         p.height_map.y_dim = -1.0;
       }},
      {"'categorize.goal_dz'", [](Params& p) { p.categorize.goal_dz = 0.0; }},
      {"'categorize.trail_densify'", [](Params& p) { p.categorize.trail_densify = -1; }},
      {"'categorize.trail_densify'", [](Params& p) { p.categorize.trail_densify = 1001; }},
      {"'bounds.resolution'", [](Params& p) { p.bounds.resolution = 0.0; }},
      {"'bounds.min_half_width'", [](Params& p) { p.bounds.min_half_width = -0.01; }},
      {"'bounds.wrist_half_width'", [](Params& p) { p.bounds.wrist_half_width = -0.2; }},
      {"'bounds.linear_axis_tolerance'", [](Params& p) { p.bounds.linear_axis_tolerance = -0.01; }},
      {"'bounds.linear_axis_tolerance'", [](Params& p) { p.bounds.linear_axis_tolerance = 1.5; }},
      {"'safety.grow_leaves'", [](Params& p) { p.safety.grow_leaves = 0.0; }},
      {"'safety.grow_leaves'", [](Params& p) { p.safety.grow_leaves = 1001.0; }},
      {"'safety.grow_leaves'", [=](Params& p) { p.safety.grow_leaves = nan; }},
      {"'cf.windows'", [](Params& p) { p.cf.windows = 0; }},
      {"'cf.samples'", [](Params& p) { p.cf.samples = 0; }},
  };
  for (const auto& c : cases) {
    Params p;
    c.set(p);
    const std::string m = error_of([&] { p.validate(); });
    EXPECT_NE(m.find(c.key), std::string::npos) << c.key << " -> " << m;
  }
}

TEST(ParamsValidateTest, MessagesNameKeyAndValue) {
  Params p;
  p.volume.d_t_lb = 2.0;
  EXPECT_EQ(error_of([&] { p.validate(); }),
            "parameter 'volume.d_t_lb' = 2 must be smaller than 'volume.d_t_ub' = 1.5");
  p = Params{};
  p.volume.h_max = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([&] { p.validate(); }), "parameter 'volume.h_max' = nan must be a finite number");
}

TEST(ParamsValidateTest, UnknownShapeIsRefusedNamingIt) {
  Params p;
  p.safety.shape = "water";
  EXPECT_EQ(error_of([&] { p.validate(); }), "parameter 'safety.shape' = 'water' must be greedy or lever");
  for (const char* ok : {"greedy", "lever"}) {
    p.safety.shape = ok;
    EXPECT_NO_THROW(p.validate()) << ok;
  }
  const std::string m =
      error_of([] { params_from_json(json::parse(R"({"safety": {"shape": 2}})"), "p.json"); });
  EXPECT_NE(m.find("'safety.shape' must be a string"), std::string::npos) << m;
}

TEST(ParamsValidateTest, BoundaryValuesAreAccepted) {
  Params p;
  p.volume.d_t_lb = 0.0;
  p.volume.d_g_lb = 0.0;
  p.height_map.max_cells = 1;
  p.categorize.trail_densify = 1000;
  p.bounds.min_half_width = 0.0;
  p.bounds.linear_axis_tolerance = 1.0;
  p.cf.windows = 1;
  p.cf.samples = 1;
  EXPECT_NO_THROW(p.validate());
  p.height_map.max_cells = 1000000;
  p.bounds.linear_axis_tolerance = 0.0;
  EXPECT_NO_THROW(p.validate());
  // With auto_extent the explicit dimensions are ignored, zeros included (the defaults).
  p.height_map.auto_extent = true;
  p.height_map.x_dim = 0.0;
  EXPECT_NO_THROW(p.validate());
}

TEST(ReadParamsTest, ReadsAFile) {
  test::TempDir dir;
  const Params p = read_params(dir.write("p.json", R"({"volume": {"reach_radius": 3.0}})"));
  EXPECT_EQ(p.volume.reach_radius, 3.0);
}

TEST(ReadParamsTest, MissingFileNamesIt) {
  test::TempDir dir;
  const std::string path = (dir.path() / "nope.json").string();
  const std::string m = error_of([&] { read_params(path); });
  EXPECT_NE(m.find(path), std::string::npos) << m;
}

TEST(ReadParamsTest, MalformedJsonNamesTheFileOnOneLine) {
  test::TempDir dir;
  const std::string path = dir.write("bad.json", "{\"volume\": {\"h_max\": 1.5,,\n}}\n");
  const std::string m = error_of([&] { read_params(path); });
  EXPECT_EQ(m.rfind(path + ": ", 0), 0u) << m;
  EXPECT_NE(m.find("parse error"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

TEST(ReadParamsTest, InvalidValueInFileNamesFileAndKey) {
  test::TempDir dir;
  const std::string path = dir.write("p.json", R"({"volume": {"d_g_lb": 2.5}})");
  const std::string m = error_of([&] { read_params(path); });
  EXPECT_EQ(m, path + ": parameter 'volume.d_g_lb' = 2.5 must be smaller than 'volume.d_g_ub' = 2");
}

}  // namespace
}  // namespace leeway

namespace leeway {
namespace {

TEST(ParamsLayeringTest, KeysInTheFileOverrideTheBaseOthersKeepIt) {
  // A cell's defaults (DLR: reach 3.0 m, obstacle boxes) survive a file that sets only the margin.
  Params base;
  base.volume.reach_radius = 3.0;
  base.volume.add_obstacle_boxes = true;
  const Params p =
      params_from_json(nlohmann::json::parse(R"({"volume": {"trail_margin": 0.1}})"), "p.json", base);
  EXPECT_EQ(p.volume.reach_radius, 3.0);
  EXPECT_TRUE(p.volume.add_obstacle_boxes);
  EXPECT_EQ(p.volume.trail_margin, 0.1);
  EXPECT_EQ(p.volume.d_t_lb, 0.35);  // untouched default
}

}  // namespace
}  // namespace leeway
