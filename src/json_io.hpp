#pragma once
// Internal: the JSON helpers shared by the library's readers and writers (not public API).

#include <Eigen/Core>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "leeway/error.hpp"

namespace leeway::detail {

//! A vector as a JSON array of numbers (joint values in the bounds, path and check files).
inline nlohmann::json to_json_array(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

//! Parses the JSON file at `path`; `what` names the kind of file in the error ("bounds file").
//! @throws InputError "PATH: cannot open the WHAT" or "PATH: malformed JSON: ..." (one line).
inline nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the " + what);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    std::string message = e.what();
    for (char& ch : message)
      if (ch == '\n' || ch == '\r') ch = ' ';
    throw InputError(path + ": malformed JSON: " + message);
  }
}

}  // namespace leeway::detail
