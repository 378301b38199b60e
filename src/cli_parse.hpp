#pragma once
// Internal: command-line parsing and error reporting shared by the leeway and leeway-tune programs
// (not part of the public API).

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <optional>

#include "leeway/error.hpp"

namespace leeway::detail {

//! Parses argv into `app`. Returns the exit code the program should return now (0 after --help or
//! --version, kExitBadInput after a parse error, which CLI11 has reported on standard error), or
//! nothing when the program should go on.
inline std::optional<int> parse_cli(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  return std::nullopt;
}

//! Runs a program's `body` (returning its exit code) and turns an escaping exception into one line
//! on standard error: an InputError gives "PROGRAM: error: ..." and kExitBadInput, anything else
//! "PROGRAM: internal error (please report): ..." and kExitInternal.
template <class Body>
int run_reporting_errors(const char* program, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << program << ": internal error (please report): " << e.what() << "\n";
    return kExitInternal;
  }
}

}  // namespace leeway::detail
