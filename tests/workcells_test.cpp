// The bundled workcells (mjcf/workcells/): what issue "Foundation" and chapter 4 require of the thesis
// cells, and what the two cells not used for tuning (press_shop, rail_hall) are built to show.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "leeway/core/check.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::workcell;

class WorkcellsTest : public test::MujocoTest {};

//! A goal keyframe of a bundled cell: the goal site it puts tool0 on and the site's goal obstacle.
struct GoalKey {
  const char* key;
  const char* site;
  const char* obstacle;  // the first box straight below the site (Algorithm 1)
};

//! A bundled cell and its goal keyframes, in the order of the goal sites in the file.
struct BundledCell {
  const char* name;
  std::vector<GoalKey> goals;
};

//! The three thesis cells, the cells not used for tuning and the imported wide-elbow arm
//! (docs/workcells.md).
std::vector<BundledCell> bundled_cells() {
  return {
      {"dallara", {{"patch", "patch", "patch_table"}, {"mould", "mould", "mould_table"}}},
      {"baltico", {{"patch", "patch", "patch_table"}, {"mould", "mould", "mould"}}},
      {"dlr", {{"patch", "patch", "patch_table"}, {"mould", "mould", "mould"}}},
      {"press_shop", {{"pick", "pick", "conveyor"}, {"place", "place", "press_bed"}}},
      {"rail_hall", {{"patch", "patch", "trolley"}, {"mould", "mould", "mould"}}},
      {"shelf_bay", {{"pick", "pick", "table_low"}, {"place", "place", "table_high"}}},
      {"wide_elbow", {{"pick", "pick", "table"}, {"place", "place", "table"}}},
      {"low_beam", {{"pick", "pick", "table_left"}, {"place", "place", "table_right"}}},
      {"round_pillars", {{"pick", "pick", "pick_table"}, {"place", "place", "place_fixture"}}},
      {"round_pillars_boxed", {{"pick", "pick", "pick_table"}, {"place", "place", "place_fixture"}}},
      {"cad_cell_boxed", {{"pick", "pick", "table_top"}, {"place", "place", "conveyor_belt"}}},
  };
}

//! The cells with mesh obstacles (docs/workcells.md, "Real geometry"): the thesis cells' mesh twins,
//! dallara with a thin wall (as a box and as a mesh) and the CAD cell. Their goal obstacles are not
//! named here: a mesh's bounding box decides which obstacle lies first below a goal.
std::vector<const char*> mesh_cells() {
  return {"mesh_twins/dallara_mesh",     "mesh_twins/baltico_mesh",      "mesh_twins/dlr_mesh",
          "mesh_twins/dallara_wall_box", "mesh_twins/dallara_wall_mesh", "cad_cell"};
}

//! The joint-linear path from a to b as configurations no joint moves more than `step` [rad or m]
//! between, both ends included.
std::vector<Eigen::VectorXd> joint_linear(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double step) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / step)));
  std::vector<Eigen::VectorXd> path;
  for (int i = 0; i <= n; ++i) path.push_back(a + (b - a) * (static_cast<double>(i) / n));
  return path;
}

TEST_F(WorkcellsTest, BundledCellsPassTheCheck) {
  for (const BundledCell& cell : bundled_cells()) {
    SCOPED_TRACE(cell.name);
    const Scene scene = Scene::load(workcell(cell.name));
    const CheckReport r = check_scene(scene);
    EXPECT_TRUE(r.ok()) << ::testing::PrintToString(r.problems);
    // Every keyframe is collision-free and within the joint limits.
    for (const auto& kf : r.keyframes) {
      EXPECT_TRUE(kf.collisions.empty()) << kf.name;
      EXPECT_TRUE(kf.limit_violations.empty()) << kf.name;
    }
    // Each goal site lies above its table, conveyor, press bed, trolley or mould (Algorithm 1) and
    // is reachable, tool down; its goal keyframe puts tool0 on it.
    ASSERT_EQ(r.goals.size(), cell.goals.size());
    for (size_t i = 0; i < cell.goals.size(); ++i) {
      const GoalKey& want = cell.goals[i];
      const GoalFindings& g = r.goals[i];
      EXPECT_EQ(g.site, want.site);
      ASSERT_GE(g.goal_obstacle, 0) << g.site;
      EXPECT_EQ(scene.geom_label(g.goal_obstacle), want.obstacle) << g.site;
      EXPECT_TRUE(g.reachable_tool_down) << g.site;
      const auto kf = std::find_if(r.keyframes.begin(), r.keyframes.end(),
                                   [&](const KeyframeFindings& k) { return k.name == want.key; });
      ASSERT_NE(kf, r.keyframes.end()) << want.key;
      EXPECT_LT((kf->tool.position - g.position).norm(), 1e-3) << want.key;
    }
  }
}

