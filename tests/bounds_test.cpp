// Jointspace exploration (thesis section 3.3): Algorithm 2 against hand-worked bisection sequences
// and an analytic MuJoCo scene, Algorithm 3's properties on the Dallara cell with a real volume.
#include "leeway/core/bounds.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::workcell;
using ::testing::HasSubstr;

Eigen::VectorXd vec1(double v) {
  Eigen::VectorXd q(1);
  q << v;
  return q;
}

// ---------------------------------------------------------------------------------------------
// WaypointBounds

Eigen::VectorXd vec3(double a, double b, double c) { return Eigen::Vector3d(a, b, c); }

TEST(WaypointBoundsTest, CheckedConstructorAndContains) {
  const WaypointBounds w(vec3(0, 1, -1), vec3(-0.5, 0.5, -1), vec3(0.5, 1, 0));
  EXPECT_EQ(w.collapsed, std::vector<bool>(3, false));
  EXPECT_EQ(w.guide_lower, w.lower);
  EXPECT_EQ(w.guide_upper, w.upper);
  EXPECT_FALSE(w.nominal_in_volume);
  EXPECT_EQ(w.checks, 0);
  EXPECT_TRUE(w.contains(w.q));
  EXPECT_TRUE(w.contains(w.lower));  // closed intervals
  EXPECT_TRUE(w.contains(w.upper));
  EXPECT_TRUE(w.contains(vec3(0.25, 0.75, -0.5)));
  EXPECT_FALSE(w.contains(vec3(0.51, 0.75, -0.5)));
  EXPECT_FALSE(w.contains(vec3(0, 0.49, -0.5)));
  EXPECT_FALSE(w.contains(vec3(0, 0.75, NAN)));
  EXPECT_THROW(w.contains(vec1(0.0)), InputError);

  auto message = [](const Eigen::VectorXd& q, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi) {
    try {
      WaypointBounds bad(q, lo, hi);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message(vec3(0, 0, 0), vec1(0), vec3(0, 0, 0)), HasSubstr("lower 1"));
  EXPECT_THAT(message(vec3(0, 0, 2), vec3(0, 0, 0), vec3(1, 1, 1)), HasSubstr("joint 2: nominal 2"));
  EXPECT_THAT(message(vec3(0, 0, 0), vec3(0, 1, 0), vec3(1, 0, 1)), HasSubstr("joint 1"));
  EXPECT_THAT(message(vec3(0, NAN, 0), vec3(0, 0, 0), vec3(1, 1, 1)), HasSubstr("not finite"));

  // Default construction stays available for the algorithms that fill the fields.
  WaypointBounds empty;
  EXPECT_EQ(empty.q.size(), 0);
}

TEST(BoundUpperTest, LimitOnTheWrongSideIsRejected) {
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  long checks = 0;
  EXPECT_THROW(bound_upper(never, vec1(0.5), 0, 0.2, 0.01, checks), InputError);
  EXPECT_THROW(bound_lower(never, vec1(0.5), 0, 0.8, 0.01, checks), InputError);
  EXPECT_THROW(bound_upper(never, vec1(0.5), 1, 1.0, 0.01, checks), InputError);
  EXPECT_EQ(checks, 0);
  // A limit at the value itself is allowed (a joint at its limit).
  EXPECT_EQ(bound_upper(never, vec1(0.5), 0, 0.5, 0.01, checks), 0.5);
}

// ---------------------------------------------------------------------------------------------
// Algorithm 2 with plain predicates (no MuJoCo)

TEST(BoundUpperTest, BisectionSequenceWorkedByHand) {
  // collides(q) = q > 0.3, nominal A = 0, limit 1, delta 0.01. Algorithm 2 (range = B - A):
  //  check 1: B = 1        collides -> B = 0.5,       range 0.5
  //  check 2: B = 0.5      collides -> C = 0.5,       B = 0.25,      range 0.25
  //  check 3: B = 0.25     free     -> A = 0.25,      B = 0.375,     range 0.125
  //  check 4: B = 0.375    collides -> C = 0.375,     B = 0.3125,    range 0.0625
  //  check 5: B = 0.3125   collides -> C = 0.3125,    B = 0.28125,   range 0.03125
  //  check 6: B = 0.28125  free     -> A = 0.28125,   B = 0.296875,  range 0.015625
  //  check 7: B = 0.296875 free     -> A = 0.296875,  B = 0.3046875, range 0.0078125 <= 0.01: stop
  // Returns A = 0.296875 (= 19/64) after 7 checks. All values are dyadic, hence exact doubles.
  std::vector<double> probes;
  const CollisionFn collides = [&probes](const Eigen::VectorXd& q) {
    probes.push_back(q[0]);
    return q[0] > 0.3;
  };
  long checks = 100;  // incremented, not reset
  const double b = bound_upper(collides, vec1(0.0), 0, 1.0, 0.01, checks);
  EXPECT_EQ(probes, (std::vector<double>{1.0, 0.5, 0.25, 0.375, 0.3125, 0.28125, 0.296875}));
  EXPECT_EQ(b, 0.296875);
  EXPECT_EQ(checks, 107);
  // Collision-free, below the boundary 0.3 and within delta of it (0.3 - 0.296875 = 0.003125).
  EXPECT_LE(b, 0.3);
  EXPECT_LT(0.3 - b, 0.01);
}

TEST(BoundUpperTest, LowerIsTheMirrorImage) {
  // collides(q) = q < -0.3, nominal 0, limit -1: the same sequence negated, A = -0.296875, 7 checks.
  std::vector<double> probes;
  const CollisionFn collides = [&probes](const Eigen::VectorXd& q) {
    probes.push_back(q[0]);
    return q[0] < -0.3;
  };
  long checks = 0;
  const double b = bound_lower(collides, vec1(0.0), 0, -1.0, 0.01, checks);
  EXPECT_EQ(probes, (std::vector<double>{-1.0, -0.5, -0.25, -0.375, -0.3125, -0.28125, -0.296875}));
  EXPECT_EQ(b, -0.296875);
  EXPECT_EQ(checks, 7);
}

TEST(BoundUpperTest, FinalBracketIsTwiceDeltaAsInThePseudocode) {
  // Algorithm 2 stops when range = B - A <= delta, and B is the midpoint of [A, C]: the bracket
  // [A, C] that holds the boundary is then up to 2 delta wide, not delta. With the boundary at
  // 0.312 the probes are those of the test above (0.3125 > 0.312 still collides), so the result is
  // again A = 0.296875 with C = 0.3125: bracket 0.015625 > delta = 0.01, and the result lies
  // 0.312 - 0.296875 = 0.015125 below the boundary (more than delta, less than 2 delta).
  // (bounds.hpp says "until the bracket is at most `delta` wide": it is up to 2 delta.)
  const CollisionFn collides = [](const Eigen::VectorXd& q) { return q[0] > 0.312; };
  long checks = 0;
  const double b = bound_upper(collides, vec1(0.0), 0, 1.0, 0.01, checks);
  EXPECT_EQ(b, 0.296875);
  EXPECT_EQ(checks, 7);
  EXPECT_GT(0.312 - b, 0.01);
  EXPECT_LT(0.312 - b, 0.02);
}

TEST(BoundUpperTest, FreeLimitIsReturnedAfterOneCheck) {
  std::vector<double> probes;
  const CollisionFn never = [&probes](const Eigen::VectorXd& q) {
    probes.push_back(q[0]);
    return false;
  };
  long checks = 0;
  EXPECT_EQ(bound_upper(never, vec1(0.2), 0, 2.5, 0.01, checks), 2.5);
  EXPECT_EQ(checks, 1);
  EXPECT_EQ(bound_lower(never, vec1(0.2), 0, -1.75, 0.01, checks), -1.75);
  EXPECT_EQ(checks, 2);
  EXPECT_EQ(probes, (std::vector<double>{2.5, -1.75}));
}

TEST(BoundUpperTest, EverythingCollidingReturnsTheNominalValue) {
  // Every probe collides: C walks down to A, which never moves. Nominal 0.2, limit 1: D = 0.8,
  // checks = ceil(log2(0.8 / 0.01)) = ceil(log2 80) = ceil(6.32) = 7 (see the step-count test).
  const CollisionFn always = [](const Eigen::VectorXd&) { return true; };
  long checks = 0;
  EXPECT_EQ(bound_upper(always, vec1(0.2), 0, 1.0, 0.01, checks), 0.2);
  EXPECT_EQ(checks, 7);
  checks = 0;
  // Lower: nominal 0.2, limit -1: D = 1.2, ceil(log2 120) = ceil(6.91) = 7.
  EXPECT_EQ(bound_lower(always, vec1(0.2), 0, -1.0, 0.01, checks), 0.2);
  EXPECT_EQ(checks, 7);
}

TEST(BoundUpperTest, StepCountAgainstTheThesisFormula) {
  // Section 3.3 claims k = 1 + ceil(log2(D / r)) checks when the loop is entered. After the first
  // check, range = D / 2, and every loop check halves it; the loop runs while range > r, so it
  // makes m = ceil(log2(D / r)) - 1 checks and the total is ceil(log2(D / r)) (at least 1): ONE
  // FEWER than the thesis's prose. The code follows the thesis's pseudocode, whose exit test uses
  // B - A (half the bracket [A, C]); the prose's count assumes the test uses C - A. The number of
  // checks does not depend on the outcomes once the limit collides, so a predicate that always
  // collides measures it.
  struct Case {
    double d, r;
    long checks;
  };
  const Case cases[] = {
      {1.0, 0.01, 7},          // log2 100 = 6.64 -> 7 (thesis: 8)
      {1.0, 0.015625, 6},      // r = 2^-6: log2 64 = 6 exactly; range 2^-6 is not > r (thesis: 7)
      {0.75, 0.01, 7},         // log2 75 = 6.23 -> 7 (thesis: 8)
      {2.0, 0.01, 8},          // log2 200 = 7.64 -> 8 (thesis: 9)
      {0.03125, 0.015625, 1},  // D / r = 2: range after the first check = r, the loop never runs
      {0.005, 0.01, 1},        // D < r: one check
  };
  const CollisionFn always = [](const Eigen::VectorXd&) { return true; };
  for (const auto& c : cases) {
    long up = 0, down = 0;
    bound_upper(always, vec1(0.0), 0, c.d, c.r, up);
    bound_lower(always, vec1(0.0), 0, -c.d, c.r, down);
    EXPECT_EQ(up, c.checks) << "D " << c.d << " r " << c.r;
    EXPECT_EQ(down, c.checks) << "D " << c.d << " r " << c.r;
  }
}

TEST(BoundUpperTest, OnlyTheBoundJointMoves) {
  // Joint 1 of a 3-vector is bisected; joints 0 and 2 keep their values in every probe.
  Eigen::VectorXd q(3);
  q << 0.7, -0.1, 0.4;
  const CollisionFn collides = [](const Eigen::VectorXd& x) {
    EXPECT_EQ(x[0], 0.7);
    EXPECT_EQ(x[2], 0.4);
    return x[1] > 0.3;
  };
  long checks = 0;
  // Nominal -0.1, limit 0.9 (D = 1): probes 0.9 c, 0.4 c, 0.15 f, 0.275 f, 0.3375 c, 0.30625 c,
  // 0.290625 f -> range 0.0078125 <= 0.01: returns 0.290625 after 7 checks. (Up to rounding of
  // -0.1, which is not dyadic.)
  EXPECT_NEAR(bound_upper(collides, q, 1, 0.9, 0.01, checks), 0.290625, 1e-15);
  EXPECT_EQ(checks, 7);
}

// ---------------------------------------------------------------------------------------------
// Algorithm 2 through MuJoCo: the one-link arm against two walls

class BoundsSceneTest : public test::MujocoTest {};

// Walls whose near faces are the planes y = +0.6 and y = -0.6 over x in [0, 2], z in [0, 1]
// (the link spans z 0.45 .. 0.55).
constexpr const char* kTwoWalls = R"(<geom name="wall_left" type="box" size="1 0.1 0.5" pos="1 0.7 0.5"/>
    <geom name="wall_right" type="box" size="1 0.1 0.5" pos="1 -0.7 0.5"/>)";

