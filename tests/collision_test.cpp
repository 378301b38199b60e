// The fast collision core: the midphase grid against brute force, and the midphase
// checker against MuJoCo's full mj_collision pass on the three thesis cells.
#include "leeway/core/collision.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "core/random.hpp"
#include "leeway/core/bounds.hpp"
#include "leeway/core/box.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/midphase.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/volume.hpp"
#include "leeway/core/volume_world.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

class CollisionTest : public test::MujocoTest {};

// ---------------------------------------------------------------- the grid

std::set<int> brute_force(const std::vector<Aabb>& boxes, const Aabb& q, double tol) {
  std::set<int> out;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (overlaps(q, boxes[i], tol)) out.insert(static_cast<int>(i));
  return out;
}

TEST(AabbGridTest, ReturnsExactlyTheOverlappingBoxes) {
  // A height map of 0.1 m cells with random heights, a few large boxes, a flat one, an infinite one.
  std::mt19937_64 rng(7);
  auto u = [&](double lo, double hi) { return lo + (hi - lo) * detail::unit(rng); };
  std::vector<Aabb> boxes;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 30; ++j) {
      if (u(0, 1) < 0.2) continue;  // holes, as cells beyond reach
      const double h = u(0.01, 1.5);
      boxes.push_back({{i * 0.1 - 2, j * 0.1 - 1.5, 0}, {i * 0.1 - 1.9, j * 0.1 - 1.4, h}});
    }
  boxes.push_back({{-3, -3, 0.5}, {3, -2.5, 2.0}});       // a wall: larger than two cells
  boxes.push_back({{0.5, 0.5, 1.0}, {0.55, 0.55, 1.0}});  // flat
  const double inf = std::numeric_limits<double>::infinity();
  boxes.push_back({{-inf, -inf, -inf}, {inf, inf, 0}});  // a floor plane
  AabbGrid grid;
  grid.build(boxes, 1e-9);
  EXPECT_EQ(grid.size(), static_cast<int>(boxes.size()));
  EXPECT_NEAR(grid.cell_side(), 0.1, 1e-12);  // the median footprint
  EXPECT_EQ(grid.large(), 2);                 // the wall and the plane

  int nonempty = 0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d c(u(-2.5, 2.5), u(-2, 2), u(-0.5, 2.5)), e(u(0, 0.6), u(0, 0.6), u(0, 0.4));
    const Aabb q{c - e, c + e};
    std::set<int> got;
    EXPECT_FALSE(grid.any(q, [&](int i) {
      EXPECT_TRUE(got.insert(i).second) << "box " << i << " visited twice";
      return false;
    }));
    ASSERT_EQ(got, brute_force(boxes, q, 1e-9)) << "query " << k;
    nonempty += got.size() > 1;
  }
  EXPECT_GT(nonempty, 1000);
}

TEST(AabbGridTest, TouchingWithinTheToleranceCountsAndTheFirstHitStops) {
  std::vector<Aabb> boxes = {{{0, 0, 0}, {1, 1, 1}}, {{1, 0, 0}, {2, 1, 1}}, {{2, 0, 0}, {3, 1, 1}}};
  AabbGrid grid;
  grid.build(boxes, 1e-9);
  // Touching the first box's top face from above, 0.5e-9 m up: within the tolerance.
  const Aabb above{{0.2, 0.2, 1 + 0.5e-9}, {0.4, 0.4, 2}};
  EXPECT_TRUE(grid.any(above, [](int i) { return i == 0; }));
  const Aabb clear{{0.2, 0.2, 1 + 2e-9}, {0.4, 0.4, 2}};
  EXPECT_FALSE(grid.any(clear, [](int) { return true; }));
  int visits = 0;
  const Aabb all{{-1, -1, -1}, {4, 2, 2}};
  EXPECT_TRUE(grid.any(all, [&](int) { return ++visits == 2; }));
  EXPECT_EQ(visits, 2);
}

