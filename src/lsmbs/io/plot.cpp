#include "lsmbs/io/plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string_view>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/png.hpp"

#if defined(__SANITIZE_ADDRESS__)
// Under AddressSanitizer (scripts/sanitize.sh): fontconfig, which cairo's text calls load, keeps
// its configuration and font cache for the life of the process and frees part of it never; the
// leak checker reports those blocks at exit (about 1 kB in 12 blocks, in FcValueSave, on a machine
// whose font cache is cold). They are one-time library state, not a leak of lsmbs: suppressed
// here, in every executable that draws, whatever environment a test starts it in.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libfontconfig.so\nleak:libcairo.so\n";
}
#endif

namespace lsmbs {

namespace {

struct Rgb {
  double r, g, b;
};
constexpr Rgb kBlack{0, 0, 0}, kGrid{0.86, 0.86, 0.86}, kReference{0.35, 0.35, 0.35};

Rgb colour(int k) {
  const char* h = kSeriesColours[static_cast<size_t>(k) % std::size(kSeriesColours)];
  unsigned r = 0, g = 0, b = 0;
  std::sscanf(h, "#%02x%02x%02x", &r, &g, &b);
  return {r / 255.0, g / 255.0, b / 255.0};
}

constexpr double kFontSize = 13, kTitleSize = 15;

// A white picture with cairo drawing on it; png() encodes its pixels with io/png.hpp.
class Canvas {
 public:
  Canvas(int w, int h)
      : w_(w),
        h_(h),
        surface_(cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h), cairo_surface_destroy),
        cr_(cairo_create(surface_.get()), cairo_destroy) {
    cairo_set_source_rgb(cr(), 1, 1, 1);
    cairo_paint(cr());
    cairo_select_font_face(cr(), "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr(), kFontSize);
  }
  cairo_t* cr() const { return cr_.get(); }

  void colour(const Rgb& c) const { cairo_set_source_rgb(cr(), c.r, c.g, c.b); }

  // a crisp one-pixel line between pixel centres (horizontal or vertical)
  void hline(double x0, double x1, int y, const Rgb& c) const {
    colour(c);
    cairo_set_line_width(cr(), 1);
    cairo_move_to(cr(), x0, y + 0.5);
    cairo_line_to(cr(), x1, y + 0.5);
    cairo_stroke(cr());
  }
  void vline(int x, double y0, double y1, const Rgb& c) const {
    colour(c);
    cairo_set_line_width(cr(), 1);
    cairo_move_to(cr(), x + 0.5, y0);
    cairo_line_to(cr(), x + 0.5, y1);
    cairo_stroke(cr());
  }

  double text_width(const std::string& s, double size) const {
    cairo_set_font_size(cr(), size);
    cairo_text_extents_t e;
    cairo_text_extents(cr(), s.c_str(), &e);
    return e.x_advance;
  }
  // `s` (already displayable) cut with an ellipsis to at most `room` pixels
  std::string fit(std::string s, double size, double room) const {
    if (text_width(s, size) <= room) return s;
    while (!s.empty()) {
      do s.pop_back();  // whole UTF-8 sequences
      while (!s.empty() && (static_cast<unsigned char>(s.back()) & 0xC0) == 0x80);
      if (!s.empty()) s.pop_back();
      if (text_width(s + "\xE2\x80\xA6", size) <= room) return s + "\xE2\x80\xA6";
    }
    return s;
  }
  // text anchored at (x, y): ax, ay in {0, 0.5, 1} (left/centre/right, top/middle/baseline-ish)
  void text(double x, double y, const std::string& raw, double ax, double ay,
            double size = kFontSize, double room = 1e9, double angle = 0, bool bold = false,
            const Rgb& c = kBlack) const {
    if (raw.empty()) return;
    const std::string s = fit(displayable_text(raw), size, room);
    cairo_save(cr());
    cairo_select_font_face(cr(), "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr(), size);
    cairo_font_extents_t fe;
    cairo_font_extents(cr(), &fe);
    cairo_text_extents_t te;
    cairo_text_extents(cr(), s.c_str(), &te);
    cairo_translate(cr(), x, y);
    cairo_rotate(cr(), angle);
    colour(c);
    cairo_move_to(cr(), -ax * te.x_advance, fe.ascent - ay * (fe.ascent + fe.descent));
    cairo_show_text(cr(), s.c_str());
    cairo_restore(cr());
  }

  // The pixels as RGB bytes to io/png.hpp (atomic write; a write failure throws).
  void png(const std::string& path) const {
    cairo_surface_flush(surface_.get());
    if (cairo_status(cr()) != CAIRO_STATUS_SUCCESS)
      throw std::runtime_error(std::string("cairo: ") + cairo_status_to_string(cairo_status(cr())));
    const unsigned char* data = cairo_image_surface_get_data(surface_.get());
    const int stride = cairo_image_surface_get_stride(surface_.get());
    std::vector<uint8_t> px(static_cast<size_t>(w_) * h_ * 3);
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        uint32_t v;  // RGB24: one native-endian 32-bit word per pixel, 0x00RRGGBB
        std::memcpy(&v, data + static_cast<size_t>(y) * stride + 4 * static_cast<size_t>(x), 4);
        uint8_t* p = px.data() + 3 * (static_cast<size_t>(y) * w_ + x);
        p[0] = static_cast<uint8_t>(v >> 16), p[1] = static_cast<uint8_t>(v >> 8),
        p[2] = static_cast<uint8_t>(v);
      }
    write_png_rgb(path, w_, h_, px);
  }

 private:
  int w_, h_;
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
  std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr_;
};

// An axis: the data interval [lo, hi] on the pixel interval [p0, p1] (linear or log10).
struct Axis {
  double lo = 0, hi = 1, p0 = 0, p1 = 1;
  bool log = false;
  double pixel(double v) const {
    const double a = log ? std::log10(lo) : lo, b = log ? std::log10(hi) : hi,
                 u = log ? std::log10(v) : v;
    return p0 + (u - a) / (b - a) * (p1 - p0);
  }
  bool drawable(double v) const { return std::isfinite(v) && (!log || v > 0); }
};

// 1, 2 or 5 × 10^k for about n steps over span
double nice_step(double span, int n) {
  const double raw = span / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * p >= raw * (1 - 1e-12)) return m * p;
  return 10 * p;
}

std::string number_label(double v, double step) {
  char b[40];
  if (std::abs(v) < 1e-9 * step) v = 0;
  const double a = std::max(std::abs(v), step);
  if (a >= 1e5 || a < 1e-3)
    std::snprintf(b, sizeof b, "%.3g", v);
  else
    std::snprintf(b, sizeof b, "%.*f",
                  std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9))), v);
  return b;
}

