#include "cli/video.hpp"

#include <unistd.h>

#include <cstdlib>

#include "leeway/core/error.hpp"

namespace leeway::cli {

std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = dirs.find(':', start);
    const std::string dir = dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return "";
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

Mp4Stream::Mp4Stream(const std::string& path, const std::string& option, int width, int height,
                     const std::string& ffmpeg)
    : path_(path), option_(option), temp_(path), width_(width), height_(height) {
  if (width % 2 || height % 2)
    throw InputError(option + " " + path +
                     ": a video's width and height must be even (H.264 in yuv420p), not " +
                     std::to_string(width) + "x" + std::to_string(height));
  const std::string command =
      shell_quote(ffmpeg) + " -hide_banner -loglevel error -y -f rawvideo -pix_fmt rgb24 -s " +
      std::to_string(width) + "x" + std::to_string(height) + " -r " + std::to_string(kFps) +
      " -i - -an -c:v libx264 -pix_fmt yuv420p -f mp4 " + shell_quote(temp_.path());
  pipe_ = ::popen(command.c_str(), "w");
  if (!pipe_) throw InputError(option + ": could not start " + ffmpeg);
}

Mp4Stream::~Mp4Stream() {
  if (pipe_) ::pclose(pipe_);
}

void Mp4Stream::add(const Image& image) {
  if (failed_ || !pipe_) return;
  if (image.width != width_ || image.height != height_ ||
      std::fwrite(image.rgb.data(), 1, image.rgb.size(), pipe_) != image.rgb.size()) {
    failed_ = true;
    return;
  }
  ++frames_;
}

long Mp4Stream::finish() {
  const int status = pipe_ ? ::pclose(pipe_) : -1;
  pipe_ = nullptr;
  if (failed_ || status != 0)
    throw InputError(option_ + " " + path_ + ": ffmpeg failed (exit status " + std::to_string(status) +
                     "); no video written");
  temp_.commit();
  return frames_;
}

}  // namespace leeway::cli
