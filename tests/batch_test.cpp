// leeway batch: suites with passing, failing and erroring scenarios, the JUnit report
// parsed as a CI server would, bad suites refused before anything runs, and the same results over
// MPI ranks (when mpirun was found at configure time).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "leeway/apps/batch.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using json = nlohmann::json;

// ------------------------------------------------------------------ a tiny XML reader for the tests

// An element: name, attributes, text (entities decoded) and children.
struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
  std::vector<std::unique_ptr<Element>> children;
  std::vector<const Element*> all(const std::string& child) const {
    std::vector<const Element*> out;
    for (const auto& c : children)
      if (c->name == child) out.push_back(c.get());
    return out;
  }
  const Element* first(const std::string& child) const {
    const auto a = all(child);
    return a.empty() ? nullptr : a.front();
  }
};

// Parses the XML this project writes: a declaration, elements, attributes in double quotes, text and
// the five entities. Throws std::runtime_error on anything malformed (an unknown entity, a raw '<' or
// '&', mismatched tags), so a test fails when the report would not load in a CI server.
class XmlReader {
 public:
  explicit XmlReader(std::string text) : s_(std::move(text)) {}
  std::unique_ptr<Element> document() {
    skip_space();
    if (s_.compare(i_, 5, "<?xml") == 0) i_ = s_.find("?>", i_) + 2;
    skip_space();
    auto root = element();
    skip_space();
    if (i_ != s_.size()) fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("XML at byte " + std::to_string(i_) + ": " + what);
  }
  void skip_space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  std::string name() {
    const size_t b = i_;
    while (i_ < s_.size() &&
           (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '-' || s_[i_] == '_'))
      ++i_;
    if (b == i_) fail("a name expected");
    return s_.substr(b, i_ - b);
  }
  std::string decode(const std::string& raw) const {
    std::string out;
    for (size_t k = 0; k < raw.size(); ++k) {
      if (raw[k] == '<') fail("a raw '<' in text");
      if (raw[k] != '&') {
        out += raw[k];
        continue;
      }
      const size_t end = raw.find(';', k);
      if (end == std::string::npos) fail("an unterminated entity");
      const std::string e = raw.substr(k + 1, end - k - 1);
      static const std::map<std::string, char> kEntities = {
          {"amp", '&'}, {"lt", '<'}, {"gt", '>'}, {"quot", '"'}, {"apos", '\''}};
      if (!kEntities.count(e)) fail("unknown entity &" + e + ";");
      out += kEntities.at(e);
      k = end;
    }
    return out;
  }
  std::unique_ptr<Element> element() {
    if (s_[i_] != '<') fail("'<' expected");
    ++i_;
    auto el = std::make_unique<Element>();
    el->name = name();
    for (;;) {
      skip_space();
      if (s_.compare(i_, 2, "/>") == 0) {
        i_ += 2;
        return el;
      }
      if (s_[i_] == '>') {
        ++i_;
        break;
      }
      const std::string key = name();
      if (s_.compare(i_, 2, "=\"") != 0) fail("=\" expected after attribute " + key);
      i_ += 2;
      const size_t end = s_.find('"', i_);
      if (end == std::string::npos) fail("an unterminated attribute");
      if (el->attributes.count(key)) fail("attribute " + key + " twice");
      el->attributes[key] = decode(s_.substr(i_, end - i_));
      i_ = end + 1;
    }
    for (;;) {
      const size_t lt = s_.find('<', i_);
      if (lt == std::string::npos) fail("unterminated element " + el->name);
      el->text += decode(s_.substr(i_, lt - i_));
      i_ = lt;
      if (s_.compare(i_, 2, "</") == 0) {
        i_ += 2;
        if (name() != el->name) fail("mismatched end tag of " + el->name);
        skip_space();
        if (s_[i_] != '>') fail("'>' expected");
        ++i_;
        return el;
      }
      el->children.push_back(element());
    }
  }
  std::string s_;
  size_t i_ = 0;
};

using test::read_text;