// tick values and their labels inside [lo, hi]
std::vector<std::pair<double, std::string>> ticks(const Axis& a, int n) {
  std::vector<std::pair<double, std::string>> t;
  if (a.log) {
    const int d0 = static_cast<int>(std::ceil(std::log10(a.lo) - 1e-9)),
              d1 = static_cast<int>(std::floor(std::log10(a.hi) + 1e-9));
    const int every = std::max(1, (d1 - d0 + 1 + 7) / 8);  // at most about 8 labels
    for (int d = d0; d <= d1; d += every) {
      char b[16];
      std::snprintf(b, sizeof b, "1e%d", d);
      t.emplace_back(std::pow(10.0, d), b);
    }
    if (t.size() < 2)  // less than a decade: 2 and 5 too
      for (int d = d0 - 1; d <= d1; ++d)
        for (double m : {2.0, 5.0})
          if (const double v = m * std::pow(10.0, d); v >= a.lo && v <= a.hi) {
            char b[16];
            std::snprintf(b, sizeof b, "%ge%d", m, d);
            t.emplace_back(v, b);
          }
    return t;
  }
  const double step = nice_step(a.hi - a.lo, n);
  for (double k = std::ceil(a.lo / step - 1e-9); k * step <= a.hi + 1e-9 * step; k += 1)
    t.emplace_back(k * step, number_label(k * step, step));
  return t;
}