TEST_F(WorkcellsTest, ThesisPathsAreCollisionFreeAndPatchMouldPassesNearBothTables) {
  // The three thesis paths joined linearly in joint space, sampled every 1/400 of the path.
  const std::pair<const char*, const char*> paths[] = {
      {"home", "patch"}, {"patch", "mould"}, {"mould", "home"}};
  for (const char* cell : {"dallara", "baltico", "dlr"}) {
    const Scene scene = Scene::load(workcell(cell));
    RobotState state(scene);
    const int patch_table = mj_name2id(&scene.model(), mjOBJ_GEOM, "patch_table");
    const int mould_table = mj_name2id(&scene.model(), mjOBJ_GEOM, "mould_table");
    ASSERT_GE(patch_table, 0);
    ASSERT_GE(mould_table, 0);
    for (const auto& [from, to] : paths) {
      const Eigen::VectorXd a = scene.keyframe(from).q, b = scene.keyframe(to).q;
      for (int i = 0; i <= 400; ++i) {
        const Eigen::VectorXd q = a + (b - a) * (i / 400.0);
        ASSERT_FALSE(state.in_collision(q)) << cell << " " << from << "-" << to << " at " << i << "/400";
      }
    }
    // Patch-mould starts 4 cm above the patch table (the carried patch) and ends over the mould
    // table's goal obstacle: the robot comes within 0.5 m of both tables on the way.
    const Eigen::VectorXd a = scene.keyframe("patch").q, b = scene.keyframe("mould").q;
    double near_patch = INFINITY, near_mould = INFINITY;
    const mjModel& m = scene.model();
    for (int i = 0; i <= 100; ++i) {
      state.set(a + (b - a) * (i / 100.0));
      for (int l : scene.link_geoms()) {
        const Box link = geom_box(m, state.data(), l);
        near_patch = std::min(near_patch, box_distance(link, geom_box(m, state.data(), patch_table)));
        near_mould = std::min(near_mould, box_distance(link, geom_box(m, state.data(), mould_table)));
      }
    }
    EXPECT_LT(near_patch, 0.5) << cell;
    EXPECT_LT(near_mould, 0.5) << cell;
  }
}

TEST_F(WorkcellsTest, NewCellsJointLinearPathsAreCollisionFreeExceptPressShopPickPlace) {
  // The cells not used for tuning, every joint-linear path between their keyframes that should be
  // free (press_shop's pick-place is not: see the next test), stepped at 0.002 rad (or m).
  const std::array<std::array<const char*, 3>, 5> paths = {{{"press_shop", "home", "pick"},
                                                            {"press_shop", "place", "home"},
                                                            {"rail_hall", "home", "patch"},
                                                            {"rail_hall", "patch", "mould"},
                                                            {"rail_hall", "mould", "home"}}};
  for (const auto& [cell, from, to] : paths) {
    const Scene scene = Scene::load(workcell(cell));
    RobotState state(scene);
    const auto path = joint_linear(scene.keyframe(from).q, scene.keyframe(to).q, 0.002);
    for (size_t i = 0; i < path.size(); ++i) {
      ASSERT_FALSE(state.in_collision(path[i]))
          << cell << " " << from << "-" << to << " at " << i << "/" << path.size() - 1;
    }
  }
}

TEST_F(WorkcellsTest, PressShopStraightPickPlaceHitsThePillar) {
  // press_shop's pillar stands across the joint-linear pick -> place path (j1 swings through its
  // bearing). Stepped at 0.002 rad, the first configuration in contact touches the pillar and
  // nothing else: this fails if the pillar is moved out of the way.
  const Scene scene = Scene::load(workcell("press_shop"));
  RobotState state(scene);
  const auto path = joint_linear(scene.keyframe("pick").q, scene.keyframe("place").q, 0.002);
  size_t first = path.size();
  std::vector<Contact> hit;
  for (size_t i = 0; i < path.size() && first == path.size(); ++i) {
    hit = state.contacts(path[i]);
    if (!hit.empty()) first = i;
  }
  ASSERT_LT(first, path.size()) << "the joint-linear pick-place path is collision-free";
  for (const Contact& c : hit) {
    EXPECT_EQ(scene.geom_label(c.obstacle_geom), "pillar")
        << scene.geom_label(c.link_geom) << " at " << first << "/" << path.size() - 1;
  }
}

