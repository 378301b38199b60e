// The `leeway` command-line program: subcommands over the library, one per file in src/cli/ (each
// an XxxArgs struct, add_xxx() declaring its options and run_xxx() doing the work). This file only
// wires them into CLI11 and dispatches. Exit codes: error.hpp.
#include <CLI/CLI.hpp>

#include <functional>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cli/batch.hpp"
#include "cli/bounds.hpp"
#include "cli/cf.hpp"
#include "cli/check.hpp"
#include "cli/common.hpp"
#include "cli/fk.hpp"
#include "cli/ik.hpp"
#include "cli/import_mesh.hpp"
#include "cli/import_urdf.hpp"
#include "cli/new_cell.hpp"
#include "cli/params.hpp"
#include "cli/plan.hpp"
#include "cli/plot.hpp"
#include "cli/render.hpp"
#include "cli/sample.hpp"
#include "cli/simulate.hpp"
#include "cli/sweep.hpp"
#include "cli/view.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mujoco_util.hpp"

int main(int argc, char** argv) {
  using namespace leeway::cli;
  ignore_sigpipe();                         // a closed standard output is exit 2, not SIGPIPE
  leeway::install_mujoco_error_handlers();  // MuJoCo errors become exceptions, not exit()
  leeway::install_temp_file_cleanup();      // no .NAME.tmpPID left behind by SIGTERM, SIGINT, SIGHUP
  CLI::App app{
      "leeway: collision-free joint intervals around a nominal robot path (SI units: metres, radians)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("leeway ") + LEEWAY_VERSION);

  CheckArgs check;
  FkArgs fk;
  IkArgs ik;
  PlanArgs plan;
  BoundsArgs bounds;
  CfArgs cf;
  SampleArgs sample;
  SweepArgs sweep;
  ParamsArgs params;
  ImportUrdfArgs import_urdf;
  ImportMeshArgs import_mesh;
  NewCellArgs new_cell;
  RenderArgs render;
  ViewArgs view;
  PlotArgs plot;
  BatchArgs batch;
  SimulateArgs simulate;
  // In the order of `leeway --help`.
  const std::vector<std::pair<CLI::App*, std::function<int()>>> commands = {
      {add_check(app, check), [&] { return run_check(check); }},
      {add_fk(app, fk), [&] { return run_fk(fk); }},
      {add_ik(app, ik), [&] { return run_ik(ik); }},
      {add_plan(app, plan), [&] { return run_plan(plan); }},
      {add_bounds(app, bounds), [&] { return run_bounds(bounds); }},
      {add_cf(app, cf), [&] { return run_cf(cf); }},
      {add_sample(app, sample), [&] { return run_sample(sample); }},
      {add_simulate(app, simulate), [&] { return run_simulate(simulate); }},
      {add_sweep(app, sweep), [&] { return run_sweep(sweep); }},
      {add_params(app, params), [&] { return run_params(params); }},
      {add_import_urdf(app, import_urdf), [&] { return run_import_urdf(import_urdf); }},
      {add_import_mesh(app, import_mesh), [&] { return run_import_mesh(import_mesh); }},
      {add_new_cell(app, new_cell), [&] { return run_new_cell(new_cell); }},
      {add_render(app, render), [&] { return run_render(render); }},
      {add_view(app, view), [&] { return run_view(view); }},
      {add_plot(app, plot), [&] { return run_plot(plot); }},
      {add_batch(app, batch), [&] { return run_batch(batch); }},
  };

  return run_reporting_errors("leeway", [&]() -> int {
    // CLI11 would only say "A subcommand is required" for a mistyped one: name it.
    const std::string first = argc > 1 ? argv[1] : "";
    bool known = false;
    std::string names;
    for (const auto& [sub, run] : commands) {
      known = known || first == sub->get_name();
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!first.empty() && first[0] != '-' && !known) {
      std::cerr << "leeway: error: unknown subcommand '" << first << "'; subcommands: " << names
                << " (see leeway --help)\n";
      return leeway::kExitBadInput;
    }
    if (const auto code = parse_cli(app, argc, argv, "leeway")) return *code;
    for (const auto& [sub, run] : commands)
      if (*sub) return run();
    return leeway::kExitOk;
  });
}
