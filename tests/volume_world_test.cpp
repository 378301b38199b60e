#include "leeway/core/volume_world.hpp"

#include <gtest/gtest.h>
#include <mujoco/mjxmacro.h>

#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include "core/random.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::workcell;

class VolumeWorldTest : public test::MujocoTest {};

std::string pool_xml(int n) {
  std::ostringstream os;
  os << R"(<mujoco><compiler autolimits="true"/><worldbody>
    <body name="arm" pos="0 0 1"><joint name="j" type="hinge" axis="0 0 1" range="-3 3"/>
      <geom name="l" type="box" size="1 0.05 0.05" pos="1 0 0"/><site name="tool0"/></body>
    <body name="pool">)";
  for (int i = 0; i < n; ++i)
    os << R"(<geom type="box" size="0.001 0.001 0.001" contype="0" conaffinity="0" group="5"/>)";
  os << "</body></worldbody></mujoco>";
  return os.str();
}

// Arrays the growth leaves as they were, by design: the name table (MuJoCo gives every unnamed geom
// an empty name of its own, so later names shift) and the mass and inertia that the compiler sums
// over a body's geoms (the pool body is static: MuJoCo's collision never reads them).
bool compare_array(const char* name) {
  const std::string n(name);
  return n != "names" && n.rfind("name_", 0) != 0 && n != "body_mass" && n != "body_subtreemass" &&
         n != "body_inertia";
}

