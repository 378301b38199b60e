#pragma once
//! @file render.hpp
//! Pictures of a cell: offscreen MuJoCo renders through OSMesa (no display needed) of the
//! robot at a configuration, the generated volume as semi-transparent boxes coloured by height, and
//! ghosts of the robot at the extremes of its intervals; PNG encoding; the volume of a bounds file.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/box.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume.hpp"

namespace leeway {

//! An 8-bit RGB image, rows top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<unsigned char> rgb;  //!< 3 * width * height bytes
  //! The pixel at column x, row y (row 0 at the top).
  std::array<unsigned char, 3> at(int x, int y) const;
};

//! The image as a PNG file (8-bit RGB, no interlace, zlib-compressed; deterministic bytes).
std::string encode_png(const Image& image);

//! Reads the width and height of a PNG file's header. @throws InputError naming the file when it
//! is not a PNG.
std::array<int, 2> png_size(const std::string& path);

//! Writes a PNG atomically (no partial file on failure). @throws InputError naming the file.
void write_png(const std::string& path, const Image& image);

//! A MuJoCo free camera: it looks at `lookat` from `distance` [m] along the direction given by
//! `azimuth` (from world +x towards +y) and `elevation` (negative: looking down) [rad]: the camera
//! sits at lookat - distance * (cos el cos az, cos el sin az, sin el).
struct RenderCamera {
  double azimuth = -2.4;                             //!< [rad]
  double elevation = -0.9;                           //!< [rad], within [-pi/2, pi/2]
  double distance = 8.0;                             //!< [m], > 0
  Eigen::Vector3d lookat = Eigen::Vector3d::Zero();  //!< [m]
};

//! The default camera: at the default azimuth and elevation, looking at the middle of a cylinder
//! standing on the floor (the reach circle `center`, `radius` [m], up to `height` [m]) from far
//! enough that its bounding sphere fits the vertical field of view `fovy` [rad].
RenderCamera frame_circle(const Eigen::Vector2d& center, double radius, double height, double fovy);

//! The world box [m] holding the robot's geoms (links and base; planes excluded) at every
//! configuration of `qs`. @throws InputError on a configuration that does not fit the scene.
Eigen::AlignedBox3d robot_extent(const Scene& scene, const std::vector<Eigen::VectorXd>& qs);

//! What a robot picture frames: `robot` grown by `near` [m] on every side, shrunk to the robot and
//! the parts of the obstacles inside that grown box (the nearby tables, walls and the patch, not the
//! whole floor or a distant fence).
Eigen::AlignedBox3d robot_neighbourhood(const Scene& scene, const Eigen::AlignedBox3d& robot, double near);

//! A camera at `direction`'s azimuth and elevation looking at the centre of `region` [m] from far
//! enough that the region's bounding sphere fits both the vertical field of view `fovy` [rad] and
//! the horizontal one of an image `aspect` (width / height) wide.
RenderCamera frame_box(const Eigen::AlignedBox3d& region, const RenderCamera& direction, double fovy,
                       double aspect);

//! Height of render_legend's band [pixels].
constexpr int kLegendHeight = 56;

//! The legend band under a render, `width` x kLegendHeight pixels on white: the volume's colour
//! scale from 0 to `max_top` [m] with ticks (when max_top > 0), the two ghost tints (when
//! `ghosts`), and a note on the faded boxes (when `faded`). @throws InputError on a width below 16.
Image render_legend(int width, double max_top, bool ghosts, bool faded);

//! Images of one width stacked, top to bottom. @throws InputError on no image or widths that differ.
Image stack_vertically(const std::vector<Image>& images);

//! Images of one height side by side, left to right. @throws InputError on no image or heights
//! that differ.
Image tile_horizontally(const std::vector<Image>& images);

//! Which ghosts to draw around the rendered configuration.
enum class GhostMode {
  kNone,     //!< none
  kCorners,  //!< two: every joint at its lower bound, every joint at its upper bound
  kJoints,   //!< two per joint with a non-empty interval: that joint at each bound, the others nominal
};

//! What to render and how.
struct RenderRequest {
  int width = 1280, height = 960;  //!< image size [pixels]
  RenderCamera camera;
  Eigen::VectorXd q;                    //!< the robot's configuration (robot joints in order)
  std::vector<Box> volume;              //!< boxes drawn semi-transparent, coloured by their top's height
  std::vector<Eigen::VectorXd> ghosts;  //!< configurations drawn as translucent robots
  double volume_alpha = 0.45;           //!< opacity of the volume boxes
  //! Volume boxes that meet this region [m], or stand between it and the camera (nearer than its
  //! far side, their picture overlapping its picture), are drawn at `faded_alpha`: the volume
  //! faded around and in front of the robot, so that the robot stays visible. Empty: none.
  Eigen::AlignedBox3d fade_region;
  double faded_alpha = 0.08;
};

