#include "cli/render.hpp"
#include "cli/video.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>

#include "core/json_io.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"
#include "leeway/viz/render.hpp"

namespace leeway::cli {
namespace {

// Height [m] --frame volume frames without a volume (an industrial arm's reach upwards).
constexpr double kRobotHeight = 2.5;
// --frame robot: obstacles within this of the robot's box [m] are framed with it.
constexpr double kNearObstacles = 0.3;
// --volume fade: volume boxes within this of the robot's box [m] are drawn nearly clear.
constexpr double kFadeMargin = 0.05;
// --strip: at most this many frames.
constexpr int kMaxStrip = 64;
// --legend on: drawn on images at least this wide [pixels], leaving a picture at least this high.
constexpr int kLegendMinWidth = 320;
constexpr int kLegendMinPicture = 120;

// The robot's base on the floor at q: the first hinge joint's anchor (the reach circle's centre).
Eigen::Vector2d arm_base(const Scene& scene, const Eigen::VectorXd& q) {
  DataPtr d = make_data(scene.model());
  scene.set_qpos(*d, q);
  mj_kinematics(&scene.model(), d.get());
  for (const auto& j : scene.joints())
    if (!j.prismatic) return {d->xanchor[3 * j.id], d->xanchor[3 * j.id + 1]};
  return {0, 0};
}

}  // namespace

std::optional<RenderInput> render_input(const RenderArgs& args, const Scene& scene, Params& p,
                                        bool show_volume) {
  RenderInput in;
  if (!args.bounds.empty()) {
    BoundsFileVolume file = read_bounds_volume(args.bounds, scene, /*require_volume=*/show_volume);
    in.bounds = std::move(file.bounds);
    in.volume = std::move(file.volume);
    p = file.params;
    in.what = args.bounds;
    in.trajectory.emplace(read_bounds_trajectory(args.bounds, scene));
    const nlohmann::json safety =
        detail::read_json_file(args.bounds, "bounds file").value("safety", nlohmann::json::object());
    in.safety_mode = safety.value("mode", std::string("none"));
    in.proven = safety.value("certified", false);
    in.margin = safety.value("margin", 0.0);
  } else if (!args.from.empty()) {
    if (args.waypoints < 2)
      throw InputError("--waypoints " + std::to_string(args.waypoints) + " must be >= 2");
    require_memory(args.waypoints * kBytesPerWaypoint, "--waypoints " + std::to_string(args.waypoints));
    // As leeway bounds: a colliding straight path is planned around (default planner options).
    PathRequest request;
    request.from = args.from;
    request.to = args.to;
    request.waypoints = args.waypoints;
    request.plan_around = !args.no_plan;
    const NominalPath path = resolve_nominal_path(scene, request);
    if (!report_refusal(path)) return std::nullopt;
    if (!path.replaced.empty()) std::cout << path.replaced << "\n";
    const int n = static_cast<int>(path.waypoints.size());
    if (args.waypoint >= n)
      throw InputError("--waypoint " + std::to_string(args.waypoint) + ": the path has " + std::to_string(n) +
                       " waypoints (0 .. " + std::to_string(n - 1) + ")");
    VolumeModel world(scene, VolumeModel::capacity_for(scene, p.height_map.max_cells));
    BoundsRun run = compute_bounds(scene, world, path.waypoints, p, args.threads);
    in.bounds = std::move(run.bounds);
    in.volume = std::move(run.volume);
    in.what = path.label;
    in.trajectory.emplace(scene, in.bounds);
    in.safety_mode = safety_mode_name(run.safety.mode);
    in.proven = run.safety.mode == SafetyMode::kCertified && run.safety.all_passed;
    in.margin = p.safety.margin;
  }
  return in;
}

void add_shown_path_options(CLI::App* sub, RenderArgs& args, CLI::Option* bounds) {
  sub->add_option(
         "--from", args.from,
         "Start: a keyframe, site:NAME or xyz:X,Y,Z (bounds computed here, planned as leeway bounds plans)")
      ->excludes(bounds);
  sub->add_option("--to", args.to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z")->excludes(bounds);
  sub->add_option("--key", args.key, "Keyframe to show without bounds (default: the cell's first)")
      ->excludes(bounds);
}

void add_shown_computation_options(CLI::App* sub, RenderArgs& args, CLI::Option* bounds) {
  sub->add_flag("--no-plan", args.no_plan,
                "Exit 1 when the straight path between two keyframes collides instead of planning around it")
      ->excludes(bounds);
  sub->add_option("--waypoints", args.waypoints, "Waypoints along the joint-linear path (with --from/--to)")
      ->capture_default_str();
  sub->add_option("--max-cells", args.max_cells, "MAX_cells of the height-map (with --from/--to)");
  sub->add_option("--params", args.params, "Parameter file (JSON; with --from/--to)")
      ->check(file_name_check());
  add_preset_options(sub, args.preset, args.safety);
  add_joint_bounds_options(sub, args.joints);
  sub->add_option("--threads", args.threads, "Worker threads")->capture_default_str();
  sub->final_callback([sub, &args] { args.max_cells_given = sub->count("--max-cells") > 0; });
}

void check_shown_path(const RenderArgs& args) {
  const bool with_path = !args.from.empty() || !args.to.empty();
  if (with_path && (args.from.empty() || args.to.empty()))
    throw InputError("--from and --to go together (two keyframes)");
  if (with_path && !args.key.empty())
    throw InputError("--key shows a keyframe without bounds: not with --from/--to");
}

Params shown_params(const Scene& scene, const RenderArgs& args) {
  Params p = load_params(scene, args.preset, args.params, args.safety);
  if (args.max_cells_given) p.height_map.max_cells = args.max_cells;
  p.validate();
  apply_joint_bounds_options(scene, args.joints, p);
  return p;
}

Eigen::VectorXd shown_keyframe(const Scene& scene, const RenderArgs& args) {
  return !args.key.empty()            ? scene.keyframe(args.key).q
         : !scene.keyframes().empty() ? scene.keyframes().front().q
                                      : Eigen::VectorXd::Zero(scene.dof());
}

CLI::App* add_render(CLI::App& app, RenderArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "render",
      "An offscreen picture (PNG, no display needed) of the cell with the robot at a waypoint and, with\n"
      "bounds (--bounds, or --from/--to computed as leeway bounds does), the volume's boxes coloured by\n"
      "height and ghosts of the robot at the extremes of its intervals. Exit 0 on success, 1 a colliding\n"
      "path that cannot be planned around, an unreachable goal or no path, 2 bad input (nothing written).");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  auto* bounds = sub->add_option("--bounds", args.bounds, "Bounds file written by leeway bounds --out")
                     ->check(file_name_check());
  add_shown_path_options(sub, args, bounds);
  sub->add_option("--out", args.out, "PNG file to write")->check(file_name_check())->required();
  sub->add_option("--waypoint", args.waypoint, "Waypoint shown, from 0 (default: the last)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            return text.find('-') == 0 ? "'" + text + "' must be a waypoint index, 0 or more" : "";
          },
          ""));
  sub->add_option("--camera", args.camera,
                  "Camera \"az,el,dist\": azimuth and elevation [rad] (elevation < 0 looks down), distance\n"
                  "[m] (default: -2.4,-0.9 and the distance --frame gives)")
      ->check(non_empty_check("three numbers az,el,dist"));
  sub->add_option("--lookat", args.lookat,
                  "Point the camera looks at, \"x,y,z\" [m] (default: the centre --frame gives)")
      ->check(non_empty_check("three numbers x,y,z"));
  sub->add_option("--size", args.size, "Image size WIDTHxHEIGHT [pixels]")->capture_default_str();
  sub->add_option("--volume", args.volume,
                  "Draw the volume: fade (boxes around the robot nearly clear, so that it stays visible),\n"
                  "on (every box alike) or off (the thesis's fig. 3.4 after/before)")
      ->capture_default_str();
  sub->add_option("--frame", args.frame,
                  "Default camera: robot (the robot, its ghosts and the obstacles near them) or volume\n"
                  "(the height-map's square up to its highest box, or the reach circle without a volume)")
      ->capture_default_str();
  sub->add_option("--strip", args.strip,
                  "K frames at evenly spaced nominal times along the path, side by side in one image\n"
                  "(--size is the whole image; with --bounds or --from/--to)");
  sub->add_option("--video", args.video,
                  "Also write an MP4 of the path (30 frames per second of nominal time, the robot and its\n"
                  "ghosts at each; needs ffmpeg; even --size)");
  sub->add_option(
         "--legend", args.legend,
         "A legend band under the picture (the volume's colour scale in metres, the ghosts' tints):\n"
         "on or off (none below 320x176 pixels)")
      ->capture_default_str();
  sub->add_option("--ghosts", args.ghosts,
                  "Ghosts of the robot: corners (all joints at their lower, all at their upper bound),\n"
                  "joints (each joint at each bound) or none")
      ->capture_default_str();
  add_shown_computation_options(sub, args, bounds);
  return sub;
}

