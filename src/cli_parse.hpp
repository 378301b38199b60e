#pragma once
// Internal: command-line parsing shared by the leeway and leeway-tune programs (not part of the
// public API).

#include <CLI/CLI.hpp>
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

}  // namespace leeway::detail
