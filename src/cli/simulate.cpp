#include "cli/simulate.hpp"
#include "cli/video.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/viz/render.hpp"

namespace leeway::cli {

CLI::App* add_simulate(CLI::App& app, SimulateArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Closed loop: a simulated co-worker pushes the tool, a controller keeps the robot in the bounds");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  sub->add_option("--bounds", args.bounds, "Bounds file written by leeway bounds --out")->required();
  sub->add_option("--human", args.human,
                  "The push: random, push-toward NAME (an obstacle geom or body, or nearest), file F "
                  "(t fx fy fz [tx ty tz] per line), or none")
      ->expected(1, 2)
      ->capture_default_str();
  sub->add_option("--amplitude", args.options.human.amplitude,
                  "random: standard deviation of each force component; push-toward: the force [N]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--bandwidth", args.options.human.bandwidth, "random: corner frequency of the push [Hz]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--seed", args.options.seed, "Random seed of the push")
      ->check(seed_check_for(args.options.seed))
      ->capture_default_str();
  sub->add_option("--speed", args.options.speed, "Progress along the path relative to the nominal timing")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--controller", args.controller, "mpc, or projection (the baseline)")
      ->check(CLI::IsMember({"mpc", "projection"}))
      ->capture_default_str();
  sub->add_option("--max-accel", args.options.max_accel,
                  "Acceleration limit of every joint [rad/s^2 or m/s^2]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--admittance-damping", args.options.admittance_damping,
                  "Admittance damping per joint [N m s/rad or N s/m]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--admittance-inertia", args.options.admittance_inertia,
                  "Admittance inertia per joint [kg m^2 or kg]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--end-hold", args.options.end_hold, "Simulated time after the path's end [s]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--max-time", args.options.max_time,
                  "Longest simulated time [s]; 0: 3 x the nominal duration / speed + end hold + 5 s")
      ->check(finite_check())
      ->capture_default_str();
  add_tool_option(sub, args.tool);
  sub->add_flag("--json", args.json, "Print the report as JSON");
  sub->add_option("--out", args.out, "Write the report as JSON")->check(file_name_check());
  sub->add_option("--video", args.video, "Write an MP4 (30 fps, rendered offscreen, encoded by ffmpeg)")
      ->check(file_name_check());
  sub->add_option("--size", args.size, "Video size WxH [pixels]")->capture_default_str();
  return sub;
}

namespace {

HumanOptions human_options(const SimulateArgs& args) {
  HumanOptions h = args.options.human;
  const std::string& kind = args.human.at(0);
  const std::string arg = args.human.size() > 1 ? args.human[1] : "";
  const auto takes = [&](bool needs, const char* what) {
    if (needs && arg.empty()) throw InputError("--human " + kind + " needs " + what);
    if (!needs && !arg.empty()) throw InputError("--human " + kind + " takes no value ('" + arg + "' given)");
  };
  if (kind == "random") {
    takes(false, "");
    h.kind = HumanKind::kRandom;
  } else if (kind == "none") {
    takes(false, "");
    h.kind = HumanKind::kNone;
  } else if (kind == "push-toward") {
    takes(true, "an obstacle geom's or body's name, or nearest");
    h.kind = HumanKind::kPushToward;
    h.target = arg;
  } else if (kind == "file") {
    takes(true, "a push file (t fx fy fz [tx ty tz] per line)");
    require_regular_input(arg, "--human file");
    h.kind = HumanKind::kFile;
    h.samples = read_wrench_file(arg);
  } else {
    throw InputError("--human '" + kind + "' is not one of: random, push-toward NAME, file F, none");
  }
  return h;
}

// Frames at 30 fps of simulated time, piped as raw RGB into ffmpeg, which writes an H.264 MP4 into
// a temporary file renamed over the target when it succeeds.
class VideoWriter {
 public:
  VideoWriter(const Scene& scene, const BoundsTrajectory& bounds, const std::string& path, int width,
              int height, const std::string& ffmpeg)
      : scene_(scene), stream_(path, "--video", width, height, ffmpeg) {
    // The camera frames the tool's reach along the path: around the first hinge's anchor, out to
    // the farthest nominal tool position plus 1 m.
    DataPtr d = make_data(scene.model());
    Eigen::Vector2d base(0, 0);
    double radius = 1.0;
    bool have_base = false;
    for (const auto& w : bounds.waypoints()) {
      scene.set_qpos(*d, w.q);
      mj_kinematics(&scene.model(), d.get());
      if (!have_base)
        for (const auto& j : scene.joints())
          if (!j.prismatic) {
            base = {d->xanchor[3 * j.id], d->xanchor[3 * j.id + 1]};
            have_base = true;
            break;
          }
      const int site = scene.tool_site();
      radius = std::max(
          radius, (Eigen::Vector2d(d->site_xpos[3 * site], d->site_xpos[3 * site + 1]) - base).norm() + 1);
    }
    const double fovy = scene.model().vis.global.fovy * 3.14159265358979323846 / 180;
    RenderCamera camera = frame_circle(base, radius, 2.5, fovy);
    camera.elevation = -0.45;  // lower than a still picture's: the push is mostly level or down
    renderer_ = std::make_unique<FrameRenderer>(scene, width, height, camera);
  }

  // Called at every control period: renders a frame whenever 1/30 s of simulated time has passed.
  void on_frame(const mjModel& m, const mjData& d, const SimFrame& f) {
    if (f.t + 1e-9 < next_) return;
    next_ += 1.0 / Mp4Stream::kFps;
    Eigen::VectorXd q(scene_.dof());
    for (int j = 0; j < scene_.dof(); ++j)
      q[j] = d.qpos[m.jnt_qposadr[scene_.joints()[static_cast<size_t>(j)].id]];
    const WaypointBounds box(f.box.nominal, f.box.lower, f.box.upper);
    // The push as an arrow at the tool, 1 cm per newton.
    const Image image =
        renderer_->render(q, ghost_configurations(box, GhostMode::kCorners), f.tool, 0.01 * f.force);
    stream_.add(image);
  }