namespace {

// --ghosts: corners, joints or none.
GhostMode parse_ghosts(const std::string& text) {
  if (text == "corners") return GhostMode::kCorners;
  if (text == "joints") return GhostMode::kJoints;
  if (text != "none") throw InputError("--ghosts '" + text + "' must be corners, joints or none");
  return GhostMode::kNone;
}

// --camera AZIMUTH,ELEVATION,DISTANCE [rad, rad, m].
RenderCamera parse_camera(const std::string& text) {
  const Eigen::VectorXd c = parse_vector(text, "--camera");
  if (c.size() != 3)
    throw InputError("--camera '" + text +
                     "' must be three numbers: azimuth [rad], elevation [rad], distance [m]");
  if (!(c[2] > 0)) throw InputError("--camera distance " + format_number(c[2]) + " m must be > 0");
  if (std::abs(c[1]) > 1.5707963267948966)
    throw InputError("--camera elevation " + format_number(c[1]) + " rad must be within [-pi/2, pi/2]");
  RenderCamera camera;
  camera.azimuth = c[0];
  camera.elevation = c[1];
  camera.distance = c[2];
  return camera;
}

}  // namespace

namespace {

// One picture: the robot at q and its ghosts.
struct Frame {
  Eigen::VectorXd q;
  std::vector<Eigen::VectorXd> ghosts;
  Eigen::AlignedBox3d robot;  // the robot's extent at q and at the ghosts [m]
};

Frame make_frame(const Scene& scene, Eigen::VectorXd q, std::vector<Eigen::VectorXd> ghosts) {
  std::vector<Eigen::VectorXd> shown = ghosts;
  shown.push_back(q);
  const Eigen::AlignedBox3d robot = robot_extent(scene, shown);
  return Frame{std::move(q), std::move(ghosts), robot};
}

// The frame at one point of the path: the nominal configuration and the ghosts of the box there.
Frame stage_frame(const Scene& scene, const BoundsStage& at, GhostMode ghosts) {
  return make_frame(scene, at.nominal,
                    ghost_configurations(WaypointBounds(at.nominal, at.lower, at.upper), ghosts));
}

// The frames shown: the bare cell's keyframe, waypoint k, or (--strip K) K boxes at evenly spaced
// nominal times along the path (BoundsTrajectory: linear in the path parameter between waypoints).
std::vector<Frame> render_frames(const RenderArgs& args, const Scene& scene,
                                 const std::vector<WaypointBounds>& bounds, int k, GhostMode ghosts) {
  if (bounds.empty()) {
    return {make_frame(scene, shown_keyframe(scene, args), {})};
  }
  if (args.strip == 0)
    return {make_frame(scene, bounds[static_cast<size_t>(k)].q,
                       ghost_configurations(bounds[static_cast<size_t>(k)], ghosts))};
  const BoundsTrajectory path(scene, bounds);
  std::vector<Frame> out;
  for (int j = 0; j < args.strip; ++j)
    out.push_back(stage_frame(scene, path.at_t(path.duration() * j / (args.strip - 1)), ghosts));
  return out;
}

// The default camera: --frame robot fits every frame's robot and ghosts and the obstacles near them;
// --frame volume the volume's height-map when there is one (also with --volume off, so that both
// views of fig. 3.4 share the camera), else the reach circle at the first frame.
RenderCamera default_camera(const RenderArgs& args, const Scene& scene, const Params& p, const Volume& volume,
                            const Eigen::AlignedBox3d& robots, const Eigen::VectorXd& q, double aspect) {
  const double fovy = scene.model().vis.global.fovy * 3.14159265358979323846 / 180;
  if (args.frame == "robot")
    return frame_box(robot_neighbourhood(scene, robots, kNearObstacles), RenderCamera{}, fovy, aspect);
  if (volume.grid.rows > 0) {
    const Grid& g = volume.grid;
    const Eigen::Vector2d centre(g.origin_x + 0.5 * g.rows * g.side, g.origin_y + 0.5 * g.cols * g.side);
    const double top = std::max(kRobotHeight, highest_top(volume.boxes));
    return frame_circle(centre, 0.5 * std::max(g.rows, g.cols) * g.side, top, fovy);
  }
  return frame_circle(arm_base(scene, q), p.volume.reach_radius, kRobotHeight, fovy);
}

// Checks every flag that needs no cell, before any work.
void check_render_args(const RenderArgs& args) {
  if (args.volume != "fade" && args.volume != "on" && args.volume != "off")
    throw InputError("--volume '" + args.volume + "' must be fade, on or off");
  if (args.legend != "on" && args.legend != "off")
    throw InputError("--legend '" + args.legend + "' must be on or off");
  if (args.frame != "robot" && args.frame != "volume")
    throw InputError("--frame '" + args.frame + "' must be robot or volume");
  check_shown_path(args);
  const bool with_path = !args.from.empty() || !args.to.empty();
  if (!with_path && args.bounds.empty() && args.waypoint != -1)
    throw InputError("--waypoint " + std::to_string(args.waypoint) +
                     ": there is no path without --bounds or --from/--to");
  if (args.strip != 0 && (args.strip < 2 || args.strip > kMaxStrip))
    throw InputError("--strip " + std::to_string(args.strip) + " must be within 2 .. " +
                     std::to_string(kMaxStrip));
  if (args.strip != 0 && !with_path && args.bounds.empty())
    throw InputError("--strip " + std::to_string(args.strip) +
                     ": there is no path without --bounds or --from/--to");
  if (!args.video.empty() && !with_path && args.bounds.empty())
    throw InputError("--video " + args.video + ": there is no path without --bounds or --from/--to");
  if (args.strip != 0 && args.waypoint != -1)
    throw InputError("--strip shows the whole path: not with --waypoint " + std::to_string(args.waypoint));
  require_threads(args.threads);
}

// Draws frames: each rendered with the volume (faded around its robot with --volume fade), side by
// side, the legend band under them.
struct Painter {
  const Scene& scene;
  const RenderArgs& args;
  const RenderInput& in;
  const Params& params;
  bool show_volume, legend;
  int frame_height;
  bool camera_given;
  RenderCamera camera;     // --camera's angles and distance (when given)
  Eigen::Vector3d lookat;  // --lookat (when given)

