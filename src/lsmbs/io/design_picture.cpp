#include "lsmbs/io/design_picture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/element_types.hpp"
#include "lsmbs/io/png.hpp"

namespace lsmbs {
namespace {

using Rgb = std::array<uint8_t, 3>;
constexpr Rgb kBlack = {0, 0, 0}, kWhite = {255, 255, 255}, kBackground = {230, 230, 230},
              kContour = {220, 0, 0};

// 5 × 7 glyphs, one byte a row, bit 4 the leftmost pixel. 'u' stands for μ.
struct Glyph {
  char c;
  std::array<uint8_t, 7> rows;
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {'-', {0x00, 0x00, 0x00, 0x0E, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}},
    {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
    {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'h', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'i', {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {'p', {0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10}},
    {'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'y', {0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
    {'u', {0x00, 0x11, 0x11, 0x11, 0x13, 0x1D, 0x10}},
    {' ', {0, 0, 0, 0, 0, 0, 0}},
};
constexpr int kScale = 2;             // glyph pixels per font pixel
constexpr int kAdvance = 6 * kScale;  // glyph width plus one column of space
constexpr int kTextHeight = 7 * kScale;

struct Canvas {
  int w, h;
  std::vector<uint8_t> px;
  Canvas(int w_, int h_) : w(w_), h(h_), px(static_cast<size_t>(w_) * h_ * 3, 255) {}
  void set(int x, int y, const Rgb& c) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    std::copy(c.begin(), c.end(), px.begin() + 3 * (static_cast<size_t>(y) * w + x));
  }
  void fill(int x0, int y0, int x1, int y1, const Rgb& c) {  // [x0, x1) × [y0, y1)
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) set(x, y, c);
  }
  void frame(int x0, int y0, int x1, int y1) {  // one pixel around [x0, x1) × [y0, y1)
    fill(x0 - 1, y0 - 1, x1 + 1, y0, kBlack);
    fill(x0 - 1, y1, x1 + 1, y1 + 1, kBlack);
    fill(x0 - 1, y0, x0, y1, kBlack);
    fill(x1, y0, x1 + 1, y1, kBlack);
  }
  // a segment between continuous pixel coordinates, one pixel wide, inside the clip box
  void segment(Vec2 a, Vec2 b, const Rgb& c, int cx0, int cy0, int cx1, int cy1) {
    const int n = std::max(1, static_cast<int>(std::ceil(4 * (b - a).norm())));
    for (int k = 0; k <= n; ++k) {
      const Vec2 p = a + (b - a) * (static_cast<double>(k) / n);
      const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
      if (x >= cx0 && x < cx1 && y >= cy0 && y < cy1) set(x, y, c);
    }
  }
  static int text_width(const std::string& s) { return static_cast<int>(s.size()) * kAdvance; }
  void text(int x, int y, const std::string& s, const Rgb& c = kBlack) {  // (x, y): top left
    for (char ch : s) {
      const Glyph* g = nullptr;
      for (const auto& f : kFont)
        if (f.c == ch) g = &f;
      if (!g) throw std::logic_error(std::string("design picture: no glyph for '") + ch + "'");
      for (int r = 0; r < 7; ++r)
        for (int col = 0; col < 5; ++col)
          if (g->rows[r] & (0x10 >> col))
            fill(x + col * kScale, y + r * kScale, x + (col + 1) * kScale, y + (r + 1) * kScale, c);
      x += kAdvance;
    }
  }
};

// The tick step for about `n` ticks over `span`: 1, 2 or 5 × 10^k.
double nice_step(double span, int n) {
  const double raw = span / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw * (1 - 1e-12)) return m * p;
  return 10 * p;
}

std::string tick_label(double v, double step) {
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", decimals, std::abs(v) < 1e-9 * step ? 0.0 : v);
  return b;
}

uint8_t grey(double mu, double mu_min) {
  return static_cast<uint8_t>(std::lround(255 * std::clamp((1 - mu) / (1 - mu_min), 0.0, 1.0)));
}

}  // namespace

void write_design_png(const std::string& path, const Mesh2D& mesh, const Vec& mu, double mu_min,
                      const Vec& phi, int width) {
  using L = DesignPictureLayout;
  if (width < L::kMinWidth)
    throw Error("design picture " + path + ": width " + std::to_string(width) + " < " +
                std::to_string(L::kMinWidth) + " pixels");
  if (mu.size() != mesh.num_elements() || (phi.size() && phi.size() != mesh.num_nodes()))
    throw Error("design picture " + path + ": field sizes do not match the mesh");
  Vec2 lo = mesh.nodes[0], hi = mesh.nodes[0];
  for (const auto& p : mesh.nodes) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double extent = (hi - lo).maxCoeff(), margin = 0.02 * extent;
  lo -= Vec2::Constant(margin);
  hi += Vec2::Constant(margin);
  const int bw = width - L::kLeft - L::kRight;  // the drawn box
  const double scale = bw / (hi.x() - lo.x());  // pixels per metre
  const int bh = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) * scale)));
  const int bar_h = std::max(bh, L::kMinBarHeight);
  const int height = L::kTop + bar_h + L::kBottom;
  Canvas cv(width, height);
  const int x0 = L::kLeft, y0 = L::kTop, x1 = x0 + bw, y1 = y0 + bh;
  // body frame → continuous pixel coordinates (y down)
  auto to_px = [&](const Vec2& X) {
    return Vec2(x0 + (X.x() - lo.x()) * scale, y1 - (X.y() - lo.y()) * scale);
  };
  cv.fill(x0, y0, x1, y1, kBackground);

  // elements: every pixel whose centre lies in the (convex) cell
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Cell& q = mesh.cells[static_cast<size_t>(e)];
    const int nk = q.size();
    Vec2 P[Cell::kMaxNodes], bl = Vec2::Constant(1e300), bu = Vec2::Constant(-1e300);
    for (int k = 0; k < nk; ++k) {
      P[k] = to_px(mesh.nodes[q[k]]);
      bl = bl.cwiseMin(P[k]), bu = bu.cwiseMax(P[k]);
    }
    const uint8_t g = grey(mu[e], mu_min);
    for (int y = std::max(y0, static_cast<int>(bl.y()));
         y <= std::min(y1 - 1, static_cast<int>(bu.y())); ++y)
      for (int x = std::max(x0, static_cast<int>(bl.x()));
           x <= std::min(x1 - 1, static_cast<int>(bu.x())); ++x) {
        const Vec2 c(x + 0.5, y + 0.5);
        bool in = true;  // same-side test of the centre against the edges
        double sgn = 0;
        for (int k = 0; k < nk && in; ++k) {
          const Vec2 a = P[k], b = P[(k + 1) % nk];
          const double cr = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
          if (cr != 0) {
            if (sgn == 0)
              sgn = cr;
            else if ((cr > 0) != (sgn > 0))
              in = false;
          }
        }
        if (in) cv.set(x, y, {g, g, g});
      }
  }

  // zero contours of the nodal level set, cell by cell (CellShape::contour: marching squares on
  // quadrilaterals, marching triangles on triangles)
  if (phi.size()) {
    std::vector<std::pair<Vec2, Vec2>> segments;
    for (int e = 0; e < mesh.num_elements(); ++e) {
      const Cell& q = mesh.cells[static_cast<size_t>(e)];
      double f[Cell::kMaxNodes];
      for (int k = 0; k < q.size(); ++k) f[k] = phi[q[k]];
      segments.clear();
      element_type(q.type).shape->contour(mesh.cell_nodes(e).data(), f, segments);
      for (const auto& [a, b] : segments) cv.segment(to_px(a), to_px(b), kContour, x0, y0, x1, y1);
    }
  }
  cv.frame(x0, y0, x1, y1);

  // axes: ticks at multiples of a nice step, in mm below 2 m of extent
  const bool mm = extent < 2;
  const double unit = mm ? 1e3 : 1;  // label units per metre
  const std::string u = mm ? "mm" : "m";
  auto ticks = [&](double a, double b) {  // tick values (in metres) in [a, b]
    const double step = nice_step((b - a) * unit, 5);
    std::vector<std::pair<double, std::string>> t;
    for (double k = std::ceil(a * unit / step - 1e-9);
         k * step <= b * unit * (1 + 1e-12) + 1e-9 * step; ++k)
      t.emplace_back(k * step / unit, tick_label(k * step, step));
    return t;
  };
  for (const auto& [v, s] : ticks(lo.x(), hi.x())) {
    const int px = static_cast<int>(std::floor(to_px(Vec2(v, lo.y())).x()));
    cv.fill(px, y1 + 1, px + 1, y1 + 6, kBlack);
    cv.text(px - Canvas::text_width(s) / 2, y1 + 9, s);
  }
  const std::string xl = "x [" + u + "]";
  cv.text(x0 + bw / 2 - Canvas::text_width(xl) / 2, y1 + 9 + kTextHeight + 8, xl);
  for (const auto& [v, s] : ticks(lo.y(), hi.y())) {
    const int py = static_cast<int>(std::floor(to_px(Vec2(lo.x(), v)).y()));
    cv.fill(x0 - 6, py, x0 - 1, py + 1, kBlack);
    cv.text(x0 - 9 - Canvas::text_width(s), py - kTextHeight / 2, s);
  }
  const std::string yl = "y [" + u + "]";
  cv.text(4, std::max(0, y0 - kTextHeight - 10), yl);

  // colour bar: row r (from the top) shows μ = 1 − (r + ½)/bar_h · (1 − μ_min)
  const int bx0 = x1 + L::kBarGap, bx1 = bx0 + L::kBarWidth, by0 = y0, by1 = y0 + bar_h;
  for (int r = 0; r < bar_h; ++r) {
    const uint8_t g = grey(1 - (r + 0.5) / bar_h * (1 - mu_min), mu_min);
    cv.fill(bx0, by0 + r, bx1, by0 + r + 1, {g, g, g});
  }
  cv.frame(bx0, by0, bx1, by1);
  auto bar_row = [&](double m) { return by0 + (1 - m) / (1 - mu_min) * bar_h; };
  std::vector<std::pair<double, std::string>> bar_ticks = {{1.0, "1"}};
  for (double m : {0.75, 0.5, 0.25})
    if (m > mu_min + 0.1) bar_ticks.emplace_back(m, tick_label(m, 0.01));
  char mm_label[32];
  std::snprintf(mm_label, sizeof mm_label, "%g", mu_min);
  bar_ticks.emplace_back(mu_min, mm_label);
  for (const auto& [m, s] : bar_ticks) {
    const int py = std::min(by1 - 1, static_cast<int>(std::floor(bar_row(m))));
    cv.fill(bx1 + 1, py, bx1 + 6, py + 1, kBlack);
    cv.text(bx1 + 9, py - kTextHeight / 2, s);
  }
  cv.text(bx0 - 2, std::max(0, by0 - kTextHeight - 10), "ue");
  // the contour's key under the bar
  if (phi.size()) {
    cv.fill(bx0 - 10, by1 + 20, bx0 + 10, by1 + 22, kContour);
    cv.text(bx0 + 16, by1 + 14, "phi=0", kContour);
  }
  write_png_rgb(path, width, height, cv.px);
}

}  // namespace lsmbs
