// write_png_gray: the file decodes, with decoders independent of the writer (Pillow and a
// struct + zlib one in png_check.py), to exactly the pixels drawn, and it is compressed.
#include "lsmbs/io/png.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"

namespace {

namespace fs = std::filesystem;

// A picture like the design pictures (a light background, a black body, a white hole), plus a
// grey ramp and a block of pseudo-random noise that no compressor can shrink.
std::vector<uint8_t> drawing(int w, int h) {
  std::vector<uint8_t> px(static_cast<size_t>(w) * h, 230);
  uint32_t lcg = 12345;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t& p = px[static_cast<size_t>(y) * w + x];
      if (x >= 10 && x < 240 && y >= 8 && y < 100) p = 0;
      if ((x - 120) * (x - 120) + (y - 50) * (y - 50) < 30 * 30) p = 255;
      if (y >= 105 && y < 115) p = static_cast<uint8_t>(x % 256);
      if (x >= 200 && x < 232 && y >= 115 && y < 147) {
        lcg = lcg * 1664525u + 1013904223u;
        p = static_cast<uint8_t>(lcg >> 24);
      }
    }
  return px;
}

TEST(Png, DecodesToTheDrawnPixelsAndIsCompressed) {
  const int w = 257, h = 151;  // odd sizes: no row or byte alignment to lean on
  const auto px = drawing(w, h);
  const fs::path dir = fs::temp_directory_path() / ("lsmbs_png_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string png = (dir / "drawing.png").string(), raw = (dir / "drawing.raw").string();
  lsmbs::write_png_gray(png, w, h, px);
  std::ofstream(raw, std::ios::binary).write(reinterpret_cast<const char*>(px.data()), px.size());
  const std::string cmd = std::string(LSMBS_TEST_PYTHON) + " " + LSMBS_SOURCE_DIR +
                          "/tests/unit/io/png_check.py " + png + " " + raw + " " +
                          std::to_string(w) + " " + std::to_string(h);
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  // 38,807 bytes of pixels, 1,024 of them noise: the file must be far smaller than the pixels
  const auto size = fs::file_size(png);
  EXPECT_LT(size, px.size() / 8) << size << " bytes";
  std::printf("PNG %d x %d: %zu bytes of pixels, %ju bytes written\n", w, h, px.size(),
              static_cast<uintmax_t>(size));
  fs::remove_all(dir);
}

TEST(Png, RefusesPixelsThatDoNotFitTheSize) {
  EXPECT_THROW(lsmbs::write_png_gray("/nonexistent/x.png", 4, 4, std::vector<uint8_t>(15)),
               lsmbs::Error);
}

}  // namespace