  // The camera: --camera and --lookat where given, the default framing of `frames` elsewhere.
  RenderCamera camera_for(const std::vector<Frame>& frames, int frame_width) const {
    Eigen::AlignedBox3d robots;
    for (const Frame& f : frames) robots.extend(f.robot);
    const RenderCamera framed = default_camera(args, scene, params, in.volume, robots, frames.front().q,
                                               static_cast<double>(frame_width) / frame_height);
    RenderCamera c = camera;
    if (!camera_given) c.distance = framed.distance;
    c.lookat = args.lookat.empty() ? framed.lookat : lookat;
    return c;
  }

  // One renderer for every frame of this size (a video's frames, a strip's): the model copy, the
  // scene buffer and the OpenGL context are made once.
  mutable std::unique_ptr<SceneRenderer> renderer;
  mutable int renderer_width = 0;
  mutable size_t renderer_ghosts = 0;

  Image draw(const std::vector<Frame>& frames, const RenderCamera& c, int frame_width) const {
    std::vector<Image> images;
    size_t ghosts = 0;
    for (const Frame& f : frames) ghosts = std::max(ghosts, f.ghosts.size());
    if (!renderer || renderer_width != frame_width || renderer_ghosts < ghosts) {
      renderer.reset();  // one OpenGL context at a time
      renderer = std::make_unique<SceneRenderer>(scene, frame_width, frame_height,
                                                 show_volume ? in.volume.boxes.size() : 0, ghosts);
      renderer_width = frame_width;
      renderer_ghosts = ghosts;
    }
    for (const Frame& f : frames) {
      RenderRequest request;
      request.width = frame_width;
      request.height = frame_height;
      request.camera = c;
      request.q = f.q;
      request.ghosts = f.ghosts;
      if (show_volume) request.volume = in.volume.boxes;
      if (args.volume == "fade")
        request.fade_region =
            Eigen::AlignedBox3d(f.robot.min().array() - kFadeMargin, f.robot.max().array() + kFadeMargin);
      images.push_back(renderer->render(request));
    }
    Image image = images.size() == 1 ? images.front() : tile_horizontally(images);
    if (!legend) return image;
    const double max_top = show_volume ? highest_top(in.volume.boxes) : 0.0;
    return stack_vertically(
        {image, render_legend(image.width, max_top, !frames.front().ghosts.empty(), args.volume == "fade")});
  }
};

// --video: the robot and its ghosts along the path at 30 frames per second of nominal time (and a
// last frame at the path's end), one camera fitted to every frame. Without ffmpeg on PATH a
// warning, and no video.
void write_video(const Painter& painter, int width, GhostMode ghosts) {
  const std::string ffmpeg = find_on_path("ffmpeg");
  if (ffmpeg.empty()) {
    std::cerr << "leeway: warning: --video " << painter.args.video
              << ": ffmpeg is not on PATH (Debian: apt-get install ffmpeg); no video is written\n";
    return;
  }
  const BoundsTrajectory path(painter.scene, painter.in.bounds);
  std::vector<double> times;
  for (long j = 0; static_cast<double>(j) / Mp4Stream::kFps < path.duration() - 1e-9; ++j)
    times.push_back(static_cast<double>(j) / Mp4Stream::kFps);
  times.push_back(path.duration());
  std::vector<Frame> frames;
  for (double t : times) frames.push_back(stage_frame(painter.scene, path.at_t(t), ghosts));
  const RenderCamera camera = painter.camera_for(frames, width);
  const int height = painter.frame_height + (painter.legend ? kLegendHeight : 0);
  Mp4Stream stream(painter.args.video, "--video", width, height, ffmpeg);
  for (const Frame& f : frames) stream.add(painter.draw({f}, camera, width));
  const long written = stream.finish();
  std::cout << "wrote " << painter.args.video << " (" << written << " frames at " << Mp4Stream::kFps
            << " fps, " << format_number(path.duration()) << " s of nominal time)\n";
}

}  // namespace

