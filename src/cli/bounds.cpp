#include "cli/bounds.hpp"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <utility>

#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/room.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"
#include "leeway/path/planner.hpp"
#include "leeway/viz/export_mjcf.hpp"

namespace leeway::cli {
namespace {

using nlohmann::json;

// "  (safety shrank it: lower +0.0312, upper -0.0000)": what the safety stage took off joint i's guide
// interval, and what its growth added beyond it.
std::string shrink_note(const WaypointBounds& w, int i) {
  const auto [below, above] = w.shrunk_by(i);
  std::ostringstream o;
  o << std::fixed << std::setprecision(4);
  if (below > 0 || above > 0)
    o << "  (safety shrank it: lower +" << std::max(0.0, below) << ", upper -" << std::max(0.0, above) << ")";
  if (below < 0 || above < 0)
    o << "  (grown beyond the guide: lower -" << std::max(0.0, -below) << ", upper +" << std::max(0.0, -above)
      << ")";
  return o.str();
}

// Two lines on the room: each joint's kept share of its one-joint free range and their mean; the
// tool's room at the start and the goal, and the largest along the path.
void print_room(const Scene& scene, const RoomReport& room, const RoomOptions& options) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1)
    << "room: share of each joint's one-joint free range kept [%], mean over "
    << (room.waypoints.size() < static_cast<size_t>(room.waypoints.back().waypoint + 1)
            ? std::to_string(room.waypoints.size()) + " evenly spaced waypoints:"
            : std::string("the waypoints:"));
  for (int i = 0; i < scene.dof(); ++i) {
    o << (i ? ", " : " ") << scene.joints()[static_cast<size_t>(i)].name << " ";
    if (std::isnan(room.joint_share[i]))
      o << "-";
    else
      o << 100 * room.joint_share[i];
  }
  o << "; mean " << 100 * room.mean_share << "\n";
  size_t widest = 0;
  for (size_t k = 0; k < room.waypoints.size(); ++k)
    if (room.waypoints[k].tool_translation > room.waypoints[widest].tool_translation) widest = k;
  o << std::setprecision(3) << "tool's room (largest over the corners and " << options.tool_samples
    << " samples of each box, a lower bound):";
  auto at = [&](const std::string& what, size_t k) {
    o << " " << what << " " << room.waypoints[k].tool_translation << " m, " << room.waypoints[k].tool_rotation
      << " rad";
  };
  at("start", 0);
  o << ";";
  at("goal", room.waypoints.size() - 1);
  o << ";";
  at("most (waypoint " + std::to_string(room.waypoints[widest].waypoint) + ")", widest);
  std::cout << o.str() << "\n";
}

// Per segment that could not be certified: the pair that stopped the proof, where, and how far apart
// the two geoms are on the nominal path there, with a hint for a robot pair.
void print_blocked(const Scene& scene, const SafetyReport& r) {
  for (size_t k = 0; k < r.segments.size(); ++k) {
    const SegmentSafety& s = r.segments[k];
    if (s.passed || s.blocking_link < 0) continue;
    std::cout << "safety: segment " << k << " (waypoints " << k << "-" << k + 1
              << ") not certified: " << (s.blocking_self ? "robot geoms " : "link ")
              << scene.geom_label(s.blocking_link) << (s.blocking_self ? " and " : " and obstacle ")
              << scene.geom_label(s.blocking_other) << " at t = " << format_number(s.blocking_t)
              << " of the segment, " << format_number(s.blocking_distance)
              << " m apart on the nominal path there";
    if (s.blocking_self)
      std::cout << " (a robot pair: if the two geoms only touch where the real links do not, exclude "
                   "the pair in the cell, docs/mjcf-conventions.md \"Self-collision\")";
    std::cout << "\n";
  }
}

// One line on the safety stage: mode, outcome, work.
void print_safety(const SafetyReport& r, const SafetyParams& params) {
  int passed = 0;
  int exhausted = 0;
  for (const auto& s : r.segments) {
    passed += s.passed ? 1 : 0;
    exhausted += s.budget_exhausted ? 1 : 0;
  }
  const auto n = r.segments.size();
  switch (r.mode) {
    case SafetyMode::kNone:
      std::cout << "safety: none (the thesis's bounds, not checked against the obstacles)\n";
      break;
    case SafetyMode::kCertified:
      std::cout << "safety: certified, " << passed << " of " << n
                << " segments proven free of the cell and of itself (margin " << format_number(params.margin)
                << " m; " << r.stats.leaves << " leaves, depth " << r.stats.max_depth << ")"
                << (r.all_passed ? ""
                    : exhausted > 0
                        ? "; NOT CERTIFIED where the nominal path is too close or the leaf budget ran out"
                        : "; NOT CERTIFIED where the nominal path is too close")
                << "\n";
      if (exhausted > 0)
        std::cout
            << "safety: the leaf budget (" << segment_leaf_budget(params) << " per segment, "
            << kSegmentLeafBudgetFactor << " x safety.max_leaves) ran out on " << exhausted << " of " << n
            << " segments (NOT CERTIFIED where it ran out before the proof, narrower bounds where it ran "
               "out while regrowing)\n";
      if (r.grow.ran)
        std::cout << "safety: grew " << r.grow.grown << " intervals beyond the guide, every growth proven ("
                  << r.grow.stats.leaves << " of the leaves)\n";
      break;
    case SafetyMode::kSampled:
      std::cout << "safety: sampled, " << passed << " of " << n << " segments passed "
                << r.samples_per_segment << " collision-free samples (epsilon "
                << format_number(params.epsilon) << ", delta " << format_number(params.delta) << ")\n";
      break;
  }
}

}  // namespace

