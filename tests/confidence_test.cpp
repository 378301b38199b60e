// The Confidence Factor (thesis section 4.1) against hand-computed Wilson intervals and the
// analytic collision-free share of the one-link arm next to a wall.
#include "leeway/core/confidence.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;

constexpr double kZ = 1.959963984540054;  // the 97.5 % quantile of the standard normal
constexpr double kZ2 = kZ * kZ;           // 3.8414588...

// A wall whose near face is the plane y = 0.6 over x in [0, 2], z in [0, 1].
constexpr const char* kWall = R"(<geom name="wall" type="box" size="1 0.1 0.5" pos="1 0.7 0.5"/>)";

// The one-link arm first touches the wall at theta* = asin(0.6 / sqrt(1.0025)) - atan(0.05)
// = 0.5926073 rad (its far corner (1, 0.05) reaches y = 0.6; bounds_test.cpp derives it), and
// collides for every theta in [theta*, pi/2] (the corner's y keeps growing, its x stays >= 0.02
// up to theta = 1.5). Negative angles turn the link away from the wall.
double theta_star() { return std::asin(0.6 / std::sqrt(1.0025)) - std::atan(0.05); }

WaypointBounds one_joint(double q, double lower, double upper) {
  WaypointBounds w;
  w.q = Eigen::VectorXd::Constant(1, q);
  w.lower = Eigen::VectorXd::Constant(1, lower);
  w.upper = Eigen::VectorXd::Constant(1, upper);
  w.collapsed = {false};
  return w;
}

TEST(WilsonTest, HalfOfOneHundred) {
  // p = 1/2: centre (p + z^2 / 2n) / (1 + z^2 / n) = 1/2 exactly; half-width
  // z sqrt(p (1 - p) / n + z^2 / 4n^2) / (1 + z^2 / n) = z / (2 sqrt(n + z^2))
  // = 1.959964 / (2 sqrt(103.8414588)) = 1.959964 / 20.380529 = 0.0961685.
  const auto [lo, hi] = wilson_interval(50, 100);
  EXPECT_NEAR((lo + hi) / 2, 0.5, 1e-15);
  EXPECT_NEAR(lo, 0.5 - 0.0961685, 1e-7);
  EXPECT_NEAR(hi, 0.5 + 0.0961685, 1e-7);
}

TEST(WilsonTest, AllAndNone) {
  // p = 1: centre (1 + z^2 / 2n) / d, half (z^2 / 2n) / d with d = 1 + z^2 / n, so
  // lower = 1 / d = n / (n + z^2) = 100 / 103.8414588 = 0.9630065 and upper = 1.
  auto [lo, hi] = wilson_interval(100, 100);
  EXPECT_NEAR(lo, 0.9630065, 1e-7);
  EXPECT_NEAR(lo, 100 / (100 + kZ2), 1e-12);
  EXPECT_EQ(hi, 1.0);  // exactly: a CF of 100 % lies inside its own interval
  EXPECT_EQ(wilson_interval(300000, 300000).second, 1.0);
  // p = 0: lower 0, upper z^2 / (n + z^2) = 3.8414588 / 103.8414588 = 0.0369935.
  std::tie(lo, hi) = wilson_interval(0, 100);
  EXPECT_EQ(lo, 0.0);
  EXPECT_NEAR(hi, 0.0369935, 1e-7);
  // No trials: the whole of [0, 1].
  std::tie(lo, hi) = wilson_interval(0, 0);
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 1.0);
}

TEST(WilsonTest, NinetyOfOneHundred) {
  // p = 0.9, n = 100: d = 1.038414588; centre (0.9 + 0.019207294) / d = 0.919207294 / 1.038414588
  // = 0.885203; half = z sqrt(0.0009 + 0.0000960365) / d = 1.959964 x 0.0315600 / 1.038414588
  // = 0.0595683 -> [0.825634, 0.944771].
  const auto [lo, hi] = wilson_interval(90, 100);
  EXPECT_NEAR(lo, 0.825634, 1e-6);
  EXPECT_NEAR(hi, 0.944771, 1e-6);
}