TEST_F(BoundsSceneTest, OneLinkArmAgainstWallsMatchesTheGeometry) {
  // The link is the box x in [0, 1], y in [-0.05, 0.05] of the link frame, turned by theta about
  // z. Its point of largest y for 0 < theta < pi/2 is the far corner (1, 0.05):
  //   y(theta) = sin(theta) + 0.05 cos(theta) = sqrt(1.0025) sin(theta + atan(0.05)),
  // increasing up to theta = pi/2 - atan(0.05) and equal to 1 at pi/2. It reaches the wall face
  // y = 0.6 at theta* = asin(0.6 / sqrt(1.0025)) - atan(0.05) = 0.6425657 - 0.0499584 = 0.5926073,
  // where the corner's x = cos(theta*) - 0.05 sin(theta*) = 0.80 lies over the wall (x in [0, 2]).
  // By the symmetry of the link and the walls, the lower boundary is -theta*.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", one_link_cell(kTwoWalls)));
  RobotState state(scene);
  const CollisionFn collides = [&state](const Eigen::VectorXd& q) { return state.in_collision(q); };
  const double theta = std::asin(0.6 / std::sqrt(1.0025)) - std::atan(0.05);
  ASSERT_NEAR(theta, 0.5926073, 1e-7);
  // The real collision check agrees with the geometry on both sides of +-theta*.
  EXPECT_FALSE(collides(vec1(0.0)));
  EXPECT_FALSE(collides(vec1(theta - 1e-4)));
  EXPECT_TRUE(collides(vec1(theta + 1e-4)));
  EXPECT_FALSE(collides(vec1(-theta + 1e-4)));
  EXPECT_TRUE(collides(vec1(-theta - 1e-4)));

  // Upper bound from 0 with the limit pi/2 (the whole of (theta*, pi/2] collides), delta 0.01.
  // By hand: 1.5708 c, 0.7854 c, 0.3927 f, 0.5890 f, 0.6872 c, 0.6381 c, 0.6136 c, 0.6013 c
  // -> A = 3 pi / 16 = 0.5890486 after ceil(log2(157.08)) = 8 checks; theta* - A = 0.0036 < delta.
  long checks = 0;
  const double up = bound_upper(collides, vec1(0.0), 0, M_PI / 2, 0.01, checks);
  EXPECT_NEAR(up, 3 * M_PI / 16, 1e-12);
  EXPECT_EQ(checks, 8);
  EXPECT_LE(up, theta);
  EXPECT_LT(theta - up, 0.01);
  EXPECT_FALSE(collides(vec1(up)));
  EXPECT_TRUE(collides(vec1(up + 0.01)));

  checks = 0;
  const double down = bound_lower(collides, vec1(0.0), 0, -M_PI / 2, 0.01, checks);
  EXPECT_NEAR(down, -3 * M_PI / 16, 1e-12);
  EXPECT_EQ(checks, 8);
  EXPECT_GE(down, -theta);
  EXPECT_LT(down + theta, 0.01);
  EXPECT_FALSE(collides(vec1(down)));
  EXPECT_TRUE(collides(vec1(down - 0.01)));
}