CLI::App* add_bounds(CLI::App& app, BoundsArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "bounds",
      "Joint bounds along a path (thesis chapter 3): the joint-linear path between two keyframes, a\n"
      "planned path when --from/--to name a gripper goal (site:NAME, xyz:X,Y,Z), or every waypoint of\n"
      "a path file (--path). The path is checked densely first; a colliding straight path between two\n"
      "keyframes is planned around (RRT-Connect). Exit 0 on success, 1 a colliding path, an unreachable\n"
      "goal or no path, 2 bad input.");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  add_checker_option(sub, args.checker);
  auto* path_opt =
      sub->add_option("--path", args.path, "Path file written by leeway plan --out (instead of --from/--to)")
          ->check(file_name_check());
  sub->add_option("--from", args.from, "Start: a keyframe, site:NAME or xyz:X,Y,Z")->excludes(path_opt);
  sub->add_option("--to", args.to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z")->excludes(path_opt);
  sub->add_option("--waypoints", args.waypoints,
                  "Waypoints along the joint-linear path between two keyframes (>= 2; the thesis: 2)")
      ->capture_default_str();
  sub->add_option("--seed", args.plan.seed, "Planner seed (gripper goals)")
      ->check(seed_check_for(args.plan.seed))
      ->capture_default_str();
  sub->add_option("--time-limit", args.plan.time_limit, "Planner time budget [s] (gripper goals)")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--ik-seed", args.ik_seed, "Keyframe seeding the inverse kinematics of gripper goals");
  sub->add_option("--max-cells", args.max_cells,
                  "MAX_cells of the height-map (default: from --params, 20000)");
  sub->add_option("--params", args.params, "Parameter file (JSON; see leeway params)")
      ->check(file_name_check());
  add_preset_options(sub, args.preset, args.safety);
  add_joint_bounds_options(sub, args.joints);
  sub->add_option("--out", args.out, "Write the bounds file here (JSON)")->check(file_name_check());
  sub->add_option("--export-mjcf", args.export_mjcf,
                  "Write the cell with its volume as MJCF (named visual-only box geoms) for mujoco-simulate")
      ->check(file_name_check());
  sub->add_option("--export-mjb", args.export_mjb, "Write the same model compiled, as MuJoCo's binary MJB")
      ->check(file_name_check());
  sub->add_option("--threads", args.threads, "Worker threads")->capture_default_str();
  sub->add_flag("--json", args.json, "Print the bounds file to standard output");
  sub->add_flag("--no-plan", args.no_plan,
                "Exit 1 when the straight path between two keyframes collides instead of planning around it");
  sub->add_option("--room", args.room,
                  "Measure the room the bounds keep (on, off; default: on, off with --preset thesis, "
                  "whose output stays the published method's)")
      ->check(CLI::IsMember({"on", "off"}));
  sub->final_callback([sub, &args] {
    args.max_cells_given = sub->count("--max-cells") > 0;
    args.waypoints_given = sub->count("--waypoints") > 0;
  });
  return sub;
}

