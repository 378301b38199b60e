#include "leeway/core/numbers.hpp"

#include <sstream>

namespace leeway {

std::string format_number(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

}  // namespace leeway