TEST_F(BoundsSceneTest, OneLinkWaypointIsBisectedBetweenTheWalls) {
  // One hinge: bisected, limits -3 .. 3. At theta = 3 the link points back along -x, its corners at
  // y = sin 3 +- 0.05 cos 3 = 0.092 / 0.191 (the walls are at x >= 0, |y| >= 0.6): the limit is
  // free, so Algorithm 2 returns it after one check; likewise -3. The bound is then [-3, 3]: Algorithm
  // 2 assumes the colliding set is connected to the limit, and a wall in the middle of the sweep
  // is jumped over. This documents that property of the thesis's algorithm.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", one_link_cell(kTwoWalls)));
  RobotState state(scene);
  const CollisionFn collides = [&state](const Eigen::VectorXd& q) { return state.in_collision(q); };
  ASSERT_EQ(bound_kinds(scene, BoundsParams{}), std::vector<BoundKind>{BoundKind::kBisected});
  const WaypointBounds w = bound_waypoint(scene, collides, vec1(0.0), BoundsParams{});
  EXPECT_EQ(w.lower[0], -3.0);
  EXPECT_EQ(w.upper[0], 3.0);
  EXPECT_FALSE(w.nominal_in_volume);
  EXPECT_EQ(w.checks, 3);                 // nominal, upper limit, lower limit
  EXPECT_TRUE(collides(vec1(M_PI / 2)));  // ... although pi/2, inside [-3, 3], collides
}

// ---------------------------------------------------------------------------------------------
// Algorithm 3 on the Dallara cell with a real volume

class DallaraBoundsTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    test::MujocoTest::SetUp();
    scene_ = std::make_unique<Scene>(Scene::load(workcell("dallara")));
    apply_cell_defaults(*scene_, params_);
    params_.height_map.max_cells = 500;
    params_.safety.mode = SafetyMode::kNone;  // these tests are about Algorithms 2 and 3 themselves
    world_ = std::make_unique<VolumeModel>(
        *scene_, params_.height_map.max_cells + static_cast<int>(scene_->obstacle_geoms().size()));
  }
  std::unique_ptr<Scene> scene_;
  Params params_;
  std::unique_ptr<VolumeModel> world_;
};

// The base configurations Algorithm 3 bounds joint `j` (0, 1 or 2 of the bisected joints) from.
std::vector<Eigen::VectorXd> algorithm3_bases(const WaypointBounds& w, const std::vector<int>& bisected,
                                              size_t j) {
  std::vector<Eigen::VectorXd> bases = {w.q};
  for (size_t k = 0; k < j; ++k) {
    std::vector<Eigen::VectorXd> next;
    for (const auto& b : bases)
      for (double v : {w.lower[bisected[k]], w.upper[bisected[k]]}) {
        Eigen::VectorXd x = b;
        x[bisected[k]] = v;
        next.push_back(x);
      }
    bases = next;
  }
  return bases;
}

