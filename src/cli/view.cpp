#include "cli/view.hpp"

#include <iostream>

#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/viz/viewer.hpp"

namespace leeway::cli {

CLI::App* add_view(CLI::App& app, ViewArgs& args) {
  RenderArgs& a = args.shown;
  CLI::App* sub = app.add_subcommand(
      "view",
      "One self-contained HTML file (three.js inlined; opens without a network) showing the cell, the "
      "robot,\n"
      "the volume and, with bounds (--bounds, or --from/--to computed as leeway bounds does), a time slider\n"
      "along the nominal path, ghosts at the bounds and one slider per joint limited to the bounds at that\n"
      "time. Exit 0 on success, 1 a colliding path that cannot be planned around, an unreachable goal or\n"
      "no path, 2 bad input (nothing written).");
  sub->add_option("cell", a.cell, "MJCF file of the workcell")->required();
  auto* bounds = sub->add_option("--bounds", a.bounds, "Bounds file written by leeway bounds --out")
                     ->check(file_name_check());
  add_shown_path_options(sub, a, bounds);
  sub->add_option("--out", a.out, "HTML file to write")->check(file_name_check())->required();
  sub->add_option("--volume", a.volume,
                  "The volume when the page opens: fade (boxes around the robot nearly clear), on or off\n"
                  "(the page can switch)")
      ->capture_default_str();
  sub->add_option("--max-boxes", args.max_boxes,
                  "Most volume boxes and cell geoms drawn; more is refused (exit 2), not thinned")
      ->capture_default_str();
  add_shown_computation_options(sub, a, bounds);
  return sub;
}

int run_view(const ViewArgs& args) {
  const RenderArgs& a = args.shown;
  // Every flag is checked before any work, so that bad input writes nothing.
  std::vector<std::string> inputs = model_input_files(a.cell);
  inputs.insert(inputs.end(), {a.bounds, a.params});
  require_outputs({{a.out, "--out", {".html"}}}, inputs);
  if (a.volume != "fade" && a.volume != "on" && a.volume != "off")
    throw InputError("--volume '" + a.volume + "' must be fade, on or off");
  if (args.max_boxes < 0) throw InputError("--max-boxes " + std::to_string(args.max_boxes) + " must be >= 0");
  check_shown_path(a);
  require_threads(a.threads);
  ViewerOptions options;
  options.max_boxes = args.max_boxes;
  options.three_dir = default_three_dir();
  // three.js is looked for before the bounds are computed: a missing package is found at once.
  require_three_js(options.three_dir);

  const auto scene = Scene::load(a.cell, scene_options(kDefaultTool));
  Params p = shown_params(scene, a);
  std::optional<RenderInput> in = render_input(a, scene, p, /*show_volume=*/false);
  if (!in) return kExitFindings;

  ViewerContent content;
  content.title = a.cell + (in->what.empty() ? "" : ": " + in->what);
  content.path = in->trajectory;
  if (!content.path) content.q = shown_keyframe(scene, a);
  content.volume = std::move(in->volume.boxes);
  content.safety_mode = in->bounds.empty() ? "" : in->safety_mode;
  content.proven = in->proven;
  content.margin = in->margin;
  content.initial_volume = a.volume;
  const std::string page = viewer_html(scene, content, options);
  write_file_atomic(a.out, page);
  std::cout << "wrote " << a.out << " (" << format_number(static_cast<double>(page.size()) / 1e6) << " MB; "
            << (content.path ? std::to_string(content.path->waypoint_count()) + " waypoints over " +
                                   format_number(content.path->duration()) + " s of nominal time"
                             : std::string("no bounds"))
            << ", " << content.volume.size() << " volume boxes, " << scene.dof() << " joint sliders)\n";
  return kExitOk;
}

}  // namespace leeway::cli