// Every "timing" object removed: what must be the same on any number of ranks.
json without_timing(json j) {
  if (j.is_object()) {
    j.erase("timing");
    for (auto& [k, v] : j.items()) v = without_timing(v);
  } else if (j.is_array()) {
    for (auto& v : j) v = without_timing(v);
  }
  return j;
}

TEST(XmlEscapeTest, EscapesTheFiveCharactersAndDropsControlCharacters) {
  EXPECT_EQ(xml_escape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
  EXPECT_EQ(xml_escape(std::string("x\x01y\nz")), "x?y\nz");
}

// The suite of the nine thesis paths that ships in suites/ is valid.
TEST(ThesisSuiteTest, ReadsAndValidatesItsNineScenarios) {
  install_mujoco_error_handlers();
  const Suite suite = read_suite(std::string(LEEWAY_MJCF_DIR) + "/../suites/thesis.json");
  EXPECT_EQ(suite.name, "thesis");
  ASSERT_EQ(suite.scenarios.size(), 9u);
  for (const auto& s : suite.scenarios) {
    EXPECT_EQ(s.expect.check, true) << s.name;
    EXPECT_EQ(s.expect.certified, true) << s.name;
    EXPECT_TRUE(s.expect.cf_min && s.expect.mean_width_min && s.expect.time_max) << s.name;
  }
}

// ------------------------------------------------------------------ the suites

// The one-link cell of the tuning tests: keyframes a and b, a table under the tool at b.
const char* kWorld = R"(
    <geom name="table" type="box" size="0.2 0.2 0.2" pos="0.54 0.84 0.2"/>
    <geom name="pillar" type="box" size="0.1 0.1 0.4" pos="-0.2 -0.9 0.4"/>)";
const char* kKeys = R"(<key name="a" qpos="0"/>
    <key name="b" qpos="1.0"/>)";

class BatchTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    test::MujocoTest::SetUp();
    dir_.write("cell.xml", test::one_link_cell(kWorld, kKeys));
  }
  // A suite in the test's folder; the cell is "cell.xml" beside it. Defaults keep runs to milliseconds.
  std::string suite(const json& scenarios, const std::string& name = "suite.json") const {
    const json s = {{"format", "leeway-suite-1"},
                    {"name", "tiny"},
                    {"defaults",
                     {{"cell", "cell.xml"},
                      {"params", {{"height_map", {{"max_cells", 500}}}, {"volume", {{"reach_radius", 1.5}}}}},
                      {"cf", {{"windows", 4}, {"samples", 200}}}}},
                    {"scenarios", scenarios}};
    return dir_.write(name, s.dump(2));
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  // The scenario that meets its expectations (a name that needs escaping in XML); its time limit of 0 s
  // is only a warning.
  static json passing() {
    return {{"name", "a<b & \"c\""},
            {"from", "a"},
            {"to", "b"},
            {"expect", {{"cf_min", 0.5}, {"mean_width_min", 0.01}, {"time_max", 0}}}};
  }
  test::TempDir dir_;
};

