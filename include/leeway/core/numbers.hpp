#pragma once
//! @file numbers.hpp
//! Numbers in messages, and the physical bound every input length is checked against. Shared by the
//! scene's checks of a cell and the parameters' checks, so that neither depends on the other.

#include <string>

namespace leeway {

//! Physical bounds on the input: a workcell is metres across, so lengths (parameters,
//! joint ranges of slide joints [m], obstacle positions and sizes) and hinge ranges [rad] beyond
//! this are refused as mistakes; they would only produce unusable bounds or overflow.
constexpr double kMaxLength = 1e3;

//! Formats a value compactly with up to 6 significant digits.
std::string format_number(double v);

}  // namespace leeway
