// Tuning: the core in the library (cases, variables, time proxy, objective), the NLopt
// loop of tuning/ on synthetic objectives, and leeway-tune run as a user runs it on a tiny cell.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "apps/statistics.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/error.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"
#include "tuner.hpp"

namespace leeway {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

// The one-link arm swinging j1 from 0 (key a) to 1 rad (key b) past a table and a pillar.
const char* kTinyWorld = R"(
    <geom name="table" type="box" size="0.2 0.2 0.2" pos="0.54 0.84 0.2"/>
    <geom name="pillar" type="box" size="0.1 0.1 0.4" pos="-0.2 -0.9 0.4"/>)";
const char* kTinyKeys = R"(<key name="a" qpos="0"/>
    <key name="b" qpos="1.0"/>)";

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Comma-separated fields of a CSV line (the logs quote nothing).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::string f;
  for (char c : line + ",") {
    if (c == ',') {
      out.push_back(f);
      f.clear();
    } else {
      f += c;
    }
  }
  return out;
}

// Column `name` of a CSV log, one value per data row.
std::vector<std::string> column(const std::string& csv, const std::string& name) {
  const auto lines = lines_of(csv);
  std::vector<std::string> out;
  if (lines.empty()) return out;
  const auto head = fields(lines[0]);
  const auto it = std::find(head.begin(), head.end(), name);
  if (it == head.end()) return out;
  const auto k = static_cast<size_t>(it - head.begin());
  for (size_t i = 1; i < lines.size(); ++i) out.push_back(fields(lines[i]).at(k));
  return out;
}

std::string tune_program() {
  return (std::filesystem::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
}

// Runs leeway-tune with `args`; output is stdout and stderr together.
test::CliResult run_tune(const std::string& args) { return test::run_program(tune_program(), args); }

class TuningTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    test::MujocoTest::SetUp();
    cell_ = dir_.write("cell.xml", test::one_link_cell(kTinyWorld, kTinyKeys));
    // Small maps keep every run in milliseconds; a 1.5 m reach fits the 1 m arm.
    base_ = dir_.write("base.json", R"({"height_map": {"max_cells": 500}, "volume": {"reach_radius": 1.5}})");
  }
  //! The common arguments of a quick run on the tiny cell.
  std::string quick(const std::string& more) const {
    return "--case " + cell_ + ":a:b --params " + base_ +
           " --range max_cells=20:500 --cf-samples 100 --final-samples 200 --final-repeats 1 " + more;
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  test::TempDir dir_;
  std::string cell_, base_;
};

// ---------------------------------------------------------------- the core

TEST(ParseCaseTest, SplitsAtTheLastTwoColons) {
  const auto c = parse_case("mjcf/workcells/dallara.xml:home:patch");
  EXPECT_EQ(c.cell, "mjcf/workcells/dallara.xml");
  EXPECT_EQ(c.from, "home");
  EXPECT_EQ(c.to, "patch");
  EXPECT_EQ(c.label(), "dallara:home:patch");
  EXPECT_EQ(parse_case("odd:dir/cell.xml:a:b").cell, "odd:dir/cell.xml");
}

TEST(ParseCaseTest, MalformedCasesNameTheText) {
  for (const char* bad : {"cell.xml", "cell.xml:home", ":a:b", "cell.xml::b", "cell.xml:a:", ""}) {
    try {
      parse_case(bad);
      ADD_FAILURE() << "no error for '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(std::string("tuning case '") + bad + "' must be CELL.xml:FROM:TO"));
    }
  }
}

TEST_F(TuningTest, BadCasesFailWhenLoadedNamingTheCase) {
  try {
    TuningCase(CaseSpec{path("missing.xml"), "a", "b"}, json(), 2, 100);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing.xml:a:b'"));
    EXPECT_THAT(e.what(), HasSubstr("no such file"));
  }
  try {
    TuningCase(CaseSpec{cell_, "a", "nowhere"}, json(), 2, 100);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no keyframe 'nowhere'"));
    EXPECT_THAT(e.what(), HasSubstr("'a', 'b'"));
  }
  try {
    TuningCase(CaseSpec{cell_, "a", "b"}, json{{"volume", {{"d_t_lb", 2.0}}}}, 2, 100);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("volume.d_t_lb"));
  }
}