  // Ends the stream; returns the frame count. @throws InputError when ffmpeg failed.
  long finish() { return stream_.finish(); }

 private:
  const Scene& scene_;
  Mp4Stream stream_;
  std::unique_ptr<FrameRenderer> renderer_;
  double next_ = 0;
};

void print_report(const Scene& scene, const SimulationReport& r, const SimulateOptions& o) {
  std::ostringstream out;
  out << std::setprecision(4);
  out << "simulated " << r.simulated_time << " s (" << r.steps << " steps of " << r.timestep << " s) in "
      << r.wall_time << " s wall: " << (r.wall_time > 0 ? r.simulated_time / r.wall_time : 0)
      << " x real time\n";
  out << "path: " << (r.reached_end ? "reached the end at " : "did not reach the end; stopped at ")
      << r.end_time << " s (nominal duration " << r.nominal_duration << " s at speed " << o.speed << ")\n";
  out << "push: " << human_kind_name(o.human.kind) << ", RMS " << r.rms_force << " N, max " << r.max_force
      << " N\n";
  if (r.first_contact) {
    const SimContact& c = *r.first_contact;
    out << "contacts: " << r.contact_steps << " steps with contact; first at t = " << c.t << " s: " << c.geom1
        << " - " << c.geom2 << ", depth " << c.depth << " m" << (c.self ? " (self)" : "") << "\n";
  } else {
    out << "contacts: 0";
    if (r.min_distance_capped)
      out << " (nothing came within " << o.distance_range << " m)\n";
    else
      out << " (min distance " << r.min_distance << " m: " << r.min_distance_geom1 << " - "
          << r.min_distance_geom2 << " at t = " << r.min_distance_t << " s)\n";
  }
  out << "bounds: " << (r.left_bounds ? "LEFT (max excursion " : "never left (max excursion ")
      << r.max_excursion << " rad or m); safety clamp on " << r.clamp_steps << " steps; limits exceeded in "
      << r.limit_steps << " control periods (by up to x" << r.max_limit_ratio << "); max tracking error "
      << r.max_tracking_error << " rad or m\n";
  out << "freedom used [share of the room to the bound, per joint]:";
  for (Eigen::Index j = 0; j < r.freedom_used.size(); ++j)
    out << " " << scene.joint_names()[j] << " " << r.freedom_used[j];
  out << "\nmax deviation from nominal [rad, m for slide joints]:";
  for (Eigen::Index j = 0; j < r.max_deviation.size(); ++j) out << " " << r.max_deviation[j];
  out << "\n";
  std::cout << out.str();
}

}  // namespace

int run_simulate(const SimulateArgs& args) {
  std::vector<std::string> inputs = {args.bounds};
  for (const auto& f : model_input_files(args.cell)) inputs.push_back(f);
  if (args.human.size() > 1 && args.human[0] == "file") inputs.push_back(args.human[1]);
  std::vector<OutputFile> outputs;
  if (!args.out.empty()) outputs.push_back({args.out, "--out", {".json"}});
  if (!args.video.empty()) outputs.push_back({args.video, "--video", {".mp4"}});
  require_outputs(outputs, inputs);

  SimulateOptions options = args.options;
  options.human = human_options(args);
  options.controller = args.controller == "projection" ? ControllerKind::kProjection : ControllerKind::kMpc;
  options.check();

  std::optional<std::pair<int, int>> size;
  std::string ffmpeg;
  if (!args.video.empty()) {
    size = parse_size(args.size, "--size");
    if (size->first % 2 || size->second % 2)
      throw InputError("--size " + args.size +
                       ": a video's width and height must be even (H.264 in yuv420p)");
    ffmpeg = find_on_path("ffmpeg");
  }

  const auto scene = Scene::load(args.cell, scene_options(args.tool));
  const BoundsTrajectory bounds = read_bounds_trajectory(args.bounds, scene);
  std::unique_ptr<VideoWriter> video;
  if (!args.video.empty() && ffmpeg.empty())
    std::cerr << "leeway: warning: --video " << args.video
              << ": ffmpeg is not on PATH (Debian: apt-get install ffmpeg); no video is written, the "
                 "simulation runs\n";
  if (!ffmpeg.empty())
    video = std::make_unique<VideoWriter>(scene, bounds, args.video, size->first, size->second, ffmpeg);
  FrameCallback on_frame;
  if (video)
    on_frame = [&](const mjModel& m, const mjData& d, const SimFrame& f) { video->on_frame(m, d, f); };
  const SimulationReport report = simulate(scene, bounds, options, on_frame);
  nlohmann::json j = simulation_json(scene, report, options, args.cell, args.bounds);
  if (!args.video.empty()) {
    j["video"] = nullptr;
    if (video) {
      const long frames = video->finish();
      j["video"] = {{"path", args.video}, {"frames", frames}, {"fps", 30}};
    }
  }
  if (!args.out.empty()) write_file_atomic(args.out, j.dump(2) + "\n");
  if (args.json)
    std::cout << j.dump(2) << "\n";
  else
    print_report(scene, report, options);
  if (j.contains("video") && !j["video"].is_null())
    std::cout << "wrote " << args.video << ": " << j["video"]["frames"].get<long>() << " frames at 30 fps ("
              << size->first << "x" << size->second << " pixels)\n";
  return report.first_contact || report.left_bounds ? kExitFindings : kExitOk;
}

}  // namespace leeway::cli