TEST(AabbGridTest, EmptyAndNonFinite) {
  AabbGrid grid;
  grid.build({});
  EXPECT_FALSE(grid.any({{-1, -1, -1}, {1, 1, 1}}, [](int) { return true; }));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  grid.build({{{nan, 0, 0}, {1, 1, 1}}});
  EXPECT_EQ(grid.large(), 1);  // kept, and visited by every query: the narrowphase decides
  EXPECT_FALSE(grid.any({{-1, -1, -1}, {1, 1, 1}}, [](int) { return true; }));  // NaN never overlaps
}

TEST(CheckerNameTest, ParsesBothAndRefusesOthers) {
  EXPECT_EQ(parse_checker("midphase"), CollisionChecker::kMidphase);
  EXPECT_EQ(parse_checker("mujoco"), CollisionChecker::kMujoco);
  EXPECT_STREQ(checker_name(CollisionChecker::kMujoco), "mujoco");
  try {
    parse_checker("fcl");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'fcl' is not one of: midphase, mujoco"), std::string::npos);
  }
}

// ---------------------------------------------------------------- excludes and the fast core

TEST_F(CollisionTest, ARobotBodyExcludeKeepsTheFastCore) {
  // In a Scene the robot's geoms never touch one another by their (normalised) bitmasks: an exclude
  // between two robot bodies only drops self pairs, and mj_collision's answer stays the midphase's.
  test::TempDir dir;
  const Scene s = Scene::load(dir.write(
      "cell.xml", test::three_link_cell(R"(<contact><exclude body1="link3" body2="base"/></contact>)")));
  const mjModel& m = s.model();
  ASSERT_EQ(m.nexclude, 1);
  const auto [b1, b2] = excluded_bodies(m, 0);
  EXPECT_EQ(object_name(m, mjOBJ_BODY, b1), "base");  // sorted by body id
  EXPECT_EQ(object_name(m, mjOBJ_BODY, b2), "link3");
  EXPECT_FALSE(excludes_a_contact(m));
  EXPECT_TRUE(emulates_mj_collision(m));
  EXPECT_EQ(s.checker(), CollisionChecker::kMidphase);
}

TEST_F(CollisionTest, AnExcludeBetweenBodiesThatCouldTouchNeedsMujoco) {
  // The same excludes on the model as written (every geom contype = conaffinity = 1, the MJCF
  // default): the bodies could touch, so the exclude changes what mj_collision reports.
  const std::string robot_pair = R"(<contact><exclude body1="base" body2="link3"/></contact>)";
  const ModelPtr raw = load_model_text(test::three_link_cell(robot_pair), "raw.xml");
  EXPECT_TRUE(excludes_a_contact(*raw));
  EXPECT_FALSE(emulates_mj_collision(*raw));
  // Two cell bodies: 'stand' (block: contype 0, conaffinity 1) and 'crate' (the defaults) can touch.
  const std::string crate = R"(<contact><exclude body1="stand" body2="crate"/></contact>)";
  std::string xml = test::three_link_cell(crate);
  xml.replace(xml.find("  </worldbody>"), 0,
              "    <body name=\"crate\" pos=\"-1.5 1 0\"><geom name=\"crate_box\" type=\"box\" "
              "size=\"0.2 0.2 0.2\" pos=\"0 0 0.2\"/></body>\n");
  const ModelPtr cell = load_model_text(xml, "crate.xml");
  EXPECT_TRUE(excludes_a_contact(*cell));
  EXPECT_FALSE(emulates_mj_collision(*cell));
  // Bodies whose bitmasks cannot meet (both contype 0): the exclude removes nothing.
  std::string apart = xml;
  apart.replace(apart.find("size=\"0.2 0.2 0.2\""), 0, "contype=\"0\" ");
  const ModelPtr none = load_model_text(apart, "apart.xml");
  EXPECT_FALSE(excludes_a_contact(*none));
  EXPECT_TRUE(emulates_mj_collision(*none));
}

// ---------------------------------------------------------------- checker parity

struct Case {
  const char* cell;
  const char* from;
  const char* to;
};

