#pragma once
//! @file file_io.hpp
//! Input files checked before they are opened, and output files written whole or not at all.

#include <string>
#include <vector>

namespace leeway {

//! Checks that `path` names an existing regular file (or a link to one) without opening it: a FIFO,
//! folder or device would block or fail in a reader. `what` names the kind of file ("bounds file").
//! @throws InputError "PATH: cannot open the WHAT (missing or unreadable)" or "PATH: the WHAT is a
//! folder/FIFO/device, not a regular file".
void require_regular_input(const std::string& path, const std::string& what);

//! Checks that `path` can take an output file: not empty, not an existing folder, FIFO, device or
//! other non-regular file, and not the same file as any of `inputs` (std::filesystem::equivalent).
//! @throws InputError naming the path and the reason.
void require_regular_output(const std::string& path, const std::vector<std::string>& inputs = {});

//! Writes text to a temporary file beside `path`, flushes it to disk (fsync) and renames it over
//! `path`: no partial file on failure. The temporary file is registered for removal should the
//! process be ended by SIGTERM, SIGINT or SIGHUP meanwhile (install_temp_file_cleanup).
//! @throws InputError naming the file when it cannot be written or `path` is not a regular file.
void write_file_atomic(const std::string& path, const std::string& text);

//! Installs handlers for SIGTERM, SIGINT and SIGHUP that remove the temporary files of
//! write_file_atomic in progress, then end the process as the signal would have. Process-wide;
//! programs call it once at the start of main() (a later handler for one of these signals replaces
//! it for that signal). Idempotent.
void install_temp_file_cleanup();

}  // namespace leeway