// The tuner gets its path as leeway bounds does (resolve_nominal_path): checked, so a keyframe inside
// a wall is refused before anything is tuned.
TEST_F(TuningTest, ACaseWhosePathCollidesIsRefusedNamingTheKeyframe) {
  const std::string walled = dir_.write(
      "walled.xml", test::one_link_cell(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)",
                                        R"(<key name="a" qpos="0"/>
    <key name="in" qpos="1.5708"/>)"));
  try {
    TuningCase(CaseSpec{walled, "a", "in"}, json(), 2, 100);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("walled.xml:a:in': collision: "));
    EXPECT_THAT(e.what(), HasSubstr("hits 'wall'"));
    EXPECT_THAT(e.what(), HasSubstr("keyframe 'in' itself is not free"));
  }
}

TEST(TunedVariablesTest, ThesisValuesRoundTripThroughParams) {
  const auto vars = tuned_variables();
  ASSERT_EQ(vars.size(), 11u);
  const auto x = variables_of(Params{});
  for (size_t i = 0; i < vars.size(); ++i) {
    EXPECT_NEAR(x[i], vars[i].thesis, 1e-12) << vars[i].name;
    EXPECT_LE(vars[i].lower, vars[i].thesis) << vars[i].name;
    EXPECT_GE(vars[i].upper, vars[i].thesis) << vars[i].name;
    EXPECT_LT(vars[i].lower, vars[i].upper) << vars[i].name;
  }
  const Params p = apply_variables(Params{}, x);
  EXPECT_EQ(to_json(p), to_json(Params{}));
  EXPECT_EQ(max_cells_from_log10(std::log10(1234.4)), 1234);
  EXPECT_EQ(max_cells_from_log10(std::log10(1234.6)), 1235);
  EXPECT_THROW(apply_variables(Params{}, std::vector<double>(3, 0.0)), InputError);
  auto nan = x;
  nan[4] = std::nan("");
  EXPECT_THROW(apply_variables(Params{}, nan), InputError);
}

TEST(TunedVariablesTest, ConstraintsAreTheGapsOfBothPairs) {
  auto x = variables_of(Params{});
  auto c = bound_constraints(x);
  EXPECT_NEAR(c[0], 0.35 - 1.5 + kMinBoundGap, 1e-12);
  EXPECT_NEAR(c[1], 0.1 - 2.0 + kMinBoundGap, 1e-12);
  x[0] = 1.48;  // d_t_lb within the gap of d_t_ub
  EXPECT_GT(bound_constraints(x)[0], 0);
  EXPECT_FALSE(meets_bound_constraints(x));
  x[0] = 1.5 - 0.5;  // well below d_t_ub
  EXPECT_TRUE(meets_bound_constraints(x));
  x[2] = 2.0;  // d_g_lb at d_g_ub
  EXPECT_FALSE(meets_bound_constraints(x));
  EXPECT_TRUE(meets_bound_constraints(variables_of(Params{})));
}

TEST(MedianTest, OddEvenAndEmpty) {
  EXPECT_EQ(detail::median({3, 1, 2}), 2);
  EXPECT_EQ(detail::median({4, 1, 3, 2}), 2.5);
  EXPECT_EQ(detail::median({7}), 7);
  EXPECT_EQ(detail::median({}), 0);
}

TEST(TunedParamsJsonTest, HoldsTheTunedKeysOverTheBaseAndReadsBack) {
  Params p;
  p.volume.d_t_lb = 0.2;
  p.volume.alpha_g = 2.5;
  p.volume.trail_margin = 0.12;
  p.height_map.max_cells = 777;
  const json base = {{"bounds", {{"resolution", 0.005}}}};
  const json j = tuned_params_json(base, p);
  EXPECT_EQ(j["bounds"]["resolution"], 0.005);
  EXPECT_EQ(j["height_map"]["max_cells"], 777);
  EXPECT_FALSE(j["volume"].contains("reach_radius"));  // a cell's own reach is kept
  const Params back = params_from_json(j, "tuned");
  EXPECT_EQ(back.volume.d_t_lb, 0.2);
  EXPECT_EQ(back.volume.alpha_g, 2.5);
  EXPECT_EQ(back.volume.trail_margin, 0.12);
  EXPECT_EQ(back.height_map.max_cells, 777);
  EXPECT_EQ(back.bounds.resolution, 0.005);
}

