#include "cli/params.hpp"

#include <iostream>

#include "leeway/core/cell_defaults.hpp"

namespace leeway::cli {

CLI::App* add_params(CLI::App& app, ParamsArgs& args) {
  CLI::App* sub =
      app.add_subcommand("params", "Print the default parameters as JSON (SI units), or a cell's");
  sub->add_option("cell", args.cell, "Also apply this cell's own defaults (MJCF custom numerics)");
  sub->add_option("--preset", args.preset, "Parameter set to print: leeway or thesis")->capture_default_str();
  return sub;
}

int run_params(const ParamsArgs& args) {
  Params p = preset_params(args.preset);
  if (!args.cell.empty()) apply_cell_defaults(Scene::load(args.cell, scene_options(kDefaultTool)), p);
  std::cout << to_json(p).dump(2) << "\n";
  return kExitOk;
}

}  // namespace leeway::cli
