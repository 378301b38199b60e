#include "cli/batch.hpp"

#include <sched.h>

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "apps/dist.hpp"
#include "leeway/apps/batch.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"

namespace leeway::cli {
namespace {

using nlohmann::json;

std::string fixed(double v, int decimals) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(decimals) << v;
  return o.str();
}

// "CF 99.9987 %, certified, mean width 0.851 rad, method 0.47 s", or the error.
std::string outcome(const json& r) {
  if (r["status"] != "ok") return "ERROR: " + r.value("error", std::string());
  const json& m = r["measured"];
  std::string s = "CF " + fixed(100 * m["cf"].get<double>(), 4) + " %, " +
                  (m["certified"].get<bool>() ? "certified" : "safety " + m["safety"].get<std::string>()) +
                  ", mean width " + fixed(m["mean_width"].get<double>(), 3) + " rad, method " +
                  fixed(r["timing"].value("method_s", 0.0), 2) + " s";
  for (const auto& e : r["expectations"])
    if (!e["passed"].get<bool>())
      s += "; FAILED " + e["title"].get<std::string>() + " (measured " +
           (e["measured"].is_number() ? format_number(e["measured"].get<double>()) : e["measured"].dump()) +
           ")";
  if (r["timing"].contains("time_max") && r["timing"]["time_max"]["warning"].get<bool>())
    s += "; warning: over " + r["timing"]["time_max"]["title"].get<std::string>();
  return s;
}

// The cores divided among this machine's ranks, and no more than this process may run on: mpirun
// binds each of 2 ranks to one core by default, and its threads would share that core.
int default_batch_threads(int local_ranks) {
  int cores = static_cast<int>(std::thread::hardware_concurrency()) / std::max(1, local_ranks);
  cpu_set_t mask;
  if (::sched_getaffinity(0, sizeof mask, &mask) == 0) cores = std::min(cores, CPU_COUNT(&mask));
  return std::max(1, cores);
}

}  // namespace

CLI::App* add_batch(CLI::App& app, BatchArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "batch",
      "Run a suite of scenarios (cells, paths, parameters) and test their expectations (docs/batch.md);\n"
      "under mpirun the scenarios are spread over the ranks. Exit 0 every expectation met, 1 one failed\n"
      "or a scenario could not run, 2 a bad suite (nothing run).");
  sub->add_option("suite", args.suite, "Suite file (JSON, format leeway-suite-1)")->required();
  sub->add_option("--junit", args.junit, "Write a JUnit XML report here");
  sub->add_option("--out", args.out, "Write every result here (JSON)");
  sub->add_option("--threads", args.threads,
                  "Worker threads per scenario (default: the cores divided among this machine's ranks)")
      ->check(CLI::Range(1, kMaxThreads));
  return sub;
}