TEST(TimeModelTest, FitRecoversExactCoefficients) {
  std::vector<TimingSample> s;
  TimeModel truth;
  truth.ms_fixed = 0.5;
  truth.ms_per_check = 0.002;
  truth.ms_per_check_box = 1e-4;
  truth.ms_per_check_near = 5e-5;
  for (long checks : {100L, 150L, 220L})
    for (long boxes : {50L, 800L, 12000L})
      for (double near : {10.0, 400.0}) {
        s.push_back({checks, boxes, near, truth.predict(checks, boxes, near)});
      }
  const TimeModel m = fit_time_model(s);
  EXPECT_NEAR(m.ms_fixed, truth.ms_fixed, 1e-6);
  EXPECT_NEAR(m.ms_per_check, truth.ms_per_check, 1e-8);
  EXPECT_NEAR(m.ms_per_check_box, truth.ms_per_check_box, 1e-10);
  EXPECT_NEAR(m.ms_per_check_near, truth.ms_per_check_near, 1e-10);
  EXPECT_NEAR(m.r2, 1.0, 1e-9);
  EXPECT_NEAR(m.median_rel_error, 0.0, 1e-9);
  EXPECT_EQ(m.samples, 18);
}

TEST(TimeModelTest, CoefficientsStayNonNegative) {
  // Time falling with the box count would need a negative coefficient: the fit drops that term.
  std::vector<TimingSample> s = {{100, 10, 0, 5.0}, {100, 1000, 0, 4.0}, {200, 10, 0, 9.0}};
  const TimeModel m = fit_time_model(s);
  for (double c : {m.ms_fixed, m.ms_per_check, m.ms_per_check_box, m.ms_per_check_near}) EXPECT_GE(c, 0);
  EXPECT_THROW(fit_time_model({s[0]}), InputError);
}

TEST(ObjectiveTest, ScoreByHandAndAggregates) {
  Objective o;  // lambda 1 %/s, mu 10, min width 0.1 rad
  CaseEval a;
  a.cf = 0.99;
  a.cost_ms = 500;
  a.wall_ms = 900;
  a.cpu_ms = 800;
  a.shortfall = 0.25;
  score_case(a, o);
  EXPECT_NEAR(a.score, 99 - 0.5 - 2.5, 1e-12);
  o.time = Objective::Time::kWall;
  score_case(a, o);
  EXPECT_NEAR(a.score, 99 - 0.9 - 2.5, 1e-12);
  o.time = Objective::Time::kCpu;
  score_case(a, o);
  EXPECT_NEAR(a.score, 99 - 0.8 - 2.5, 1e-12);
  CaseEval b;
  b.score = 90;
  EXPECT_NEAR(aggregate_score({a, b}, o), (a.score + 90) / 2, 1e-12);
  o.worst_case = true;
  EXPECT_EQ(aggregate_score({a, b}, o), 90);
}

TEST_F(TuningTest, WidthShortfallCountsCollapsedAsOneAndNarrowPartly) {
  const Scene scene = Scene::load(cell_);
  WaypointBounds w;
  w.q = Eigen::VectorXd::Zero(1);
  w.lower = Eigen::VectorXd::Constant(1, -0.02);
  w.upper = Eigen::VectorXd::Constant(1, 0.02);  // 0.04 rad wide: 60 % short of 0.1
  w.collapsed = {false};
  WaypointBounds c = w;
  c.collapsed = {true};  // widened by the guard: counts as fully short whatever its width
  WaypointBounds wide = w;
  wide.upper[0] = 1.0;
  CaseEval e;
  width_stats(scene, BoundsParams{}, {w, c, wide}, 0.1, e);
  EXPECT_EQ(e.bisected, 3);
  EXPECT_EQ(e.collapsed, 1);
  EXPECT_NEAR(e.shortfall, (0.6 + 1.0 + 0.0) / 3, 1e-12);
  EXPECT_NEAR(e.mean_width, (0.04 + 0.04 + 1.02) / 3, 1e-12);
}