int run_bounds(const BoundsArgs& args) {
  const bool cell_is_mjb = std::filesystem::path(args.cell).extension() == ".mjb";
  if (cell_is_mjb && (!args.export_mjcf.empty() || !args.export_mjb.empty()))
    throw InputError(std::string(args.export_mjcf.empty() ? "--export-mjb" : "--export-mjcf") +
                     " needs the cell's MJCF text; " + args.cell +
                     " is a compiled MuJoCo model (.mjb): give the cell's .xml file");
  const auto scene = Scene::load(args.cell, scene_options(kDefaultTool, args.checker));
  Params p = load_params(scene, args.preset, args.params, args.safety);
  if (args.max_cells_given) p.height_map.max_cells = args.max_cells;
  p.validate();
  apply_joint_bounds_options(scene, args.joints, p);
  require_threads(args.threads);
  // No output may replace a file the run reads: the cell, its includes and meshes, the parameter
  // and path files.
  std::vector<std::string> inputs = model_input_files(args.cell);
  inputs.insert(inputs.end(), {args.params, args.path});
  require_outputs({{args.out, "--out", {}},
                   {args.export_mjcf, "--export-mjcf", {".xml"}},
                   {args.export_mjb, "--export-mjb", {".mjb"}}},
                  inputs);
  const bool linear = args.path.empty() && !is_gripper_goal(args.from) && !is_gripper_goal(args.to);
  if (!linear && args.waypoints_given)
    throw InputError("--waypoints applies to the joint-linear path between two keyframes only, not to " +
                     std::string(args.path.empty() ? "a planned path" : "--path"));
  if (args.path.empty() && (args.from.empty() || args.to.empty()))
    throw InputError(args.cell +
                     ": give the path with --from and --to (keyframes, site:NAME or xyz:X,Y,Z)"
                     " or with --path FILE");
  if (linear) {
    // The library names the data; the command line names its flag.
    if (args.waypoints < 2)
      throw InputError("--waypoints " + std::to_string(args.waypoints) + " must be >= 2");
    require_memory(args.waypoints * kBytesPerWaypoint, "--waypoints " + std::to_string(args.waypoints));
  }
  PathRequest request;
  request.file = args.path;
  request.from = args.from;
  request.to = args.to;
  request.waypoints = args.waypoints;
  request.ik_seed = args.ik_seed;
  request.plan = args.plan;
  request.plan_around = !args.no_plan;
  const NominalPath nominal_path = resolve_nominal_path(scene, request);
  if (!report_refusal(nominal_path)) return kExitFindings;
  // Standard output stays one JSON object with --json.
  if (!nominal_path.replaced.empty()) (args.json ? std::cerr : std::cout) << nominal_path.replaced << "\n";
  const std::vector<Eigen::VectorXd>& path = nominal_path.waypoints;
  const std::string& label = nominal_path.label;
  json nominal = nominal_path.record;
  VolumeModel world(scene, VolumeModel::capacity_for(scene, p.height_map.max_cells));
  const auto run = compute_bounds(scene, world, path, p, args.threads);
  json out = bounds_json(scene, run, p);
  out["nominal_path"] = nominal;
  const RoomOptions room_options;
  std::optional<RoomReport> room;
  if (args.room == "on" || (args.room.empty() && args.preset != "thesis")) {
    room = measure_room(scene, run.bounds, room_options, args.threads);
    out["room"] = room_json(scene, *room, room_options);
    out["timing_ms"]["room"] = room->ms;
  }
  // The exports first: the MJB compiles the model and may fail; then nothing else is written.
  std::string mjcf, mjb;
  if (!args.export_mjcf.empty()) mjcf = volume_mjcf(scene.source(), run.volume.boxes, args.export_mjcf);
  if (!args.export_mjb.empty()) mjb = volume_mjb(scene.source(), run.volume.boxes, args.export_mjb);
  if (!args.out.empty()) write_file_atomic(args.out, out.dump(2) + "\n");
  if (!args.export_mjcf.empty()) write_file_atomic(args.export_mjcf, mjcf);
  if (!args.export_mjb.empty()) write_file_atomic(args.export_mjb, mjb);
  if (args.json) {
    std::cout << out.dump(2) << "\n";
    return kExitOk;
  }
  std::cout << scene.source() << " " << label << " (units: rad, m, ms)\n";
  std::cout << "MAX_cells " << p.height_map.max_cells << ", boxes " << run.volume.boxes.size()
            << ", goal obstacle " << out["goal_obstacle"].dump() << ", collision checks " << run.checks
            << "\n";
  std::cout << std::fixed << std::setprecision(4);
  for (size_t w = 0; w < run.bounds.size(); ++w) {
    std::cout << "waypoint " << w << ":\n";
    for (int i = 0; i < scene.dof(); ++i)
      std::cout << "  " << std::setw(8) << scene.joints()[static_cast<size_t>(i)].name << "  ["
                << run.bounds[w].lower[i] << ", " << run.bounds[w].upper[i] << "]  nominal "
                << run.bounds[w].q[i]
                << (run.bounds[w].collapsed[static_cast<size_t>(i)] ? "  (collapsed, widened)" : "")
                << shrink_note(run.bounds[w], i) << "\n";
  }
  print_safety(run.safety, p.safety);
  print_blocked(scene, run.safety);
  if (room) print_room(scene, *room, room_options);
  std::cout << std::setprecision(1) << "time [ms]: categorize " << run.ms_categorize << ", volume "
            << run.ms_volume << ", inject " << run.ms_inject << ", bounds " << run.ms_bounds << ", safety "
            << run.ms_safety << ", total " << run.ms_total() << "\n";
  if (!args.out.empty()) std::cout << "wrote " << args.out << "\n";
  for (const auto& file : {args.export_mjcf, args.export_mjb})
    if (!file.empty())
      std::cout << "wrote " << file << " (the cell with " << run.volume.boxes.size()
                << " volume boxes in body '" << kExportBodyName << "')\n";
  return kExitOk;
}

}  // namespace leeway::cli
