#include "cli/plot.hpp"

#include <filesystem>
#include <iostream>

#include "leeway/pipeline.hpp"
#include "leeway/render.hpp"

namespace leeway::cli {

CLI::App* add_plot(CLI::App& app, PlotArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "plot",
      "Each joint's lower bound, nominal value and upper bound along the path of a bounds file (the\n"
      "thesis's figs. 4.4-4.16), intervals shrunk by the safety stage and collapsed ones marked; SVG or PNG\n"
      "by the output's extension. Exit 0 on success, 2 bad input (nothing written).");
  sub->add_option("bounds", args.bounds, "Bounds file written by leeway bounds --out")->required();
  sub->add_option("--out", args.out, "Plot file to write: .svg or .png")->required();
  sub->add_option("--size", args.size,
                  "Image size WIDTHxHEIGHT [pixels] (default: 1000 wide, 240 per row of panels)");
  return sub;
}

int run_plot(const PlotArgs& args) {
  require_output(args.out, "--out", {".svg", ".png"});
  int width = 1000, height = 0;
  if (!args.size.empty()) std::tie(width, height) = parse_size(args.size, "--size");
  const BoundsSeries series = read_bounds_series(args.bounds);
  if (height == 0) {
    const size_t cols = series.joints.size() > 3 ? 2 : 1;
    height = 60 + 240 * static_cast<int>((series.joints.size() + cols - 1) / cols);
    height = std::min(height, 8192);
  }
  if (std::filesystem::path(args.out).extension() == ".svg")
    write_file_atomic(args.out, bounds_svg(series, width, height));
  else
    write_png(args.out, bounds_image(series, width, height));
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
  constexpr int kWidth = 1200, kHeight = 420;
  if (std::filesystem::path(path).extension() == ".svg")
    write_file_atomic(path, sweep_svg(series, title, kWidth, kHeight));
  else
    write_png(path, sweep_image(series, title, kWidth, kHeight));
}

}  // namespace leeway::cli
