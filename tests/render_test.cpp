// render.hpp: PNG encoding, the camera model, height colours, ghosts and an offscreen render of a
// one-link cell with one volume box, checked against hand-worked values.
#include "leeway/viz/render.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "leeway/core/error.hpp"
#include "png_util.hpp"
#include "test_util.hpp"
#include "viz/canvas.hpp"

namespace leeway {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(PngTest, EncodesHeaderChunksAndPixels) {
  Image image;
  image.width = 3;
  image.height = 2;
  // Row 0: red, green, blue; row 1: black, white, (1, 2, 3).
  image.rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 1, 2, 3};
  const std::string png = encode_png(image);
  ASSERT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // IHDR: length 13, "IHDR", width 3, height 2, 8 bits, colour type 2 (RGB), deflate, filter, no interlace.
  EXPECT_EQ(png.substr(8, 8), std::string("\x00\x00\x00\x0dIHDR", 8));
  EXPECT_EQ(png.substr(16, 13), std::string("\x00\x00\x00\x03\x00\x00\x00\x02\x08\x02\x00\x00\x00", 13));
  // The file ends with the empty IEND chunk, whose CRC is the constant AE 42 60 82.
  EXPECT_EQ(png.substr(png.size() - 12), std::string("\x00\x00\x00\x00IEND\xae\x42\x60\x82", 12));
  const Image back = test::decode_png(png);
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_EQ(back.at(2, 1), (std::array<unsigned char, 3>{1, 2, 3}));
  // Deterministic bytes.
  EXPECT_EQ(encode_png(image), png);
}

TEST(PngTest, SizeOfAWrittenFileAndOfANonPng) {
  test::TempDir dir;
  Image image;
  image.width = 40;
  image.height = 17;
  image.rgb.assign(3 * 40 * 17, 128);
  const std::string path = (dir.path() / "a.png").string();
  write_png(path, image);
  EXPECT_EQ(png_size(path), (std::array<int, 2>{40, 17}));
  const std::string text = dir.write("b.png", "not a png at all, just some text");
  EXPECT_THROW(png_size(text), InputError);
}

TEST(ProjectTest, HandWorkedPinhole) {
  // Looking along +x from (-10, 0, 0): right is -y, up is +z. A 90 degree vertical field of view on
  // a 200 x 100 image has a focal length of 50 pixels.
  RenderCamera c;
  c.azimuth = 0;
  c.elevation = 0;
  c.distance = 10;
  c.lookat = Eigen::Vector3d::Zero();
  Eigen::Vector2d px;
  ASSERT_TRUE(project_point(c, kPi / 2, 200, 100, {0, 0, 0}, px));
  EXPECT_NEAR(px.x(), 100, 1e-9);
  EXPECT_NEAR(px.y(), 50, 1e-9);
  ASSERT_TRUE(project_point(c, kPi / 2, 200, 100, {0, -1, 0}, px));  // 1 m right at 10 m: 5 pixels
  EXPECT_NEAR(px.x(), 105, 1e-9);
  EXPECT_NEAR(px.y(), 50, 1e-9);
  ASSERT_TRUE(project_point(c, kPi / 2, 200, 100, {0, 0, 1}, px));  // 1 m up: 5 pixels up
  EXPECT_NEAR(px.x(), 100, 1e-9);
  EXPECT_NEAR(px.y(), 45, 1e-9);
  EXPECT_FALSE(project_point(c, kPi / 2, 200, 100, {-20, 0, 0}, px));  // behind the camera
  // Straight down from (0, 0, 10) at azimuth 0: the image's up is +x and its right is -y.
  c.elevation = -kPi / 2;
  ASSERT_TRUE(project_point(c, kPi / 2, 200, 100, {1, 0, 0}, px));
  EXPECT_NEAR(px.x(), 100, 1e-9);
  EXPECT_NEAR(px.y(), 45, 1e-9);
  ASSERT_TRUE(project_point(c, kPi / 2, 200, 100, {0, 1, 0}, px));
  EXPECT_NEAR(px.x(), 95, 1e-9);
  EXPECT_NEAR(px.y(), 50, 1e-9);
}

TEST(FrameTest, SphereOfTheCylinderFitsTheFieldOfView) {
  // Radius 3 m, height 8 m: bounding sphere radius 5 m around (1, 2, 4); with a 60 degree field of
  // view, distance = 1.05 * 5 / sin(30 degrees) = 10.5 m.
  const RenderCamera c = frame_circle({1, 2}, 3, 8, kPi / 3);
  EXPECT_NEAR(c.distance, 10.5, 1e-12);
  EXPECT_EQ(c.lookat, Eigen::Vector3d(1, 2, 4));
}