// The frame of a plot area [x0, x1] × [y0, y1] (pixel rows/columns of its borders), light grid
// lines at the ticks, tick marks, and labels where asked.
void frame(const Canvas& cv, const Axis& x, const Axis& y, bool x_labels) {
  const int c0 = static_cast<int>(x.p0), c1 = static_cast<int>(x.p1);
  const int r0 = static_cast<int>(y.p1), r1 = static_cast<int>(y.p0);  // top, bottom rows
  for (const auto& [v, s] : ticks(x, 8)) {
    const int c = static_cast<int>(std::lround(x.pixel(v)));
    if (c > c0 && c < c1) cv.vline(c, r0 + 1, r1, kGrid);
    cv.vline(c, r1 - 5, r1, kBlack);
    if (x_labels) cv.text(c + 0.5, r1 + 6, s, 0.5, 0);
  }
  for (const auto& [v, s] : ticks(y, 5)) {
    const int r = static_cast<int>(std::lround(y.pixel(v)));
    if (r > r0 && r < r1) cv.hline(c0 + 1, c1, r, kGrid);
    cv.hline(c0, c0 + 6, r, kBlack);
    cv.text(c0 - 6, r + 0.5, s, 1, 0.5);
  }
  cv.hline(c0, c1 + 1, r0, kBlack);
  cv.hline(c0, c1 + 1, r1, kBlack);
  cv.vline(c0, r0, r1 + 1, kBlack);
  cv.vline(c1, r0, r1 + 1, kBlack);
}

// a vertical axis title left of the tick labels, centred on the rows [r0, r1]
void ylabel(const Canvas& cv, const std::string& s, int r0, int r1) {
  cv.text(14, 0.5 * (r0 + r1), s, 0.5, 0, kFontSize, r1 - r0 + 40, -std::numbers::pi / 2);
}

void set_dash(cairo_t* cr, int dash) {
  static const double kDashed[] = {6, 4}, kDotted[] = {1.5, 3};
  if (dash == 1) cairo_set_dash(cr, kDashed, 2, 0);
  if (dash == 2) cairo_set_dash(cr, kDotted, 2, 0);
}

// A series' polyline (breaks at points it cannot draw) and markers, clipped to the plot area.
void draw_series(const Canvas& cv, const Axis& x, const Axis& y, const std::vector<double>& xs,
                 const std::vector<double>& ys, const Rgb& c, bool lines, bool points, int dash) {
  cairo_t* cr = cv.cr();
  cairo_save(cr);
  cairo_rectangle(cr, x.p0 + 1, y.p1 + 1, x.p1 - x.p0 - 1, y.p0 - y.p1 - 1);
  cairo_clip(cr);
  cv.colour(c);
  cairo_set_line_width(cr, 1.5);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  set_dash(cr, dash);
  const size_t n = std::min(xs.size(), ys.size());
  if (lines) {
    bool open = false;
    for (size_t i = 0; i < n; ++i) {
      if (!x.drawable(xs[i]) || !y.drawable(ys[i])) {
        open = false;
        continue;
      }
      const double px = x.pixel(xs[i]), py = y.pixel(ys[i]);
      if (open)
        cairo_line_to(cr, px, py);
      else
        cairo_move_to(cr, px, py);
      open = true;
    }
    cairo_stroke(cr);
  }
  if (points) {
    cairo_set_dash(cr, nullptr, 0, 0);
    for (size_t i = 0; i < n; ++i)
      if (x.drawable(xs[i]) && y.drawable(ys[i])) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, x.pixel(xs[i]), y.pixel(ys[i]), 2.6, 0, 2 * std::numbers::pi);
      }
    cairo_fill(cr);
  }
  cairo_restore(cr);
}

// Legend entries in the right margin from (x, y) down: a line sample in the series' colour,
// then its title cut to the room left
struct Key {
  std::string title;
  Rgb c;
  int dash = 0;
  bool box = false;
};
void legend(const Canvas& cv, double x, double y, double room, const std::vector<Key>& keys) {
  for (const auto& k : keys) {
    cairo_t* cr = cv.cr();
    cairo_save(cr);
    cv.colour(k.c);
    if (k.box) {
      cairo_rectangle(cr, x, y - 6, 22, 12);
      cairo_fill(cr);
    } else {
      cairo_set_line_width(cr, 2);
      set_dash(cr, k.dash);
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + 22, y);
      cairo_stroke(cr);
    }
    cairo_restore(cr);
    cv.text(x + 28, y, k.title, 0, 0.5, kFontSize, room - 28);
    y += 19;
  }
}

// [lo, hi] of the drawable values, or false
bool extent(const std::vector<const std::vector<double>*>& vs, bool log, double& lo, double& hi) {
  lo = INFINITY, hi = -INFINITY;
  for (const auto* v : vs)
    for (double a : *v)
      if (std::isfinite(a) && (!log || a > 0)) lo = std::min(lo, a), hi = std::max(hi, a);
  return hi >= lo;
}