TEST_F(DallaraBoundsTest, HomeToPatchBoundsHaveTheAlgorithmsProperties) {
  const auto path = keyframe_path(*scene_, "home", "patch", 3);
  const BoundsRun run = compute_bounds(*scene_, *world_, path, params_, 2);
  ASSERT_EQ(run.bounds.size(), 3u);
  ASSERT_GT(run.volume.boxes.size(), 0u);
  const Eigen::VectorXd lo = scene_->lower_limits(), hi = scene_->upper_limits();
  const auto kinds = bound_kinds(*scene_, params_.bounds);
  ASSERT_EQ(kinds, (std::vector<BoundKind>{BoundKind::kBisected, BoundKind::kBisected, BoundKind::kBisected,
                                           BoundKind::kFixed, BoundKind::kFixed, BoundKind::kFixed}));
  const std::vector<int> bisected = {0, 1, 2};
  const double res = params_.bounds.resolution;
  VolumeChecker checker(*world_);
  auto collides = [&checker](const Eigen::VectorXd& q) { return checker.in_collision(q); };
  auto with = [](Eigen::VectorXd x, int j, double v) {
    x[j] = v;
    return x;
  };
  int checked_sides = 0;
  for (size_t wi = 0; wi < run.bounds.size(); ++wi) {
    const WaypointBounds& w = run.bounds[wi];
    SCOPED_TRACE("waypoint " + std::to_string(wi));
    EXPECT_EQ(w.q, path[wi]);
    // The volume is cleared under the trail: the nominal pose is free of it.
    EXPECT_FALSE(w.nominal_in_volume);
    EXPECT_FALSE(collides(w.q));
    for (int j = 0; j < 6; ++j) {
      SCOPED_TRACE("joint " + std::to_string(j + 1));
      EXPECT_LE(w.lower[j], w.q[j]);
      EXPECT_LE(w.q[j], w.upper[j]);
      EXPECT_GE(w.lower[j], lo[j]);
      EXPECT_LE(w.upper[j], hi[j]);
      if (kinds[static_cast<size_t>(j)] == BoundKind::kFixed) {
        // Wrist: nominal +- wrist_half_width = 0.2 rad, clamped to the limits.
        EXPECT_DOUBLE_EQ(w.lower[j], std::max(lo[j], w.q[j] - 0.2));
        EXPECT_DOUBLE_EQ(w.upper[j], std::min(hi[j], w.q[j] + 0.2));
        EXPECT_FALSE(w.collapsed[static_cast<size_t>(j)]);
        continue;
      }
      if (w.collapsed[static_cast<size_t>(j)]) continue;
      // j1 from the nominal pose; j2 with j1 at each of its bounds; j3 with each combination.
      const auto bases = algorithm3_bases(w, bisected, static_cast<size_t>(j));
      ASSERT_EQ(bases.size(), size_t{1} << j);
      for (int side : {-1, +1}) {
        const double bound = side > 0 ? w.upper[j] : w.lower[j];
        const double limit = side > 0 ? hi[j] : lo[j];
        int free_at_bound = 0, colliding_beyond = 0;
        for (const auto& b : bases) {
          free_at_bound += collides(with(b, j, bound)) ? 0 : 1;
          const double beyond =
              side > 0 ? std::min(limit, bound + 2 * res) : std::max(limit, bound - 2 * res);
          colliding_beyond += collides(with(b, j, beyond)) ? 1 : 0;
        }
        if (bound == limit) {
          // Returned only when the limit itself was free for every base.
          EXPECT_EQ(free_at_bound, static_cast<int>(bases.size())) << "side " << side;
          continue;
        }
        // The most restrictive base gives a free bound with a collision just beyond it. "Just beyond"
        // is 2 resolutions: Algorithm 2 stops when B - A <= delta, so the lowest colliding probe C
        // = 2B - A may lie up to 2 delta past A (FinalBracketIsTwiceDeltaAsInThePseudocode). With
        // bound +- 1 resolution, 5 of the sides checked here find no collision for any base: the
        // boundary lies 1.0 .. 1.5 resolutions out (bounds.hpp promises a bracket of delta).
        EXPECT_GE(free_at_bound, 1) << "side " << side << " bound " << bound;
        EXPECT_GE(colliding_beyond, 1) << "side " << side << " bound " << bound;
        ++checked_sides;
      }
      if (j == 0) {
        // j1 is bounded with every other joint at nominal: free at both bounds.
        EXPECT_FALSE(collides(with(w.q, 0, w.lower[0])));
        EXPECT_FALSE(collides(with(w.q, 0, w.upper[0])));
      }
    }
  }
  // The property is not vacuous: bisection ended inside the range on several sides.
  EXPECT_GE(checked_sides, 4);
}

TEST_F(DallaraBoundsTest, SameBoundsForOneAndTwoThreads) {
  const auto path = keyframe_path(*scene_, "home", "patch", 4);
  const BoundsRun run = compute_bounds(*scene_, *world_, path, params_, 1);
  const auto two = bound_path(*world_, path, params_.bounds, 2);
  ASSERT_EQ(two.size(), run.bounds.size());
  for (size_t i = 0; i < two.size(); ++i) {
    EXPECT_EQ(two[i].q, run.bounds[i].q) << i;
    EXPECT_EQ(two[i].lower, run.bounds[i].lower) << i;
    EXPECT_EQ(two[i].upper, run.bounds[i].upper) << i;
    EXPECT_EQ(two[i].collapsed, run.bounds[i].collapsed) << i;
    EXPECT_EQ(two[i].nominal_in_volume, run.bounds[i].nominal_in_volume) << i;
    EXPECT_EQ(two[i].checks, run.bounds[i].checks) << i;
  }
  // And the same again with 1 thread through bound_path directly.
  const auto one = bound_path(*world_, path, params_.bounds, 1);
  for (size_t i = 0; i < one.size(); ++i) EXPECT_EQ(one[i].upper, two[i].upper) << i;
}

// ---------------------------------------------------------------------------------------------
// Algorithm 3 with plain predicates: collapse guard, fixed and linear-axis joints

