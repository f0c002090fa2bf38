#include "lsmbs/io/png.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/output.hpp"

namespace lsmbs {
namespace {

void put32(std::string& s, uint32_t v) {
  for (int i = 3; i >= 0; --i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

void chunk(std::string& out, const char* type, const std::string& data) {
  put32(out, static_cast<uint32_t>(data.size()));
  std::string td = std::string(type, 4) + data;
  out += td;
  put32(out, static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(td.data()),
                                         static_cast<uInt>(td.size()))));
}

// colour type 0 (greyscale, 1 channel) or 2 (RGB, 3 channels), 8 bits each
void write_png(const std::string& path, const char* caller, int w, int h, int channels,
               const std::vector<uint8_t>& px) {
  const size_t row = static_cast<size_t>(w) * static_cast<size_t>(channels);
  if (w < 1 || h < 1 || px.size() != row * static_cast<size_t>(h))
    throw Error(std::string(caller) + "(" + path + "): " + std::to_string(px.size()) +
                " bytes for an image of " + std::to_string(w) + " x " + std::to_string(h) +
                " pixels of " + std::to_string(channels) + " bytes");
  std::string raw;  // scanlines, each with filter byte 0 (none): flat regions deflate well as is
  raw.reserve(static_cast<size_t>(h) * (row + 1));
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);
    raw.append(reinterpret_cast<const char*>(px.data()) + static_cast<size_t>(y) * row, row);
  }
  // the zlib stream of the IDAT chunk (PNG: deflate inside a zlib wrapper), best compression
  uLongf zn = compressBound(static_cast<uLong>(raw.size()));
  std::string z(zn, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &zn, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), Z_BEST_COMPRESSION) != Z_OK)
    throw Error(std::string(caller) + "(" + path + "): zlib compress2 failed");
  z.resize(zn);
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  put32(ihdr, w);
  put32(ihdr, h);
  ihdr +=
      std::string(1, '\x08') + std::string(1, channels == 3 ? '\x02' : '\x00') +
      std::string(3, '\0');  // bit depth 8, colour type, deflate, adaptive filters, no interlace
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", "");
  write_file_atomic(path, png);
}

}  // namespace

void write_png_gray(const std::string& path, int w, int h, const std::vector<uint8_t>& px) {
  write_png(path, "write_png_gray", w, h, 1, px);
}

void write_png_rgb(const std::string& path, int w, int h, const std::vector<uint8_t>& px) {
  write_png(path, "write_png_rgb", w, h, 3, px);
}

}  // namespace lsmbs
