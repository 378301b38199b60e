// libFuzzer target: a parameter file through read_params (docs/testing.md, "Fuzzing").
//
// Contract: read_params (params.hpp) returns validated parameters or throws leeway::InputError
// naming the file, the key and the value: unreadable file, malformed JSON (nlohmann's parse errors,
// nesting deeper than 64 levels, a key given twice, a number beyond the double range), not an
// object, an unknown section or key, a value of the wrong type or out of range (Params::validate).
// Anything else is a finding: another exception (nlohmann::json::exception escaping the reader,
// std::logic_error from LEEWAY_DEMAND, std::bad_alloc), a crash, a sanitizer report, a leak, a
// timeout.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz_input.hpp"
#include "leeway/core/params.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const leeway::fuzz::InputFile input("params.json");
  const std::string& path = input.write(data, size);
  try {
    const leeway::Params p = leeway::read_params(path);
    // What was read must write and read back to the same parameters: to_json is the other half
    // of the file format (leeway params prints it; the bounds file embeds it).
    const leeway::Params again = leeway::params_from_json(leeway::to_json(p), path);
    if (leeway::to_json(again) != leeway::to_json(p)) {
      std::fprintf(stderr, "leeway fuzz: parameters do not survive to_json and back\n");
      std::abort();
    }
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
  }
  return 0;
}
