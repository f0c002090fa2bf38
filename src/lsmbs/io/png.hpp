#pragma once
// Minimal PNG output: 8-bit greyscale or RGB, deflated by zlib at its best compression. Design
// pictures are drawn by io/design_picture.hpp.
#include <cstdint>
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"

namespace lsmbs {

void write_png_gray(const std::string& path, int width, int height,
                    const std::vector<uint8_t>& pixels);
/// 8-bit RGB: three bytes per pixel, row-major, top row first.
void write_png_rgb(const std::string& path, int width, int height,
                   const std::vector<uint8_t>& pixels);

}  // namespace lsmbs
