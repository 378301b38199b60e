// The bundled workcells (mjcf/workcells/): what issue "Foundation" and chapter 4 require of them.
#include <gtest/gtest.h>

#include "leeway/check.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::workcell;

class WorkcellsTest : public test::MujocoTest {};

TEST_F(WorkcellsTest, ThesisCellsPassTheCheck) {
  for (const char* cell : {"dallara", "baltico", "dlr"}) {
    const Scene scene = Scene::load(workcell(cell));
    const CheckReport r = check_scene(scene);
    EXPECT_TRUE(r.ok()) << cell << ": " << ::testing::PrintToString(r.problems);
    // Both goal sites lie above a table or mould (Algorithm 1) and are reachable, tool down.
    ASSERT_EQ(r.goals.size(), 2u) << cell;
    for (const auto& g : r.goals) {
      EXPECT_GE(g.goal_obstacle, 0) << cell << " " << g.site;
      EXPECT_TRUE(g.reachable_tool_down) << cell << " " << g.site;
    }
    // The goal keyframes put tool0 on their sites (the published positions).
    for (const char* key : {"patch", "mould"}) {
      const auto& kf = r.keyframes.at(key == std::string("patch") ? 1 : 2);
      ASSERT_EQ(kf.name, key);
      const Eigen::Vector3d site = r.goals[key == std::string("patch") ? 0 : 1].position;
      EXPECT_LT((kf.tool.position - site).norm(), 1e-3) << cell << " " << key;
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

TEST_F(WorkcellsTest, ExampleCellPasses) {
  const Scene scene = Scene::load(workcell("example"));
  const CheckReport r = check_scene(scene);
  EXPECT_TRUE(r.ok()) << ::testing::PrintToString(r.problems);
  ASSERT_EQ(r.goals.size(), 1u);
  EXPECT_EQ(scene.geom_label(r.goals[0].goal_obstacle), "table");
}

}  // namespace
}  // namespace leeway