int run_batch(const BatchArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  int threads = args.threads;
  auto pool = dist::make_pool(
      [&threads](const std::string& task) { return run_scenario(json::parse(task), threads).dump(); });
  if (threads == 0) threads = default_batch_threads(pool->local_size());
  if (pool->rank() != 0) {
    pool->serve();
    return kExitOk;
  }
  if (args.threads < 0)
    throw InputError("--threads " + std::to_string(args.threads) + " must be >= 1 (or 0: the default)");
  // Everything is checked before the first scenario runs.
  const Suite suite = read_suite(args.suite);
  // No report may replace the suite or a file a scenario reads (its cell with the cell's includes
  // and meshes, its path and parameter files), nor the other report.
  std::vector<std::string> inputs = {args.suite};
  for (const auto& s : suite.scenarios) {
    const json& run = s.resolved.at("run");
    const std::vector<std::string> cell = model_input_files(run.at("cell").get<std::string>());
    inputs.insert(inputs.end(), cell.begin(), cell.end());
    for (const char* key : {"path", "params"})
      if (run.contains(key) && run[key].is_string()) inputs.push_back(run[key].get<std::string>());
  }
  require_outputs({{args.junit, "--junit", {".xml"}}, {args.out, "--out", {".json"}}}, inputs);
  const size_t n = suite.scenarios.size();
  std::cout << "suite " << suite.name << ": " << n << " scenario" << (n == 1 ? "" : "s") << " on "
            << pool->size() << " rank" << (pool->size() == 1 ? "" : "s") << " x " << threads << " thread"
            << (threads == 1 ? "" : "s") << " (units: CF %, width rad, time s)\n"
            << std::flush;
  std::vector<std::string> tasks;
  for (const auto& s : suite.scenarios) tasks.push_back(s.resolved.dump());
  // Each result judged as it comes, for the progress line; kept in suite order.
  std::vector<json> results(n);
  size_t finished = 0;
  const auto result_of = [&](size_t i, const dist::Reply& reply) {
    json r;
    if (reply.ok) {
      r = json::parse(reply.text);
    } else {
      r = {{"name", suite.scenarios[i].name},
           {"status", "error"},
           {"error", reply.text},
           {"timing", json::object()}};
    }
    judge(suite.scenarios[i], r);
    return r;
  };
  pool->map(tasks, [&](size_t i, const dist::Reply& reply, int rank) {
    results[i] = result_of(i, reply);
    ++finished;
    std::cout << "[" << finished << "/" << n << "] " << suite.scenarios[i].name << " ("
              << suite.scenarios[i].label << "): " << outcome(results[i]) << "; "
              << fixed(results[i]["timing"].value("seconds", 0.0), 2) << " s"
              << (pool->size() > 1 ? " on rank " + std::to_string(rank) : std::string()) << "\n"
              << std::flush;
    results[i]["timing"]["rank"] = rank;
  });

  // The summary table, in suite order.
  int passed = 0, failed = 0, errors = 0, warnings = 0;
  std::cout << "\n| scenario | status | CF [%] | certified | mean width [rad] | method [s] | expectations |\n"
            << "|---|---|---:|---|---:|---:|---|\n";
  for (size_t i = 0; i < n; ++i) {
    const json& r = results[i];
    const bool ok = r["status"] == "ok";
    const bool pass = ok && r["passed"].get<bool>();
    errors += ok ? 0 : 1;
    passed += pass ? 1 : 0;
    failed += ok && !pass ? 1 : 0;
    int met = 0;
    for (const auto& e : r["expectations"]) met += e["passed"].get<bool>() ? 1 : 0;
    const bool slow = r["timing"].contains("time_max") && r["timing"]["time_max"]["warning"].get<bool>();
    warnings += slow ? 1 : 0;
    std::cout << "| " << suite.scenarios[i].name << " | " << (ok ? (pass ? "passed" : "FAILED") : "ERROR")
              << " | ";
    if (ok) {
      const json& m = r["measured"];
      std::cout << fixed(100 * m["cf"].get<double>(), 4) << " | "
                << (m["certified"].get<bool>() ? "yes" : "no") << " | "
                << fixed(m["mean_width"].get<double>(), 3) << " | "
                << fixed(r["timing"].value("method_s", 0.0), 2) << (slow ? " (slow)" : "") << " | ";
    } else {
      std::cout << "- | - | - | - | ";
    }
    std::cout << met << "/" << r["expectations"].size() << " |\n";
  }
  std::cout << "\n"
            << passed << " passed, " << failed << " failed, " << errors << " error"
            << (errors == 1 ? "" : "s") << ", " << warnings << " time warning" << (warnings == 1 ? "" : "s")
            << "\n";
  if (!args.out.empty()) {
    json all = suite_results_json(suite, results);
    all["timing"]["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    all["timing"]["ranks"] = pool->size();
    all["timing"]["threads"] = threads;
    write_file_atomic(args.out, all.dump(2) + "\n");
    std::cout << "wrote " << args.out << "\n";
  }
  if (!args.junit.empty()) {
    write_file_atomic(args.junit, junit_xml(suite, results));
    std::cout << "wrote " << args.junit << "\n";
  }
  return failed + errors == 0 ? kExitOk : kExitFindings;
}

}  // namespace leeway::cli
