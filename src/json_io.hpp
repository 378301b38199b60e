#pragma once
// Internal: the JSON helpers shared by the library's readers and writers (not public API).

#include <Eigen/Core>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "leeway/error.hpp"
#include "leeway/file_io.hpp"

namespace leeway::detail {

//! Deepest nesting of arrays and objects a JSON input may have: leeway's files need 4; deeper
//! inputs are refused before anything (printing a value in an error message) recurses into them.
inline constexpr int kMaxJsonDepth = 64;

//! A vector as a JSON array of numbers (joint values in the bounds, path and check files).
inline nlohmann::json to_json_array(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

//! Parses JSON text from `source` (a file name, for the messages): nesting deeper than
//! kMaxJsonDepth and a key given twice in one object are refused, as is a number outside the double
//! range (nlohmann's "number overflow parsing '1e400'").
//! @throws InputError "SOURCE: malformed JSON: ..." or "SOURCE: ..." naming the key (one line).
inline nlohmann::json parse_json_text(const std::string& text, const std::string& source) {
  // The parser is iterative; the callback sees every event with its depth before any recursion.
  std::vector<std::set<std::string>> keys;  // the keys seen in each open object
  auto callback = [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (depth > kMaxJsonDepth)
      throw InputError(source + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    if (event == E::object_start) keys.emplace_back();
    if (event == E::object_end && !keys.empty()) keys.pop_back();
    if (event == E::key && !keys.empty()) {
      const std::string key = parsed.get<std::string>();
      if (!keys.back().insert(key).second)
        throw InputError(source + ": JSON key '" + key + "' appears twice in one object");
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, callback);
  } catch (const nlohmann::json::exception& e) {
    std::string message = e.what();
    for (char& ch : message)
      if (ch == '\n' || ch == '\r') ch = ' ';
    throw InputError(source + ": malformed JSON: " + message);
  }
}

//! Parses the JSON file at `path`; `what` names the kind of file in the error ("bounds file").
//! @throws InputError "PATH: cannot open the WHAT", "PATH: ... not a regular file" or
//! "PATH: malformed JSON: ..." (one line).
inline nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  require_regular_input(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the " + what);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read the " + what);
  return parse_json_text(text.str(), path);
}

}  // namespace leeway::detail
