// The closed loop: the one-joint MPC against answers worked out by hand, and `simulate` on a one-link
// arm beside a wall whose bounds are known, on the Dallara cell with the default bounds (no contact,
// never outside the bounds, checked at every control period from outside the simulation) and with
// the thesis preset's bounds where its CF is below 100 % (the adversarial push finds a contact).
#include "leeway/core/simulate.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/joint_mpc.hpp"
#include "leeway/io/bounds_file.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::error_of;
using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------------
// JointMpc

// One stage, loose limits: the cost (q1 - r)^2 + c a^2 with q1 = q0 + h v0 + h^2 a / 2 is least at
// a = (r - q0 - h v0) g / (g^2 + c), g = h^2 / 2.
TEST(JointMpc, OneStageMatchesTheClosedForm) {
  JointMpcOptions o;
  o.horizon = 1;
  o.first_period = 0.01;
  o.max_speed = 100;
  o.max_accel = 100;
  o.iterations = 400;
  JointMpc mpc(o);
  const Eigen::VectorXd r = Eigen::VectorXd::Constant(1, 0.001);
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(1, -10), hi = Eigen::VectorXd::Constant(1, 10);
  const double g = 0.01 * 0.01 / 2, c = o.accel_weight;
  const double expected = 0.001 * g / (g * g + c);
  const JointPlan plan = mpc.solve(0, 0, r, lo, hi);
  EXPECT_NEAR(plan.accel[0], expected, 1e-6 * std::abs(expected));
  EXPECT_NEAR(plan.position[0], g * plan.accel[0], 1e-12);
  EXPECT_NEAR(plan.speed[0], 0.01 * plan.accel[0], 1e-12);
}

// Driven toward a reference beyond its upper bound, a joint run with the plan's first acceleration
// stops at the bound: it brakes in time (v^2 / 2 a_max = 0.125 m from full speed, more than the
// 0.48 s horizon's reach at the start), never exceeds the speed limit, and ends on the bound.
TEST(JointMpc, StopsAtTheBoundWithinTheLimits) {
  JointMpcOptions o;
  o.max_speed = 1.0;
  o.max_accel = 4.0;
  JointMpc mpc(o);
  const int n = o.horizon;
  const Eigen::VectorXd r = Eigen::VectorXd::Constant(n, 1.0);
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(n, -1), hi = Eigen::VectorXd::Constant(n, 0.3);
  double q = 0, v = 0, max_q = 0, max_v = 0;
  const double h = 0.01;
  for (int i = 0; i < 150; ++i) {
    const double a = mpc.solve(q, v, r, lo, hi).accel[0];
    EXPECT_LE(std::abs(a), 4.0 * 1.05) << "step " << i;
    q += h * v + 0.5 * h * h * a;
    v += h * a;
    max_q = std::max(max_q, q);
    max_v = std::max(max_v, std::abs(v));
  }
  EXPECT_NEAR(q, 0.3, 1e-4);
  EXPECT_LT(max_q, 0.3 + 1e-3);  // the overshoot stays under the simulation's 1 mrad plan margin
  EXPECT_LE(max_v, 1.0 + 1e-3);
  EXPECT_GT(max_v, 0.9);  // it did go at (nearly) full speed
}

TEST(JointMpc, RefusesOptionsOutOfRange) {
  JointMpcOptions o;
  o.horizon = 0;
  EXPECT_THAT(error_of([&] { JointMpc m(o); }), HasSubstr("horizon 0"));
  o = {};
  o.max_accel = std::nan("");
  EXPECT_THAT(error_of([&] { JointMpc m(o); }), HasSubstr("max_accel"));
}

// ---------------------------------------------------------------------------------------------
// The one-link arm beside a wall (tests/test_util.hpp): the link's corner (1, 0.05) in the link's
// frame is at y = sqrt(1.0025) sin(q + atan(0.05)), and the wall's face is at y = 0.5, so the link
// is `clearance` from the wall at q = asin((0.5 - clearance) / sqrt(1.0025)) - atan(0.05).
const char* kWall = R"(<geom name="wall" type="box" size="0.6 0.1 0.5" pos="0.6 0.6 0.5"/>)";
double wall_angle(double clearance) {
  return std::asin((0.5 - clearance) / std::sqrt(1.0025)) - std::atan(0.05);
}

// A two-waypoint path that stays at q = 0 with bounds [-0.4, upper].
BoundsTrajectory still_path(double upper) {
  const WaypointBounds w(Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, -0.4),
                         Eigen::VectorXd::Constant(1, upper));
  return BoundsTrajectory({w, w}, {0, 0}, true);
}

SimulateOptions push_toward_wall() {
  SimulateOptions o;
  o.human.kind = HumanKind::kPushToward;
  o.human.target = "wall";
  o.human.amplitude = 60;
  o.end_hold = 4;
  return o;
}