TEST_F(BoundsSceneTest, CollapseGuardWidensAnIntervalShrunkToTheNominal) {
  // Dallara robot; the predicate collides everywhere except where j1..j3 are exactly nominal.
  // q: the patch pose with j1 = 2.95 (upper limit 2.9671) and j5 = 2.2 (upper limit 2.2689).
  const Scene scene = Scene::load(workcell("dallara"));
  Eigen::VectorXd q(6);
  q << 2.95, 0.734922, 0.0866255, -3.14159, 2.2, -1.11219;
  const CollisionFn collides = [&q](const Eigen::VectorXd& x) { return x.head<3>() != q.head<3>(); };
  BoundsParams p;
  p.resolution = 0.01;
  p.min_half_width = 0.05;  // distinct from the resolution, to see which one widens
  p.wrist_half_width = 0.2;
  const WaypointBounds w = bound_waypoint(scene, collides, q, p);
  EXPECT_FALSE(w.nominal_in_volume);
  EXPECT_EQ(w.collapsed, (std::vector<bool>{true, true, true, false, false, false}));
  // Every probe collides: lower = upper = nominal -> [nominal - 0.05, nominal + 0.05], clamped.
  EXPECT_NEAR(w.lower[0], 2.90, 1e-12);
  EXPECT_NEAR(w.upper[0], 2.9671, 1e-12);  // 3.00 clamped to the limit
  EXPECT_NEAR(w.lower[1], 0.684922, 1e-12);
  EXPECT_NEAR(w.upper[1], 0.784922, 1e-12);
  EXPECT_NEAR(w.lower[2], 0.0366255, 1e-12);
  EXPECT_NEAR(w.upper[2], 0.1366255, 1e-12);
  // Wrist: +- 0.2, j5 clamped at 2.2689.
  EXPECT_NEAR(w.lower[3], -3.34159, 1e-12);
  EXPECT_NEAR(w.upper[3], -2.94159, 1e-12);
  EXPECT_NEAR(w.lower[4], 2.0, 1e-12);
  EXPECT_NEAR(w.upper[4], 2.2689, 1e-12);
  EXPECT_NEAR(w.lower[5], -1.31219, 1e-12);
  EXPECT_NEAR(w.upper[5], -0.91219, 1e-12);
  // Checks, from the step count ceil(log2(D / 0.01)) per bisection (at least 1):
  //   nominal: 1
  //   j1 (1 base):  up D = 2.9671 - 2.95 = 0.0171 -> 1; down D = 5.9171 -> ceil(9.21) = 10
  //   j2 (2 bases): up D = 1.4835 - 0.734922 = 0.748578 -> ceil(6.23) = 7;
  //                 down D = 0.734922 + 1.1345 = 1.869422 -> ceil(7.55) = 8       -> 2 x 15 = 30
  //   j3 (4 bases): up D = 1.2217 - 0.0866255 = 1.1350745 -> ceil(6.83) = 7;
  //                 down D = 0.0866255 + 3.1416 = 3.2282255 -> ceil(8.33) = 9     -> 4 x 16 = 64
  //   total 1 + 11 + 30 + 64 = 106 (the thesis's 1 + 2 + 4 = 7 bisections per side).
  EXPECT_EQ(w.checks, 106);
}

TEST_F(BoundsSceneTest, FreeSpaceGivesLimitsAndTheRailGetsThreePercent) {
  // DLR: rail_x (slide, -9 .. 1 m) then the six hinges. Nothing collides: j1..j3 get their limits
  // after one check each per base, the wrist +- 0.2 rad and the rail +- 3 % of 10 m = +- 0.3 m.
  const Scene scene = Scene::load(workcell("dlr"));
  ASSERT_EQ(bound_kinds(scene, BoundsParams{}),
            (std::vector<BoundKind>{BoundKind::kLinear, BoundKind::kBisected, BoundKind::kBisected,
                                    BoundKind::kBisected, BoundKind::kFixed, BoundKind::kFixed,
                                    BoundKind::kFixed}));
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  Eigen::VectorXd q = scene.keyframe("home").q;  // -4, pi/2, 0, 0, 0, 0, 0
  WaypointBounds w = bound_waypoint(scene, never, q, BoundsParams{});
  EXPECT_NEAR(w.lower[0], -4.3, 1e-12);
  EXPECT_NEAR(w.upper[0], -3.7, 1e-12);
  for (int j = 1; j <= 3; ++j) {
    EXPECT_EQ(w.lower[j], scene.joints()[static_cast<size_t>(j)].lower);
    EXPECT_EQ(w.upper[j], scene.joints()[static_cast<size_t>(j)].upper);
  }
  for (int j = 4; j <= 6; ++j) {
    EXPECT_NEAR(w.lower[j], q[j] - 0.2, 1e-12);
    EXPECT_NEAR(w.upper[j], q[j] + 0.2, 1e-12);
  }
  EXPECT_EQ(w.collapsed, std::vector<bool>(7, false));
  EXPECT_EQ(w.checks, 1 + 2 * (1 + 2 + 4));  // nominal + one check per bisection
  // Near the rail's end: -8.9 - 0.3 is clamped to the limit -9.
  q[0] = -8.9;
  w = bound_waypoint(scene, never, q, BoundsParams{});
  EXPECT_NEAR(w.lower[0], -9.0, 1e-12);
  EXPECT_NEAR(w.upper[0], -8.6, 1e-12);
}

