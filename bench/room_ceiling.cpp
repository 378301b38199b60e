// The room measure's ceiling on one path (docs/results.md, "Room: the ceiling"): how much room
// box bounds could keep under the bounds file's contract, found by sampling instead of proof
// (room_ceiling.hpp says how, and why the estimate errs both ways).
//
// For a bounds file and its cell: the file's own mean share; then two contracts, each grown twice,
// from the file's bounds and from the nominal configurations, keeping the larger mean share:
//   waypoint: each waypoint's box alone: its corners and --samples random configurations;
//   segment:  lower and upper linear between waypoints (the file's contract): on every segment next
//             to the grown waypoint, the corners of the interpolated box at --slices + 1 evenly
//             spaced parameters and --samples random (parameter, configuration) pairs.
// The kept segment-contract bounds are then checked with --check random configurations along the
// path (another stream), and the collisions found are printed beside the shares. With --certify,
// they are scaled toward the nominal values by each of the given factors and every segment is
// given to the certificate (default options, --certify-leaves leaves per segment): how much of the
// sampled room a proof keeps, and at what cost.
//
// Usage: leeway-bench-room-ceiling --cell CELL.xml --bounds BOUNDS.json [--samples 400]
//          [--slices 8] [--check 20000] [--seed 1] [--certify 1,0.75,0.5]
//          [--certify-leaves 65536] [--json OUT]
// Prints a Markdown table; --json writes the numbers. Shares are in [0, 1] of the one-joint free
// range. Exit 2 on bad input.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/io/bounds_file.hpp"
#include "room_ceiling.hpp"

namespace {

using Eigen::VectorXd;

struct Options {
  std::string cell, bounds, json;
  leeway::CeilingOptions ceiling;
  int check = 20000;
  std::vector<double> certify;  // scales of the segment ceiling given to the certificate
  long certify_leaves = 65536;
};

std::vector<double> scales(const std::string& text) {
  std::vector<double> out;
  size_t from = 0;
  while (from <= text.size()) {
    const size_t comma = std::min(text.find(',', from), text.size());
    size_t used = 0;
    const std::string item = text.substr(from, comma - from);
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || !(v >= 0 && v <= 1))
      throw leeway::InputError("--certify: '" + item + "' is not a scale in [0, 1]");
    out.push_back(v);
    from = comma + 1;
  }
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) throw leeway::InputError(arg + " needs a value");
      return argv[++a];
    };
    if (arg == "--cell")
      o.cell = value();
    else if (arg == "--bounds")
      o.bounds = value();
    else if (arg == "--json")
      o.json = value();
    else if (arg == "--samples")
      o.ceiling.samples = std::stoi(value());
    else if (arg == "--slices")
      o.ceiling.slices = std::stoi(value());
    else if (arg == "--check")
      o.check = std::stoi(value());
    else if (arg == "--seed")
      o.ceiling.seed = std::stoull(value());
    else if (arg == "--certify")
      o.certify = scales(value());
    else if (arg == "--certify-leaves")
      o.certify_leaves = std::stol(value());
    else
      throw leeway::InputError("unknown option " + arg);
  }
  if (o.cell.empty() || o.bounds.empty()) throw leeway::InputError("--cell and --bounds are needed");
  if (o.ceiling.samples < 0 || o.ceiling.slices < 1 || o.check < 0 || o.certify_leaves < 1)
    throw leeway::InputError(
        "--samples and --check must not be negative, --slices and --certify-leaves must be positive");
  return o;
}

nlohmann::json shares_json(const leeway::Scene& scene, const VectorXd& share) {
  nlohmann::json j = nlohmann::json::object();
  for (int i = 0; i < scene.dof(); ++i)
    j[scene.joints()[static_cast<size_t>(i)].name] =
        std::isnan(share[i]) ? nlohmann::json() : nlohmann::json(share[i]);
  return j;
}

// The segment ceiling's extents, scaled, given to the certificate: a line each, and out["certify"].
void certify(const leeway::Scene& scene, const leeway::RoomCeiling& ceiling,
             const leeway::CeilingExtents& best, const Options& o, nlohmann::json& out) {
  if (o.certify.empty()) return;
  const leeway::Certifier certifier(scene, leeway::CertifyOptions{});
  leeway::CertifyContext ctx(scene);
  out["certify"] = nlohmann::json::array();
  for (double scale : o.certify) {
    const leeway::CeilingProof p = ceiling.certify(best, scale, o.certify_leaves, certifier, ctx);
    out["certify"].push_back({{"scale", p.scale},
                              {"mean_share", p.share},
                              {"segments", p.segments},
                              {"certified", p.certified},
                              {"leaves", p.leaves},
                              {"max_leaves", o.certify_leaves}});
    std::cout << "| segment x " << scale << ", certified " << p.certified << " of " << p.segments
              << " segments | | " << p.share << " | " << p.leaves << " leaves | |\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    leeway::SceneOptions so;
    so.tool_site = "tool0";
    const auto scene = leeway::Scene::load(o.cell, so);
    const auto path = leeway::read_bounds(o.bounds, scene);
    const auto t0 = std::chrono::steady_clock::now();
    leeway::RoomCeiling ceiling(scene, path, o.ceiling);
    nlohmann::json out = {{"cell", o.cell},
                          {"bounds", o.bounds},
                          {"waypoints", ceiling.waypoints()},
                          {"samples", o.ceiling.samples},
                          {"slices", o.ceiling.slices},
                          {"seed", o.ceiling.seed}};
    VectorXd share;
    const leeway::CeilingExtents file = ceiling.from_file();
    out["file"] = {{"mean_share", ceiling.mean_share(file, &share)},
                   {"joint_share", shares_json(scene, share)}};
    std::cout << "| contract | start | mean share | per joint | check hits |\n|---|---|---:|---|---:|\n";
    std::cout << "| file | | " << ceiling.mean_share(file) << " | | |\n";
    for (bool segment : {false, true}) {
      const char* name = segment ? "segment" : "waypoint";
      leeway::CeilingExtents best;
      double best_share = -1;
      std::string best_start;
      for (const char* start : {"file", "zero"}) {
        const leeway::CeilingExtents grown =
            ceiling.grow(std::string(start) == "file" ? file : ceiling.zero(), segment);
        const double s = ceiling.mean_share(grown, &share);
        out[name]["from_" + std::string(start)] = {{"mean_share", s},
                                                   {"joint_share", shares_json(scene, share)}};
        if (s > best_share) {
          best_share = s;
          best = grown;
          best_start = start;
        }
      }
      ceiling.mean_share(best, &share);
      out[name]["mean_share"] = best_share;
      out[name]["start"] = best_start;
      out[name]["joint_share"] = shares_json(scene, share);
      long hits = -1;
      if (segment) {
        hits = ceiling.check(best, o.check);
        out[name]["check"] = {{"samples", o.check}, {"collisions", hits}};
        certify(scene, ceiling, best, o, out);
      }
      std::cout << "| " << name << " | " << best_start << " | " << best_share << " | "
                << out[name]["joint_share"].dump() << " | "
                << (hits < 0 ? std::string() : std::to_string(hits)) << " |\n";
    }
    out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!o.json.empty()) {
      std::ofstream f(o.json + ".tmp");
      f << out.dump(1) << "\n";
      f.close();
      if (!f || std::rename((o.json + ".tmp").c_str(), o.json.c_str()) != 0)
        throw leeway::InputError(o.json + ": cannot write");
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "leeway-bench-room-ceiling: " << e.what() << "\n";
    return 2;
  }
}
