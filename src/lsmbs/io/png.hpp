#pragma once
// Minimal PNG output (8-bit greyscale, deflated by zlib at its best compression) and a
// rasterizer that draws element values of a quad mesh as grey levels, the way the paper shows
// designs (Figs. 1(d), 6, 13): μ = 1 black (material), μ = μ_min white (void).
#include <cstdint>
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"

namespace lsmbs {

void write_png_gray(const std::string& path, int width, int height,
                    const std::vector<uint8_t>& pixels);

/// Image of the mesh (design frame) `width` pixels wide; element e painted with grey level
/// 255 (1 − μ_e)/(1 − μ_min). Returns the pixels (row-major, top row first); `height` receives
/// the image height.
std::vector<uint8_t> render_element_field(const Mesh2D& mesh, const Vec& mu, double mu_min,
                                          int width, int& height);

}  // namespace lsmbs
