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

}  // namespace

void write_png_gray(const std::string& path, int w, int h, const std::vector<uint8_t>& px) {
  if (w < 1 || h < 1 || px.size() != static_cast<size_t>(w) * static_cast<size_t>(h))
    throw Error("write_png_gray(" + path + "): " + std::to_string(px.size()) +
                " pixels for an image of " + std::to_string(w) + " x " + std::to_string(h));
  std::string raw;  // scanlines, each with filter byte 0 (none): flat regions deflate well as is
  raw.reserve(static_cast<size_t>(h) * (w + 1));
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);
    raw.append(reinterpret_cast<const char*>(px.data()) + static_cast<size_t>(y) * w, w);
  }
  // the zlib stream of the IDAT chunk (PNG: deflate inside a zlib wrapper), best compression
  uLongf zn = compressBound(static_cast<uLong>(raw.size()));
  std::string z(zn, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &zn, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), Z_BEST_COMPRESSION) != Z_OK)
    throw Error("write_png_gray(" + path + "): zlib compress2 failed");
  z.resize(zn);
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  put32(ihdr, w);
  put32(ihdr, h);
  ihdr += std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit greyscale
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", "");
  write_file_atomic(path, png);
}

std::vector<uint8_t> render_element_field(const Mesh2D& mesh, const Vec& mu, double mu_min,
                                          int width, int& height) {
  Vec2 lo = mesh.nodes[0], hi = mesh.nodes[0];
  for (const auto& p : mesh.nodes) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double margin = 0.02 * (hi - lo).maxCoeff();
  lo -= Vec2::Constant(margin);
  hi += Vec2::Constant(margin);
  const double scale = width / (hi.x() - lo.x());
  height = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) * scale)));
  std::vector<uint8_t> px(static_cast<size_t>(width) * height, 230);  // light grey background
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& q = mesh.quads[e];
    Vec2 P[4];
    Vec2 bl = Vec2::Constant(1e300), bh = Vec2::Constant(-1e300);
    for (int k = 0; k < 4; ++k) {
      P[k] = (mesh.nodes[q[k]] - lo) * scale;
      P[k].y() = height - P[k].y();
      bl = bl.cwiseMin(P[k]), bh = bh.cwiseMax(P[k]);
    }
    const double t = std::clamp((1 - mu[e]) / (1 - mu_min), 0.0, 1.0);
    const uint8_t g = static_cast<uint8_t>(std::lround(255 * t));
    for (int y = std::max(0, static_cast<int>(bl.y()));
         y <= std::min(height - 1, static_cast<int>(bh.y())); ++y)
      for (int x = std::max(0, static_cast<int>(bl.x()));
           x <= std::min(width - 1, static_cast<int>(bh.x())); ++x) {
        const Vec2 c(x + 0.5, y + 0.5);
        bool in = true;  // convex quad, clockwise after the y flip: same-side test
        double sgn = 0;
        for (int k = 0; k < 4 && in; ++k) {
          const Vec2 a = P[k], b = P[(k + 1) % 4];
          const double cr = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
          if (cr != 0) {
            if (sgn == 0)
              sgn = cr;
            else if ((cr > 0) != (sgn > 0))
              in = false;
          }
        }
        if (in) px[static_cast<size_t>(y) * width + x] = g;
      }
  }
  return px;
}

}  // namespace lsmbs