TEST(HeightColourTest, ScaleEndsAndMiddle) {
  const auto low = height_colour(0, 2), mid = height_colour(1, 2), high = height_colour(2, 2);
  EXPECT_FLOAT_EQ(low[0], 0.267f);
  EXPECT_FLOAT_EQ(low[2], 0.329f);
  EXPECT_FLOAT_EQ(mid[1], 0.567f);
  EXPECT_FLOAT_EQ(high[0], 0.993f);
  EXPECT_FLOAT_EQ(high[2], 0.144f);
  EXPECT_EQ(height_colour(5, 2), high);  // clamped
  EXPECT_EQ(height_colour(1, 0), low);   // no height range
}

TEST(GhostTest, CornersAndJoints) {
  const WaypointBounds w(Eigen::Vector2d(0, 0.5), Eigen::Vector2d(-1, 0.5), Eigen::Vector2d(1, 0.7));
  EXPECT_TRUE(ghost_configurations(w, GhostMode::kNone).empty());
  const auto corners = ghost_configurations(w, GhostMode::kCorners);
  ASSERT_EQ(corners.size(), 2u);
  EXPECT_EQ(corners[0], Eigen::Vector2d(-1, 0.5));
  EXPECT_EQ(corners[1], Eigen::Vector2d(1, 0.7));
  // Joint 0 at -1 and at 1; joint 1 only at 0.7 (its lower bound is the nominal value).
  const auto joints = ghost_configurations(w, GhostMode::kJoints);
  ASSERT_EQ(joints.size(), 3u);
  EXPECT_EQ(joints[0], Eigen::Vector2d(-1, 0.5));
  EXPECT_EQ(joints[1], Eigen::Vector2d(1, 0.5));
  EXPECT_EQ(joints[2], Eigen::Vector2d(0, 0.7));
}

class RenderTest : public test::MujocoTest {
 protected:
  Scene scene() {
    return Scene::load(dir_.write("one_link.xml", test::one_link_cell("", R"(<key name="home" qpos="0"/>)")));
  }
  // The arm at 0 seen from 8 m almost straight above the origin, 160 x 120 pixels.
  static RenderRequest top_down() {
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    r.q = Eigen::VectorXd::Zero(1);
    r.camera.azimuth = 0;
    r.camera.elevation = -1.5;
    r.camera.distance = 8;
    r.camera.lookat = Eigen::Vector3d::Zero();
    return r;
  }
  // A box on the floor away from the arm, which lies along +x.
  static Box beside_the_arm() {
    Box box;
    box.center = {-1.5, 1.5, 0.25};
    box.half_size = {0.4, 0.4, 0.25};
    return box;
  }
  test::TempDir dir_;
};

TEST_F(RenderTest, VolumeBoxColoursThePixelItProjectsTo) {
  const Scene s = scene();
  RenderRequest r = top_down();
  const Box box = beside_the_arm();
  const Image off = render_scene(s, r);
  r.volume = {box};
  const Image on = render_scene(s, r);
  ASSERT_EQ(on.width, 160);
  ASSERT_EQ(on.height, 120);
  Eigen::Vector2d px;
  const double fovy = s.model().vis.global.fovy * kPi / 180;
  ASSERT_TRUE(project_point(r.camera, fovy, r.width, r.height, {-1.5, 1.5, 0.5}, px));
  const int x = static_cast<int>(px.x()), y = static_cast<int>(px.y());
  ASSERT_TRUE(x >= 0 && x < 160 && y >= 0 && y < 120) << x << " " << y;
  // The only box is the highest: yellow (0.993, 0.906, 0.144) at 30 % over the grey floor, so red
  // clearly exceeds blue there; without the volume the floor is grey (red equals blue).
  const auto a = on.at(x, y), b = off.at(x, y);
  EXPECT_GT(int{a[0]} - int{a[2]}, 40) << int{a[0]} << " " << int{a[1]} << " " << int{a[2]};
  EXPECT_LT(std::abs(int{b[0]} - int{b[2]}), 12) << int{b[0]} << " " << int{b[1]} << " " << int{b[2]};
  // Far from the box the two renders agree.
  ASSERT_TRUE(project_point(r.camera, fovy, r.width, r.height, {-1.5, -1.5, 0}, px));
  const auto c = on.at(static_cast<int>(px.x()), static_cast<int>(px.y()));
  const auto d = off.at(static_cast<int>(px.x()), static_cast<int>(px.y()));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[static_cast<size_t>(k)], d[static_cast<size_t>(k)], 2);
}

