// Golden outputs of the leeway program: each command's exit code, standard output and standard error,
// byte for byte, against tests/data/cli_golden/NAME.txt (recorded before the CLI was split into
// src/cli/). Only the fields listed in kStrips (wall-clock times and the machine's thread count) are
// masked before the comparison.
//
// To record again (only when a change of output is intended): LEEWAY_UPDATE_GOLDEN=1 leeway_tests
// --gtest_filter='CliGolden*', then review the diff of tests/data/cli_golden/.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include <sys/wait.h>

#include "test_util.hpp"

namespace leeway {
namespace {

const std::string kGoldenDir = std::string(LEEWAY_TEST_DATA_DIR) + "/cli_golden";

//! One masked field: every match of `pattern` is replaced by `replacement`.
struct Strip {
  const char* what;
  std::regex pattern;
  const char* replacement;
};

// The explicit list of what may differ between runs; everything else must be identical.
const std::vector<Strip>& strips() {
  static const std::vector<Strip> kStrips = {
      // plan --json: "time": {"plan", "simplify", "total"} [s].
      {"plan time", std::regex(R"("time": \{[^{}]*\})"), R"("time": "<stripped>")"},
      // bounds --json: "timing_ms": {...} [ms].
      {"bounds timing_ms", std::regex(R"("timing_ms": \{[^{}]*\})"), R"("timing_ms": "<stripped>")"},
      // bounds text: the "time [ms]: ..." line.
      {"bounds time line", std::regex(R"(time \[ms\]: [^\n]*)"), "time [ms]: <stripped>"},
      // plan text: "..., 0.0123 s, seed 1".
      {"plan seconds", std::regex(R"(, [-+0-9.e]+ s, seed )"), ", <stripped> s, seed "},
      // sweep Markdown: the "Computational Time [ms]" column (third).
      {"sweep time column", std::regex(R"(\n\| ([0-9]+) \| ([0-9]+) \| [0-9.]+ \|)"),
       "\n| $1 | $2 | <stripped> |"},
      // --help: the default of --threads is std::thread::hardware_concurrency().
      {"threads default", std::regex(R"(--threads INT=[0-9]+)"), "--threads INT=<cores>"},
  };
  return kStrips;
}

struct GoldenCase {
  std::string name;  // file name in tests/data/cli_golden without .txt
  std::string args;  // run from the project's root directory, so paths are relative to it
};

// gtest prints the command instead of the struct's bytes.
void PrintTo(const GoldenCase& c, std::ostream* os) { *os << "leeway " << c.args; }

std::vector<GoldenCase> golden_cases() {
  std::vector<GoldenCase> c;
  for (const std::string cell : {"dallara", "baltico", "dlr"}) {
    const std::string f = "mjcf/workcells/" + cell + ".xml";
    c.push_back({"check_" + cell, "check " + f});
    c.push_back({"check_json_" + cell, "check " + f + " --json"});
    c.push_back({"fk_" + cell, "fk " + f + " --key patch"});
    c.push_back({"fk_json_" + cell, "fk " + f + " --key patch --json"});
    c.push_back({"ik_" + cell, "ik " + f + " --site patch"});
    c.push_back({"ik_json_" + cell, "ik " + f + " --site patch --json"});
    c.push_back({"params_" + cell, "params " + f});
    c.push_back({"plan_json_" + cell, "plan " + f + " --from home --to patch --json"});
  }
  const std::string dallara = "mjcf/workcells/dallara.xml", dlr = "mjcf/workcells/dlr.xml";
  c.push_back({"params", "params"});
  c.push_back({"params_thesis", "params --preset thesis"});
  c.push_back({"plan_dallara", "plan " + dallara + " --from home --to patch"});
  c.push_back(
      {"bounds_json_dallara", "bounds " + dallara + " --from home --to patch --max-cells 300 --json"});
  c.push_back({"bounds_json_dlr", "bounds " + dlr + " --from home --to patch --max-cells 300 --json"});
  c.push_back({"bounds_dallara", "bounds " + dallara + " --from home --to patch --max-cells 300"});
  c.push_back({"bounds_thesis_dallara",
               "bounds " + dallara + " --from home --to patch --max-cells 300 --preset thesis --json"});
  c.push_back({"cf_json_dallara",
               "cf " + dallara + " tests/data/cli_golden/dallara_bounds.json --samples 200 --json"});
  c.push_back({"cf_dallara", "cf " + dallara + " tests/data/cli_golden/dallara_bounds.json --samples 200"});
  c.push_back({"sweep_dallara",
               "sweep " + dallara + " --from home --to patch --max-cells 200,300 --windows 2 --samples 20"});
  c.push_back({"help", "--help"});
  c.push_back({"version", "--version"});
  for (const std::string sub :
       {"check", "fk", "ik", "plan", "bounds", "cf", "sweep", "params", "render", "view", "plot", "simulate"})
    c.push_back({"help_" + sub, sub + " --help"});
  c.push_back({"help_import_urdf", "import-urdf --help"});
  c.push_back({"help_new_cell", "new-cell --help"});
  c.push_back(
      {"error_import_urdf_no_tool", "import-urdf tests/data/urdf/arm7.urdf --tool hand --out arm7.xml"});
  // Errors.
  c.push_back({"error_no_subcommand", ""});
  c.push_back({"error_unknown_subcommand", "frobnicate " + dallara});
  c.push_back({"error_unknown_option", "check " + dallara + " --frobnicate"});
  c.push_back({"error_missing_file", "check mjcf/workcells/absent.xml"});
  c.push_back({"error_missing_file_bounds", "bounds mjcf/workcells/absent.xml --from home --to patch"});
  c.push_back(
      {"error_bounds_max_cells", "bounds " + dallara + " --from home --to patch --max-cells 2000000"});
  c.push_back(
      {"error_bounds_max_cells_text", "bounds " + dallara + " --from home --to patch --max-cells abc"});
  c.push_back({"error_bounds_no_path", "bounds " + dallara});
  c.push_back({"error_bounds_waypoints", "bounds " + dallara + " --from home --to site:patch --waypoints 3"});
  c.push_back({"error_sweep_max_cells", "sweep " + dallara + " --from home --to patch --max-cells 100,1.5"});
  c.push_back({"error_sweep_max_cells_empty", "sweep " + dallara + " --from home --to patch --max-cells ,"});
  c.push_back({"error_fk_no_q", "fk " + dallara});
  c.push_back({"error_fk_q_and_key", "fk " + dallara + " --key home --q 0,0,0,0,0,0"});
  c.push_back({"error_ik_no_goal", "ik " + dallara});
  c.push_back({"error_ik_lock", "ik " + dallara + " --site patch --lock j1,nope"});
  c.push_back({"error_plan_unknown_key", "plan " + dallara + " --from home --to nowhere"});
  c.push_back({"error_params_preset", "params --preset nope"});
  c.push_back({"error_bounds_safety", "bounds " + dallara + " --from home --to patch --safety nope"});
  c.push_back({"error_bounds_checker", "bounds " + dallara + " --from home --to patch --checker fcl"});
  c.push_back({"error_cf_checker", "cf " + dallara + " nothing.json --checker MuJoCo"});
  return c;
}

using test::read_text;

//! Runs the CLI as "leeway" (argv[0], which CLI11 prints in --help) from the project's root; returns
//! "exit: N\n--- stdout\n...--- stderr\n..." with the strips applied.
std::string run_golden(const std::string& args, const test::TempDir& tmp) {
  const std::string root = std::string(LEEWAY_MJCF_DIR) + "/..";
  const auto out = tmp.path() / "stdout", err = tmp.path() / "stderr";
  const std::string cmd = "bash -c 'cd \"" + root + "\" && exec -a leeway \"" + LEEWAY_CLI + "\" " + args +
                          " >\"" + out.string() + "\" 2>\"" + err.string() + "\"'";
  const int status = std::system(cmd.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::string text =
      "exit: " + std::to_string(code) + "\n--- stdout\n" + read_text(out) + "--- stderr\n" + read_text(err);
  for (const auto& s : strips()) text = std::regex_replace(text, s.pattern, s.replacement);
  return text;
}

class CliGolden : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(CliGolden, OutputIsUnchanged) {
  const GoldenCase& c = GetParam();
  const test::TempDir tmp;
  const std::string actual = run_golden(c.args, tmp);
  const std::filesystem::path file = kGoldenDir + "/" + c.name + ".txt";
  if (const char* update = std::getenv("LEEWAY_UPDATE_GOLDEN"); update && std::string(update) == "1") {
    std::ofstream(file, std::ios::binary) << actual;
    GTEST_SKIP() << "recorded " << file;
  }
  ASSERT_TRUE(std::filesystem::exists(file)) << file << " is missing; leeway " << c.args;
  EXPECT_EQ(actual, read_text(file)) << "leeway " << c.args;
}

INSTANTIATE_TEST_SUITE_P(Commands, CliGolden, ::testing::ValuesIn(golden_cases()),
                         [](const ::testing::TestParamInfo<GoldenCase>& param_info) {
                           return param_info.param.name;
                         });

// Every golden file belongs to a case (a renamed case leaves no stale file behind).
TEST(CliGoldenFiles, EveryFileHasACase) {
  std::vector<std::string> names;
  for (const auto& c : golden_cases()) names.push_back(c.name + ".txt");
  for (const auto& e : std::filesystem::directory_iterator(kGoldenDir)) {
    const std::string n = e.path().filename().string();
    if (n == "dallara_bounds.json") continue;  // the input of the cf cases
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
}

}  // namespace
}  // namespace leeway
