#pragma once
// Internal: command-line parsing, checks of option values and error reporting shared by the leeway
// program (src/cli/) and leeway-tune (tuning/); header-only, target leeway_cli_support (not part
// of the public API).

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <limits>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/numbers.hpp"

namespace leeway::cli {

//! Most worker threads a program accepts (--threads).
inline constexpr int kMaxThreads = 256;

//! Checks --threads: from 1 to kMaxThreads. @throws InputError naming the flag and the value.
inline void require_threads(int threads, const std::string& flag = "--threads") {
  if (threads < 1 || threads > kMaxThreads)
    throw InputError(flag + " " + std::to_string(threads) + " must be from 1 to " +
                     std::to_string(kMaxThreads));
}

//! Parses argv into `app`. Returns the exit code the program should return now (0 after --help or
//! --version, kExitBadInput after a parse error, reported as one line "PROGRAM: error: ..." on
//! standard error), or nothing when the program should go on.
inline std::optional<int> parse_cli(CLI::App& app, int argc, char** argv, const char* program = "leeway") {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string message = e.what();
    // CLI11 checks required arguments before unknown ones: `leeway bounds --foo` would say "cell is
    // required". An argument that no option takes is the more likely mistake: name it first.
    if (dynamic_cast<const CLI::RequiredError*>(&e)) {
      const std::vector<std::string> extra = app.remaining(true);
      if (!extra.empty()) {
        message =
            "The following argument" + std::string(extra.size() > 1 ? "s were" : " was") + " not expected:";
        for (const auto& arg : extra) message += " " + arg;
      }
    }
    for (char& ch : message)
      if (ch == '\n' || ch == '\r') ch = ' ';
    while (!message.empty() && message.back() == ' ') message.pop_back();
    std::cerr << program << ": error: " << message << " (see " << program << " --help)\n";
    return kExitBadInput;
  }
  return std::nullopt;
}

//! Lets a write to a closed pipe fail with EPIPE instead of killing the process with SIGPIPE
//! (`leeway check --json | head -c 1` ended in 141): finish_stdout then reports the lost output as
//! exit 2. Programs call it first in main().
inline void ignore_sigpipe() { std::signal(SIGPIPE, SIG_IGN); }

//! Flushes standard output and checks that everything written to it arrived: a full disk, a
//! closed pipe or /dev/full must not end in exit 0. Returns `code`, or kExitBadInput after one line
//! on standard error when the output was lost.
inline int finish_stdout(const char* program, int code) {
  std::cout.flush();
  const bool lost = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
  if (!lost) return code;
  const int err = errno;
  std::cout.clear();
  std::cerr << program << ": error: standard output: writing failed (" << std::strerror(err ? err : EIO)
            << "); the output is incomplete\n";
  return kExitBadInput;
}

//! `message` on one line: a line break or other control character (a name in the input holding
//! "&#10;" reaches the message as it is) is written as \n, \r or \xHH, so that no input can add a
//! line of its own to the error.
inline std::string one_line_message(const std::string& message) {
  std::string out;
  out.reserve(message.size());
  for (const char c : message) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (u < 0x20 || u == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    } else {
      out += c;
    }
  }
  return out;
}

//! Runs a program's `body` (returning its exit code) and turns an escaping exception into one line
//! on standard error: an InputError gives "PROGRAM: error: ..." and kExitBadInput, an allocation
//! failure "PROGRAM: error: out of memory ..." and kExitBadInput, anything else
//! "PROGRAM: internal error (please report): ..." and kExitInternal. Standard output is flushed and
//! checked before an exit code is returned (finish_stdout).
template <class Body>
int run_reporting_errors(const char* program, Body&& body) {
  int code = kExitInternal;
  try {
    code = body();
  } catch (const InputError& e) {
    std::cerr << program << ": error: " << one_line_message(e.what()) << "\n";
    code = kExitBadInput;
  } catch (const std::bad_alloc&) {
    std::cerr << program
              << ": error: out of memory: the input needs more memory than the system grants"
                 " (fewer waypoints, windows, samples or MAX_cells need less); nothing written\n";
    code = kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << program << ": internal error (please report): " << one_line_message(e.what()) << "\n";
    code = kExitInternal;
  }
  return finish_stdout(program, code);
}

//! Memory leeway lets the command line ask for in the data it sizes (waypoints, CF windows), in
//! bytes: above it a run is refused up front rather than ending in an allocation failure.
inline constexpr double kMemoryLimit = 4.0 * 1024 * 1024 * 1024;

//! Estimated bytes per waypoint of a bounded path (the path, its intervals, the safety stage's
//! segments and the bounds file as JSON), for require_memory.
inline constexpr double kBytesPerWaypoint = 4096;

//! Estimated bytes per CF window (its counts, its CF and its entry in the JSON output).
inline constexpr double kBytesPerWindow = 96;

//! Refuses `what` ("--waypoints 1000000000") when `bytes` exceeds kMemoryLimit.
//! @throws InputError with the estimate and the limit.
inline void require_memory(double bytes, const std::string& what) {
  if (bytes <= kMemoryLimit) return;
  auto gib = [](double b) { return format_number(b / (1024.0 * 1024 * 1024)); };
  throw InputError(what + " would need about " + gib(bytes) + " GiB of memory (estimated); the limit is " +
                   gib(kMemoryLimit) + " GiB");
}

//! A CLI11 check for a seed: a whole number from 0 to `max` written in decimal digits (CLI11 would
//! wrap "-1" and round 1e23 to the largest value).
inline CLI::Validator seed_check(std::uint64_t max = std::numeric_limits<std::uint64_t>::max()) {
  return CLI::Validator(
      [max](std::string& text) -> std::string {
        const std::string bad = "'" + text + "' must be a whole number from 0 to " + std::to_string(max);
        if (text.empty() || text.size() > 20 || text.find_first_not_of("0123456789") != std::string::npos)
          return bad;
        errno = 0;
        const unsigned long long v = std::strtoull(text.c_str(), nullptr, 10);
        if (errno == ERANGE || v > max) return bad;
        return "";
      },
      "");
}

//! seed_check up to the largest value of the seed's type.
template <class T>
CLI::Validator seed_check_for(const T&) {
  return seed_check(static_cast<std::uint64_t>(std::numeric_limits<T>::max()));
}

//! A CLI11 check for a file name: not empty.
inline CLI::Validator file_name_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "the file name is empty" : ""; }, "");
}

//! A CLI11 check that an option given is not empty ("--safety ''"): `expected` says what to give.
inline CLI::Validator non_empty_check(const std::string& expected) {
  return CLI::Validator(
      [expected](std::string& text) -> std::string {
        return text.empty() ? "is empty; give " + expected : "";
      },
      "");
}

//! A CLI11 check for a number: finite (CLI11 accepts "nan" and "inf" for a double).
inline CLI::Validator finite_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
        return "";
      },
      "");
}

}  // namespace leeway::cli