TEST_F(BatchTest, PassingFailingAndErroringScenariosGiveExitOneAndTheirJUnitTestcases) {
  const json scenarios = {
      passing(),
      {{"name", "too-narrow"}, {"from", "b"}, {"to", "a"}, {"expect", {{"mean_width_min", 50}}}},
      {{"name", "unreachable"}, {"from", "a"}, {"to", "xyz:5,5,5"}, {"expect", {{"cf_min", 0.5}}}}};
  const auto r = test::run_cli("batch " + suite(scenarios) + " --junit " + path("report.xml") + " --out " +
                               path("results.json") + " --threads 1");
  ASSERT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("[3/3]"));
  EXPECT_THAT(r.out, HasSubstr("1 passed, 1 failed, 1 error, 1 time warning"));

  const auto xml = XmlReader(read_text(path("report.xml"))).document();
  ASSERT_EQ(xml->name, "testsuites");
  const Element* ts = xml->first("testsuite");
  ASSERT_NE(ts, nullptr);
  // run + 3 expectations; run + 1; run + 1 (skipped).
  EXPECT_EQ(ts->attributes.at("tests"), "8");
  EXPECT_EQ(ts->attributes.at("failures"), "1");
  EXPECT_EQ(ts->attributes.at("errors"), "1");
  EXPECT_EQ(ts->attributes.at("skipped"), "1");
  std::map<std::string, const Element*> cases;  // "classname/name"
  for (const Element* c : ts->all("testcase"))
    cases[c->attributes.at("classname") + "/" + c->attributes.at("name")] = c;
  ASSERT_EQ(cases.size(), 8u);
  const std::string pass = "tiny.a<b & \"c\"";
  for (const char* name : {"/run", "/CF >= 0.5", "/mean width >= 0.01 rad"}) {
    ASSERT_TRUE(cases.count(pass + name)) << name;
    EXPECT_TRUE(cases[pass + name]->children.empty()) << name;
  }
  const Element* slow = cases.at(pass + "/time <= 0 s (soft)");
  ASSERT_NE(slow->first("system-out"), nullptr);
  EXPECT_THAT(slow->first("system-out")->text, HasSubstr("warning: the method took"));
  EXPECT_EQ(slow->first("failure"), nullptr);

  const Element* narrow = cases.at("tiny.too-narrow/mean width >= 50 rad");
  ASSERT_NE(narrow->first("failure"), nullptr);
  EXPECT_THAT(narrow->first("failure")->attributes.at("message"), HasSubstr("measured "));
  EXPECT_THAT(narrow->first("failure")->attributes.at("message"),
              HasSubstr(", expected mean width >= 50 rad"));
  EXPECT_TRUE(cases.at("tiny.too-narrow/run")->children.empty());

  const Element* error = cases.at("tiny.unreachable/run");
  ASSERT_NE(error->first("error"), nullptr);
  EXPECT_THAT(error->first("error")->attributes.at("message"), HasSubstr("unreachable"));
  EXPECT_NE(cases.at("tiny.unreachable/CF >= 0.5")->first("skipped"), nullptr);

  const json results = test::read_json(path("results.json"));
  EXPECT_EQ(results["counts"], json({{"scenarios", 3}, {"passed", 1}, {"failed", 1}, {"errors", 1}}));
  ASSERT_EQ(results["scenarios"].size(), 3u);
  EXPECT_EQ(results["scenarios"][0]["name"], "a<b & \"c\"");
  EXPECT_EQ(results["scenarios"][1]["expectations"][0]["passed"], false);
  EXPECT_GT(results["scenarios"][1]["expectations"][0]["measured"].get<double>(), 0.0);
  EXPECT_EQ(results["scenarios"][2]["status"], "error");
}

