#pragma once
// `leeway view`: the browser viewer, one self-contained HTML file.

#include <CLI/CLI.hpp>

#include "cli/render.hpp"

namespace leeway::cli {

//! The command line of `leeway view`: what to show as `leeway render` takes it, and the page's limit.
struct ViewArgs {
  RenderArgs shown;          //!< cell, --bounds or --from/--to (and their options), --key, --out, --volume
  long max_boxes = 200'000;  //!< most volume boxes and cell geoms drawn; more is refused
};

//! Adds the `view` subcommand, parsing into `args`; returns it.
CLI::App* add_view(CLI::App& app, ViewArgs& args);

//! Runs `leeway view`: writes the HTML file and returns kExitOk; kExitFindings when the straight path
//! between the keyframes collides and cannot be planned around (nothing written).
//! @throws InputError on a bad cell, bounds file, output path, or more boxes than --max-boxes.
int run_view(const ViewArgs& args);

}  // namespace leeway::cli
