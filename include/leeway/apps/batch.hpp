#pragma once
//! @file batch.hpp
//! Scenario suites: many (cell, path, parameters) runs of the method with expectations
//! on their outcome, their results as JSON and as a JUnit XML report. docs/batch.md gives the
//! suite format; the `leeway batch` program runs a suite on one process or over MPI ranks.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace leeway {

//! What a scenario must achieve; absent expectations are not tested.
struct Expectations {
  std::optional<bool> check;                    //!< `leeway check` of the cell passes (true) or not (false)
  std::optional<double> cf_min;                 //!< Confidence Factor >= this (fraction, 0..1)
  std::optional<bool> certified;                //!< the safety stage certified every segment (or not)
  std::optional<double> mean_width_min;         //!< mean width of the bisected intervals >= this [rad]
  std::optional<long> self_collisions_max;      //!< CF samples where the robot hits itself <= this
  std::optional<double> time_max;               //!< the method's time <= this [s]; a soft warning only
  std::optional<long> simulate_contacts_max;    //!< closed-loop steps with a contact <= this
  std::optional<double> simulate_min_distance;  //!< closed-loop smallest distance >= this [m]
  std::optional<double> room_mean_share_min;    //!< the room's mean kept share >= this (fraction, 0..1)
  std::optional<double> room_tool_translation_min;  //!< the tool's room at the goal >= this [m]
};

//! One scenario of a suite, validated.
struct Scenario {
  std::string name;         //!< unique within the suite
  std::string label;        //!< "dallara home -> patch", for progress lines
  nlohmann::json resolved;  //!< what run_scenario() reads: the fields with the defaults merged in
                            //!< and file names resolved against the suite's folder
  Expectations expect;
};

//! A suite read from its file.
struct Suite {
  std::string file;  //!< the suite file
  std::string name;  //!< its "name", or the file's stem
  std::vector<Scenario> scenarios;
};

//! Reads and validates a whole suite before anything runs: every field's type and range, unknown
//! keys, unique names, and each scenario's cell (loaded), keyframes, goal sites, path file and
//! parameters.
//! @throws InputError naming the suite file, the scenario and the field.
Suite read_suite(const std::string& file);

//! Runs one scenario (Scenario::resolved) with `threads` worker threads: the cell check when
//! expected, the nominal path (planned around a colliding straight path, as `leeway bounds`), the
//! method, the Confidence Factor. Never throws: a run-time failure (unreachable goal, no path, any
//! exception) is returned as {"status": "error", "error": message}. Timings are in the "timing"
//! object only, so everything else is the same on any machine, process or thread count.
nlohmann::json run_scenario(const nlohmann::json& resolved, int threads);

//! Judges a scenario's result against its expectations: sets "expectations" (one entry each, with
//! the measured value and "passed") and "passed" in `result`; the soft time expectation goes into
//! result["timing"] and never fails.
void judge(const Scenario& scenario, nlohmann::json& result);

//! The JSON of a whole run: format, suite, scenarios in suite order, counts; timings only in
//! "timing" objects.
nlohmann::json suite_results_json(const Suite& suite, const std::vector<nlohmann::json>& results);

//! The JUnit XML report: one testsuite, and per scenario a testcase "run" (an <error> when it did
//! not finish) and one per expectation (a <failure> with the measured value; <skipped> when the run
//! did not finish). Times in seconds.
std::string junit_xml(const Suite& suite, const std::vector<nlohmann::json>& results);

//! Text escaped for XML attributes and character data (&, <, >, ", ' and control characters).
std::string xml_escape(const std::string& text);

}  // namespace leeway
