#pragma once
// Internal: the JSON helpers shared by the library's readers and writers (not public API).

#include <Eigen/Core>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"

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
// A SAX handler that builds the document as nlohmann's own DOM parser does (linear time; its
// callback parser scans the parent array at every object's end, quadratic for a long list of
// waypoints) while refusing nesting deeper than kMaxJsonDepth and a key given twice in one object.
// The parser is iterative, so deep input is refused before anything recurses into it.
class CheckedJsonSax {
 public:
  using json = nlohmann::json;
  CheckedJsonSax(json& result, const std::string& source) : dom_(result, true), source_(source) {}

  bool null() { return value() && dom_.null(); }
  bool boolean(bool v) { return value() && dom_.boolean(v); }
  bool number_integer(json::number_integer_t v) { return value() && dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value() && dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const json::string_t& s) {
    return value() && dom_.number_float(v, s);
  }
  bool string(json::string_t& v) { return value() && dom_.string(v); }
  bool binary(json::binary_t& v) { return value() && dom_.binary(v); }
  bool start_object(std::size_t n) {
    value();
    ++depth_;
    keys_.emplace_back();
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    if (!keys_.back().insert(k).second)
      throw InputError(source_ + ": JSON key '" + k + "' appears twice in one object");
    return dom_.key(k);
  }
  bool end_object() {
    --depth_;
    keys_.pop_back();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    value();
    ++depth_;
    return dom_.start_array(n);
  }
  bool end_array() {
    --depth_;
    return dom_.end_array();
  }
  template <class Exception>
  bool parse_error(std::size_t, const std::string&, const Exception& e) {
    std::string message = e.what();
    for (char& ch : message)
      if (ch == '\n' || ch == '\r') ch = ' ';
    throw InputError(source_ + ": malformed JSON: " + message);
  }

 private:
  // Every value, containers included, sits at the depth of the containers open around it.
  bool value() const {
    if (depth_ > kMaxJsonDepth)
      throw InputError(source_ + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    return true;
  }
  nlohmann::detail::json_sax_dom_parser<json> dom_;
  const std::string& source_;
  int depth_ = 0;
  std::vector<std::set<std::string>> keys_;  // the keys seen in each open object
};

inline nlohmann::json parse_json_text(const std::string& text, const std::string& source) {
  nlohmann::json result;
  CheckedJsonSax sax(result, source);
  nlohmann::json::sax_parse(text, &sax);
  return result;
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