TEST_F(BatchTest, ASuiteWhoseExpectationsAllHoldExitsZero) {
  const auto r = test::run_cli("batch " + suite(json::array({passing()})) + " --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("1 passed, 0 failed, 0 errors"));
}

// The closed loop in a suite: a co-worker pushing the one-link arm toward the table inside its
// certified bounds makes no contact; an expectation of 50 m of clearance fails with the measured
// distance.
TEST_F(BatchTest, SimulateExpectationsJudgeTheClosedLoop) {
  const json push = {{"human", "push-toward"}, {"target", "table"}, {"amplitude", 80}};
  const json scenarios = {{{"name", "held"},
                           {"from", "a"},
                           {"to", "b"},
                           {"simulate", push},
                           {"expect", {{"simulate", {{"contacts", 0}, {"min_distance", 0.0005}}}}}},
                          {{"name", "far"},
                           {"from", "a"},
                           {"to", "b"},
                           {"simulate", push},
                           {"expect", {{"simulate", {{"min_distance", 50}}}}}}};
  const auto r =
      test::run_cli("batch " + suite(scenarios) + " --out " + path("results.json") + " --threads 1");
  ASSERT_EQ(r.exit_code, 1) << r.out;
  const json results = test::read_json(path("results.json"));
  const json& held = results["scenarios"][0];
  EXPECT_EQ(held["passed"], true) << held.dump(1);
  EXPECT_EQ(held["measured"]["simulate_contacts"], 0);
  EXPECT_EQ(held["measured"]["simulate_left_bounds"], false);
  EXPECT_GE(held["measured"]["simulate_min_distance"].get<double>(), 0.0005);
  EXPECT_LT(held["measured"]["simulate_min_distance"].get<double>(), 0.5);  // it was pushed close
  const json& far = results["scenarios"][1];
  EXPECT_EQ(far["passed"], false);
  EXPECT_EQ(far["expectations"][0]["title"], "simulated min distance >= 50 m");
  EXPECT_EQ(far["expectations"][0]["measured"], held["measured"]["simulate_min_distance"]);
}

TEST_F(BatchTest, RoomExpectationsJudgeTheKeptShareAndTheToolsRoom) {
  const json scenarios = {
      {{"name", "roomy"},
       {"from", "a"},
       {"to", "b"},
       {"expect", {{"room", {{"mean_share_min", 0.01}, {"tool_translation_min", 0.001}}}}}},
      {{"name", "greedy"}, {"from", "a"}, {"to", "b"}, {"expect", {{"room", {{"mean_share_min", 1.0}}}}}}};
  const auto r =
      test::run_cli("batch " + suite(scenarios) + " --out " + path("results.json") + " --threads 1");
  ASSERT_EQ(r.exit_code, 1) << r.out;
  const json results = test::read_json(path("results.json"));
  const json& roomy = results["scenarios"][0];
  EXPECT_EQ(roomy["passed"], true) << roomy.dump(1);
  const double share = roomy["measured"]["room_mean_share"].get<double>();
  EXPECT_GT(share, 0.01);
  EXPECT_LE(share, 1.0);
  // The same bounds through `leeway bounds` give the same room.
  // (The suite's default parameters, as a parameter file.)
  const std::string params =
      dir_.write("params.json", R"({"height_map": {"max_cells": 500}, "volume": {"reach_radius": 1.5}})");
  const auto b =
      test::run_cli("bounds " + path("cell.xml") + " --from a --to b --json --threads 1 --params " + params);
  ASSERT_EQ(b.exit_code, 0) << b.out;
  const json bounds = json::parse(b.out);
  EXPECT_DOUBLE_EQ(bounds["room"]["mean_share"].get<double>(), share);
  EXPECT_DOUBLE_EQ(bounds["room"]["waypoints"].back()["tool_translation"].get<double>(),
                   roomy["measured"]["room_goal_tool_translation"].get<double>());
  const json& greedy = results["scenarios"][1];
  EXPECT_EQ(greedy["passed"], false);
  EXPECT_EQ(greedy["expectations"][0]["title"], "room: mean kept share >= 1");
  EXPECT_EQ(greedy["expectations"][0]["measured"], roomy["measured"]["room_mean_share"]);
}

TEST_F(BatchTest, ABadSuiteIsExitTwoBeforeAnyScenarioRunsAndWritesNothing) {
  json second = {{"name", "second"}, {"from", "a"}, {"to", "b"}};
  const auto with = [&](const std::string& key, const json& value) {
    json s = second;
    s[key] = value;
    return s;
  };
  const std::vector<std::pair<json, std::string>> bad = {
      {{passing(), with("to", "nowhere")},
       "scenario 2 'second': field 'to': " + path("cell.xml") + ": no keyframe 'nowhere'"},
      {{passing(), with("expect", {{"cf_mni", 0.9}})},
       "scenario 2 'second': field 'expect.cf_mni' is not a known key"},
      {{passing(), with("expect", {{"cf_min", 1.5}})},
       "scenario 2 'second': field 'expect.cf_min' 1.5 must be"},
      {{passing(), with("expect", {{"room", {{"share", 0.3}}}})},
       "scenario 2 'second': field 'expect.room.share' is not a known key"},
      {{passing(), with("expect", {{"room", {{"mean_share_min", 30}}}})},
       "scenario 2 'second': field 'expect.room.mean_share_min' 30 must be"},
      {{passing(), with("colour", "red")}, "scenario 2 'second': field 'colour' is not a known key"},
      {{passing(), with("max_cells", -3)},
       "scenario 2 'second': field 'max_cells' -3 must be a whole number"},
      {{passing(), with("safety", "maybe")}, "field 'safety' 'maybe' must be one of"},
      {{passing(), with("name", "a<b & \"c\"")}, "field 'name' 'a<b & \"c\"' is used by an earlier scenario"},
      {{passing(), with("path", "missing.json")}, "field 'path' excludes 'from' and 'to'"},
      {{passing(), with("params", {{"volume", {{"h_max", -1}}}})}, "scenario 2 'second': field 'params': "},
      {{passing(), with("params", 7)}, "field 'params' must be a parameter file's name or an object"},
      // Joint names are checked against the scenario's robot before any scenario runs.
      {{passing(), with("params", {{"bounds", {{"bisect", json::array({"elbow"})}}}})},
       "scenario 2 'second': field 'params': " + path("cell.xml") +
           ": parameter 'bounds.bisect' names joint 'elbow', which the robot does not have (joints: j1)"},
      {{passing(), with("params", {{"bounds", {{"half_width", {{"j1", 0.1}}}}}})},
       "scenario 2 'second': field 'params': " + path("cell.xml") +
           ": parameter 'bounds.half_width.j1' = 0.1: joint 'j1' is bisected"},
      {{passing(), with("simulate", {{"human", "shove"}})}, "field 'simulate.human' 'shove' must be one of"},
      {{passing(), with("simulate", {{"human", "push-toward"}})}, "field 'simulate.target' is missing"},
      {{passing(), with("simulate", {{"amplitude", 1e6}})}, "field 'simulate.amplitude' 1000000.0 must be"},
      {{passing(), with("expect", {{"simulate", {{"contacts", -1}}}})},
       "field 'expect.simulate.contacts' -1 must be a whole number"},
      {{passing(), with("expect", {{"simulate", {{"touches", 0}}}})},
       "field 'expect.simulate.touches' is not a known key"},
  };
  for (const auto& [scenarios, message] : bad) {
    const auto r =
        test::run_cli("batch " + suite(scenarios) + " --junit " + path("r.xml") + " --out " + path("r.json"));
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_THAT(r.out, HasSubstr(message));
    EXPECT_THAT(r.out, Not(HasSubstr("[1/")));
    EXPECT_FALSE(std::filesystem::exists(path("r.xml")));
    EXPECT_FALSE(std::filesystem::exists(path("r.json")));
  }
  // The output files are checked before anything runs too.
  const auto txt = test::run_cli("batch " + suite(json::array({passing()})) + " --junit " + path("r.txt"));
  EXPECT_EQ(txt.exit_code, 2) << txt.out;
  EXPECT_THAT(txt.out, HasSubstr("--junit " + path("r.txt") + ": the file name must end in .xml"));
  EXPECT_THAT(txt.out, Not(HasSubstr("[1/")));
  // The top level too.
  const std::string no_format = dir_.write("f.json", R"({"scenarios": []})");
  const auto r = test::run_cli("batch " + no_format);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.out, HasSubstr("f.json: field 'format' must be \"leeway-suite-1\""));
}

