// The bounds, cf, sweep and params subcommands as a user runs them: exit codes, files, messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace leeway {
namespace {

using test::run_cli;
using test::workcell;
using ::testing::HasSubstr;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

using test::read_text;

class CliBoundsTest : public ::testing::Test {
 protected:
  //! Runs `bounds` home -> patch on the Dallara cell into b.json (once per test that needs it).
  std::string bounds_file() {
    const std::string out = (dir_.path() / "b.json").string();
    if (!std::filesystem::exists(out)) {
      const auto r =
          run_cli("bounds " + workcell("dallara") + " --from home --to patch --max-cells 300 --out " + out);
      EXPECT_EQ(r.exit_code, 0) << r.out;
    }
    return out;
  }
  test::TempDir dir_;
};

TEST_F(CliBoundsTest, BoundsWritesTheBoundsFile) {
  const std::string out = (dir_.path() / "b.json").string();
  const auto r =
      run_cli("bounds " + workcell("dallara") + " --from home --to patch --max-cells 300 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("wrote " + out));
  const auto j = nlohmann::json::parse(read_text(out));
  ASSERT_EQ(j.at("waypoints").size(), 2u);
  EXPECT_EQ(j.at("max_cells").get<int>(), 300);
  EXPECT_EQ(j.at("joints").size(), 6u);
  // The first waypoint is home (all zeros) and its bounds contain it.
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(j["waypoints"][0]["q"][i].get<double>(), 0.0);
    EXPECT_LE(j["waypoints"][0]["lower"][i].get<double>(), 0.0);
    EXPECT_GE(j["waypoints"][0]["upper"][i].get<double>(), 0.0);
  }
}

TEST_F(CliBoundsTest, BoundsJsonOnStandardOutput) {
  const auto r = run_cli("bounds " + workcell("dallara") +
                         " --from home --to patch --max-cells 200 --waypoints 3 --threads 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("waypoints").size(), 3u);
  EXPECT_EQ(j.at("max_cells").get<int>(), 200);
}

TEST_F(CliBoundsTest, CfOfABoundsFile) {
  const std::string b = bounds_file();
  const auto r = run_cli("cf " + workcell("dallara") + " " + b + " --samples 200 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  const double cf = j.at("cf").get<double>();
  EXPECT_GE(cf, 0.0);
  EXPECT_LE(cf, 1.0);
  EXPECT_LE(j.at("ci95")[0].get<double>(), cf);
  EXPECT_GE(j.at("ci95")[1].get<double>(), cf);
  EXPECT_EQ(j.at("samples").get<long>(), 30 * 200);  // 30 windows by default
  EXPECT_EQ(j.at("window_cf").size(), 30u);
  // cf = 1 - collisions / samples
  EXPECT_NEAR(cf, 1.0 - j.at("collisions").get<double>() / 6000, 1e-12);
}

TEST_F(CliBoundsTest, SweepPrintsTheTableAndWritesTheCsv) {
  const std::string csv = (dir_.path() / "s.csv").string();
  const auto r = run_cli("sweep " + workcell("dallara") +
                         " --from home --to patch --max-cells 100,200 --samples 100 --csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  int header = 0, rows = 0;
  for (const auto& line : lines_of(r.out)) {
    if (line.rfind("| Max CBox |", 0) == 0) ++header;
    if (line.rfind("| 100 |", 0) == 0 || line.rfind("| 200 |", 0) == 0) ++rows;
  }
  EXPECT_EQ(header, 1) << r.out;
  EXPECT_EQ(rows, 2) << r.out;
  const auto csv_lines = lines_of(read_text(csv));
  ASSERT_EQ(csv_lines.size(), 3u);
  EXPECT_EQ(csv_lines[0].rfind("max_cells,boxes,", 0), 0u);
  EXPECT_EQ(csv_lines[1].rfind("100,", 0), 0u);
  EXPECT_EQ(csv_lines[2].rfind("200,", 0), 0u);
}

TEST_F(CliBoundsTest, SweepTakesCfSettingsFromTheParameterFile) {
  // 3 windows x 7 samples = 21 samples. A 200-cell sweep of home-patch is collision-free in most
  // samples; with n = 21 the Wilson interval is wide: for 21 of 21 its lower end is
  // 21 / (21 + 1.96^2) = 0.845, for fewer it is lower still, so ci_low < 0.9. With the default
  // 30 x 10,000 samples it would be within 0.01 of cf.
  const std::string params = (dir_.path() / "p.json").string();
  std::ofstream(params) << R"({"cf": {"windows": 3, "samples": 7}})";
  const std::string csv = (dir_.path() / "s.csv").string();
  const auto r = run_cli("sweep " + workcell("dallara") +
                         " --from home --to patch --max-cells 200 --params " + params + " --csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto rows = lines_of(read_text(csv));
  ASSERT_EQ(rows.size(), 2u);
  // max_cells,boxes,time_ms,volume_ms,bounds_ms,checks,cf,ci_low,...
  std::vector<std::string> f;
  std::stringstream ss(rows[1]);
  for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
  ASSERT_GE(f.size(), 8u);
  EXPECT_LT(std::stod(f[7]), 0.9) << rows[1];
}

TEST_F(CliBoundsTest, ParamsPrintsTheCellsDefaults) {
  auto r = run_cli("params " + workcell("dlr"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("volume").at("reach_radius").get<double>(), 3.0);
  EXPECT_TRUE(j.at("volume").at("add_obstacle_boxes").get<bool>());
  r = run_cli("params --preset thesis");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("volume").at("reach_radius").get<double>(), 2.8);
  EXPECT_EQ(j.at("height_map").at("max_cells").get<int>(), 20000);  // section 4.1's table row
  EXPECT_EQ(j.at("volume").at("d_t_lb").get<double>(), 0.35);       // section 4.1: 350 mm
  EXPECT_EQ(j.at("safety").at("mode").get<std::string>(), "none");
  // The default preset: leeway-tune's parameters (docs/data/tuning/preset.json), certified.
  r = run_cli("params");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("height_map").at("max_cells").get<int>(), 1725);
  EXPECT_EQ(j.at("safety").at("mode").get<std::string>(), "certified");
}

TEST_F(CliBoundsTest, BadInputsExitTwoNameTheValueAndWriteNothing) {
  const std::string cell = workcell("dallara");
  const std::string lb = dir_.write("lb.json", R"({"volume": {"d_t_lb": 2.0}})");
  const std::string malformed = dir_.write("malformed.json", R"({"volume": {"d_t_lb": )");
  const std::string nan = dir_.write("nan.json", R"({"volume": {"d_t_lb": "nan"}})");
  const std::string out = (dir_.path() / "out.json").string();
  const std::string csv = (dir_.path() / "out.csv").string();
  const std::string bounds = "bounds " + cell + " --from home --to patch --max-cells 300 --out " + out + " ";
  const std::string sweep = "sweep " + cell + " --from home --to patch --samples 10 --csv " + csv + " ";
  struct Case {
    std::string args;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      {"bounds " + cell + " --from nowhere --to patch --max-cells 300 --out " + out,
       {"'nowhere'", "'home', 'patch', 'mould'"}},
      {"bounds " + cell + " --from home --to patch --max-cells 2000000 --out " + out,
       {"max_cells", "2000000", "1000000"}},
      {bounds + "--params " + lb, {"lb.json", "d_t_lb", "= 2", "d_t_ub"}},
      {bounds + "--params " + malformed, {"malformed.json", "malformed JSON"}},
      {bounds + "--params " + nan, {"nan.json", "d_t_lb", "\"nan\""}},
      {bounds + "--waypoints 1", {"--waypoints 1", "must be >= 2"}},
      {bounds + "--threads 0", {"--threads 0"}},
      {sweep + "--max-cells 0", {"--max-cells", "'0'"}},
      {sweep + "--max-cells 100,-3", {"--max-cells", "'-3'"}},
      {sweep + "--max-cells 100 --params " + lb, {"lb.json", "d_t_lb"}},
      {"sweep " + cell + " --from home --to nowhere --max-cells 100 --csv " + csv, {"'nowhere'"}},
      {sweep + "--max-cells 100 --threads 0", {"--threads 0"}},
  };
  for (const auto& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr("leeway: error:")) << c.args;
    for (const auto& f : c.fragments) EXPECT_THAT(r.out, HasSubstr(f)) << c.args;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
    EXPECT_FALSE(std::filesystem::exists(csv)) << c.args;
  }
}

TEST_F(CliBoundsTest, BisectAndHalfWidthChooseTheJoints) {
  // The elbow-like j4 bisected instead of j3, j3 and j6 with half-widths of their own; no safety
  // stage, so the bounds are those of Algorithms 2 and 3 and the fixed widths (clamped).
  const auto r = run_cli("bounds " + workcell("dallara") +
                         " --from home --to patch --max-cells 300 --safety none --threads 1 --json"
                         " --bisect j4,j1,j2 --half-width j3=0.05,j6=0.1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("joint_bounding"),
            nlohmann::json::parse(R"(["bisected", "bisected", "fixed", "bisected", "fixed", "fixed"])"));
  EXPECT_EQ(j.at("params").at("bounds").at("bisect"), nlohmann::json::parse(R"(["j4", "j1", "j2"])"));
  EXPECT_EQ(j.at("params").at("bounds").at("half_width"),
            nlohmann::json::parse(R"({"j3": 0.05, "j6": 0.1})"));
  for (const auto& w : j.at("waypoints")) {
    const double q2 = w["q"][2].get<double>(), q4 = w["q"][4].get<double>(), q5 = w["q"][5].get<double>();
    EXPECT_NEAR(w["upper"][2].get<double>() - q2, 0.05, 1e-12);
    EXPECT_NEAR(q2 - w["lower"][2].get<double>(), 0.05, 1e-12);
    EXPECT_NEAR(w["upper"][4].get<double>() - q4, std::min(0.2, 2.2689 - q4), 1e-12);  // j5: the wrist's
    EXPECT_NEAR(w["upper"][5].get<double>() - q5, 0.1, 1e-12);
  }
  // A parameter file gives the same as the flags.
  const std::string params = dir_.write(
      "p.json", R"({"bounds": {"bisect": ["j4", "j1", "j2"], "half_width": {"j3": 0.05, "j6": 0.1}}})");
  const auto f =
      run_cli("bounds " + workcell("dallara") +
              " --from home --to patch --max-cells 300 --safety none --threads 1 --json --params " + params);
  ASSERT_EQ(f.exit_code, 0) << f.out;
  const auto k = nlohmann::json::parse(f.out);
  EXPECT_EQ(k.at("waypoints"), j.at("waypoints"));
  EXPECT_EQ(k.at("joint_bounding"), j.at("joint_bounding"));
}

TEST_F(CliBoundsTest, BisectAndHalfWidthRefusalsNameTheFlagTheJointAndTheValue) {
  const std::string cell = workcell("dallara");
  const std::string out = (dir_.path() / "out.json").string();
  const std::string csv = (dir_.path() / "out.csv").string();
  const std::string bounds = "bounds " + cell + " --from home --to patch --max-cells 300 --out " + out + " ";
  const std::string sweep = "sweep " + cell + " --from home --to patch --max-cells 100 --csv " + csv + " ";
  const std::string both = dir_.write("both.json", R"({"bounds": {"half_width": {"j4": 0.1}}})");
  struct Case {
    std::string args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {bounds + "--bisect j1,j2,elbow", "--bisect j1,j2,elbow: " + cell +
                                            ": parameter 'bounds.bisect' names joint 'elbow', which the "
                                            "robot does not have (joints: j1, j2, j3, j4, "
                                            "j5, j6)"},
      {bounds + "--bisect j1,j2,j1", "--bisect j1,j2,j1: parameter 'bounds.bisect' names joint 'j1' twice"},
      {bounds + "--bisect j1,j2,j3,j4,j5,j6,j7",
       "--bisect j1,j2,j3,j4,j5,j6,j7: parameter 'bounds.bisect' names 7 joints; at most 6 can be bisected"},
      {bounds + "--bisect j1,", "--bisect 'j1,': an empty item"},
      {bounds + "--bisect ''", "--bisect: is empty; give joint names"},
      {bounds + "--half-width j5", "--half-width 'j5' must be NAME=VALUE"},
      {bounds + "--half-width j5=0.3x", "--half-width 'j5=0.3x' must be NAME=VALUE"},
      {bounds + "--half-width =0.3", "--half-width '=0.3' must be NAME=VALUE"},
      {bounds + "--half-width j5=0.3,j5=0.1", "--half-width j5=0.3,j5=0.1: joint 'j5' is given twice"},
      {bounds + "--half-width j5=-0.3",
       "--half-width j5=-0.3: parameter 'bounds.half_width.j5' = -0.3 must be between 0 and 1000"},
      {bounds + "--half-width j5=inf",
       "--half-width j5=inf: parameter 'bounds.half_width.j5' = inf must be a finite number"},
      {bounds + "--half-width j5=2000",
       "--half-width j5=2000: parameter 'bounds.half_width.j5' = 2000 must be between 0 and 1000"},
      {bounds + "--half-width j2=0.3",
       "--half-width j2=0.3: " + cell +
           ": parameter 'bounds.half_width.j2' = 0.3: joint 'j2' is bisected, so it has no fixed half-width "
           "(without 'bounds.bisect' the first three hinge joints are)"},
      {bounds + "--half-width wrist=0.3",
       "parameter 'bounds.half_width.wrist' = 0.3 names a joint the robot"},
      // The file's half-width for j4 and the flag's bisected j4.
      {bounds + "--params " + both + " --bisect j1,j2,j4",
       "--bisect j1,j2,j4: " + cell + ": parameter 'bounds.half_width.j4' = 0.1: joint 'j4' is bisected"},
      {sweep + "--bisect j9", "--bisect j9: " + cell + ": parameter 'bounds.bisect' names joint 'j9'"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr("leeway: error: ")) << c.args;
    EXPECT_THAT(r.out, HasSubstr(c.message)) << c.args;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
    EXPECT_FALSE(std::filesystem::exists(csv)) << c.args;
  }
}

TEST_F(CliBoundsTest, CfBadInputsExitTwo) {
  const std::string b = bounds_file();
  struct Case {
    std::string args;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      // A Dallara bounds file against the DLR cell (rail_x + j1..j6).
      {"cf " + workcell("dlr") + " " + b, {"b.json", "do not match", "dlr.xml"}},
      {"cf " + workcell("dallara") + " " + b + " --samples 0", {"samples 0"}},
      {"cf " + workcell("dallara") + " " + b + " --windows 0", {"windows 0"}},
      {"cf " + workcell("dallara") + " " + b + " --threads 0", {"--threads 0"}},
      {"cf " + workcell("dallara") + " " + (dir_.path() / "absent.json").string(), {"absent.json"}},
  };
  for (const auto& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    for (const auto& f : c.fragments) EXPECT_THAT(r.out, HasSubstr(f)) << c.args;
  }
}

// `bounds --max-cells 0` is taken as "not given" (src/cli/main.cpp: `if (b_cells != 0)`), so it runs
// with the default MAX_cells 20000 and exits 0 instead of rejecting 0. Enable once fixed.
TEST_F(CliBoundsTest, BoundsRejectsMaxCellsZero) {
  const std::string out = (dir_.path() / "out.json").string();
  const auto r =
      run_cli("bounds " + workcell("dallara") + " --from home --to patch --max-cells 0 --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("0"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliBoundsTest, HelpOnTheNewSubcommands) {
  for (const char* sub : {"bounds", "cf", "sweep", "params"}) {
    const auto r = run_cli(std::string(sub) + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub;
    EXPECT_THAT(r.out, HasSubstr("--help")) << sub;
  }
}

// A path whose end comes 0.5 mm from a wall cannot be certified with the 1 mm margin: `bounds` names
// the pair, where along the segment and how far apart the two are there. The one-link arm's tip
// corner reaches the wall's face y = 0.5 at sin(t) + 0.05 cos(t) = 0.5 - c, i.e. t = asin((0.5 - c)
// / sqrt(1.0025)) - atan(0.05); c = 0.5 mm there.
TEST_F(CliBoundsTest, BoundsNamesThePairThatStopsTheProof) {
  const double end = std::asin(0.4995 / std::sqrt(1.0025)) - std::atan(0.05);
  const std::string cell = dir_.write(
      "cell.xml", test::one_link_cell(
                      R"(<geom name="wall" type="box" size="0.6 0.1 0.5" pos="0.6 0.6 0.5"/>)",
                      R"(<key name="a" qpos="0"/><key name="b" qpos=")" + std::to_string(end) + R"("/>)"));
  const auto r = run_cli("bounds " + cell + " --from a --to b --no-plan");
  EXPECT_THAT(r.out,
              HasSubstr("segment 0 (waypoints 0-1) not certified: link link_box and obstacle wall at t = "));
  EXPECT_THAT(r.out, HasSubstr(" m apart on the nominal path there"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("exclude the pair")));
}

}  // namespace
}  // namespace leeway