class ConfidenceTest : public test::MujocoTest {
 protected:
  Scene load(const std::string& world) { return Scene::load(dir_.write("cell.xml", one_link_cell(world))); }
  test::TempDir dir_;
};

TEST_F(ConfidenceTest, NoObstaclesGiveExactlyOne) {
  const Scene scene = load("");
  ASSERT_TRUE(scene.obstacle_geoms().empty());
  CfParams p;
  p.windows = 7;
  p.samples = 300;
  const CfResult r = confidence_factor(scene, {one_joint(0, -3, 3), one_joint(1, 0.5, 2.9)}, p, 2);
  EXPECT_EQ(r.cf, 1.0);
  EXPECT_EQ(r.collisions, 0);
  EXPECT_EQ(r.samples, 7 * 300);
  EXPECT_EQ(r.window_cf, std::vector<double>(7, 1.0));
  EXPECT_EQ(r.worst_window_cf, 1.0);
  EXPECT_EQ(r.worst_window, 0);  // the first of equals
  EXPECT_NEAR(r.ci_high, 1.0, 1e-12);
  EXPECT_NEAR(r.ci_low, 2100 / (2100 + kZ2), 1e-12);  // n / (n + z^2) = 0.998174
}

TEST_F(ConfidenceTest, AnalyticShareNextToAWall) {
  // Bounds [-0.5, 1.0] on j1, the same at both waypoints: j1 is uniform on [-0.5, 1.0] and free
  // exactly on [-0.5, theta*): CF = (theta* + 0.5) / 1.5 = 1.0926073 / 1.5 = 0.7284049.
  // 30 windows x 2000 samples: sigma = sqrt(p (1 - p) / 60000) = 0.0018158; tolerance 4 sigma.
  const Scene scene = load(kWall);
  const double expected = (theta_star() + 0.5) / 1.5;
  ASSERT_NEAR(expected, 0.7284049, 1e-7);
  CfParams p;
  p.windows = 30;
  p.samples = 2000;
  const CfResult r = confidence_factor(scene, {one_joint(0, -0.5, 1.0), one_joint(0, -0.5, 1.0)}, p, 2);
  const double sigma = std::sqrt(expected * (1 - expected) / 60000);
  EXPECT_NEAR(r.cf, expected, 4 * sigma);
  EXPECT_EQ(r.samples, 60000);
  EXPECT_EQ(r.collisions, 60000 - std::lround(r.cf * 60000));
  EXPECT_LE(r.ci_low, r.cf);
  EXPECT_GE(r.ci_high, r.cf);
  // The Wilson interval's half-width is about 1.96 sigma here (n large, p away from 0 and 1).
  EXPECT_NEAR((r.ci_high - r.ci_low) / 2, kZ * sigma, 0.1 * sigma);
  // Every window is a binomial sample of 2000 with the same p: within 5 of its sigmas (0.0099).
  const double window_sigma = std::sqrt(expected * (1 - expected) / 2000);
  ASSERT_EQ(r.window_cf.size(), 30u);
  double mean = 0;
  for (double w : r.window_cf) {
    EXPECT_NEAR(w, expected, 5 * window_sigma);
    mean += w / 30;
  }
  EXPECT_NEAR(mean, r.cf, 1e-12);  // cf is the mean of equal-sized windows
}

TEST_F(ConfidenceTest, DeterministicForASeedAndAnyThreadCount) {
  const Scene scene = load(kWall);
  const std::vector<WaypointBounds> b = {one_joint(0, -0.5, 1.0), one_joint(0.2, -0.3, 1.2)};
  CfParams p;
  p.windows = 9;
  p.samples = 400;
  p.seed = 11;
  const CfResult one = confidence_factor(scene, b, p, 1);
  const CfResult again = confidence_factor(scene, b, p, 1);
  const CfResult two = confidence_factor(scene, b, p, 2);
  const CfResult many = confidence_factor(scene, b, p, 16);  // more threads than windows
  for (const CfResult* r : {&again, &two, &many}) {
    EXPECT_EQ(r->window_cf, one.window_cf);
    EXPECT_EQ(r->collisions, one.collisions);
    EXPECT_EQ(r->cf, one.cf);
    EXPECT_EQ(r->worst_window, one.worst_window);
  }
  // Not vacuous: this scene has collisions, and another seed draws other samples.
  EXPECT_GT(one.collisions, 0);
  p.seed = 12;
  EXPECT_NE(confidence_factor(scene, b, p, 2).collisions, one.collisions);
}