TEST_F(BoundsSceneTest, DlrRealVolumeKeepsTheRailTolerance) {
  const Scene scene = Scene::load(workcell("dlr"));
  Params p;
  apply_cell_defaults(scene, p);
  p.height_map.max_cells = 300;
  p.safety.mode = SafetyMode::kNone;  // the thesis's rail tolerance, before any safety stage
  VolumeModel world(scene, p.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
  const auto path = keyframe_path(scene, "home", "patch", 2);
  const BoundsRun run = compute_bounds(scene, world, path, p, 2);
  // Rail: home -4 m -> [-4.3, -3.7]; patch -0.916442 m -> [-1.216442, -0.616442].
  ASSERT_EQ(run.bounds.size(), 2u);
  EXPECT_NEAR(run.bounds[0].lower[0], -4.3, 1e-12);
  EXPECT_NEAR(run.bounds[0].upper[0], -3.7, 1e-12);
  EXPECT_NEAR(run.bounds[1].lower[0], -1.216442, 1e-12);
  EXPECT_NEAR(run.bounds[1].upper[0], -0.616442, 1e-12);
  for (const auto& w : run.bounds)
    for (int j = 0; j < 7; ++j) {
      EXPECT_LE(w.lower[j], w.q[j]);
      EXPECT_LE(w.q[j], w.upper[j]);
    }
}

TEST_F(BoundsSceneTest, RejectsNominalsOutsideTheLimitsOrOfTheWrongSize) {
  const Scene scene = Scene::load(workcell("dallara"));
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
  q[1] = 1.6;  // j2 upper limit 1.4835
  EXPECT_THROW(bound_waypoint(scene, never, q, BoundsParams{}), InputError);
  EXPECT_THROW(bound_waypoint(scene, never, Eigen::VectorXd::Zero(5), BoundsParams{}), InputError);
  q[1] = std::nan("");
  EXPECT_THROW(bound_waypoint(scene, never, q, BoundsParams{}), InputError);
}

// ---------------------------------------------------------------------------------------------
// bounds.bisect and bounds.half_width: which joints Algorithm 3 bisects, per-joint fixed widths

// A serial chain of n hinges as tools/chain_cell.py writes it (about z and y in turn, 1.6 m in all,
// a 6 cm box per link on a fixed base), with every joint's range [-1.5, 1.5] rad and a wall whose
// near face is the plane x = 0.25 (x 0.25 .. 0.35, y -1 .. 1, z 0.5 .. 2.5). Keyframes: a (straight
// up) and b (j1 = 0.3, j2 = -0.2: turned, and tilted away from the wall).
std::string chain_cell(int n) {
  return test::serial_chain_cell(n, "-1.5 1.5", "0.3 0 1.5", [](int i) {
    return i == 0 ? "0.3" : i == 1 ? "-0.2" : "0";
  });
}

BoundsParams bisecting(std::vector<std::string> joints) {
  BoundsParams p;
  p.bisect = std::move(joints);
  return p;
}

TEST_F(BoundsSceneTest, TheFourthJointOfAChainIsBisectedToItsTouchAngle) {
  // Four hinges, j4 (about y, pivot at z = 1.4) named in bounds.bisect: j1..j3 are fixed, j4 is
  // bisected from the straight pose. The link l4 is the box x, y in [-0.03, 0.03], z in [0.04, 0.36]
  // of its frame; turned by theta about y, its point of largest x is the corner (0.03, 0.36):
  //   x(theta) = 0.03 cos(theta) + 0.36 sin(theta) = sqrt(0.1305) sin(theta + atan(0.03 / 0.36)),
  // which reaches the wall face x = 0.25 at
  //   theta* = asin(0.25 / sqrt(0.1305)) - atan(1 / 12) = 0.7644972 - 0.0831412 = 0.6811779,
  // the corner then at z = 1.4 - 0.03 sin(theta*) + 0.36 cos(theta*) = 1.66, in front of the wall.
  // The other links stay within |x| <= 0.1 (the base) at every probe.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("chain.xml", chain_cell(4)));
  RobotState state(scene);
  const CollisionFn collides = [&state](const Eigen::VectorXd& q) { return state.obstacle_contact(q); };
  const double theta = std::asin(0.25 / std::sqrt(0.1305)) - std::atan(0.03 / 0.36);
  ASSERT_NEAR(theta, 0.6811779, 1e-7);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(4);
  auto at = [&q](double j4) {
    Eigen::VectorXd x = q;
    x[3] = j4;
    return x;
  };
  EXPECT_FALSE(collides(at(theta - 1e-4)));
  EXPECT_TRUE(collides(at(theta + 1e-4)));

  // The thesis's rule bisects j1..j3 and gives j4 the wrist's fixed +- 0.2 rad.
  EXPECT_EQ(bound_kinds(scene, BoundsParams{}),
            (std::vector<BoundKind>{BoundKind::kBisected, BoundKind::kBisected, BoundKind::kBisected,
                                    BoundKind::kFixed}));
  const BoundsParams p = bisecting({"j4"});
  ASSERT_EQ(bound_kinds(scene, p), (std::vector<BoundKind>{BoundKind::kFixed, BoundKind::kFixed,
                                                           BoundKind::kFixed, BoundKind::kBisected}));
  const WaypointBounds w = bound_waypoint(scene, collides, q, p);
  // Upper side, from 0 to the limit 1.5, delta 0.01. By hand: 1.5 c, 0.75 c, 0.375 f, 0.5625 f,
  // 0.65625 f, 0.703125 c, 0.6796875 f, 0.69140625 c -> B = 0.685546875, B - A = 0.0059 <= delta:
  // A = 0.6796875 (= 87/128) after 8 checks, theta* - A = 0.0015 < delta.
  EXPECT_EQ(w.upper[3], 0.6796875);
  EXPECT_LE(w.upper[3], theta);
  EXPECT_LT(theta - w.upper[3], 0.01);
  // Lower side: the chain turns away from the wall, the limit -1.5 is free (1 check).
  EXPECT_EQ(w.lower[3], -1.5);
  // j1..j3: nominal +- wrist_half_width.
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(w.lower[j], -0.2) << j;
    EXPECT_EQ(w.upper[j], 0.2) << j;
  }
  EXPECT_EQ(w.collapsed, std::vector<bool>(4, false));
  EXPECT_FALSE(w.nominal_in_volume);
  EXPECT_EQ(w.checks, 1 + 8 + 1);
}

TEST_F(BoundsSceneTest, BisectedJointsAreBoundedBaseToTipWhateverTheListsOrder) {
  // bounds.bisect = {j4, j2}: j2 first (from the nominal pose), then j4 from j2 at each of its bounds.
  // Nothing collides, so every run is one check at the limit (+-1.5); the probes, in order:
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("chain.xml", chain_cell(4)));
  std::vector<Eigen::VectorXd> probes;
  const CollisionFn never = [&probes](const Eigen::VectorXd& x) {
    probes.push_back(x);
    return false;
  };
  const WaypointBounds w = bound_waypoint(scene, never, Eigen::VectorXd::Zero(4), bisecting({"j4", "j2"}));
  auto pose = [](double j2, double j4) { return Eigen::VectorXd(Eigen::Vector4d(0, j2, 0, j4)); };
  const std::vector<Eigen::VectorXd> expected = {
      pose(0, 0),                         // nominal
      pose(-1.5, 0),    pose(1.5, 0),     // j2: lower, upper
      pose(-1.5, -1.5), pose(-1.5, 1.5),  // j4 with j2 at its lower bound
      pose(1.5, -1.5),  pose(1.5, 1.5),   // j4 with j2 at its upper bound
  };
  ASSERT_EQ(probes.size(), expected.size());
  for (size_t i = 0; i < probes.size(); ++i) EXPECT_EQ(probes[i], expected[i]) << "probe " << i;
  EXPECT_EQ(w.checks, 7);
  EXPECT_EQ(w.lower, Eigen::Vector4d(-0.2, -1.5, -0.2, -1.5));
  EXPECT_EQ(w.upper, Eigen::Vector4d(0.2, 1.5, 0.2, 1.5));
}