TEST_F(WorkcellsTest, MeshCellsLoadAndPassTheCheck) {
  for (const char* cell : mesh_cells()) {
    SCOPED_TRACE(cell);
    const Scene scene = Scene::load(workcell(cell));
    const CheckReport r = check_scene(scene);
    EXPECT_TRUE(r.ok()) << ::testing::PrintToString(r.problems);
    for (const auto& kf : r.keyframes) {
      EXPECT_TRUE(kf.collisions.empty()) << kf.name;
      EXPECT_TRUE(kf.limit_violations.empty()) << kf.name;
    }
    // Every goal site has a goal keyframe of its name that puts tool0 on it.
    for (const GoalFindings& g : r.goals) {
      EXPECT_TRUE(g.reachable_tool_down) << g.site;
      const auto kf = std::find_if(r.keyframes.begin(), r.keyframes.end(),
                                   [&](const KeyframeFindings& k) { return k.name == g.site; });
      ASSERT_NE(kf, r.keyframes.end()) << g.site;
      EXPECT_LT((kf->tool.position - g.position).norm(), 1e-3) << g.site;
    }
  }
}

TEST_F(WorkcellsTest, MeshTwinsHaveTheirBoxCellsObstaclesAsMeshes) {
  // Same obstacles, in the same order, under the same names, at the same world boxes; only the type
  // differs (the wall cells: only the wall).
  const std::pair<const char*, const char*> twins[] = {
      {"dallara", "mesh_twins/dallara_mesh"},
      {"baltico", "mesh_twins/baltico_mesh"},
      {"dlr", "mesh_twins/dlr_mesh"},
      {"mesh_twins/dallara_wall_box", "mesh_twins/dallara_wall_mesh"}};
  for (const auto& [box_cell, mesh_cell] : twins) {
    SCOPED_TRACE(mesh_cell);
    const Scene a = Scene::load(workcell(box_cell)), b = Scene::load(workcell(mesh_cell));
    ASSERT_EQ(a.obstacle_geoms().size(), b.obstacle_geoms().size());
    ASSERT_EQ(a.keyframe("home").q, b.keyframe("home").q);
    for (size_t i = 0; i < a.obstacle_geoms().size(); ++i) {
      const int ga = a.obstacle_geoms()[i], gb = b.obstacle_geoms()[i];
      EXPECT_EQ(a.geom_label(ga), b.geom_label(gb));
      EXPECT_EQ(a.model().geom_contype[ga], b.model().geom_contype[gb]);
      EXPECT_EQ(a.model().geom_conaffinity[ga], b.model().geom_conaffinity[gb]);
      if (b.model().geom_type[gb] == mjGEOM_MESH) {
        EXPECT_EQ(a.model().geom_type[ga], mjGEOM_BOX);
        // The mesh is the box: its vertices, placed in the world (MuJoCo re-centres and turns a mesh
        // to its inertial frame and moves the geom's frame to match), span the axis-aligned box.
        const mjModel& mb = b.model();
        const int mesh = mb.geom_dataid[gb];
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
        for (int v = 0; v < mb.mesh_vertnum[mesh]; ++v) {
          const float* p = mb.mesh_vert + 3 * (mb.mesh_vertadr[mesh] + v);
          mjtNum local[3] = {p[0], p[1], p[2]}, world[3];
          mju_rotVecQuat(world, local, mb.geom_quat + 4 * gb);
          for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], world[k] + mb.geom_pos[3 * gb + k]);
            hi[k] = std::max(hi[k], world[k] + mb.geom_pos[3 * gb + k]);
          }
        }
        for (int k = 0; k < 3; ++k) {
          const double centre = a.model().geom_pos[3 * ga + k], half = a.model().geom_size[3 * ga + k];
          EXPECT_NEAR(lo[k], centre - half, 1e-5) << a.geom_label(ga);
          EXPECT_NEAR(hi[k], centre + half, 1e-5) << a.geom_label(ga);
        }
      }
    }
  }
}

TEST_F(WorkcellsTest, RealGeometryCellsJointLinearPathsAreCollisionFree) {
  // round_pillars and cad_cell (real shapes, MuJoCo's collision of the hulls): every joint-linear
  // path between their keyframes, stepped at 0.002 rad.
  for (const char* cell : {"round_pillars", "cad_cell"}) {
    const Scene scene = Scene::load(workcell(cell));
    RobotState state(scene);
    const std::pair<const char*, const char*> paths[] = {
        {"home", "pick"}, {"pick", "place"}, {"place", "home"}};
    for (const auto& [from, to] : paths) {
      const auto path = joint_linear(scene.keyframe(from).q, scene.keyframe(to).q, 0.002);
      for (size_t i = 0; i < path.size(); ++i) {
        ASSERT_FALSE(state.in_collision(path[i]))
            << cell << " " << from << "-" << to << " at " << i << "/" << path.size() - 1;
      }
    }
  }
}

TEST_F(WorkcellsTest, ExampleCellPasses) {
  const Scene scene = Scene::load(workcell("example"));
  const CheckReport r = check_scene(scene);
  EXPECT_TRUE(r.ok()) << ::testing::PrintToString(r.problems);
  ASSERT_EQ(r.goals.size(), 1u);
  EXPECT_EQ(scene.geom_label(r.goals[0].goal_obstacle), "table");
}

}  // namespace
}  // namespace leeway