TEST_F(TuningTest, EvaluationIsDeterministicWithTheProxy) {
  TuningCase c(CaseSpec{cell_, "a", "b"}, json::parse(read_text(base_)), 2, 500);
  TimeModel model;
  model.ms_fixed = 1;
  model.ms_per_check_box = 1e-4;
  model.ms_per_check_near = 1e-4;
  CfParams cf;
  cf.samples = 200;
  const Params p = c.cell_params();
  const CaseEval a = evaluate_case(c, p, cf, 1, 1, model, Objective{});
  const CaseEval b = evaluate_case(c, p, cf, 1, 2, model, Objective{});
  EXPECT_EQ(a.score, b.score);  // same CF seed (common random numbers), same proxy
  EXPECT_EQ(a.cf, b.cf);
  EXPECT_EQ(a.cost_ms, b.cost_ms);
  EXPECT_GT(a.checks, 0);
  EXPECT_GT(a.near, 0);
  EXPECT_EQ(a.bisected, 2);
}

// ---------------------------------------------------------------- the NLopt loop

// The tuned-variable space with two free variables, d_t_lb and d_t_ub, the others fixed.
tune::Space two_variable_space() {
  tune::Space s;
  for (const auto& v : tuned_variables()) {
    s.names.push_back(v.name);
    s.lower.push_back(v.lower);
    s.upper.push_back(v.upper);
  }
  s.start = variables_of(Params{});
  s.fixed.assign(s.start.size(), true);
  s.fixed[0] = s.fixed[1] = false;
  s.constraints = bound_constraints;
  s.constraint_count = 2;
  return s;
}

// Maximised at d_t_lb = 1.2, d_t_ub = 0.6: outside LB + gap <= UB, so the constrained optimum lies
// on the constraint, at d_t_lb = 0.875, d_t_ub = 0.925 (J = -0.2112...).
double pulled_apart(const std::vector<double>& x) {
  return -(x[0] - 1.2) * (x[0] - 1.2) - (x[1] - 0.6) * (x[1] - 0.6);
}

class SearchTest : public ::testing::TestWithParam<const char*> {};

TEST_P(SearchTest, ConstrainedOptimumIsReachedAndRespected) {
  tune::Settings settings;
  settings.stages = tune::parse_stages(GetParam(), 0.5);
  settings.budget_evals = 400;
  settings.population = 20;
  settings.infeasible_value = -100;
  std::vector<tune::Record> records;
  const auto out = tune::search(
      two_variable_space(), settings, [](const auto& x) { return std::optional(pulled_apart(x)); },
      [] { return false; }, [&](const tune::Record& r) { records.push_back(r); });
  ASSERT_FALSE(records.empty());
  EXPECT_EQ(records.front().stage, "start");
  EXPECT_GT(out.best, records.front().objective);                        // improved over the start
  EXPECT_LE(bound_constraints(out.best_x)[0], settings.constraint_tol);  // and the best is feasible
  EXPECT_NEAR(out.best, -0.21125, 0.01);
  EXPECT_NEAR(out.best_x[0], 0.875, 0.08);
  EXPECT_NEAR(out.best_x[1], 0.925, 0.08);
  for (const auto& r : records) {
    // Infeasible points are never run and never the best; fixed variables never move.
    if (!r.feasible) {
      EXPECT_EQ(r.objective, -100);
    }
    EXPECT_EQ(r.x[5], 1.5);
  }
}

INSTANTIATE_TEST_SUITE_P(Algorithms, SearchTest,
                         ::testing::Values("cobyla", "bobyqa", "isres+cobyla", "direct+cobyla"));

TEST(SearchBudgetTest, StopsAfterExactlyNEvaluations) {
  for (const char* algorithm : {"cobyla", "isres", "crs2+neldermead"}) {
    tune::Settings settings;
    settings.stages = tune::parse_stages(algorithm, 0.5);
    settings.budget_evals = 17;
    int calls = 0, records = 0;
    const auto out = tune::search(
        two_variable_space(), settings,
        [&](const auto& x) {
          ++calls;
          return std::optional(pulled_apart(x) + 1e-3 * calls);  // never the same value twice
        },
        [] { return false; }, [&](const tune::Record&) { ++records; });
    EXPECT_EQ(out.evaluations, 17) << algorithm;
    EXPECT_EQ(records, 17) << algorithm;
    EXPECT_LE(calls, 17) << algorithm;
    EXPECT_THAT(out.stop, HasSubstr("evaluation budget")) << algorithm;
  }
}