class SimulateTest : public test::MujocoTest {};

TEST_F(SimulateTest, PushTowardTheWallStopsAtTheBoundAndNeverTouches) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(kWall)));
  const double upper = wall_angle(0.01);  // 1 cm from the wall
  double last_q = 0;
  int frames = 0;
  const SimulationReport r = simulate(scene, still_path(upper), push_toward_wall(),
                                      [&](const mjModel& m, const mjData& d, const SimFrame& f) {
                                        last_q = d.qpos[m.jnt_qposadr[0]];
                                        if (f.t > 0) {
                                          EXPECT_GT(f.force.y(), 0) << "the push points at the wall, +y";
                                        }
                                        ++frames;
                                      });
  EXPECT_FALSE(r.first_contact.has_value());
  EXPECT_EQ(r.contact_steps, 0);
  EXPECT_FALSE(r.left_bounds);
  EXPECT_EQ(r.max_excursion, 0.0);
  // It went to the bound, less the 1 mrad plan margin: the link is 1 cm plus 1 mrad x dy/dq = 0.87
  // mm from the wall (dy/dq = sqrt(1.0025) cos(q + atan 0.05) = 0.87 there).
  EXPECT_NEAR(last_q, upper - 1e-3, 2e-4);
  EXPECT_FALSE(r.min_distance_capped);
  EXPECT_NEAR(r.min_distance, 0.01 + 0.87e-3, 2e-4);
  EXPECT_EQ(r.min_distance_geom1, "link_box");
  EXPECT_EQ(r.min_distance_geom2, "wall");
  EXPECT_GT(r.freedom_used[0], 0.99);
  EXPECT_TRUE(r.reached_end);
  EXPECT_NEAR(r.simulated_time, 4.0, 0.011);
  EXPECT_NEAR(frames, r.simulated_time / 0.01, 1);  // one per 10 ms control period
}

// Bounds that reach past the wall (it touches at 0.4729 rad): the same push finds the contact.
TEST_F(SimulateTest, BoundsPastTheWallLetThePushTouchIt) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(kWall)));
  const SimulationReport r = simulate(scene, still_path(0.6), push_toward_wall());
  ASSERT_TRUE(r.first_contact.has_value());
  EXPECT_EQ(r.first_contact->geom1, "link_box");
  EXPECT_EQ(r.first_contact->geom2, "wall");
  EXPECT_FALSE(r.first_contact->self);
  EXPECT_GT(r.contact_steps, 0);
  EXPECT_FALSE(r.left_bounds);  // the controller stayed inside its (wrong) bounds up to the contact
}

// The projection baseline also stops at the bound.
TEST_F(SimulateTest, ProjectionBaselineStopsAtTheBoundToo) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(kWall)));
  SimulateOptions o = push_toward_wall();
  o.controller = ControllerKind::kProjection;
  const SimulationReport r = simulate(scene, still_path(wall_angle(0.01)), o);
  EXPECT_FALSE(r.first_contact.has_value());
  EXPECT_FALSE(r.left_bounds);
  EXPECT_NEAR(r.min_distance, 0.01 + 0.87e-3, 2e-4);
}

TEST_F(SimulateTest, PushTargetMustNameAnObstacle) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(kWall)));
  SimulateOptions o = push_toward_wall();
  o.human.target = "link_box";
  EXPECT_THAT(error_of([&] { simulate(scene, still_path(0.3), o); }),
              HasSubstr("push-toward 'link_box' names no obstacle"));
  o.human.target = "wall";
  o.human.amplitude = 1e5;
  EXPECT_THAT(error_of([&] { simulate(scene, still_path(0.3), o); }), HasSubstr("human amplitude 100000"));
  o.human.amplitude = 60;
  o.control_period = 0.003;  // not a multiple of the 2 ms timestep
  EXPECT_THAT(error_of([&] { simulate(scene, still_path(0.3), o); }), HasSubstr("not a multiple"));
}

// ---------------------------------------------------------------------------------------------
// The Dallara cell, patch to mould: the default (certified) bounds against random and adversarial
// pushes, and the thesis preset's bounds (CF 65.5 % in docs/results.md) against the adversary.

class SimulateDallaraTest : public test::MujocoTest {
 protected:
  static std::string bounds_file(const test::TempDir& dir, const std::string& extra) {
    const std::string out =
        (dir.path() / ("b" + std::to_string(std::hash<std::string>{}(extra)) + ".json")).string();
    const auto r = test::run_cli("bounds " + test::workcell("dallara") + " --from patch --to mould " + extra +
                                 " --out " + out);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return out;
  }
};