//! The ghosts' tints (RGB): every joint at its lower bound bluish, at its upper bound reddish
//! (renders, their legend and the viewer).
inline constexpr std::array<float, 3> kLowerGhostTint = {0.35f, 0.60f, 0.95f};
inline constexpr std::array<float, 3> kUpperGhostTint = {0.95f, 0.35f, 0.35f};

//! The height of the highest box's top [m] (its centre plus its half height); 0 for no box.
double highest_top(const std::vector<Box>& boxes);

//! Colour of a volume box whose top is at `top` [m], on a blue-green-yellow scale (viridis-like)
//! from 0 to `max_top` [m]; alpha is set by the caller.
std::array<float, 3> height_colour(double top, double max_top);

//! The configurations of `mode` around waypoint bounds `w` (see GhostMode).
std::vector<Eigen::VectorXd> ghost_configurations(const WaypointBounds& w, GhostMode mode);

//! Renders the scene offscreen with MuJoCo (OSMesa context, no display).
//! @throws InputError on an image size outside 16 .. 8192 pixels, a non-finite camera or a bad q;
//! std::runtime_error when no OpenGL context can be made.
Image render_scene(const Scene& scene, const RenderRequest& request);

//! Renders many pictures of one scene at one size, as render_scene draws each, through one copy of
//! the model, one scene buffer and one OpenGL context (render_scene makes them per call): the
//! frames of `leeway render --video` and `--strip`. One per thread; the scene must outlive it.
class SceneRenderer {
 public:
  //! For requests of `width` x `height` pixels with at most `max_volume_boxes` volume boxes and
  //! `max_ghosts` ghosts. @throws InputError on a size outside 16 .. 8192 pixels or too many boxes;
  //! std::runtime_error when no OpenGL context can be made.
  SceneRenderer(const Scene& scene, int width, int height, size_t max_volume_boxes, size_t max_ghosts);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;
  //! One picture, the same as render_scene(scene, request). @throws InputError as render_scene;
  //! std::logic_error on a request of another size or with more boxes or ghosts.
  Image render(const RenderRequest& request);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! Renders many frames of one scene through one OpenGL context (a video): the robot at q, up to two
//! ghosts (tinted as render_scene's) and an arrow. One per thread; the scene must outlive it.
class FrameRenderer {
 public:
  //! @throws InputError on a size outside 16 .. 8192 pixels or a non-finite camera;
  //! std::runtime_error when no OpenGL context can be made.
  FrameRenderer(const Scene& scene, int width, int height, const RenderCamera& camera);
  ~FrameRenderer();
  FrameRenderer(const FrameRenderer&) = delete;
  FrameRenderer& operator=(const FrameRenderer&) = delete;
  //! One frame: the robot at q, the ghosts, and a green arrow from `arrow_from` along `arrow` [m]
  //! (none when `arrow` is zero).
  Image render(const Eigen::VectorXd& q, const std::vector<Eigen::VectorXd>& ghosts,
               const Eigen::Vector3d& arrow_from, const Eigen::Vector3d& arrow);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! Projects a world point [m] to pixel coordinates (column, row from the top) of an image rendered
//! with `camera` and vertical field of view `fovy` [rad]: MuJoCo's free-camera pinhole model. Returns
//! false when the point is behind the camera.
bool project_point(const RenderCamera& camera, double fovy, int width, int height, const Eigen::Vector3d& p,
                   Eigen::Vector2d& pixel);

//! A bounds file with the volume it was computed against, regenerated from its nominal path and
//! parameters (the volume is deterministic).
struct BoundsFileVolume {
  std::vector<WaypointBounds> bounds;
  Params params;
  Volume volume;
  int recorded_boxes = -1;  //!< the file's "boxes"
};

//! Reads a bounds file written for `scene` and regenerates its volume from its nominal path and
//! "params" (an older file without "params" gives an empty volume unless `require_volume`).
//! @throws InputError naming the file when it was written for another cell (its "cell" names another
//! file, or the regenerated volume has another box count than its "boxes"), or when
//! `require_volume` and it has no "params".
BoundsFileVolume read_bounds_volume(const std::string& path, const Scene& scene, bool require_volume = true);

}  // namespace leeway