TEST(SearchBudgetTest, InterruptKeepsTheBestSoFar) {
  tune::Settings settings;
  settings.stages = tune::parse_stages("cobyla", 0.5);
  settings.budget_evals = 1000;
  int records = 0;
  const auto out = tune::search(
      two_variable_space(), settings, [](const auto& x) { return std::optional(pulled_apart(x)); },
      [&] { return records >= 5; }, [&](const tune::Record&) { ++records; });
  EXPECT_EQ(out.evaluations, 5);
  EXPECT_THAT(out.stop, HasSubstr("interrupted"));
  EXPECT_GE(out.best_number, 1);
  EXPECT_LE(out.best_number, 5);
}

TEST(SearchBudgetTest, UnknownStagesAndMissingBudgetsAreInputErrors) {
  EXPECT_THROW(tune::parse_stages("cobyla+simplex", 0.5), InputError);
  EXPECT_THROW(tune::parse_stages("isres+cobyla", 1.5), InputError);
  const auto stages = tune::parse_stages("isres+cobyla", 0.25);
  ASSERT_EQ(stages.size(), 2u);
  EXPECT_TRUE(stages[0].global);
  EXPECT_DOUBLE_EQ(stages[0].share, 0.25);
  EXPECT_DOUBLE_EQ(stages[1].share, 0.75);
  tune::Settings none;
  none.stages = stages;
  EXPECT_THROW(tune::search(
                   two_variable_space(), none, [](const auto&) { return std::optional(0.0); },
                   [] { return false; }, [](const tune::Record&) {}),
               InputError);
}

// ---------------------------------------------------------------- leeway-tune

// Known optimum: CF is 100 % and the intervals wide whatever MAX_cells, so with a heavy price on time
// the best MAX_cells is the smallest allowed (20); the thesis's map (500 here) scores far lower.
TEST_F(TuningTest, TheLoopImprovesOnTheStartTowardsTheKnownOptimum) {
  std::string fix;
  for (const char* v : {"d_t_lb=0.35", "d_t_ub=1.5", "d_g_lb=0.1", "d_g_ub=2", "d_ng_ub=0.5", "h_max=1.5",
                        "alpha_t=1", "alpha_g=1", "alpha_ng=1", "trail_margin=0"})
    fix += std::string(" --fix ") + v;
  // A given time proxy (1 us per check and box), so that the objective does not depend on how busy
  // the machine is: the smallest maps are then the optimum.
  const auto r =
      run_tune(quick("--lambda 10000 --time-model 0,0,0.001,0 --min-width 0 --budget-evals 15 "
                     "--recheck 2 --log " +
                     path("log.csv") + " --out " + path("t.json") + fix));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto objective = column(read_text(path("log.csv")), "objective");
  ASSERT_EQ(objective.size(), 15u);
  double best = -1e9;
  for (const auto& o : objective) best = std::max(best, std::stod(o));
  EXPECT_GT(best, std::stod(objective.front()) + 1.0) << r.out;
  const auto tuned = json::parse(read_text(path("t.json")));
  EXPECT_LE(tuned["height_map"]["max_cells"].get<int>(), 40) << r.out;
  EXPECT_THAT(r.out, HasSubstr("before / after"));
  EXPECT_THAT(r.out, HasSubstr("| cell:a:b | tuned |"));
  EXPECT_THAT(r.out, HasSubstr("recheck 1: search J"));
}

TEST_F(TuningTest, AGivenTimeModelSkipsTheCalibration) {
  const auto r = run_tune(quick("--time-model 1,0.01,0.001,0 --budget-evals 3 --no-summary"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("time proxy [ms] given: 1,0.01,0.001,0"));
  EXPECT_THAT(r.out, Not(HasSubstr("calibrating")));
  for (const char* bad : {"1,2,3", "1,2,3,-1", "1,2,nan,4"}) {
    const auto b = run_tune(quick(std::string("--time-model ") + bad + " --budget-evals 3"));
    EXPECT_EQ(b.exit_code, 2) << bad;
    EXPECT_THAT(b.out, HasSubstr("--time-model")) << bad;
  }
}

TEST_F(TuningTest, ABudgetOfNEvaluationsStopsAfterN) {
  const auto r =
      run_tune(quick("--budget-evals 6 --no-summary --log " + path("log.csv") + " --out " + path("t.json")));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("evaluation budget (6) used"));
  EXPECT_THAT(r.out, HasSubstr("[6/6]"));
  EXPECT_THAT(r.out, Not(HasSubstr("[7/")));
  const auto evals = column(read_text(path("log.csv")), "eval");
  ASSERT_EQ(evals.size(), 6u);
  EXPECT_EQ(evals.back(), "6");
}