int run_render(const RenderArgs& args) {
  // Every flag is checked before any work, so that bad input writes nothing.
  std::vector<std::string> inputs = model_input_files(args.cell);
  inputs.insert(inputs.end(), {args.bounds, args.params});
  std::vector<OutputFile> outputs = {{args.out, "--out", {".png"}}};
  if (!args.video.empty()) outputs.push_back({args.video, "--video", {".mp4"}});
  require_outputs(outputs, inputs);
  const auto [width, height] = parse_size(args.size, "--size");
  const GhostMode ghosts = parse_ghosts(args.ghosts);
  const bool camera_given = !args.camera.empty();
  RenderCamera camera = camera_given ? parse_camera(args.camera) : RenderCamera{};
  Eigen::Vector3d lookat;
  if (!args.lookat.empty()) {
    const Eigen::VectorXd v = parse_vector(args.lookat, "--lookat");
    if (v.size() != 3) throw InputError("--lookat '" + args.lookat + "' must be three numbers x,y,z [m]");
    lookat = v;
  }
  check_render_args(args);
  if (!args.video.empty() && (width % 2 || height % 2))
    throw InputError("--size " + args.size + ": a video's width and height must be even (H.264 in yuv420p)");
  const int frame_width = args.strip > 0 ? width / args.strip : width;
  const bool legend =
      args.legend == "on" && width >= kLegendMinWidth && height >= kLegendHeight + kLegendMinPicture;
  const int frame_height = legend ? height - kLegendHeight : height;
  if (frame_width < 16)
    throw InputError("--size " + args.size + " with --strip " + std::to_string(args.strip) +
                     " leaves frames " + std::to_string(frame_width) + " pixels wide (at least 16)");

  const auto scene = Scene::load(args.cell, scene_options(kDefaultTool));
  Params p = shown_params(scene, args);
  const bool show_volume = args.volume != "off";
  const std::optional<RenderInput> in = render_input(args, scene, p, show_volume);
  if (!in) return kExitFindings;
  const int n = static_cast<int>(in->bounds.size());
  if (n > 0 && (args.waypoint < -1 || args.waypoint >= n))
    throw InputError("--waypoint " + std::to_string(args.waypoint) + ": " + in->what + " has " +
                     std::to_string(n) + " waypoints (0 .. " + std::to_string(n - 1) + ")");
  const int k = args.waypoint == -1 ? n - 1 : args.waypoint;
  const std::vector<Frame> frames = render_frames(args, scene, in->bounds, k, ghosts);

  const Painter painter{scene,        args,   *in,    p,       show_volume, legend, frame_height,
                        camera_given, camera, lookat, nullptr, 0,           0};
  const RenderCamera used = painter.camera_for(frames, frame_width);
  const Image image = painter.draw(frames, used, frame_width);
  write_png(args.out, image);
  const std::string shown = n == 0           ? "no bounds"
                            : args.strip > 0 ? std::to_string(args.strip) + " frames along " + in->what
                                             : "waypoint " + std::to_string(k) + " of " + in->what;
  std::cout << "wrote " << args.out << " (" << image.width << "x" << image.height << " pixels; " << shown
            << ", " << (show_volume ? in->volume.boxes.size() : 0) << " volume boxes, "
            << frames.front().ghosts.size() << " ghosts; camera " << format_number(used.azimuth) << ","
            << format_number(used.elevation) << "," << format_number(used.distance)
            << " [rad, rad, m], look-at " << format_number(used.lookat.x()) << ","
            << format_number(used.lookat.y()) << "," << format_number(used.lookat.z()) << " [m])\n";
  if (!args.video.empty()) write_video(painter, width, ghosts);
  return kExitOk;
}

}  // namespace leeway::cli