// Both checkers on one cell: scenes, volume models and checkers side by side.
struct Pair {
  Pair(const std::string& cell, int max_cells, const std::vector<Eigen::VectorXd>& path_in,
       const Params& params_in)
      : fast(Scene::load(cell)),
        reference(Scene::load(cell, options(CollisionChecker::kMujoco))),
        path(path_in),
        params(params_in) {
    params.height_map.max_cells = max_cells;
    const Categories c = categorize(fast, path, params.categorize);
    volume = generate_volume(c, params.height_map, params.volume);
    fast_world = std::make_unique<VolumeModel>(fast, 16);
    reference_world = std::make_unique<VolumeModel>(reference, 16);
    fast_world->set_boxes(volume.boxes);
    reference_world->set_boxes(volume.boxes);
    fast_checker = std::make_unique<VolumeChecker>(*fast_world);
    reference_checker = std::make_unique<VolumeChecker>(*reference_world);
  }
  static SceneOptions options(CollisionChecker c) {
    SceneOptions o;
    o.checker = c;
    return o;
  }
  Scene fast, reference;
  std::vector<Eigen::VectorXd> path;
  Params params;
  Volume volume;
  std::unique_ptr<VolumeModel> fast_world, reference_world;
  std::unique_ptr<VolumeChecker> fast_checker, reference_checker;
};

