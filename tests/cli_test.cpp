// The command-line program as a user runs it: exit codes, messages, JSON.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::run_cli;
using test::workcell;
using ::testing::HasSubstr;

TEST(CliTest, CheckExitCodes) {
  test::TempDir dir;
  EXPECT_EQ(run_cli("check " + workcell("dallara")).exit_code, 0);
  const std::string bad =
      dir.write("hit.xml", one_link_cell(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)",
                                         R"(<key name="left" qpos="1.5707963"/>)"));
  const auto r = run_cli("check " + bad);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.out, HasSubstr("collides with obstacle 'wall'"));
}

TEST(CliTest, CheckJsonIsOneObject) {
  const auto r = run_cli("check --json " + workcell("baltico"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.at("ok").get<bool>());
  EXPECT_EQ(j.at("keyframes").size(), 3u);
  EXPECT_EQ(j.at("goals").size(), 2u);
  EXPECT_EQ(j.at("robot").at("joints").size(), 6u);
}

TEST(CliTest, BadInputsExitTwoWithOneMessage) {
  test::TempDir dir;
  struct Case {
    std::string args;
    std::vector<std::string> fragments;
  };
  const std::string nan_key = dir.write("nan.xml", one_link_cell("", R"(<key name="k" qpos="nan"/>)"));
  const std::string short_key = dir.write("short.xml", one_link_cell("", R"(<key name="k" qpos="0 0"/>)"));
  const std::string malformed = dir.write("bad.xml", "<mujoco><worldbody>");
  const std::string no_robot = dir.write(
      "norobot.xml", R"(<mujoco><worldbody><geom name="t" type="box" size="1 1 1"/></worldbody></mujoco>)");
  const std::vector<Case> cases = {
      {"check " + dir.path().string() + "/absent.xml", {"absent.xml", "cannot open"}},
      {"check " + malformed, {"bad.xml", "does not compile"}},
      {"check " + no_robot, {"norobot.xml", "no robot joints"}},
      {"check " + nan_key, {"nan.xml", "key 'k' qpos 'nan' is not finite"}},
      {"check " + short_key, {"short.xml", "qpos size"}},
      {"fk " + workcell("dallara") + " --q \"0 0 nan 0 0 0\"", {"dallara.xml --q", "'nan'"}},
      {"fk " + workcell("dallara") + " --q \"0 0 inf 0 0 0\"", {"'inf'", "not finite"}},
      {"fk " + workcell("dallara") + " --q \"0 0 0\"", {"3 values given", "has 6 joints"}},
      {"fk " + workcell("dallara") + " --key nowhere", {"no keyframe 'nowhere'", "'home'"}},
      {"ik " + workcell("dallara") + " --site nowhere", {"no goal site 'nowhere'", "'patch'"}},
      {"frobnicate", {"frobnicate"}},
  };
  for (const auto& c : cases) {
    const auto r = run_cli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    for (const auto& f : c.fragments) EXPECT_THAT(r.out, HasSubstr(f)) << c.args;
  }
}

TEST(CliTest, FkJsonMatchesThePublishedPosition) {
  const auto r = run_cli("fk " + workcell("dallara") +
                         " --json --q \"-1.11219 0.734922 0.0866255 -3.14159 -0.749248 -1.11219\"");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j.at("position")[0].get<double>(), 0.943, 1e-3);
  EXPECT_NEAR(j.at("position")[1].get<double>(), -1.910, 1e-3);
  EXPECT_NEAR(j.at("position")[2].get<double>(), 0.800, 1e-3);
  EXPECT_NEAR(j.at("rotation")[2][2].get<double>(), -1.0, 1e-5);
}

TEST(CliTest, IkFindsTheMouldSite) {
  const auto r = run_cli("ik " + workcell("dallara") + " --site mould --seed-key mould --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.at("success").get<bool>());
  EXPECT_LT(j.at("position_error").get<double>(), 1e-4);
}

TEST(CliTest, HelpOnEverySubcommand) {
  for (const char* sub : {"", "check", "fk", "ik"}) {
    const auto r = run_cli(std::string(sub) + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub;
    EXPECT_THAT(r.out, HasSubstr("--help")) << sub;
  }
}

}  // namespace
}  // namespace leeway