TEST_F(TuningTest, ATimeBudgetAloneLiftsTheEvaluationBudget) {
  const auto r =
      run_tune(quick("--budget-seconds 0.3 --no-summary --algorithm isres --log " + path("log.csv")));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("time budget used"));
  EXPECT_THAT(r.out, Not(HasSubstr("/150]")));
  EXPECT_GE(column(read_text(path("log.csv")), "eval").size(), 2u);
}

TEST_F(TuningTest, TheTunedFileRoundTripsThroughLeewayBounds) {
  const std::string tuned = path("tuned.json");
  const auto r = run_tune(quick("--budget-evals 8 --no-summary --algorithm isres --out " + tuned));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const json t = json::parse(read_text(tuned));
  // Exactly what `leeway bounds --params` reads: it runs, and uses every tuned value.
  const auto b = test::run_cli("bounds " + cell_ + " --from a --to b --params " + tuned + " --json");
  ASSERT_EQ(b.exit_code, 0) << b.out;
  const json used = json::parse(b.out)["params"];
  EXPECT_EQ(used["height_map"]["max_cells"], t["height_map"]["max_cells"]);
  for (const auto& [key, value] : t["volume"].items()) EXPECT_EQ(used["volume"][key], value) << key;
  EXPECT_EQ(used["volume"]["reach_radius"], 1.5);  // from the base file, kept
  // The same bounds as the library computes with those parameters.
  const Scene scene = Scene::load(cell_);
  const Params p = read_params(tuned);
  VolumeModel world(scene, p.height_map.max_cells + 8);
  const auto run = compute_bounds(scene, world, keyframe_path(scene, "a", "b", 2), p, 1);
  const json wps = json::parse(b.out)["waypoints"];
  for (size_t w = 0; w < 2; ++w) {
    EXPECT_EQ(wps[w]["lower"][0].get<double>(), run.bounds[w].lower[0]);
    EXPECT_EQ(wps[w]["upper"][0].get<double>(), run.bounds[w].upper[0]);
  }
}

// --noise-study around a parameter file: the file's point first, then moves of at most radius x range
// per variable (d_t_lb: 0 .. 1.5 m, h_max: 0.2 .. 3 m), each feasible.
TEST_F(TuningTest, ANoiseStudyAroundAFileStaysWithinItsRadius) {
  const std::string center = dir_.write(
      "center.json",
      R"({"height_map": {"max_cells": 200}, "volume": {"d_t_lb": 0.6, "d_t_ub": 0.66, "h_max": 1.0}})");
  const std::string log = path("noise.csv");
  const auto r = run_tune(
      quick("--noise-study 4 --noise-center " + center + " --noise-radius 0.05 --seed 7 --log " + log));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string csv = read_text(log);
  const auto point = column(csv, "point"), d_t_lb = column(csv, "d_t_lb"), d_t_ub = column(csv, "d_t_ub"),
             h_max = column(csv, "h_max"), cells = column(csv, "max_cells");
  ASSERT_EQ(point.size(), 4u);  // one case, four points
  EXPECT_EQ(point[0], "1");
  EXPECT_DOUBLE_EQ(std::stod(d_t_lb[0]), 0.6);
  EXPECT_DOUBLE_EQ(std::stod(h_max[0]), 1.0);
  EXPECT_EQ(cells[0], "200");
  int moved = 0;
  for (size_t i = 1; i < 4; ++i) {
    EXPECT_LE(std::abs(std::stod(d_t_lb[i]) - 0.6), 0.05 * 1.5 + 1e-9) << i;
    EXPECT_LE(std::abs(std::stod(h_max[i]) - 1.0), 0.05 * 2.8 + 1e-9) << i;
    EXPECT_LE(std::stod(d_t_lb[i]) + kMinBoundGap, std::stod(d_t_ub[i]) + 1e-9) << i;  // feasible
    moved += std::stod(h_max[i]) != 1.0;
  }
  EXPECT_EQ(moved, 3);
  // Bad centres fail before the calibration: outside the ranges, or infeasible.
  const std::string far = dir_.write("far.json", R"({"volume": {"h_max": 5.0}})");
  const auto outside = run_tune(quick("--noise-study 2 --noise-center " + far + " --log " + log));
  EXPECT_EQ(outside.exit_code, kExitBadInput);
  EXPECT_THAT(outside.out, HasSubstr("--noise-center " + far + ": 'h_max' = 5 lies outside its range"));
  EXPECT_THAT(outside.out, Not(HasSubstr("calibrating")));
  const auto no_study = run_tune(quick("--budget-evals 2 --noise-center " + center));
  EXPECT_EQ(no_study.exit_code, kExitBadInput);
  EXPECT_THAT(no_study.out, HasSubstr("--noise-center needs --noise-study K"));
  const auto radius = run_tune(quick("--noise-study 2 --noise-radius 0 --log " + log));
  EXPECT_EQ(radius.exit_code, kExitBadInput);
  EXPECT_THAT(radius.out, HasSubstr("--noise-radius must be in (0, 1]"));
}

