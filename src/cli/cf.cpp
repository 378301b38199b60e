#include "cli/cf.hpp"

#include <iomanip>
#include <iostream>

#include "leeway/io/bounds_file.hpp"

namespace leeway::cli {

CLI::App* add_cf(CLI::App& app, CfArgs& args) {
  CLI::App* sub =
      app.add_subcommand("cf", "Confidence Factor of a bounds file against the real obstacles (section 4.1)");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  add_checker_option(sub, args.checker);
  sub->add_option("bounds", args.bounds, "Bounds file written by leeway bounds --out")->required();
  sub->add_option("--windows", args.params.windows, "Windows along the path")->capture_default_str();
  sub->add_option("--samples", args.params.samples, "Random configurations per window")
      ->capture_default_str();
  sub->add_option("--seed", args.params.seed, "Random seed")
      ->check(seed_check_for(args.params.seed))
      ->capture_default_str();
  sub->add_option("--threads", args.threads, "Worker threads")->capture_default_str();
  sub->add_flag("--self", args.params.self,
                "Count self-collisions (robot geoms touching each other) as collisions too; both counts "
                "are printed either way");
  sub->add_flag("--json", args.json, "Print JSON");
  return sub;
}

int run_cf(const CfArgs& args) {
  const auto scene = Scene::load(args.cell, scene_options(kDefaultTool, args.checker));
  require_threads(args.threads);
  if (args.params.windows >= 1)
    require_memory(args.params.windows * kBytesPerWindow, "--windows " + std::to_string(args.params.windows));
  // The file's own times (format 2), or the cell's timing (format 1).
  const auto r =
      confidence_factor(scene, read_bounds_trajectory(args.bounds, scene), args.params, args.threads);
  if (args.json) {
    nlohmann::json out = {
        {"cf", r.cf},
        {"ci95", {r.ci_low, r.ci_high}},
        {"worst_window", {{"index", r.worst_window}, {"cf", r.worst_window_cf}}},
        {"window_cf", r.window_cf},
        {"samples", r.samples},
        {"collisions", r.collisions},
        {"counts", args.params.self ? "obstacle and self collisions" : "obstacle collisions"},
        {"obstacle_collisions", r.obstacle_collisions},
        {"self_collisions", r.self_collisions},
        {"any_collisions", r.any_collisions},
        {"windows", args.params.windows},
        {"windows_by", r.timed ? "time" : "path parameter"},
        {"duration", r.duration},
        {"seed", args.params.seed},
        {"units",
         "cf and ci95 are fractions (1 = 100 %); duration in seconds when windows_by "
         "is time, else in segments"}};
    std::cout << out.dump(2) << "\n";
  } else {
    std::cout << std::fixed << std::setprecision(4) << "CF " << 100 * r.cf << " % (95 % CI " << 100 * r.ci_low
              << " .. " << 100 * r.ci_high << " %), " << r.collisions << " of " << r.samples
              << " samples collide; worst window " << r.worst_window << " of " << args.params.windows << ": "
              << 100 * r.worst_window_cf << " %\n";
    std::cout << "collisions: " << r.obstacle_collisions << " with obstacles, " << r.self_collisions
              << " self-collisions, " << r.any_collisions << " samples with either"
              << (args.params.self ? " (CF counts both: --self)\n"
                                   : " (CF counts obstacles only; --self counts both)\n");
    if (r.timed)
      std::cout << std::setprecision(3) << "windows: " << args.params.windows << " of equal duration, "
                << r.duration / args.params.windows
                << " s each (the path timed by the joints' nominal speeds: " << r.duration << " s)\n";
    else
      std::cout << "windows: " << args.params.windows
                << " of equal path parameter (a joint has no nominal speed, so the path is not timed)\n";
  }
  return kExitOk;
}

}  // namespace leeway::cli