#ifdef LEEWAY_MPIRUN
// mpirun with two ranks on this machine (as root too, where the tests run in containers).
std::string mpirun() {
  return std::string(LEEWAY_MPIRUN) + " --oversubscribe" + (::getuid() == 0 ? " --allow-run-as-root" : "") +
         " -np 2 ";
}

TEST_F(BatchTest, TwoMpiRanksGiveTheSingleProcessResultsByteForByte) {
  json scenarios = json::array();
  for (int i = 0; i < 4; ++i)
    scenarios.push_back({{"name", "s" + std::to_string(i)},
                         {"from", i % 2 ? "a" : "b"},
                         {"to", i % 2 ? "b" : "a"},
                         {"max_cells", 200 + 100 * i},
                         {"expect", {{"cf_min", 0.5}}}});
  scenarios.push_back({{"name", "unreachable"}, {"from", "a"}, {"to", "xyz:5,5,5"}});
  const std::string s = suite(scenarios);
  const auto one = test::run_cli("batch " + s + " --threads 1 --out " + path("one.json"));
  ASSERT_EQ(one.exit_code, 1) << one.out;
  const auto two =
      test::run_program(mpirun() + LEEWAY_CLI, "batch " + s + " --threads 1 --out " + path("two.json") +
                                                   " --junit " + path("two.xml"));
  ASSERT_EQ(two.exit_code, 1) << two.out;
  EXPECT_THAT(two.out, HasSubstr("on 2 ranks"));
  EXPECT_THAT(two.out, HasSubstr("on rank 1"));
  const std::string a = without_timing(test::read_json(path("one.json"))).dump(2);
  const std::string b = without_timing(test::read_json(path("two.json"))).dump(2);
  EXPECT_EQ(a, b);
  EXPECT_NO_THROW(XmlReader(read_text(path("two.xml"))).document());
}