TEST_F(ConfidenceTest, WorstWindowIsWhereTheBoundsAreWide) {
  // Bounds [0, 0] at s = 0 widening linearly to [0, 1.5] at s = 1: at s, j1 is uniform on
  // [0, 1.5 s] and collides with probability max(0, 1 - theta* / 1.5 s), i.e. beyond
  // s_c = theta* / 1.5 = 0.395072. Window [s0, s1] of width h = 0.2 (5 windows) has
  //   CF = 1 - (1/h) * integral_{max(s0, s_c)}^{s1} (1 - s_c / s) ds
  //      = 1 - (s1 - m - s_c ln(s1 / m)) / h,  m = max(s0, s_c):
  //   [0, 0.2]: 1;  [0.2, 0.4]: 0.99985;  [0.4, 0.6]: 0.801;  [0.6, 0.8]: 0.568;  [0.8, 1]: 0.441.
  const Scene scene = load(kWall);
  CfParams p;
  p.windows = 5;
  p.samples = 2000;
  const CfResult r = confidence_factor(scene, {one_joint(0, 0, 0), one_joint(0, 0, 1.5)}, p, 2);
  const double sc = theta_star() / 1.5;
  ASSERT_EQ(r.window_cf.size(), 5u);
  for (int w = 0; w < 5; ++w) {
    const double s0 = 0.2 * w, s1 = s0 + 0.2, m = std::max(s0, sc);
    const double expected = s1 <= sc ? 1.0 : 1 - (s1 - m - sc * std::log(s1 / m)) / 0.2;
    const double sigma = std::sqrt(expected * (1 - expected) / 2000);
    EXPECT_NEAR(r.window_cf[static_cast<size_t>(w)], expected, 4 * sigma + 1e-3) << "window " << w;
  }
  EXPECT_EQ(r.window_cf[0], 1.0);  // never beyond theta* before s = 0.395
  EXPECT_EQ(r.worst_window, 4);
  EXPECT_EQ(r.worst_window_cf, r.window_cf[4]);
  EXPECT_NEAR(r.worst_window_cf, 1 - (0.2 - sc * std::log(1.0 / 0.8)) / 0.2, 0.04);  // 0.4408
}

TEST_F(ConfidenceTest, OneWaypointSamplesItsBoundsAlone) {
  // A single waypoint: every window samples the same box [-0.5, 1.0] (t = 0).
  const Scene scene = load(kWall);
  CfParams p;
  p.windows = 4;
  p.samples = 2500;
  const CfResult r = confidence_factor(scene, {one_joint(0, -0.5, 1.0)}, p, 1);
  const double expected = (theta_star() + 0.5) / 1.5;
  EXPECT_NEAR(r.cf, expected, 4 * std::sqrt(expected * (1 - expected) / 10000));
}

TEST_F(ConfidenceTest, RejectsBadInputs) {
  const Scene scene = load(kWall);
  const std::vector<WaypointBounds> ok = {one_joint(0, -0.5, 1.0), one_joint(0, -0.5, 1.0)};
  CfParams p;
  p.windows = 2;
  p.samples = 10;
  EXPECT_NO_THROW(confidence_factor(scene, ok, p, 1));
  CfParams bad = p;
  bad.windows = 0;
  EXPECT_THROW(confidence_factor(scene, ok, bad, 1), InputError);
  bad = p;
  bad.samples = 0;
  EXPECT_THROW(confidence_factor(scene, ok, bad, 1), InputError);
  bad = p;
  bad.samples = -5;
  EXPECT_THROW(confidence_factor(scene, ok, bad, 1), InputError);
  EXPECT_THROW(confidence_factor(scene, {}, p, 1), InputError);
  // lower > upper
  EXPECT_THROW(confidence_factor(scene, {ok[0], one_joint(0, 0.5, 0.4)}, p, 1), InputError);
  // wrong sizes: 2 joints for a 1-joint robot, in each of q, lower, upper
  for (int which = 0; which < 3; ++which) {
    WaypointBounds w = ok[1];
    Eigen::VectorXd& v = which == 0 ? w.q : which == 1 ? w.lower : w.upper;
    v = Eigen::VectorXd::Constant(2, v[0]);
    EXPECT_THROW(confidence_factor(scene, {ok[0], w}, p, 1), InputError) << which;
  }
  // not finite
  WaypointBounds nan_bound = ok[1];
  nan_bound.upper[0] = std::nan("");
  EXPECT_THROW(confidence_factor(scene, {ok[0], nan_bound}, p, 1), InputError);
}