// a range with room: log axes to whole decades, linear ones padded by 5 % (or around a constant)
void widen(double& lo, double& hi, bool log) {
  if (log) {
    lo = std::pow(10.0, std::floor(std::log10(lo) + 1e-12));
    hi = std::pow(10.0, std::ceil(std::log10(hi) - 1e-12));
    if (hi <= lo) hi = 10 * lo;
    return;
  }
  const double pad = hi > lo ? 0.05 * (hi - lo) : lo != 0 ? 0.05 * std::abs(lo) : 1.0;
  lo -= pad, hi += pad;
}

}  // namespace

bool plot(const PlotSpec& s) {
  std::vector<const std::vector<double>*> xs, ys;
  for (const auto& ser : s.series) xs.push_back(&ser.x), ys.push_back(&ser.y);
  double x0, x1, y0, y1;
  if (!extent(xs, s.logx, x0, x1) || !extent(ys, s.logy, y0, y1)) return false;
  widen(x0, x1, s.logx);
  if (s.ymax > s.ymin && (!s.logy || s.ymin > 0))
    y0 = s.ymin, y1 = s.ymax;
  else
    widen(y0, y1, s.logy);
  if (!s.logx && x1 == x0) widen(x0, x1, false);
  Canvas cv(s.width, s.height);
  const Axis x{x0, x1, double(PlotSpec::kLeft), double(s.width - PlotSpec::kRight), s.logx};
  const Axis y{y0, y1, double(s.height - PlotSpec::kBottom), double(PlotSpec::kTop), s.logy};
  frame(cv, x, y, true);
  std::vector<Key> keys;
  for (size_t k = 0; k < s.series.size(); ++k) {
    const auto& ser = s.series[k];
    const Rgb c = ser.reference ? kReference : colour(static_cast<int>(k));
    draw_series(cv, x, y, ser.x, ser.y, c, ser.lines, ser.points, ser.dash);
    keys.push_back({ser.title, c, ser.dash});
  }
  cv.text(0.5 * (x.p0 + x.p1), 12, s.title, 0.5, 0, kTitleSize, s.width - 20, 0, true);
  cv.text(0.5 * (x.p0 + x.p1), s.height - 26, s.xlabel, 0.5, 0, kFontSize, x.p1 - x.p0);
  ylabel(cv, s.ylabel, PlotSpec::kTop, s.height - PlotSpec::kBottom);
  legend(cv, x.p1 + 14, PlotSpec::kTop + 10, PlotSpec::kRight - 20, keys);
  cv.png(s.png);
  return true;
}

bool plot_panels(const PanelPlotSpec& s, const std::vector<std::vector<double>>& rows) {
  using P = PanelPlotSpec;
  if (s.panels.empty() || rows.size() < 2) return false;
  const int np = static_cast<int>(s.panels.size());
  const int W = s.width, H = P::kTop + P::kBottom + np * s.panel_height + (np - 1) * P::kGap;
  const double x0 = rows.front()[0], x1 = rows.back()[0];
  if (!(x1 > x0)) return false;
  Canvas cv(W, H);
  std::vector<double> xs;
  for (const auto& r : rows) xs.push_back(r[0]);
  for (int i = 0; i < np; ++i) {
    const Panel& p = s.panels[i];
    std::vector<std::vector<double>> cols;
    for (const auto& ser : p.series) {
      auto& col = cols.emplace_back();
      for (const auto& r : rows) col.push_back(r[static_cast<size_t>(ser.column - 1)]);
    }
    std::vector<const std::vector<double>*> vs;
    for (const auto& c : cols) vs.push_back(&c);
    double lo, hi;
    if (!extent(vs, false, lo, hi)) lo = -1, hi = 1;  // nothing finite
    widen(lo, hi, false);
    const int top = P::kTop + i * (s.panel_height + P::kGap), bottom = top + s.panel_height;
    const Axis x{x0, x1, double(P::kLeft), double(W - P::kRight), false};
    const Axis y{lo, hi, double(bottom), double(top), false};
    frame(cv, x, y, i + 1 == np);
    std::vector<Key> keys;
    for (size_t k = 0; k < cols.size(); ++k) {
      const Rgb c = colour(static_cast<int>(k));
      draw_series(cv, x, y, xs, cols[k], c, true, s.points, 0);
      keys.push_back({p.series[k].title, c});
    }
    ylabel(cv, p.ylabel, top, bottom);
    legend(cv, x.p1 + 14, top + 10, P::kRight - 20, keys);
  }
  cv.text(0.5 * (P::kLeft + W - P::kRight), 12, s.title, 0.5, 0, kTitleSize, W - 20, 0, true);
  cv.text(0.5 * (P::kLeft + W - P::kRight), H - 26, s.xlabel, 0.5, 0);
  cv.png(s.png);
  return true;
}