TEST_F(TuningTest, BadCasesFailBeforeAnyEvaluation) {
  const std::string log = path("log.csv");
  const auto unknown = run_tune(quick("--case " + cell_ + ":a:nowhere --budget-evals 5 --log " + log));
  EXPECT_EQ(unknown.exit_code, kExitBadInput);
  EXPECT_THAT(unknown.out, HasSubstr("leeway-tune: error: tuning case '" + cell_ + ":a:nowhere': "));
  EXPECT_THAT(unknown.out, HasSubstr("no keyframe 'nowhere'"));
  EXPECT_THAT(unknown.out, Not(HasSubstr("[1")));  // no evaluation, no calibration
  EXPECT_THAT(unknown.out, Not(HasSubstr("calibrating")));
  EXPECT_FALSE(std::filesystem::exists(log));
  const auto missing = run_tune(quick("--case " + path("nope.xml") + ":a:b --budget-evals 5"));
  EXPECT_EQ(missing.exit_code, kExitBadInput);
  EXPECT_THAT(missing.out, HasSubstr("nope.xml: no such file"));
  EXPECT_THAT(missing.out, Not(HasSubstr("calibrating")));
  const auto malformed = run_tune("--case " + cell_ + ":a --budget-evals 5");
  EXPECT_EQ(malformed.exit_code, kExitBadInput);
  EXPECT_THAT(malformed.out, HasSubstr("must be CELL.xml:FROM:TO"));
  const auto bad_fix = run_tune(quick("--fix d_t_lb=2 --fix d_t_ub=1"));
  EXPECT_EQ(bad_fix.exit_code, kExitBadInput);
  EXPECT_THAT(bad_fix.out, HasSubstr("violates d_t_lb"));
}

TEST_F(TuningTest, SigintStopsTheSearchAndKeepsTheBestWritten) {
  const std::string log = path("log.csv"), out = path("t.json");
  std::vector<std::string> args = {tune_program(),
                                   "--case",
                                   cell_ + ":a:b",
                                   "--params",
                                   base_,
                                   "--range",
                                   "max_cells=20:500",
                                   "--cf-samples",
                                   "400",
                                   "--final-samples",
                                   "100",
                                   "--final-repeats",
                                   "1",
                                   "--budget-evals",
                                   "100000",
                                   "--algorithm",
                                   "isres",
                                   "--log",
                                   log,
                                   "--out",
                                   out};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  // Wait for a few evaluations, then interrupt.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline &&
         (!std::filesystem::exists(log) || lines_of(read_text(log)).size() < 5))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  // The file holds the best logged evaluation.
  const std::string csv = read_text(log);
  const auto objective = column(csv, "objective"), feasible = column(csv, "feasible"),
             cells = column(csv, "max_cells");
  ASSERT_GE(objective.size(), 4u);
  size_t best = 0;
  for (size_t i = 0; i < objective.size(); ++i)
    if (feasible[i] == "1" && std::stod(objective[i]) > std::stod(objective[best])) best = i;
  const json t = json::parse(read_text(out));
  EXPECT_EQ(t["height_map"]["max_cells"].get<int>(), std::stoi(cells[best]));
  EXPECT_NEAR(t["volume"]["d_t_lb"].get<double>(), std::stod(column(csv, "d_t_lb")[best]), 1e-8);
}

}  // namespace
}  // namespace leeway
