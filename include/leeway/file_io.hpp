#pragma once
//! @file file_io.hpp
//! Output files written whole or not at all.

#include <string>

namespace leeway {

//! Writes text to a temporary file beside `path`, then renames it: no partial file on failure.
//! @throws InputError naming the file when it cannot be written.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace leeway