TEST_F(BoundsSceneTest, FourBisectedJointsTakeTwoFourEightAndSixteenRuns) {
  // A six-hinge chain with j1, j2, j4 and j5 bisected. Every probe collides: each run makes
  // ceil(log2(D / delta)) = ceil(log2(1.5 / 0.01)) = ceil(7.23) = 8 checks (D = 1.5 on both sides of
  // 0), every interval collapses to nominal +- min_half_width = +- 0.01, and the bases of a joint
  // are every combination of the earlier bisected joints at +- 0.01. Runs per level: 2, 4, 8, 16:
  // 1 + 8 x 30 = 241 checks.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("chain.xml", chain_cell(6)));
  std::vector<int> probes_of(6, 0);
  std::set<std::vector<double>> j5_bases;
  const CollisionFn always = [&](const Eigen::VectorXd& x) {
    EXPECT_EQ(x[2], 0.0);  // the fixed joints stay nominal
    EXPECT_EQ(x[5], 0.0);
    // The moving joint is the last bisected one that is off the collapsed set {0, +-0.01}.
    for (int j : {4, 3, 1, 0})
      if (std::abs(x[j]) > 0.01) {
        ++probes_of[static_cast<size_t>(j)];
        if (j == 4) j5_bases.insert({x[0], x[1], x[3]});
        break;
      }
    return true;
  };
  const BoundsParams p = bisecting({"j1", "j2", "j4", "j5"});
  ASSERT_EQ(bound_kinds(scene, p),
            (std::vector<BoundKind>{BoundKind::kBisected, BoundKind::kBisected, BoundKind::kFixed,
                                    BoundKind::kBisected, BoundKind::kBisected, BoundKind::kFixed}));
  const WaypointBounds w = bound_waypoint(scene, always, Eigen::VectorXd::Zero(6), p);
  EXPECT_EQ(w.checks, 1 + 8 * (2 + 4 + 8 + 16));
  EXPECT_TRUE(w.nominal_in_volume);
  EXPECT_EQ(w.collapsed, (std::vector<bool>{true, true, false, true, true, false}));
  EXPECT_EQ(probes_of, (std::vector<int>{8 * 2, 8 * 4, 0, 8 * 8, 8 * 16, 0}));
  EXPECT_EQ(j5_bases.size(), 8u);  // (j1, j2, j4) in {-0.01, 0.01}^3
  for (const auto& b : j5_bases)
    for (double v : b) EXPECT_EQ(std::abs(v), 0.01);
  EXPECT_EQ(w.lower[2], -0.2);
  EXPECT_EQ(w.upper[5], 0.2);
}

TEST_F(BoundsSceneTest, SixBisectedJointsTakeSixtyFourRunsAtTheLastLevel) {
  // The cap: six bisected joints of a seven-hinge chain, nothing colliding: one check per run,
  // 2 + 4 + 8 + 16 + 32 + 64 = 126 runs and the nominal check.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("chain.xml", chain_cell(7)));
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  const WaypointBounds w =
      bound_waypoint(scene, never, Eigen::VectorXd::Zero(7), bisecting({"j1", "j2", "j3", "j4", "j5", "j7"}));
  EXPECT_EQ(w.checks, 1 + 126);
  EXPECT_EQ(w.lower[5], -0.2);
  EXPECT_EQ(w.lower[6], -1.5);
}

TEST_F(BoundsSceneTest, PerJointHalfWidthsReplaceTheWristsAndTheRailsAndAreClamped) {
  // Dallara: the patch pose with j5 = 2.2 (upper limit 2.2689); nothing collides.
  const Scene scene = Scene::load(workcell("dallara"));
  Eigen::VectorXd q(6);
  q << 0.5, 0.734922, 0.0866255, -3.14159, 2.2, -1.11219;
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  BoundsParams p;
  p.half_width = {{"j5", 0.3}, {"j6", 0.1}};
  WaypointBounds w = bound_waypoint(scene, never, q, p);
  EXPECT_NEAR(w.lower[3], -3.34159, 1e-12);  // j4: wrist_half_width, 0.2
  EXPECT_NEAR(w.upper[3], -2.94159, 1e-12);
  EXPECT_NEAR(w.lower[4], 1.9, 1e-12);  // j5: 0.3, clamped at its upper limit
  EXPECT_NEAR(w.upper[4], 2.2689, 1e-12);
  EXPECT_NEAR(w.lower[5], -1.21219, 1e-12);  // j6: 0.1
  EXPECT_NEAR(w.upper[5], -1.01219, 1e-12);
  EXPECT_EQ(fixed_half_width(scene, 3, p), 0.2);
  EXPECT_EQ(fixed_half_width(scene, 4, p), 0.3);
  // A zero half-width pins the joint to its nominal value.
  p.half_width = {{"j6", 0.0}};
  w = bound_waypoint(scene, never, q, p);
  EXPECT_EQ(w.lower[5], q[5]);
  EXPECT_EQ(w.upper[5], q[5]);
  // With j4 bisected, j3 is fixed and may be given a width of its own.
  p = bisecting({"j1", "j2", "j4"});
  p.half_width = {{"j3", 0.05}};
  w = bound_waypoint(scene, never, q, p);
  EXPECT_NEAR(w.lower[2], 0.0366255, 1e-12);
  EXPECT_NEAR(w.upper[2], 0.1366255, 1e-12);
  EXPECT_EQ(w.lower[3], scene.joints()[3].lower);  // j4 bisected: the free limits
  EXPECT_EQ(w.upper[3], scene.joints()[3].upper);

  // DLR: the rail (-9 .. 1 m) gets an absolute half-width [m] instead of 3 % of its range.
  const Scene dlr = Scene::load(workcell("dlr"));
  Eigen::VectorXd r = dlr.keyframe("home").q;  // rail at -4 m
  BoundsParams rail;
  rail.half_width = {{"rail_x", 0.5}};
  EXPECT_EQ(fixed_half_width(dlr, 0, rail), 0.5);
  EXPECT_NEAR(fixed_half_width(dlr, 0, BoundsParams{}), 0.3, 1e-12);
  w = bound_waypoint(dlr, never, r, rail);
  EXPECT_NEAR(w.lower[0], -4.5, 1e-12);
  EXPECT_NEAR(w.upper[0], -3.5, 1e-12);
  r[0] = -8.9;
  w = bound_waypoint(dlr, never, r, rail);
  EXPECT_NEAR(w.lower[0], -9.0, 1e-12);  // clamped to the limit
  EXPECT_NEAR(w.upper[0], -8.4, 1e-12);
}