TEST_F(ConfidenceTest, SegmentsAreTimedByTheSlowestJoint) {
  // The one-link arm's j1 has user[0] = 1.5 rad/s: segments of 0.3, 0 and 0.6 rad last 0.2, 0 and
  // 0.4 s.
  const Scene scene = load("");
  const std::vector<WaypointBounds> b = {one_joint(0, -0.1, 0.1), one_joint(0.3, 0.2, 0.4),
                                         one_joint(0.3, 0.2, 0.4), one_joint(-0.3, -0.4, -0.2)};
  const PathTiming t = time_path(scene, b);
  ASSERT_TRUE(t.timed);
  ASSERT_EQ(t.segment.size(), 3u);
  EXPECT_NEAR(t.segment[0], 0.2, 1e-15);
  EXPECT_EQ(t.segment[1], 0.0);
  EXPECT_NEAR(t.segment[2], 0.4, 1e-15);
  EXPECT_NEAR(t.total, 0.6, 1e-15);
  // The IRB 6700 (docs/mjcf-conventions.md speeds: j1 1.9199, j6 3.6652 rad/s): j1 0.5 rad and j6
  // 1.0 rad take 0.2604 s and 0.2728 s; j6 sets the segment's duration.
  const Scene dallara = Scene::load(test::workcell("dallara"));
  Eigen::VectorXd q1 = Eigen::VectorXd::Zero(6);
  q1[0] = 0.5;
  q1[5] = 1.0;
  const WaypointBounds a(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6));
  const WaypointBounds c(q1, q1, q1);
  EXPECT_NEAR(time_path(dallara, {a, c}).total, 1.0 / 3.6652, 1e-12);
}

TEST_F(ConfidenceTest, HowThePathIsSampledDoesNotChangeTheCf) {
  // The same geometry and bounds as two, three (a duplicated end) and three (a midpoint) waypoints:
  // a duplicated waypoint is a segment of zero duration and draws nothing, so the CF is the same
  // sample for sample; a midpoint splits the time evenly, so the draws are the same up to the
  // rounding of the interpolation. (With windows of equal path parameter the duplicated end took a
  // third of the samples at one pose.)
  const Scene scene = load(kWall);
  const WaypointBounds a = one_joint(0, -0.5, 0.7), b = one_joint(0.4, 0.1, 1.2);
  const WaypointBounds mid = one_joint(0.2, -0.2, 0.95);
  CfParams p;
  p.windows = 10;
  p.samples = 2000;
  const CfResult two = confidence_factor(scene, {a, b}, p, 2);
  const CfResult dup_end = confidence_factor(scene, {a, b, b}, p, 2);
  const CfResult dup_start = confidence_factor(scene, {a, a, b}, p, 2);
  const CfResult split = confidence_factor(scene, {a, mid, b}, p, 2);
  EXPECT_GT(two.collisions, 1000);  // not vacuous: the wall is within the bounds
  EXPECT_LT(two.collisions, 19000);
  EXPECT_EQ(dup_end.collisions, two.collisions);
  EXPECT_EQ(dup_end.window_cf, two.window_cf);
  EXPECT_EQ(dup_start.collisions, two.collisions);
  EXPECT_NEAR(split.cf, two.cf, 1e-3);
  EXPECT_TRUE(two.timed);
  EXPECT_NEAR(two.duration, 0.4 / 1.5, 1e-15);
}

}  // namespace
}  // namespace leeway
