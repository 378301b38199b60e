#pragma once
// MP4 output of the leeway program: raw RGB frames piped into ffmpeg (Debian's ffmpeg, found on
// PATH), which writes H.264 into a temporary file renamed over the target when it succeeds.
#include <cstdio>
#include <string>

#include "leeway/core/file_io.hpp"
#include "leeway/viz/render.hpp"

namespace leeway::cli {

//! The path of an executable `name` on PATH, or "".
std::string find_on_path(const std::string& name);

//! `text` quoted for /bin/sh.
std::string shell_quote(const std::string& text);

//! Frames of one size at 30 fps into an MP4 file.
class Mp4Stream {
 public:
  static constexpr int kFps = 30;
  //! Starts ffmpeg. `option` names the flag in messages. @throws InputError when the size is odd
  //! (H.264 in yuv420p) or ffmpeg cannot be started.
  Mp4Stream(const std::string& path, const std::string& option, int width, int height,
            const std::string& ffmpeg);
  ~Mp4Stream();
  Mp4Stream(const Mp4Stream&) = delete;
  Mp4Stream& operator=(const Mp4Stream&) = delete;
  //! Appends a frame of the stream's size (a write error is reported by finish()).
  void add(const Image& image);
  //! Ends the stream and renames the file into place; returns the frame count.
  //! @throws InputError naming the file when ffmpeg failed (nothing is written then).
  long finish();

 private:
  std::string path_, option_;
  TempFile temp_;
  int width_, height_;
  FILE* pipe_ = nullptr;
  long frames_ = 0;
  bool failed_ = false;
};

}  // namespace leeway::cli
