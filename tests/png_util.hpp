#pragma once
// Test support: a PNG reader for the files leeway writes (8-bit RGB, filter type 0 on every row).

#include <zlib.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "leeway/viz/render.hpp"

namespace leeway::test {

namespace detail {

//! A PNG's header and its rows inflated, each row still led by its filter byte.
struct InflatedPng {
  int width = 0, height = 0;
  std::string header;  //!< IHDR's bit depth, colour type, compression, filter and interlace bytes
  std::string raw;     //!< height rows of 1 + channels * width bytes
};

//! Reads the chunks of a PNG and inflates its IDAT data for `channels` bytes per pixel, the count
//! `channels_of` gives for the header's bytes; throws std::runtime_error on a malformed file.
template <typename ChannelsOf>
InflatedPng inflate_png(const std::string& bytes, ChannelsOf channels_of) {
  if (bytes.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0)
    throw std::runtime_error("no PNG signature");
  auto u32 = [&bytes](size_t at) {
    unsigned v = 0;
    for (size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(bytes.at(at + k));
    return v;
  };
  InflatedPng png;
  std::string packed;
  for (size_t at = 8; at + 8 <= bytes.size();) {
    const size_t len = u32(at);
    const std::string type = bytes.substr(at + 4, 4);
    if (type == "IHDR") {
      png.width = static_cast<int>(u32(at + 8));
      png.height = static_cast<int>(u32(at + 12));
      png.header = bytes.substr(at + 16, 5);
    }
    if (type == "IDAT") packed += bytes.substr(at + 8, len);
    at += 12 + len;
  }
  const size_t row = static_cast<size_t>(channels_of(png.header)) * static_cast<size_t>(png.width);
  png.raw.assign((row + 1) * static_cast<size_t>(png.height), '\0');
  uLongf size = static_cast<uLongf>(png.raw.size());
  if (uncompress(reinterpret_cast<Bytef*>(png.raw.data()), &size,
                 reinterpret_cast<const Bytef*>(packed.data()), static_cast<uLong>(packed.size())) != Z_OK ||
      size != png.raw.size())
    throw std::runtime_error("IDAT does not inflate to the image size");
  return png;
}

}  // namespace detail

//! Decodes a PNG written by leeway::encode_png; throws std::runtime_error on anything else.
inline Image decode_png(const std::string& bytes) {
  const detail::InflatedPng png = detail::inflate_png(bytes, [](const std::string& header) {
    if (header != std::string("\x08\x02\x00\x00\x00", 5))
      throw std::runtime_error("not 8-bit RGB without interlace");
    return 3;
  });
  Image image;
  image.width = png.width;
  image.height = png.height;
  const size_t row = 3 * static_cast<size_t>(image.width);
  for (int y = 0; y < image.height; ++y) {
    const size_t start = (row + 1) * static_cast<size_t>(y);
    if (png.raw[start] != '\0') throw std::runtime_error("a row filter other than 0");
    image.rgb.insert(image.rgb.end(), png.raw.begin() + static_cast<long>(start + 1),
                     png.raw.begin() + static_cast<long>(start + 1 + row));
  }
  return image;
}

//! Decodes an 8-bit RGB or RGBA PNG without interlace, any row filter (what browsers write for a
//! screenshot); the alpha channel is dropped. Throws std::runtime_error on anything else.
inline Image decode_browser_png(const std::string& bytes) {
  int channels = 0;
  const detail::InflatedPng png = detail::inflate_png(bytes, [&channels](const std::string& header) {
    const int depth = header.at(0), colour = header.at(1), interlace = header.at(4);
    channels = colour == 2 ? 3 : colour == 6 ? 4 : 0;
    if (depth != 8 || channels == 0 || interlace != 0)
      throw std::runtime_error("not 8-bit RGB(A) without interlace");
    return channels;
  });
  Image image;
  image.width = png.width;
  image.height = png.height;
  const size_t row = static_cast<size_t>(channels) * static_cast<size_t>(image.width);
  std::vector<unsigned char> prior(row, 0), line(row);
  const size_t bpp = static_cast<size_t>(channels);
  for (int y = 0; y < image.height; ++y) {
    const size_t start = (row + 1) * static_cast<size_t>(y);
    const int filter = static_cast<unsigned char>(png.raw[start]);
    for (size_t i = 0; i < row; ++i) {
      const int x = static_cast<unsigned char>(png.raw[start + 1 + i]);
      const int a = i >= bpp ? line[i - bpp] : 0, b = prior[i], c = i >= bpp ? prior[i - bpp] : 0;
      int predicted = 0;
      if (filter == 1)
        predicted = a;
      else if (filter == 2)
        predicted = b;
      else if (filter == 3)
        predicted = (a + b) / 2;
      else if (filter == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        predicted = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      } else if (filter != 0)
        throw std::runtime_error("unknown row filter");
      line[i] = static_cast<unsigned char>((x + predicted) & 0xff);
    }
    for (int px = 0; px < image.width; ++px)
      for (int k = 0; k < 3; ++k) image.rgb.push_back(line[static_cast<size_t>(px * channels + k)]);
    prior = line;
  }
  return image;
}

//! Decodes a PNG file written by leeway.
inline Image read_png(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return decode_png(std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
}

}  // namespace leeway::test
