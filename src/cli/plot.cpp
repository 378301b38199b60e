#include "cli/plot.hpp"

#include <filesystem>
#include <iostream>

#include "leeway/core/file_io.hpp"
#include "leeway/viz/render.hpp"

namespace leeway::cli {

CLI::App* add_plot(CLI::App& app, PlotArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "plot",
      "Each joint's lower bound, nominal value and upper bound along the path of a bounds file (the\n"
      "thesis's figs. 4.4-4.16), intervals shrunk by the safety stage and collapsed ones marked; or boxes,\n"
      "time and CF against MAX_cells from sweep CSV files. SVG or PNG by the output's extension. Exit 0 on\n"
      "success, 2 bad input (nothing written).");
  sub->add_option("inputs", args.inputs,
                  "A bounds file written by leeway bounds --out, or sweep CSV files written by leeway sweep\n"
                  "--csv (one series each: boxes, time and CF against MAX_cells)")
      ->required();
  sub->add_option("--out", args.out, "Plot file to write: .svg or .png")
      ->check(file_name_check())
      ->required();
  sub->add_option("--size", args.size,
                  "Image size WIDTHxHEIGHT [pixels] (default: bounds 1000 wide and 240 per row of panels;\n"
                  "sweeps 1200x420)");
  sub->add_option("--x", args.x,
                  "Bounds plots' x axis: t, the waypoints' time [s] (a file without times falls back to s,\n"
                  "with a note), or s, the path parameter k / (n - 1)")
      ->check(CLI::IsMember({"t", "s"}))
      ->capture_default_str();
  sub->add_option("--thesis", args.thesis,
                  "Sweep plots: add the thesis's published table of CELL/PATH (dallara, baltico or dlr;\n"
                  "home-patch, patch-mould or mould-home)");
  return sub;
}

namespace {

bool is_csv(const std::string& file) { return std::filesystem::path(file).extension() == ".csv"; }

// Sweep CSV files, with the thesis's table when asked for.
int plot_sweeps(const PlotArgs& args, int width, int height) {
  std::vector<SweepSeries> series;
  for (const auto& file : args.inputs) series.push_back(read_sweep_csv(file));
  if (!args.thesis.empty()) {
    const size_t slash = args.thesis.find('/');
    std::string table;
    const auto rows = slash == std::string::npos
                          ? std::vector<SweepPoint>{}
                          : thesis_table(args.thesis.substr(0, slash), args.thesis.substr(slash + 1), &table);
    if (rows.empty())
      throw InputError(
          "--thesis '" + args.thesis +
          "' is not one of the thesis's nine cases (dallara, baltico or dlr / home-patch, patch-mould or "
          "mould-home)");
    series.push_back({"thesis, table " + table + " (i5-8250U)", rows});
  }
  std::string title = "leeway sweep";
  if (!args.thesis.empty()) title += " " + args.thesis;
  title += " (time in ms, CF in %)";
  if (std::filesystem::path(args.out).extension() == ".svg")
    write_file_atomic(args.out, sweep_svg(series, title, width, height));
  else
    write_png(args.out, sweep_image(series, title, width, height));
  std::cout << "wrote " << args.out << " (" << series.size() << " series; time in ms, CF in %)\n";
  return kExitOk;
}

}  // namespace

int run_plot(const PlotArgs& args) {
  require_outputs({{args.out, "--out", {".svg", ".png"}}}, args.inputs);
  int width = 0, height = 0;
  if (!args.size.empty()) std::tie(width, height) = parse_size(args.size, "--size");
  const bool csv = is_csv(args.inputs.front());
  for (const auto& file : args.inputs)
    if (is_csv(file) != csv)
      throw InputError(file + ": give one bounds file (JSON) or sweep CSV files, not both");
  if (csv) return plot_sweeps(args, width ? width : 1200, height ? height : 420);
  if (args.inputs.size() > 1)
    throw InputError(args.inputs[1] + ": one bounds file per plot (sweep plots take several CSV files)");
  if (!args.thesis.empty()) throw InputError("--thesis adds a thesis table to sweep plots (CSV files) only");
  if (width == 0) width = 1000;
  const BoundsSeries series = read_bounds_series(args.inputs.front());
  const PlotX x = args.x == "s" ? PlotX::kPathParameter : PlotX::kTime;
  if (x == PlotX::kTime && !series.has_times())
    std::cerr << "note: " << args.inputs.front()
              << " has no waypoint times 't' (or lasts 0 s): the x axis is the path parameter s\n";
  if (height == 0) {
    const size_t cols = series.joints.size() > 3 ? 2 : 1;
    height = 60 + 240 * static_cast<int>((series.joints.size() + cols - 1) / cols);
    height = std::min(height, 8192);
  }
  if (std::filesystem::path(args.out).extension() == ".svg")
    write_file_atomic(args.out, bounds_svg(series, width, height, x));
  else
    write_png(args.out, bounds_image(series, width, height, x));
  std::cout << "wrote " << args.out << " (" << series.joints.size() << " joints, " << series.q.size()
            << " waypoints; units: rad, m)\n";
  return kExitOk;
}

void write_sweep_plot(const std::string& path, const std::string& cell, const std::string& from,
                      const std::string& to, const std::string& preset, const SweepSeries& leeway) {
  // The thesis's published rows when the case is one of its nine (cell file dallara/baltico/dlr.xml,
  // keyframes home, patch, mould).
  std::string table;
  const auto stem = std::filesystem::path(cell).stem().string();
  std::vector<SweepSeries> series = {leeway};
  const auto thesis = thesis_table(stem, from + "-" + to, &table);
  if (!thesis.empty()) series.push_back({"thesis, table " + table + " (i5-8250U)", thesis});
  const std::string title = "leeway sweep " + std::filesystem::path(cell).filename().string() + " " + from +
                            " -> " + to + " (preset " + preset + ")";
  constexpr int kWidth = 1200, kHeight = 420;  // as leeway plot draws sweep CSV files
  if (std::filesystem::path(path).extension() == ".svg")
    write_file_atomic(path, sweep_svg(series, title, kWidth, kHeight));
  else
    write_png(path, sweep_image(series, title, kWidth, kHeight));
}

}  // namespace leeway::cli