bool plot_bars(const BarChartSpec& s) {
  using B = BarChartSpec;
  if (s.groups.empty() || s.series.empty() || s.values.size() != s.series.size()) return false;
  double lo = 0, hi = 0;
  for (const auto& v : s.values)
    for (double x : v)
      if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  if (!(hi > lo)) hi = 1;
  const double pad = 0.1 * (hi - lo);
  Canvas cv(s.width, s.height);
  const double ng = static_cast<double>(s.groups.size());
  // the x axis holds the groups 0 … ng−1 at unit spacing, half a unit of room at both ends
  const Axis x{-0.5, ng - 0.5, double(B::kLeft), double(s.width - B::kRight), false};
  const Axis y{lo - pad, hi + pad, double(s.height - B::kBottom), double(B::kTop), false};
  // the frame without x ticks: the group labels stand for them
  {
    for (const auto& [v, t] : ticks(y, 5)) {
      const int r = static_cast<int>(std::lround(y.pixel(v)));
      if (r > y.p1 && r < y.p0) cv.hline(x.p0 + 1, x.p1, r, kGrid);
      cv.hline(static_cast<int>(x.p0), x.p0 + 6, r, kBlack);
      cv.text(x.p0 - 6, r + 0.5, t, 1, 0.5);
    }
    const int c0 = static_cast<int>(x.p0), c1 = static_cast<int>(x.p1);
    const int r0 = static_cast<int>(y.p1), r1 = static_cast<int>(y.p0);
    cv.hline(c0, c1 + 1, r0, kBlack);
    cv.hline(c0, c1 + 1, r1, kBlack);
    cv.vline(c0, r0, r1 + 1, kBlack);
    cv.vline(c1, r0, r1 + 1, kBlack);
  }
  const double ns = static_cast<double>(s.series.size()), slot = 0.8 / ns;
  std::vector<Key> keys;
  for (size_t k = 0; k < s.series.size(); ++k) {
    const Rgb c = colour(static_cast<int>(k));
    for (size_t g = 0; g < s.groups.size() && g < s.values[k].size(); ++g) {
      const double v = s.values[k][g];
      if (!std::isfinite(v)) continue;
      const double a = x.pixel(g - 0.4 + k * slot), b = x.pixel(g - 0.4 + (k + 1) * slot);
      const double p0 = y.pixel(0), p1 = y.pixel(v);
      cv.colour(c);
      cairo_rectangle(cv.cr(), std::round(a) + 1, std::min(p0, p1),
                      std::round(b) - std::round(a) - 1, std::abs(p1 - p0));
      cairo_fill(cv.cr());
    }
    keys.push_back({s.series[k], c, false, true});
  }
  cv.hline(x.p0, x.p1, static_cast<int>(std::lround(y.pixel(0))), kBlack);  // y = 0
  for (size_t g = 0; g < s.groups.size(); ++g) {  // labels turned by 30°, ending under the group
    const double end = x.pixel(static_cast<double>(g)) + 4;
    const double room = std::min((B::kBottom - 12) / 0.5, end / std::cos(std::numbers::pi / 6) - 4);
    cv.text(end, y.p0 + 8, s.groups[g], 1, 0, kFontSize, room, -std::numbers::pi / 6);
  }
  cv.text(0.5 * (x.p0 + x.p1), 12, s.title, 0.5, 0, kTitleSize, s.width - 20, 0, true);
  ylabel(cv, s.ylabel, B::kTop, s.height - B::kBottom);
  legend(cv, x.p1 + 14, B::kTop + 10, B::kRight - 20, keys);
  cv.png(s.png);
  return true;
}

}  // namespace lsmbs