TEST_F(BatchTest, ABadSuiteUnderMpiStopsEveryRankWithExitTwo) {
  const auto r = test::run_program(
      mpirun() + LEEWAY_CLI, "batch " + suite({passing(), {{"name", "x"}}}) + " --out " + path("r.json"));
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("scenario 2 'x': field 'from' is missing"));
  EXPECT_FALSE(std::filesystem::exists(path("r.json")));
}

TEST_F(BatchTest, LeewayTuneOnTwoMpiRanksSearchesAsOneProcess) {
  // lambda 0: the objective leaves out time, so it does not depend on the calibration either.
  const std::string tune = (std::filesystem::path(LEEWAY_CLI).parent_path() / "leeway-tune").string();
  const std::string base =
      dir_.write("base.json", R"({"height_map": {"max_cells": 500}, "volume": {"reach_radius": 1.5}})");
  const std::string cell = path("cell.xml");
  const auto args = [&](const std::string& tag) {
    return "--case " + cell + ":a:b --case " + cell + ":b:a --params " + base +
           " --range max_cells=20:500 --cf-samples 100 --lambda 0 --budget-evals 8 --algorithm isres "
           "--no-summary"
           " --out " +
           path(tag + ".json") + " --log " + path(tag + ".csv");
  };
  const auto one = test::run_program(tune, args("one"));
  ASSERT_EQ(one.exit_code, 0) << one.out;
  const auto two = test::run_program(mpirun() + tune, args("two"));
  ASSERT_EQ(two.exit_code, 0) << two.out;
  EXPECT_THAT(two.out, HasSubstr("cases spread over 2 MPI ranks"));
  EXPECT_THAT(one.out, Not(HasSubstr("MPI ranks")));
  EXPECT_EQ(read_text(path("one.json")), read_text(path("two.json")));
  // The log row by row: the variables, CF, widths and objective (not the measured times).
  const auto columns = [&](const std::string& tag) {
    std::istringstream in(read_text(path(tag + ".csv")));
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
      rows.emplace_back();
      std::stringstream ls(line);
      for (std::string x; std::getline(ls, x, ',');) rows.back().push_back(x);
    }
    std::string out;
    for (size_t i = 1; i < rows.size(); ++i)
      for (size_t k = 0; k < rows[0].size() && k < rows[i].size(); ++k)
        for (const char* name : {"eval", "max_cells", "cf_mean", "cf_min", "mean_width", "objective", "best"})
          if (rows[0][k] == name) out += rows[0][k] + "=" + rows[i][k] + " ";
    return out;
  };
  EXPECT_THAT(columns("one"), HasSubstr("eval=8 "));
  EXPECT_EQ(columns("one"), columns("two"));
}
#endif

}  // namespace
}  // namespace leeway