TEST_F(CollisionTest, MidphaseGivesMujocosAnswersOnTheThesisCells) {
  // 3 cells x 3 MAX_cells x 2,300 configurations = 20,700 configurations, each checked against the
  // volume and against the real obstacles by both checkers; a third uniform within the joint limits
  // (anywhere in the cell), two thirds within 0.1 rad of the path (near the volume's surface). Tie
  // tolerance: none, the answers must be equal.
  const Case cases[] = {
      {"dallara", "home", "patch"}, {"baltico", "patch", "mould"}, {"dlr", "mould", "home"}};
  const Params params = preset_params("thesis");
  long checked = 0, volume_hits = 0, obstacle_hits = 0;
  const int samples = test::scaled_count(2300);
  for (const Case& k : cases) {
    const Scene scene = Scene::load(test::workcell(k.cell));
    const auto path = keyframe_path(scene, k.from, k.to, 2);
    for (int max_cells : {500, 3000, 12000}) {
      Pair p(test::workcell(k.cell), max_cells, path, params);
      RobotState fast_state(p.fast), reference_state(p.reference);
      std::mt19937_64 rng(static_cast<std::uint64_t>(max_cells));
      const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
      for (int s = 0; s < samples; ++s) {
        Eigen::VectorXd q(scene.dof());
        if (s % 3 == 0) {
          for (int i = 0; i < q.size(); ++i) q[i] = lo[i] + (hi[i] - lo[i]) * detail::unit(rng);
        } else {
          const double t = detail::unit(rng);
          q = path[0] + t * (path[1] - path[0]);
          for (int i = 0; i < q.size(); ++i)
            q[i] = std::clamp(q[i] + 0.2 * (detail::unit(rng) - 0.5), lo[i], hi[i]);
        }
        const bool v = p.reference_checker->in_collision(q);
        ASSERT_EQ(p.fast_checker->in_collision(q), v)
            << k.cell << " MAX_cells " << max_cells << " sample " << s;
        const bool o = reference_state.in_collision(q);
        ASSERT_EQ(fast_state.in_collision(q), o) << k.cell << " obstacles, sample " << s;
        volume_hits += v;
        obstacle_hits += o;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 9L * samples);
  // Both answers occur often, so the comparison is not one-sided (as shares of the 20,700).
  EXPECT_GT(volume_hits, checked * 2000 / 20700);
  EXPECT_LT(volume_hits, checked - checked * 500 / 20700);  // the thesis's volumes fill most of the reach
  EXPECT_GT(obstacle_hits, checked * 1000 / 20700);
  EXPECT_LT(obstacle_hits, checked - checked * 1000 / 20700);
}

TEST_F(CollisionTest, MidphaseGivesMujocosAnswersOnACellNotTunedFor) {
  // shelf_bay (a shelf of thin boards, tables at 0.60 and 1.05 m, a cover panel rotated about two
  // axes: an obstacle whose AABB is not its box), the leeway preset's volume at 20,000 cells, 3,000
  // configurations near the pick -> place path and anywhere; volume and obstacles.
  const Scene scene = Scene::load(test::workcell("shelf_bay"));
  const auto path = keyframe_path(scene, "pick", "place", 2);
  Params params = preset_params("leeway");
  Pair p(test::workcell("shelf_bay"), 20000, path, params);
  RobotState fast_state(p.fast), reference_state(p.reference);
  std::mt19937_64 rng(5);
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  long volume_hits = 0, obstacle_hits = 0;
  const int samples = test::scaled_count(3000);
  for (int s = 0; s < samples; ++s) {
    Eigen::VectorXd q = path[0] + detail::unit(rng) * (path[1] - path[0]);
    const double spread = s % 2 ? 0.4 : 3.0;
    for (int i = 0; i < q.size(); ++i)
      q[i] = std::clamp(q[i] + spread * (detail::unit(rng) - 0.5), lo[i], hi[i]);
    const bool v = p.reference_checker->in_collision(q);
    ASSERT_EQ(p.fast_checker->in_collision(q), v) << "volume, sample " << s;
    const bool o = reference_state.in_collision(q);
    ASSERT_EQ(fast_state.in_collision(q), o) << "obstacles, sample " << s;
    volume_hits += v;
    obstacle_hits += o;
  }
  // As shares of the 3,000: the volume fills most of the reach, at least 50 free ones.
  EXPECT_GT(volume_hits, samples * 300L / 3000);
  EXPECT_LT(volume_hits, samples - samples * 50L / 3000);
  EXPECT_GT(obstacle_hits, samples * 100L / 3000);
  EXPECT_LT(obstacle_hits, samples - samples * 100L / 3000);
}

TEST_F(CollisionTest, MidphaseNeverMissesAGrazingContact) {
  // Configurations within 1e-12 rad of the volume's surface (at least 25 brackets; free
  // configurations near the path are rare in the thesis's volume, hence the many attempts): from a free
  // configuration towards a colliding one (reference answers), bisected along the segment; both ends of the
  // last bracket, on both sides of the contact, must get the same answer from both checkers.
  const Params params = preset_params("thesis");
  const Scene scene = Scene::load(test::workcell("dallara"));
  const auto path = keyframe_path(scene, "home", "patch", 2);
  Pair p(test::workcell("dallara"), 5000, path, params);
  std::mt19937_64 rng(3);
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  int brackets = 0;
  for (int s = 0; s < 5000 && brackets < 150; ++s) {
    Eigen::VectorXd a = path[0] + detail::unit(rng) * (path[1] - path[0]), b(scene.dof());
    for (int i = 0; i < a.size(); ++i)
      a[i] = std::clamp(a[i] + 0.2 * (detail::unit(rng) - 0.5), lo[i], hi[i]);
    for (int i = 0; i < b.size(); ++i) b[i] = lo[i] + (hi[i] - lo[i]) * detail::unit(rng);
    if (p.reference_checker->in_collision(a) || !p.reference_checker->in_collision(b)) continue;
    for (int it = 0; it < 80 && (b - a).norm() > 1e-12; ++it) {
      const Eigen::VectorXd m = (a + b) / 2;
      (p.reference_checker->in_collision(m) ? b : a) = m;
    }
    for (const Eigen::VectorXd& q : {a, b})
      ASSERT_EQ(p.fast_checker->in_collision(q), p.reference_checker->in_collision(q)) << "bracket " << s;
    EXPECT_FALSE(p.fast_checker->in_collision(a));
    EXPECT_TRUE(p.fast_checker->in_collision(b));
    ++brackets;
  }
  EXPECT_GE(brackets, 25);
}

TEST_F(CollisionTest, BoxesPlacedAtALinksBottomCornerAgree) {
  // A one-link arm whose box is tilted (so it has one lowest corner) and one small volume box at a
  // time against that corner: its top face at the corner's height (top), also its +x face (edge),
  // also its +y face (corner to corner), moved by +-1e-6 and +-1e-9 m and 0. Both checkers must
  // agree on every placement, and the +-1e-6 m ones must come out as placed.
  test::TempDir dir;
  const std::string cell = dir.write("tilted.xml", R"(<mujoco><compiler autolimits="true"/><worldbody>
    <body name="arm" pos="0 0 1"><joint name="j" type="hinge" axis="0 0 1" range="-3 3"/>
      <geom name="l" type="box" size="0.5 0.05 0.05" pos="1 0 0" euler="0.3 0.4 0.5"/>
      <site name="tool0" pos="1.5 0 0"/></body></worldbody></mujoco>)");
  const Scene fast = Scene::load(cell);
  const Scene reference = Scene::load(cell, Pair::options(CollisionChecker::kMujoco));
  VolumeModel fast_world(fast, 4), reference_world(reference, 4);
  VolumeChecker fast_checker(fast_world), reference_checker(reference_world);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, 0.7);
  RobotState state(fast);
  state.set(q);
  const Box link = geom_box(fast.model(), state.data(), fast.link_geoms()[0]);
  Eigen::Vector3d corner(0, 0, std::numeric_limits<double>::infinity());
  for (int c = 0; c < 8; ++c) {
    Eigen::Vector3d s;
    for (int i = 0; i < 3; ++i) s[i] = (c >> i & 1) ? 1.0 : -1.0;
    const Eigen::Vector3d p = link.center + link.rotation * s.cwiseProduct(link.half_size);
    if (p.z() < corner.z()) corner = p;
  }
  int agreed = 0;
  for (int shape = 0; shape < 3; ++shape)
    for (double gap : {1e-6, 1e-9, 0.0, -1e-9, -1e-6}) {
      Box v;
      v.half_size = {0.01, 0.01, 0.01};
      v.center = corner - Eigen::Vector3d(0, 0, v.half_size.z() + gap);
      if (shape >= 1) v.center.x() -= v.half_size.x() + gap;
      if (shape == 2) v.center.y() -= v.half_size.y() + gap;
      fast_world.set_boxes({v});
      reference_world.set_boxes({v});
      const bool r = reference_checker.in_collision(q);
      EXPECT_EQ(fast_checker.in_collision(q), r) << "shape " << shape << " gap " << gap;
      if (gap == 1e-6) {
        EXPECT_FALSE(r) << "shape " << shape;
      }
      if (gap == -1e-6 && shape == 0) {
        EXPECT_TRUE(r);  // the corner 1e-6 m inside the box's top
      }
      ++agreed;
    }
  EXPECT_EQ(agreed, 15);
}

TEST_F(CollisionTest, BoundsAreIdenticalForOneTwoAndFourThreads) {
  // Two waypoints (fewer than the threads: the runs of each joint level are spread) and five (one
  // waypoint per task), on the Dallara cell with the thesis's parameters.
  const Scene scene = Scene::load(test::workcell("dallara"));
  Params params = preset_params("thesis");
  params.height_map.max_cells = 5000;
  for (int waypoints : {2, 5}) {
    const auto path = keyframe_path(scene, "home", "patch", waypoints);
    const Categories c = categorize(scene, path, params.categorize);
    VolumeModel world(scene, 16);
    world.set_boxes(generate_volume(c, params.height_map, params.volume).boxes);
    const auto one = bound_path(world, path, params.bounds, 1);
    for (int threads : {2, 4}) {
      const auto many = bound_path(world, path, params.bounds, threads);
      ASSERT_EQ(many.size(), one.size());
      for (size_t i = 0; i < one.size(); ++i) {
        EXPECT_EQ(many[i].lower, one[i].lower) << waypoints << " waypoints, " << threads << " threads";
        EXPECT_EQ(many[i].upper, one[i].upper) << waypoints << " waypoints, " << threads << " threads";
        EXPECT_EQ(many[i].collapsed, one[i].collapsed);
        EXPECT_EQ(many[i].checks, one[i].checks);
        EXPECT_EQ(many[i].nominal_in_volume, one[i].nominal_in_volume);
      }
    }
    EXPECT_GT(one[0].checks, 14);  // all 14 runs ran
  }
}

}  // namespace
}  // namespace leeway