// The one-link arm at q = 0: its base box x, y in [-0.1, 0.1], z in [0, 0.5] and its link x in
// [0, 1], z in [0.45, 0.55]: the robot's box is [-0.1, 1] x [-0.1, 0.1] x [0, 0.55] (the floor is
// a plane and not framed, and there is no other obstacle). The camera looks at its centre
// (0.45, 0, 0.275) from 1.05 r / sin(fovy / 2), r half its diagonal, fovy 45 degrees (a 4:3 image:
// the vertical field is the narrower).
TEST_F(RenderTest, RobotFramingFitsTheRobotWorkedByHand) {
  const Scene s = scene();
  const Eigen::AlignedBox3d robot = robot_extent(s, {Eigen::VectorXd::Zero(1)});
  EXPECT_TRUE(robot.min().isApprox(Eigen::Vector3d(-0.1, -0.1, 0), 1e-12)) << robot.min().transpose();
  EXPECT_TRUE(robot.max().isApprox(Eigen::Vector3d(1, 0.1, 0.55), 1e-12)) << robot.max().transpose();
  const Eigen::AlignedBox3d region = robot_neighbourhood(s, robot, 0.3);
  EXPECT_TRUE(region.isApprox(robot));
  const double fovy = s.model().vis.global.fovy * kPi / 180;
  const RenderCamera c = frame_box(region, RenderCamera{}, fovy, 4.0 / 3.0);
  const double r = 0.5 * std::sqrt(1.1 * 1.1 + 0.2 * 0.2 + 0.55 * 0.55);
  EXPECT_NEAR(c.distance, 1.05 * r / std::sin(kPi / 8), 1e-9);
  EXPECT_TRUE(c.lookat.isApprox(Eigen::Vector3d(0.45, 0, 0.275), 1e-12));
  EXPECT_EQ(c.azimuth, RenderCamera{}.azimuth);
  // Every corner of the robot's box projects into a 320 x 240 image, and their bounding rectangle
  // covers at least a fifth of it.
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector2d px;
    ASSERT_TRUE(
        project_point(c, fovy, 320, 240, robot.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)), px));
    EXPECT_TRUE(px.x() >= 0 && px.x() < 320 && px.y() >= 0 && px.y() < 240) << px.transpose();
    x0 = std::min(x0, px.x());
    x1 = std::max(x1, px.x());
    y0 = std::min(y0, px.y());
    y1 = std::max(y1, px.y());
  }
  EXPECT_GT((x1 - x0) * (y1 - y0), 0.2 * 320 * 240) << x0 << " " << x1 << " " << y0 << " " << y1;
}

// A wide image: the horizontal field (2 atan(aspect tan(fovy / 2))) is wider, so the vertical one
// still sets the distance; a tall one (aspect 1/2) is set by the horizontal field.
TEST(FrameTest, TheNarrowerFieldOfViewSetsTheDistance) {
  const Eigen::AlignedBox3d unit(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  const double fovy = kPi / 4, r = 0.5 * std::sqrt(3.0);
  EXPECT_NEAR(frame_box(unit, RenderCamera{}, fovy, 2.0).distance, 1.05 * r / std::sin(kPi / 8), 1e-12);
  const double half_w = std::atan(0.5 * std::tan(kPi / 8));
  EXPECT_NEAR(frame_box(unit, RenderCamera{}, fovy, 0.5).distance, 1.05 * r / std::sin(half_w), 1e-12);
}

// Framed on the robot, the arm is large in the picture: turning j1 by 90 degrees changes the pixels
// of the link's two positions. The camera of --frame volume for a 1.5 m reach (frame_circle up to
// 2.5 m) stands about 5.4 m away against 2.3 m here (1.05 r / sin(fovy / 2), r = 1.95 and 0.83 m):
// the link covers about (5.4 / 2.3)^2 = 5.5 times fewer pixels there; at least 3 times is required.
TEST_F(RenderTest, TurningTheFramedArmChangesManyPixels) {
  const Scene s = scene();
  const double fovy = s.model().vis.global.fovy * kPi / 180;
  auto changed = [&](const RenderCamera& camera) {
    RenderRequest r;
    r.width = 160;
    r.height = 120;
    r.camera = camera;
    r.q = Eigen::VectorXd::Zero(1);
    const Image a = render_scene(s, r);
    r.q[0] = kPi / 2;
    const Image b = render_scene(s, r);
    int n = 0;
    for (int y = 0; y < r.height; ++y)
      for (int x = 0; x < r.width; ++x) {
        const auto p = a.at(x, y), q = b.at(x, y);
        int d = 0;
        for (int k = 0; k < 3; ++k)
          d += std::abs(int{p[static_cast<size_t>(k)]} - int{q[static_cast<size_t>(k)]});
        n += d > 30 ? 1 : 0;
      }
    return n;
  };
  const std::vector<Eigen::VectorXd> both = {Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, kPi / 2)};
  const RenderCamera robot =
      frame_box(robot_neighbourhood(s, robot_extent(s, both), 0.3), RenderCamera{}, fovy, 4.0 / 3.0);
  const RenderCamera wide = frame_circle(Eigen::Vector2d::Zero(), 1.5, 2.5, fovy);
  const int near = changed(robot), far = changed(wide);
  EXPECT_GT(near, 160 * 120 / 100) << near;
  EXPECT_GT(near, 3 * far) << near << " " << far;
}

