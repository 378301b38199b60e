#pragma once
//! @file error.hpp
//! The project's exception type and the command-line exit codes.

#include <stdexcept>
#include <string>

namespace leeway {

//! Bad user input (a file, element or value leeway cannot use). The message names all three.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! Exit codes of the `leeway` program; docs/cli.md lists them.
enum ExitCode : int {
  kExitOk = 0,        //!< success, and (check) no findings
  kExitFindings = 1,  //!< usable input, negative outcome: check found problems, no IK solution, no path
  kExitBadInput = 2,  //!< the input cannot be used (missing file, malformed XML, bad value)
  kExitInternal = 3,  //!< a bug in leeway: please report it
};

//! Always-on internal invariant check: throws std::logic_error naming the condition.
#define LEEWAY_DEMAND(cond)                                                                              \
  do {                                                                                                   \
    if (!(cond))                                                                                         \
      throw std::logic_error(std::string("leeway internal check failed: ") + #cond + " at " + __FILE__ + \
                             ":" + std::to_string(__LINE__));                                            \
  } while (false)

}  // namespace leeway