TEST_F(VolumeWorldTest, GrownModelEqualsTheCompiledOne) {
  // MuJoCo's compiler for a pool of 1 + 40 geoms against our binary growth of a pool of 1.
  test::TempDir dir;
  char err[512];
  ModelPtr one(mj_loadXML(dir.write("one.xml", pool_xml(1)).c_str(), nullptr, err, sizeof(err)));
  ModelPtr many(mj_loadXML(dir.write("many.xml", pool_xml(41)).c_str(), nullptr, err, sizeof(err)));
  ASSERT_TRUE(one && many) << err;
  ModelPtr grown = grow_last_body_geoms(*one, 40);
  ASSERT_EQ(grown->ngeom, many->ngeom);
  ASSERT_EQ(grown->nbuffer - grown->nnames, many->nbuffer - many->nnames);  // unnamed geoms add name bytes
  const mjModel* a = grown.get();
  const mjModel* b = many.get();
  int compared = 0;
  {
    // X-macro expansion from mjxmacro.h, kept as written:
    // clang-format off
    MJMODEL_POINTERS_PREAMBLE(a)
#define X(type, name, nr, nc)                                                                               \
  if (compare_array(#name)) {                                                                               \
    ASSERT_EQ(a->nr, b->nr) << #name;                                                                       \
    EXPECT_EQ(0, std::memcmp(a->name, b->name, sizeof(type) * static_cast<size_t>(a->nr * (nc)))) << #name; \
    ++compared;                                                                                             \
  }
    MJMODEL_POINTERS
#undef X
  (void)nuser_body, (void)nuser_jnt, (void)nuser_geom, (void)nuser_site, (void)nuser_cam;
    (void)nuser_tendon, (void)nuser_actuator, (void)nuser_sensor, (void)nq, (void)nv, (void)na, (void)nu;
    (void)nmocap;
    // clang-format on
  }
  EXPECT_GT(compared, 100);
}

// Random boxes 1.2-3 m from the Dallara robot's base, 0.1-0.4 m across, 0.2 m to max_height high.
std::vector<Box> random_boxes(int n, std::uint64_t seed, double max_height = 3.0) {
  std::mt19937_64 rng(seed);
  auto u = [&](double lo, double hi) { return lo + (hi - lo) * leeway::detail::unit(rng); };
  std::vector<Box> boxes;
  for (int i = 0; i < n; ++i) {
    Box b;
    const double h = u(0.2, max_height);
    const double r = u(1.2, 3.0), a = u(-M_PI, M_PI);  // clear of the base and link 1
    b.center = {r * std::cos(a), r * std::sin(a), h / 2};
    b.half_size = {u(0.05, 0.2), u(0.05, 0.2), h / 2};
    boxes.push_back(b);
  }
  return boxes;
}

TEST_F(VolumeWorldTest, PoolContactsEqualAFreshlyCompiledModel) {
  const Scene scene = Scene::load(workcell("dallara"));
  VolumeModel world(scene, 64);
  const std::vector<Box> boxes = random_boxes(100, 3, 1.5);
  world.set_boxes(boxes);  // grows the pool from 64 to 128
  EXPECT_EQ(world.capacity(), 128);
  EXPECT_EQ(world.active(), 100);

  // The same boxes compiled from XML into the cell's world body; obstacles and the robot base off.
  std::ifstream in(workcell("dallara"));
  std::stringstream text;
  text << in.rdbuf();
  std::string xml = text.str();
  std::ostringstream geoms;
  geoms.precision(17);
  for (size_t i = 0; i < boxes.size(); ++i)
    geoms << "<geom name=\"vol" << i << "\" type=\"box\" contype=\"0\" conaffinity=\"2\" pos=\""
          << boxes[i].center.x() << " " << boxes[i].center.y() << " " << boxes[i].center.z() << "\" size=\""
          << boxes[i].half_size.x() << " " << boxes[i].half_size.y() << " " << boxes[i].half_size.z()
          << "\"/>";
  // In a trailing body, so the cell's geoms keep their ids (world-body geoms would be numbered first).
  xml.insert(xml.rfind("</worldbody>"), "<body name=\"fresh_volume\">" + geoms.str() + "</body>");
  // Same layout as mjcf/ so that the cell's "../robots/" include resolves.
  test::TempDir dir;
  std::filesystem::create_directory(dir.path() / "workcells");
  std::filesystem::create_directory_symlink(std::string(LEEWAY_MJCF_DIR) + "/robots", dir.path() / "robots");
  char err[512];
  ModelPtr fresh(mj_loadXML(dir.write("workcells/fresh.xml", xml).c_str(), nullptr, err, sizeof(err)));
  ASSERT_TRUE(fresh) << err;
  for (int g = 0; g < fresh->ngeom; ++g) {
    const bool link = g < scene.model().ngeom && scene.role(g) == GeomRole::kLink;
    if (link) fresh->geom_contype[g] = 2;
  }
  DataPtr fd = make_data(*fresh);

  // The reference checker (mj_collision on the pool model) against the fresh model, contact for
  // contact; the midphase against both, answer for answer.
  SceneOptions reference_options;
  reference_options.checker = CollisionChecker::kMujoco;
  const Scene reference_scene = Scene::load(workcell("dallara"), reference_options);
  VolumeModel reference_world(reference_scene, 64);
  reference_world.set_boxes(boxes);
  VolumeChecker reference(reference_world);
  ASSERT_EQ(reference.checker(), CollisionChecker::kMujoco);
  VolumeChecker checker(world);
  ASSERT_EQ(checker.checker(), CollisionChecker::kMidphase);
  std::mt19937_64 rng(11);
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  int hits = 0;
  auto sorted_dists = [](const mjData& d) {
    std::vector<double> v;
    for (int c = 0; c < d.ncon; ++c) v.push_back(d.contact[c].dist);
    std::sort(v.begin(), v.end());
    return v;
  };
  for (int k = 0; k < 500; ++k) {
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = lo[i] + (hi[i] - lo[i]) * leeway::detail::unit(rng);
    const bool pooled = reference.in_collision(q);
    const bool midphase = checker.in_collision(q);
    for (int i = 0; i < 6; ++i) fd->qpos[i] = q[i];
    mj_kinematics(fresh.get(), fd.get());
    mj_collision(fresh.get(), fd.get());
    take_mujoco_warnings();
    ASSERT_EQ(pooled, fd->ncon > 0) << "sample " << k;
    ASSERT_EQ(midphase, pooled) << "sample " << k;
    ASSERT_EQ(reference.data().ncon, fd->ncon) << "sample " << k;
    const auto a = sorted_dists(reference.data()), b = sorted_dists(*fd);
    for (size_t c = 0; c < a.size(); ++c) EXPECT_NEAR(a[c], b[c], 1e-12);
    hits += pooled;
  }
  EXPECT_GT(hits, 50);  // the comparison covers both answers
  EXPECT_LT(hits, 450);
  EXPECT_EQ(checker.checks(), 500);
}

TEST_F(VolumeWorldTest, AnXmlCompiledPoolGivesTheSameAnswers) {
  // The fall-back for an unknown binary layout: the pool compiled from XML. Both pools, both
  // checkers, 300 random configurations against 100 boxes: the same answers.
  const Scene scene = Scene::load(workcell("dallara"));
  SceneOptions reference_options;
  reference_options.checker = CollisionChecker::kMujoco;
  const Scene reference_scene = Scene::load(workcell("dallara"), reference_options);
  const std::vector<Box> boxes = random_boxes(100, 3, 1.5);
  VolumeModel binary(scene, 64), xml(scene, 64, VolumeModel::Growth::kXml),
      xml_reference(reference_scene, 64, VolumeModel::Growth::kXml);
  for (VolumeModel* w : {&binary, &xml, &xml_reference}) w->set_boxes(boxes);
  EXPECT_EQ(xml.capacity(), 128);
  EXPECT_EQ(xml.model().nbody, binary.model().nbody);
  VolumeChecker a(binary), b(xml), c(xml_reference);
  std::mt19937_64 rng(12);
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  int hits = 0;
  for (int k = 0; k < 300; ++k) {
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = lo[i] + (hi[i] - lo[i]) * leeway::detail::unit(rng);
    const bool expected = a.in_collision(q);
    ASSERT_EQ(b.in_collision(q), expected) << "sample " << k;
    ASSERT_EQ(c.in_collision(q), expected) << "sample " << k;
    hits += expected;
  }
  EXPECT_GT(hits, 30);
  EXPECT_LT(hits, 270);
}

TEST_F(VolumeWorldTest, EmptyVolumeNeverCollides) {
  const Scene scene = Scene::load(workcell("dallara"));
  VolumeModel world(scene, 16);
  world.set_boxes({});
  VolumeChecker checker(world);
  for (const auto& k : scene.keyframes()) EXPECT_FALSE(checker.in_collision(k.q)) << k.name;
  // Obstacles are not part of the volume model: a pose that hits the patch table does not count.
  Eigen::VectorXd q = scene.keyframe("patch").q;
  q[1] += 0.5;
  RobotState state(scene);
  EXPECT_TRUE(state.in_collision(q));
  EXPECT_FALSE(checker.in_collision(q));
}

TEST_F(VolumeWorldTest, HundredThousandBoxPool) {
  const Scene scene = Scene::load(workcell("dallara"));
  VolumeModel world(scene, 100000);
  EXPECT_GE(world.capacity(), 100000);
  world.set_boxes(random_boxes(100000, 5));
  EXPECT_EQ(world.active(), 100000);
  VolumeChecker checker(world);
  EXPECT_TRUE(checker.in_collision(scene.keyframe("home").q));  // boxes everywhere up to 3 m
}

}  // namespace
}  // namespace leeway