TEST_F(BoundsSceneTest, JointChoicesTheRobotCannotTakeAreRefused) {
  const Scene dallara = Scene::load(workcell("dallara"));
  const Scene dlr = Scene::load(workcell("dlr"));
  auto refusal = [](const Scene& scene, const std::function<void(Params&)>& set) {
    Params p;
    set(p);
    return test::error_of([&] { validate_for_scene(p, scene); });
  };
  const std::string d = dallara.source() + ": ";
  EXPECT_EQ(
      refusal(dallara,
              [](Params& p) {
                p.bounds.bisect = {"j1", "j9"};
              }),
      d + "parameter 'bounds.bisect' names joint 'j9', which the robot does not have (joints: j1, j2, j3, "
          "j4, j5, j6)");
  EXPECT_EQ(
      refusal(dlr,
              [](Params& p) {
                p.bounds.bisect = {"rail_x", "j1"};
              }),
      dlr.source() +
          ": parameter 'bounds.bisect' names slide joint 'rail_x': only hinge joints are bisected (a slide "
          "joint's half-width is 'bounds.linear_axis_tolerance' or 'bounds.half_width')");
  EXPECT_EQ(
      refusal(dallara,
              [](Params& p) {
                p.bounds.half_width = {{"j7", 0.1}};
              }),
      d + "parameter 'bounds.half_width.j7' = 0.1 names a joint the robot does not have (joints: j1, j2, "
          "j3, j4, j5, j6)");
  EXPECT_EQ(
      refusal(dallara,
              [](Params& p) {
                p.bounds.half_width = {{"j2", 0.1}};
              }),
      d + "parameter 'bounds.half_width.j2' = 0.1: joint 'j2' is bisected, so it has no fixed half-width "
          "(without 'bounds.bisect' the first three hinge joints are)");
  EXPECT_EQ(
      refusal(dallara,
              [](Params& p) {
                p.bounds.bisect = {"j1", "j2", "j4"};
                p.bounds.half_width = {{"j4", 0.1}};
              }),
      d + "parameter 'bounds.half_width.j4' = 0.1: joint 'j4' is bisected, so it has no fixed half-width "
          "(it is in 'bounds.bisect')");
  // Params::validate's refusals come first (duplicates, the cap, the values).
  EXPECT_EQ(refusal(dallara,
                    [](Params& p) {
                      p.bounds.bisect = {"j4", "j4"};
                    }),
            "parameter 'bounds.bisect' names joint 'j4' twice");
  // The collapse guard's check now covers the joints bisect names: min_half_width 1.6 is more than
  // half of j4's range on the chain (3 rad), when j4 is bisected only.
  test::TempDir dir;
  const Scene chain = Scene::load(dir.write("chain.xml", chain_cell(4)));
  Params wide;
  wide.bounds.min_half_width = 1.6;
  EXPECT_THAT(test::error_of([&] { validate_for_scene(wide, chain); }), HasSubstr("joint 'j1'"));
  wide.bounds.bisect = {"j4"};
  EXPECT_THAT(
      test::error_of([&] { validate_for_scene(wide, chain); }),
      HasSubstr("'bounds.min_half_width' = 1.6 rad must be smaller than half the range of joint 'j4'"));
  // The library itself refuses what it cannot bisect, also without validate_for_scene.
  const CollisionFn never = [](const Eigen::VectorXd&) { return false; };
  EXPECT_THROW(bound_waypoint(dallara, never, Eigen::VectorXd::Zero(6), bisecting({"elbow"})), InputError);
  // Valid choices pass.
  Params ok;
  ok.bounds.bisect = {"j4", "j1", "j2"};
  ok.bounds.half_width = {{"j3", 0.3}, {"j6", 0.0}};
  EXPECT_NO_THROW(validate_for_scene(ok, dallara));
  ok.bounds.bisect.clear();
  ok.bounds.half_width = {{"rail_x", 1.0}, {"j4", 0.1}};
  EXPECT_NO_THROW(validate_for_scene(ok, dlr));
}

TEST_F(BoundsSceneTest, TheBoundsFileRecordsTheChosenKinds) {
  // The pipeline end to end on the chain: j2 and j4 bisected, j1 with a half-width of its own.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("chain.xml", chain_cell(4)));
  Params p;
  p.height_map.max_cells = 200;
  p.safety.mode = SafetyMode::kNone;
  p.bounds.bisect = {"j4", "j2"};
  p.bounds.half_width = {{"j1", 0.1}};
  VolumeModel world(scene, p.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
  const auto path = keyframe_path(scene, "a", "b", 2);
  const BoundsRun run = compute_bounds(scene, world, path, p, 1);
  const nlohmann::json file = bounds_json(scene, run, p);
  EXPECT_EQ(file.at("joint_bounding"),
            nlohmann::json::parse(R"(["fixed", "bisected", "fixed", "bisected"])"));
  EXPECT_EQ(file.at("params").at("bounds").at("bisect"), nlohmann::json::parse(R"(["j4", "j2"])"));
  for (const auto& w : run.bounds) {
    EXPECT_NEAR(w.upper[0] - w.q[0], 0.1, 1e-12);
    EXPECT_NEAR(w.upper[2] - w.q[2], 0.2, 1e-12);
  }
  // Three threads for two waypoints give the same bounds (the runs of a level spread over them).
  const auto two = bound_path(world, path, p.bounds, 3);
  for (size_t i = 0; i < two.size(); ++i) {
    EXPECT_EQ(two[i].lower, run.bounds[i].lower) << i;
    EXPECT_EQ(two[i].upper, run.bounds[i].upper) << i;
    EXPECT_EQ(two[i].checks, run.bounds[i].checks) << i;
  }
}

}  // namespace
}  // namespace leeway