// One SceneRenderer for many frames draws each as render_scene does, pixel for pixel, whatever it
// drew before (the volume's geoms are rebuilt from zeros each frame): the arm turned, a box added,
// ghosts added, and back to the first frame. A request it was not made for is refused.
TEST_F(RenderTest, OneRendererForManyFramesDrawsEachAsRenderSceneDoes) {
  const Scene s = scene();
  std::vector<RenderRequest> frames(4, top_down());
  frames[1].q[0] = 1.0;
  frames[2].volume = {beside_the_arm()};
  frames[2].fade_region = Eigen::AlignedBox3d(Eigen::Vector3d(-2, 1, 0), Eigen::Vector3d(-1, 2, 1));
  frames[3].ghosts = {Eigen::VectorXd::Constant(1, -0.5), Eigen::VectorXd::Constant(1, 0.5)};
  frames.push_back(frames[0]);
  SceneRenderer renderer(s, 160, 120, 1, 2);
  std::vector<Image> drawn;
  for (const RenderRequest& r : frames) {
    drawn.push_back(renderer.render(r));
    const Image alone = render_scene(s, r);
    EXPECT_EQ(drawn.back().rgb, alone.rgb) << "frame " << drawn.size() - 1;
  }
  EXPECT_NE(drawn[0].rgb, drawn[1].rgb);
  EXPECT_NE(drawn[0].rgb, drawn[2].rgb);
  EXPECT_NE(drawn[0].rgb, drawn[3].rgb);
  RenderRequest bigger = top_down();
  bigger.width = 200;
  EXPECT_THROW(renderer.render(bigger), std::logic_error);
  RenderRequest more = top_down();
  more.volume = {beside_the_arm(), beside_the_arm()};
  EXPECT_THROW(renderer.render(more), std::logic_error);
}

// --volume fade: a box that meets the fade region, or stands between it and the camera, is drawn at
// the faded opacity; one that does neither at the normal one.
TEST_F(RenderTest, VolumeBoxesAroundTheRobotAreFaded) {
  const Scene s = scene();
  RenderRequest r = top_down();
  const Box box = beside_the_arm();
  r.volume = {box};
  const Image normal = render_scene(s, r);
  r.fade_region = Eigen::AlignedBox3d(Eigen::Vector3d(-2, 1, 0), Eigen::Vector3d(-1, 2, 1));
  const Image faded = render_scene(s, r);
  r.volume.clear();
  const Image none = render_scene(s, r);
  Eigen::Vector2d px;
  const double fovy = s.model().vis.global.fovy * kPi / 180;
  ASSERT_TRUE(project_point(r.camera, fovy, r.width, r.height, {-1.5, 1.5, 0.5}, px));
  const int x = static_cast<int>(px.x()), y = static_cast<int>(px.y());
  // Yellow over grey: red minus blue grows with the box's opacity (0 without the box).
  auto tint = [&](const Image& img) { return int{img.at(x, y)[0]} - int{img.at(x, y)[2]}; };
  EXPECT_GT(tint(normal), 40);
  EXPECT_LT(tint(faded), tint(normal) / 2) << tint(faded) << " " << tint(normal);
  EXPECT_GT(tint(faded), tint(none)) << tint(faded) << " " << tint(none);
  // A box above the region (nearer to the camera, which looks down from above) hides it: faded
  // too, though it does not meet the region.
  Box above = box;
  above.center.z() = 2.0;
  r.volume = {above};
  r.fade_region = Eigen::AlignedBox3d();
  const Image above_normal = render_scene(s, r);
  r.fade_region = Eigen::AlignedBox3d(Eigen::Vector3d(-2, 1, 0), Eigen::Vector3d(-1, 2, 1));
  const Image above_faded = render_scene(s, r);
  ASSERT_TRUE(project_point(r.camera, fovy, r.width, r.height, {-1.5, 1.5, 2.25}, px));
  const int ax = static_cast<int>(px.x()), ay = static_cast<int>(px.y());
  auto tint_at = [&](const Image& img) { return int{img.at(ax, ay)[0]} - int{img.at(ax, ay)[2]}; };
  EXPECT_GT(tint_at(above_normal), 40);
  EXPECT_LT(tint_at(above_faded), tint_at(above_normal) / 2)
      << tint_at(above_faded) << " " << tint_at(above_normal);
  r.faded_alpha = 1.5;
  r.volume = {box};
  EXPECT_THROW(render_scene(s, r), InputError);
}

