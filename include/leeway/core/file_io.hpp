#pragma once
//! @file file_io.hpp
//! Input files checked before they are opened, and the output-path policy: output files checked
//! against each other and against every file the run reads, then written whole or not at all.

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace leeway {

//! Checks that `path` names an existing regular file (or a link to one) without opening it: a FIFO,
//! folder or device would block or fail in a reader. `what` names the kind of file ("bounds file").
//! @throws InputError "PATH: cannot open the WHAT (missing or unreadable)" or "PATH: the WHAT is a
//! folder/FIFO/device, not a regular file".
void require_regular_input(const std::string& path, const std::string& what);

//! One output file of a run, as the program names it.
struct OutputFile {
  std::string path;
  std::string option;                   //!< what names it in messages: "--out"
  std::vector<std::string> extensions;  //!< the endings its name may have (".png"); empty: any
};

//! The output-path policy, applied before any work. Each output (empty paths are skipped):
//! its name ends in one of its extensions; its folder exists and is writable; it is not an existing
//! folder, FIFO, device, socket or symbolic link (outputs are replaced whole by a rename, which
//! would replace a link rather than write where it points); it is none of `inputs` (the same file by
//! device and inode, so also through links, `..` or a hard link); and no two outputs name the same
//! file. `inputs` should hold every file the run reads: the cell with its included and mesh files
//! (mjcf_input_files), parameter, path, bounds, suite and URDF files.
//! @throws InputError "OPTION PATH: reason", naming the input or the other option.
void require_outputs(const std::vector<OutputFile>& outputs, const std::vector<std::string>& inputs);

//! A new file beside `target`, for writing it whole: created with O_CREAT | O_EXCL | O_NOFOLLOW
//! (never an existing file or a link someone placed there) under an unpredictable hidden name
//! `.NAME.XXXXXXXXXXXX` in the target's folder, retried with another name while the name exists.
//! It is registered for removal should the process be ended by SIGTERM, SIGINT or SIGHUP
//! (install_temp_file_cleanup) and removed by the destructor unless commit() renamed it.
class TempFile {
 public:
  //! Creates the file with permission bits `mode` (less the umask).
  //! @throws InputError naming `target` when the folder is missing or not writable.
  explicit TempFile(const std::string& target, unsigned mode = 0644);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  //! The temporary file's path.
  const std::string& path() const { return path_; }
  //! Sets the permission bits (best effort).
  void set_mode(unsigned mode);
  //! Writes all of `text`. @throws InputError naming the target.
  void write(const std::string& text);
  //! Flushes to disk (fsync) and closes the file. @throws InputError naming the target.
  void close();
  //! close(), then renames the file over the target and flushes the folder: the target is the old
  //! file or the new one, never a partial one. @throws InputError naming the target.
  void commit();

 private:
  std::string target_, path_;
  int fd_ = -1;
  int slot_ = -1;  // in the signal handler's table
  bool done_ = false;
};

//! Writes text to a TempFile beside `path`, flushes it to disk (fsync) and renames it over `path`:
//! no partial file on failure. A file it replaces keeps its permission bits.
//! @throws InputError naming the file when it cannot be written or `path` is not a regular file
//! (a symbolic link, folder, FIFO or device).
void write_file_atomic(const std::string& path, const std::string& text);

//! An output file written as the run goes (a log or table whose rows are kept if the run is
//! interrupted): opened without following a symbolic link, refused unless a regular file, and held
//! with an exclusive lock (flock) for as long as the object lives, so that two runs never interleave
//! their rows in one file. The file's previous content is kept until truncate().
class StreamingOutput {
 public:
  StreamingOutput();
  //! Opens (creating it with mode 0644 less the umask) and locks `path`. `what` names it in messages
  //! ("--log"). @throws InputError naming `what` and the path: the folder is missing or not writable,
  //! the path is a symbolic link or not a regular file, or another process holds the lock.
  StreamingOutput(const std::string& path, const std::string& what);
  //! Closes the file (and so releases the lock); a file the constructor created and truncate()
  //! never touched is removed, so that a run refused or interrupted early leaves none.
  ~StreamingOutput();
  StreamingOutput(StreamingOutput&& other) noexcept;
  StreamingOutput& operator=(StreamingOutput&& other) noexcept;

  bool is_open() const;
  //! Empties the file: the run's first row replaces the previous content.
  void truncate();
  //! The file as a stream, written through to the file at every flush; a failed write throws
  //! InputError naming the file.
  std::ostream& stream();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! Installs handlers for SIGTERM, SIGINT and SIGHUP that remove the temporary files of
//! write_file_atomic in progress, then end the process as the signal would have. Process-wide;
//! programs call it once at the start of main() (a later handler for one of these signals replaces
//! it for that signal). Idempotent.
void install_temp_file_cleanup();

}  // namespace leeway
