#pragma once
// The picture of a design (`lsmbs geometry`, `optimize`'s final_design): μ_e of every element as
// grey levels, the way the paper shows designs (Figs. 1(d), 6, 13: μ = 1 black, μ = μ_min white),
// with what a reader needs to measure it:
//  * axes in the body (mesh) frame: a frame around the drawn box, ticks at multiples of a step of
//    1, 2 or 5 × 10^k, labelled in mm when the body's largest extent is below 2 m, in m otherwise
//    (the axis titles say which: "x [mm]", "y [mm]");
//  * the features' zero contours in red: the nodal level set φ = 0 (φ > 0 material, eq. 33), by
//    marching squares on each quad (crossings linear along the edges; a saddle decided by the
//    mean of the four nodal values);
//  * a colour bar for μ_e: the same grey map from μ_min (bottom) to 1 (top), ticks labelled.
// Text is drawn with a built-in 5 × 7 bitmap font (digits, '.', '-', '+', '=', '[', ']', and the
// letters the labels use); there is no font library.
#include <string>

#include "lsmbs/fem/mesh.hpp"

namespace lsmbs {

/// Fixed layout in pixels: the drawn box (the mesh's bounding box widened by 2 % of its largest
/// extent) is (width − kLeft − kRight) wide at the same scale in x and y, kLeft from the left and
/// kTop from the top; the colour bar is kBarWidth wide, kBarGap right of the box, at least
/// kMinBarHeight tall (the picture grows to hold it).
struct DesignPictureLayout {
  static constexpr int kLeft = 80, kRight = 130, kTop = 30, kBottom = 60;
  static constexpr int kBarGap = 30, kBarWidth = 20, kMinBarHeight = 160;
  static constexpr int kMinWidth = 300;  ///< narrower pictures have no room for the margins
};

/// Writes the picture `width` pixels wide (RGB PNG). `phi`: the level set at the nodes (empty:
/// no contours).
void write_design_png(const std::string& path, const Mesh2D& mesh, const Vec& mu, double mu_min,
                      const Vec& phi, int width);

}  // namespace lsmbs