// The legend band: the colour scale 240 pixels wide from x = 10 in 64 steps (step i coloured at the
// height (i + 0.5) / 64 of the top), 8 to 20 pixels down; then, 24 pixels on, the ghosts' swatches
// (14 x 12 pixels, tinted as the ghosts: lower (0.35, 0.60, 0.95), upper (0.95, 0.35, 0.35)).
TEST(LegendTest, ColourScaleAndGhostTintsWhereWorkedOut) {
  const Image img = render_legend(640, 2.0, true, true);
  ASSERT_EQ(img.width, 640);
  ASSERT_EQ(img.height, kLegendHeight);
  auto near = [](const std::array<unsigned char, 3>& px, double r, double g, double b) {
    return std::abs(px[0] - 255 * r) <= 3 && std::abs(px[1] - 255 * g) <= 3 && std::abs(px[2] - 255 * b) <= 3;
  };
  const auto first = height_colour(0.5 / 64 * 2.0, 2.0), last = height_colour(63.5 / 64 * 2.0, 2.0);
  EXPECT_TRUE(near(img.at(11, 14), first[0], first[1], first[2]));
  EXPECT_TRUE(near(img.at(248, 14), last[0], last[1], last[2]));
  EXPECT_TRUE(near(img.at(281, 14), 0.35, 0.60, 0.95));
  const double second = 274 + 26 + detail::text_width("ghost: joints at lower bound", 9);
  EXPECT_TRUE(near(img.at(static_cast<int>(second) + 7, 14), 0.95, 0.35, 0.35));
  // No volume and no ghosts: white where the scale and the swatch were.
  const Image bare = render_legend(640, 0, false, false);
  EXPECT_TRUE(near(bare.at(11, 14), 1, 1, 1));
  EXPECT_TRUE(near(bare.at(281, 14), 1, 1, 1));
  EXPECT_THROW(render_legend(8, 1, true, true), InputError);
}

TEST(LegendTest, StackedTopToBottom) {
  Image a, b;
  a.width = b.width = 1;
  a.height = 1;
  b.height = 2;
  a.rgb = {1, 1, 1};
  b.rgb = {2, 2, 2, 3, 3, 3};
  const Image s = stack_vertically({a, b});
  EXPECT_EQ(s.height, 3);
  EXPECT_EQ(s.rgb, (std::vector<unsigned char>{1, 1, 1, 2, 2, 2, 3, 3, 3}));
  b.width = 2;
  EXPECT_THROW(stack_vertically({a, b}), InputError);
}

TEST_F(RenderTest, BadSizesCamerasAndConfigurations) {
  const Scene s = scene();
  RenderRequest r;
  r.q = Eigen::VectorXd::Zero(1);
  r.width = 8;
  EXPECT_THROW(render_scene(s, r), InputError);
  r.width = 64;
  r.height = 9000;
  EXPECT_THROW(render_scene(s, r), InputError);
  r.height = 64;
  r.camera.distance = std::nan("");
  EXPECT_THROW(render_scene(s, r), InputError);
  r.camera.distance = 0;
  EXPECT_THROW(render_scene(s, r), InputError);
  r.camera.distance = 5;
  r.camera.elevation = 2;
  EXPECT_THROW(render_scene(s, r), InputError);
  r.camera.elevation = -0.5;
  r.q = Eigen::VectorXd::Constant(1, std::nan(""));
  EXPECT_THROW(render_scene(s, r), InputError);
  r.q = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(render_scene(s, r), InputError);
}

}  // namespace
}  // namespace leeway