TEST_F(SimulateDallaraTest, DefaultBoundsHoldAgainstEveryPushAndTheRobotNeverLeavesThem) {
  test::TempDir dir;
  const Scene scene = Scene::load(test::workcell("dallara"));
  const BoundsTrajectory bounds = read_bounds_trajectory(bounds_file(dir, ""), scene);
  for (const HumanKind kind : {HumanKind::kRandom, HumanKind::kPushToward}) {
    for (std::uint64_t seed : {1u, 2u}) {
      SCOPED_TRACE(std::string(human_kind_name(kind)) + " seed " + std::to_string(seed));
      SimulateOptions o;
      o.human.kind = kind;
      o.human.target = "nearest";
      o.seed = seed;
      long outside = 0, periods = 0;
      const SimulationReport r =
          simulate(scene, bounds, o, [&](const mjModel& m, const mjData& d, const SimFrame& f) {
            // Checked here, from the state MuJoCo holds, not from the report.
            for (int j = 0; j < scene.dof(); ++j) {
              const double q = d.qpos[m.jnt_qposadr[scene.joints()[static_cast<size_t>(j)].id]];
              if (q < f.box.lower[j] || q > f.box.upper[j]) ++outside;
            }
            ++periods;
          });
      EXPECT_EQ(outside, 0) << "of " << periods << " control periods";
      EXPECT_FALSE(r.first_contact.has_value()) << r.first_contact->geom1 << " - " << r.first_contact->geom2;
      EXPECT_FALSE(r.left_bounds) << r.max_excursion;
      EXPECT_TRUE(r.reached_end);
      EXPECT_GT(r.freedom_used.maxCoeff(), 0.5);  // the push did use the room
    }
  }
}

TEST_F(SimulateDallaraTest, ThesisPresetBoundsAreHitByTheAdversary) {
  test::TempDir dir;
  const Scene scene = Scene::load(test::workcell("dallara"));
  const BoundsTrajectory bounds = read_bounds_trajectory(bounds_file(dir, "--preset thesis"), scene);
  SimulateOptions o;
  o.human.kind = HumanKind::kPushToward;
  o.human.target = "nearest";
  const SimulationReport r = simulate(scene, bounds, o);
  ASSERT_TRUE(r.first_contact.has_value());
  EXPECT_GT(r.first_contact->depth, 0);
}

TEST_F(SimulateDallaraTest, SameSeedSameReport) {
  test::TempDir dir;
  const Scene scene = Scene::load(test::workcell("dallara"));
  const std::string file = bounds_file(dir, "");
  const BoundsTrajectory bounds = read_bounds_trajectory(file, scene);
  SimulateOptions o;
  o.seed = 7;
  auto a = simulation_json(scene, simulate(scene, bounds, o), o, "c", file);
  auto b = simulation_json(scene, simulate(scene, bounds, o), o, "c", file);
  for (auto* j : {&a, &b}) {
    j->erase("wall_time");
    j->erase("wall_per_simulated_second");
  }
  EXPECT_EQ(a.dump(), b.dump());
  o.seed = 8;
  auto c = simulation_json(scene, simulate(scene, bounds, o), o, "c", file);
  EXPECT_NE(a.at("human").at("rms_force"), c.at("human").at("rms_force"));
}

// ---------------------------------------------------------------------------------------------
// Push files

TEST(WrenchFile, ReadsSamplesWithAHeaderAndComments) {
  test::TempDir dir;
  const auto w =
      read_wrench_file(dir.write("p.csv", "t,fx,fy,fz\n# a comment\n0, 1, 2, 3\n0.5 4 5 6 0.1 0.2 0.3\n"));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[1].t, 0.5);
  EXPECT_EQ(w[1].force, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(w[1].torque, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(w[0].torque, Eigen::Vector3d::Zero());
}

TEST(WrenchFile, RefusesNanTimeGoingBackAndShortLines) {
  test::TempDir dir;
  EXPECT_THAT(error_of([&] { read_wrench_file(dir.write("a.csv", "0 1 2 3\n1 nan 0 0\n")); }),
              HasSubstr("a.csv line 2: 'nan' is not a finite number"));
  EXPECT_THAT(error_of([&] { read_wrench_file(dir.write("b.csv", "0 1 2 3\n1 0 0 0\n0.5 0 0 0\n")); }),
              HasSubstr("b.csv line 3: time 0.5 s does not come after 1 s"));
  EXPECT_THAT(error_of([&] { read_wrench_file(dir.write("c.csv", "0 1 2\n")); }),
              HasSubstr("c.csv line 1: 3 values"));
  EXPECT_THAT(error_of([&] { read_wrench_file(dir.write("d.csv", "# nothing\n")); }),
              HasSubstr("no samples"));
  EXPECT_THAT(error_of([&] { read_wrench_file(dir.write("e.csv", "0 20000 0 0\n")); }),
              HasSubstr("over 10 kN"));
}

// A recorded push is followed: a constant +y push on the one-link arm turns it toward the wall,
// and a -y push away from it.
TEST_F(SimulateTest, FilePushIsInterpolatedAndFollowed) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(kWall)));
  SimulateOptions o;
  o.human.kind = HumanKind::kFile;
  o.end_hold = 1;
  for (double sign : {1.0, -1.0}) {
    o.human.samples = {WrenchSample{0, Eigen::Vector3d(0, 30 * sign, 0), Eigen::Vector3d::Zero()},
                       WrenchSample{10, Eigen::Vector3d(0, 30 * sign, 0), Eigen::Vector3d::Zero()}};
    double last_q = 0;
    simulate(scene, still_path(0.3), o,
             [&](const mjModel& m, const mjData& d, const SimFrame&) { last_q = d.qpos[m.jnt_qposadr[0]]; });
    EXPECT_GT(sign * last_q, 0.05) << sign;
  }
}

