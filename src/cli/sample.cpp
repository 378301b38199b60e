#include "cli/sample.hpp"

#include <cmath>
#include <iostream>
#include <optional>

#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/io/bounds_export.hpp"
#include "leeway/io/bounds_file.hpp"

namespace leeway::cli {

CLI::App* add_sample(CLI::App& app, SampleArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "sample", "A bounds file as stages every --dt seconds (CSV, JSON, .npz) or Drake HPolyhedron regions");
  sub->add_option("bounds", args.bounds, "Bounds file written by leeway bounds --out")->required();
  sub->add_option("--dt", args.dt, "Time step between stages [s]; rows from t = 0 to the path's duration")
      ->check(finite_check());
  sub->add_option("--out", args.out, "Output: .csv, .json, .npz, or .yaml (drake-yaml)")
      ->required()
      ->check(file_name_check());
  sub->add_option("--format", args.format, "auto (by --out's ending), csv, json, npz or drake-yaml")
      ->check(CLI::IsMember({"auto", "csv", "json", "npz", "drake-yaml"}))
      ->capture_default_str();
  sub->add_option("--cell", args.cell,
                  "The bounds file's cell: checks the file against its robot, and times a file without "
                  "times (format 1) by its joint speeds");
  sub->add_flag("--segments", args.segments,
                "drake-yaml: also each segment's region over (q, f), f the fraction of the segment");
  return sub;
}

int run_sample(const SampleArgs& args) {
  StagesFormat format = StagesFormat::kCsv;
  if (args.format == "auto") format = stages_format_of(args.out);
  if (args.format == "csv") format = StagesFormat::kCsv;
  if (args.format == "json") format = StagesFormat::kJson;
  if (args.format == "npz") format = StagesFormat::kNpz;
  if (args.format == "drake-yaml") format = StagesFormat::kDrakeYaml;
  const char* ending = format == StagesFormat::kCsv    ? ".csv"
                       : format == StagesFormat::kJson ? ".json"
                       : format == StagesFormat::kNpz  ? ".npz"
                                                       : ".yaml";
  std::vector<std::string> inputs = {args.bounds};
  if (!args.cell.empty())
    for (const auto& f : model_input_files(args.cell)) inputs.push_back(f);
  std::vector<std::string> endings = {ending};
  if (format == StagesFormat::kDrakeYaml) endings.push_back(".yml");
  require_outputs({{args.out, "--out", endings}}, inputs);
  if (format != StagesFormat::kDrakeYaml && std::isnan(args.dt))
    throw InputError("--dt is required for " + std::string(ending) + " output (the time step [s])");
  if (args.segments && format != StagesFormat::kDrakeYaml)
    throw InputError("--segments is for --format drake-yaml only");

  std::vector<std::string> joints;
  std::optional<BoundsTrajectory> trajectory;
  if (args.cell.empty()) {
    BoundsFile file = read_bounds_file(args.bounds);
    joints = std::move(file.joints);
    trajectory.emplace(std::move(file.trajectory));
  } else {
    const auto scene = Scene::load(args.cell, scene_options(kDefaultTool));
    joints = scene.joint_names();
    trajectory.emplace(read_bounds_trajectory(args.bounds, scene));
  }
  if (format == StagesFormat::kDrakeYaml) {
    write_file_atomic(args.out, drake_yaml(*trajectory, joints, args.segments, args.bounds));
    std::cout << "wrote " << args.out << ": " << trajectory->waypoint_count() << " waypoint regions"
              << (args.segments
                      ? " and " + std::to_string(trajectory->waypoint_count() - 1) + " segment regions"
                      : "")
              << " (rad for hinge joints, m for slide joints)\n";
    return kExitOk;
  }
  const long rows = trajectory->sample_count(args.dt);
  write_stages(*trajectory, joints, args.dt, format, args.out, args.bounds);
  std::cout << "wrote " << args.out << ": " << rows << " stages from t = 0 to " << trajectory->duration()
            << " s every " << args.dt << " s ("
            << (trajectory->timed() ? "timed by the joints' speeds" : "untimed: t is the path parameter")
            << ")\n";
  return kExitOk;
}

}  // namespace leeway::cli