// ---------------------------------------------------------------------------------------------
// The command line

const std::string kDallaraBounds = std::string(LEEWAY_TEST_DATA_DIR) + "/cli_golden/dallara_bounds.json";

TEST(CliSimulate, WritesTheReportAndExitsZeroWithoutContact) {
  test::TempDir dir;
  const std::string out = (dir.path() / "r.json").string();
  const auto r = test::run_cli("simulate " + test::workcell("dallara") + " --bounds " + kDallaraBounds +
                               " --human push-toward nearest --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("contacts: 0 (min distance "));
  EXPECT_THAT(r.out, HasSubstr("bounds: never left"));
  const nlohmann::json j = test::read_json(out);
  EXPECT_EQ(j.at("format"), "leeway-simulation-1");
  EXPECT_EQ(j.at("contacts"), 0);
  EXPECT_TRUE(j.at("first_contact").is_null());
  EXPECT_EQ(j.at("left_bounds"), false);
  EXPECT_EQ(j.at("human").at("kind"), "push-toward");
  EXPECT_EQ(j.at("joints").size(), 6u);
  EXPECT_EQ(j.at("freedom_used").size(), 6u);
  EXPECT_EQ(j.at("reached_end"), true);
}

// A contact is a finding: exit 1, and the report says where.
TEST(CliSimulate, AContactIsExitOne) {
  test::TempDir dir;
  const std::string cell = dir.write("cell.xml", test::one_link_cell(kWall, R"(<key name="a" qpos="0"/>)"));
  // Bounds past the wall, written by hand in the bounds file's format 1 (the cell's joint speed
  // times it).
  const std::string bounds = dir.write("b.json", R"({"format": "leeway-bounds-1", "joints": ["j1"],
    "waypoints": [{"q": [0], "lower": [-0.4], "upper": [0.6]}, {"q": [0], "lower": [-0.4], "upper": [0.6]}]})");
  const auto r =
      test::run_cli("simulate " + cell + " --bounds " + bounds + " --human push-toward wall --json");
  ASSERT_EQ(r.exit_code, 1) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("first_contact").at("geom1"), "link_box");
  EXPECT_EQ(j.at("first_contact").at("geom2"), "wall");
}

// Without ffmpeg on PATH, --video is a warning: the run goes on and its report is written.
TEST(CliSimulate, WithoutFfmpegTheRunGoesOnWithoutAVideo) {
  test::TempDir dir;
  const std::string video = (dir.path() / "run.mp4").string(), out = (dir.path() / "r.json").string();
  const auto r = test::run_program("env PATH=" + dir.path().string() + " " + std::string(LEEWAY_CLI),
                                   "simulate " + test::workcell("dallara") + " --bounds " + kDallaraBounds +
                                       " --human none --video " + video + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("ffmpeg is not on PATH"));
  EXPECT_FALSE(std::filesystem::exists(video));
  EXPECT_TRUE(test::read_json(out).at("video").is_null());
}

// With ffmpeg: an MP4 (its first box is 'ftyp') of 30 frames per simulated second.
TEST(CliSimulate, VideoIsAnMp4AtThirtyFramesPerSecond) {
  if (std::system("command -v ffmpeg > /dev/null 2>&1") != 0) GTEST_SKIP() << "ffmpeg is not installed";
  test::TempDir dir;
  const std::string video = (dir.path() / "run.mp4").string(), out = (dir.path() / "r.json").string();
  const auto r = test::run_cli("simulate " + test::workcell("dallara") + " --bounds " + kDallaraBounds +
                               " --human random --video " + video + " --size 160x120 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string bytes = test::read_text(video);
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes.substr(4, 4), "ftyp");
  const nlohmann::json j = test::read_json(out);
  const double seconds = j.at("simulated_time").get<double>();
  EXPECT_NEAR(j.at("video").at("frames").get<double>(), 30 * seconds, 2);
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().rfind(".run.mp4", 0), std::string::npos)
        << "temporary left behind";
}

}  // namespace
}  // namespace leeway
