#include "lsmbs/mbs/table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string_view>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/file_check.hpp"
#include "lsmbs/core/text.hpp"

namespace lsmbs {

namespace {

// Solves the tridiagonal system (sub-diagonal a, diagonal b, super-diagonal c) in place of d
// (Thomas algorithm; a[0] and c[n−1] are not read).
void thomas(const std::vector<double>& a, std::vector<double> b, const std::vector<double>& c,
            std::vector<double>& d) {
  const size_t n = b.size();
  for (size_t i = 1; i < n; ++i) {
    const double w = a[i] / b[i - 1];
    b[i] -= w * c[i - 1];
    d[i] -= w * d[i - 1];
  }
  d[n - 1] /= b[n - 1];
  for (size_t i = n - 1; i-- > 0;) d[i] = (d[i] - c[i] * d[i + 1]) / b[i];
}

// Second derivatives m of the natural cubic spline through (x, y): m_0 = m_{n−1} = 0 and the
// continuity of the first derivative at the interior knots.
std::vector<double> natural_spline(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  if (n <= 2) return std::vector<double>(n, 0.0);
  std::vector<double> a(n, 0), b(n, 1), c(n, 0), d(n, 0);
  for (size_t i = 1; i + 1 < n; ++i) {
    const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
    a[i] = h0 / 6;
    b[i] = (h0 + h1) / 3;
    c[i] = h1 / 6;
    d[i] = (y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0;
  }
  thomas(a, b, c, d);
  return d;
}

// Second derivatives of the periodic cubic spline through (x, y) with x_{n−1} = x0 + period and
// y_{n−1} = y0: the N = n − 1 unknowns m_0 … m_{N−1} (m_{n−1} = m_0) satisfy the continuity of
// the first derivative at every knot, knot 0 included (its left neighbour is knot N − 1, one
// period earlier). The system is cyclic tridiagonal, symmetric and diagonally dominant; it is
// solved by the Sherman–Morrison correction of the Thomas algorithm (Numerical Recipes §2.7).
std::vector<double> periodic_spline(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size(), N = n - 1;
  std::vector<double> m(n, 0.0);
  if (N < 2) return m;  // one interval with equal end values: the constant y0
  std::vector<double> a(N), b(N), c(N), d(N);
  for (size_t i = 0; i < N; ++i) {
    const size_t im = (i + N - 1) % N;  // left neighbour of knot i
    const double h0 = x[im + 1] - x[im], h1 = x[i + 1] - x[i];
    a[i] = h0 / 6;
    b[i] = (h0 + h1) / 3;
    c[i] = h1 / 6;
    d[i] = (y[i + 1] - y[i]) / h1 - (y[im + 1] - y[im]) / h0;
  }
  if (N == 2) {  // both neighbours of each knot are the other knot: a 2 × 2 system
    const double a01 = a[0] + c[0], a10 = a[1] + c[1], det = b[0] * b[1] - a01 * a10;
    m[0] = (d[0] * b[1] - a01 * d[1]) / det;
    m[1] = (b[0] * d[1] - a10 * d[0]) / det;
    m[2] = m[0];
    return m;
  }
  // The corners are A(0, N−1) = β = a_0 and A(N−1, 0) = α = c_{N−1}. A = T + u vᵀ with
  // u = (γ, 0, …, 0, α), v = (1, 0, …, 0, β/γ) and T tridiagonal with the diagonal ends changed
  // by −γ and −αβ/γ; x = T⁻¹d − (vᵀT⁻¹d)/(1 + vᵀT⁻¹u) T⁻¹u.
  const double alpha = c[N - 1], beta = a[0], gamma = -b[0];
  std::vector<double> bb = b;
  bb[0] -= gamma;
  bb[N - 1] -= alpha * beta / gamma;
  std::vector<double> u(N, 0.0);
  u[0] = gamma;
  u[N - 1] = alpha;
  thomas(a, bb, c, d);
  thomas(a, bb, c, u);
  const double fact = (d[0] + beta * d[N - 1] / gamma) / (1 + u[0] + beta * u[N - 1] / gamma);
  for (size_t i = 0; i < N; ++i) m[i] = d[i] - fact * u[i];
  m[N] = m[0];
  return m;
}

}  // namespace

Table1D::Table1D(std::vector<double> x, std::vector<double> y, Interp interp, double period)
    : x_(std::move(x)), y_(std::move(y)), interp_(interp), period_(period) {
  const size_t n = x_.size();
  if (n < 2 || y_.size() != n)
    throw Error("table: expected at least two (x, y) points of equal count");
  for (size_t i = 0; i + 1 < n; ++i)
    if (!(x_[i + 1] > x_[i])) throw Error("table: x values must be strictly increasing");
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(x_[i]) || !std::isfinite(y_[i])) throw Error("table: non-finite value");
  if (period_ > 0) {
    // One period [x0, x0 + period]: the closing point is the first point one period later.
    const double x_end = x_.front() + period_, tol_x = 1e-9 * period_;
    double y_max = 0;
    for (double v : y_) y_max = std::max(y_max, std::abs(v));
    char buf[200];
    if (x_.back() > x_end + tol_x) {
      std::snprintf(buf, sizeof buf,
                    "table: the points span %.17g, more than the period %.17g (x0 = %.17g)",
                    x_.back() - x_.front(), period_, x_.front());
      throw Error(buf);
    }
    if (x_.back() >= x_end - tol_x) {
      if (std::abs(y_.back() - y_.front()) > 1e-9 * y_max) {
        std::snprintf(buf, sizeof buf,
                      "table: a periodic table must end with its first value: s(x0) = %.17g but "
                      "s(x0 + period) = "
                      "%.17g",
                      y_.front(), y_.back());
        throw Error(buf);
      }
      if (x_[x_.size() - 2] >= x_end) throw Error("table: x values must be strictly increasing");
      x_.back() = x_end;
      y_.back() = y_.front();
    } else {
      x_.push_back(x_end);
      y_.push_back(y_.front());
    }
  }
  if (interp_ == Interp::kCubic)
    m_ = period_ > 0 ? periodic_spline(x_, y_) : natural_spline(x_, y_);
  else
    m_.assign(x_.size(), 0.0);
}

Table1D Table1D::read_csv(const std::string& path, Interp interp, double period, double xs,
                          double ys) {
  if (const auto why = unreadable_file_reason(path); !why.empty())
    throw Error(path, "", "table file: " + why);
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, "", "cannot open table file");
  std::vector<double> x, y;
  std::vector<int> lines;  // of each point, for messages
  std::string line;
  int ln = 0;
  while (std::getline(f, line)) {
    ++ln;
    const std::string at = "line " + std::to_string(ln);
    std::string_view text(line);
    if (ln == 1 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // a UTF-8 BOM
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    if (const auto h = text.find('#'); h != std::string_view::npos) text = text.substr(0, h);
    // Fields are separated by commas or semicolons when the line has one (blanks around them
    // are not part of the field), else by tabs (each tab: a TSV cell may be empty), else by
    // runs of spaces. Each field must be a number as a whole: "0, 1 2" is (0, '1 2'), refused,
    // not (0, 1).
    std::vector<std::string_view> fields;
    const bool csv = text.find_first_of(",;") != std::string_view::npos;
    if (csv || text.find('\t') != std::string_view::npos) {
      const char* seps = csv ? ",;" : "\t";
      const char* blanks = csv ? " \t" : " ";
      for (size_t b = 0;;) {
        const size_t e = std::min(text.find_first_of(seps, b), text.size());
        std::string_view fld = text.substr(b, e - b);
        const size_t first = fld.find_first_not_of(blanks);
        fld = first == std::string_view::npos
                  ? std::string_view()
                  : fld.substr(first, fld.find_last_not_of(blanks) - first + 1);
        fields.push_back(fld);
        if (e == text.size()) break;
        b = e + 1;
      }
      // empty trailing fields ("0,1,") are empty spreadsheet columns, not data; a line of
      // separators only is an empty row
      while (!fields.empty() && fields.back().empty()) fields.pop_back();
    } else {
      fields = whitespace_fields(text);
    }
    if (fields.empty()) continue;  // blank or comment line
    std::vector<std::optional<double>> v;
    for (const auto fld : fields) v.push_back(parse_finite_double(fld));
    // a header: the first line, with no number in it and not starting like one
    const char c0 = fields[0].empty() ? ' ' : fields[0][0];
    if (ln == 1 && std::none_of(v.begin(), v.end(), [](const auto& o) { return o.has_value(); }) &&
        !(std::isdigit(static_cast<unsigned char>(c0)) || c0 == '-' || c0 == '+' || c0 == '.'))
      continue;
    if (fields.size() != 2) {
      std::string got;
      for (const auto fld : fields) got += (got.empty() ? "" : ", ") + shown(fld);
      throw Error(path, at,
                  "expected two numbers x, y (separated by a comma, semicolon, tab or spaces), "
                  "got " +
                      std::to_string(fields.size()) +
                      (fields.size() == 1 ? " field: " : " fields: ") + got);
    }
    for (size_t k = 0; k < 2; ++k)
      if (!v[k])
        throw Error(path, at,
                    std::string(k == 0 ? "x" : "y") + ": expected a finite number, got " +
                        shown(fields[k]) + " (the whole field must be a number: no units)");
    const double a = *v[0] * xs, b = *v[1] * ys;
    if (!std::isfinite(a) || !std::isfinite(b))
      throw Error(path, at,
                  std::string(std::isfinite(a) ? "y" : "x") +
                      " times its scale is beyond double range (x_scale, y_scale)");
    if (!x.empty() && !(a > x.back()))
      throw Error(path, at,
                  "x values must be strictly increasing: " + shown(fields[0]) +
                      " does not exceed the x of line " + std::to_string(lines.back()));
    x.push_back(a);
    y.push_back(b);
    lines.push_back(ln);
  }
  try {
    return Table1D(std::move(x), std::move(y), interp, period);
  } catch (const Error& e) {
    throw Error(path, "", e.what());
  }
}

void Table1D::eval(double x, double& v, double& d1, double& d2) const {
  if (period_ > 0)
    x = x_.front() + std::fmod(std::fmod(x - x_.front(), period_) + period_, period_);
  // Right-sided at every knot: the derivatives at x_k are those of the interval that starts
  // there, which is what a motion starting at x_k follows (the first point included: a law that
  // starts at t = 0 gives its initial velocity and acceleration their values after t = 0).
  if (x < x_.front() || x >= x_.back()) {
    v = x < x_.front() ? y_.front() : y_.back();
    d1 = d2 = 0;
    if (period_ <= 0) return;
  }
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  size_t i = std::clamp<size_t>(static_cast<size_t>(it - x_.begin()), 1, x_.size() - 1) - 1;
  const double h = x_[i + 1] - x_[i], A = (x_[i + 1] - x) / h, B = (x - x_[i]) / h;
  if (interp_ == Interp::kLinear) {
    v = A * y_[i] + B * y_[i + 1];
    d1 = (y_[i + 1] - y_[i]) / h;
    d2 = 0;
    return;
  }
  v = A * y_[i] + B * y_[i + 1] +
      ((A * A * A - A) * m_[i] + (B * B * B - B) * m_[i + 1]) * h * h / 6;
  d1 = (y_[i + 1] - y_[i]) / h - (3 * A * A - 1) / 6 * h * m_[i] +
       (3 * B * B - 1) / 6 * h * m_[i + 1];
  d2 = A * m_[i] + B * m_[i + 1];
}

void Table1D::kinks(double a, double b, std::vector<double>& out) const {
  if (x_.empty() || !(b > a)) return;
  std::vector<double> base;
  if (interp_ == Interp::kLinear)
    base = x_;
  else if (period_ <= 0)
    base = {x_.front(), x_.back()};
  if (period_ <= 0) {
    for (double x : base)
      if (x > a && x < b) out.push_back(x);
    return;
  }
  // periodic: x_k + j·period for every j that lands in (a, b)
  const double j0 = std::floor((a - x_.back()) / period_),
               j1 = std::ceil((b - x_.front()) / period_);
  for (double j = j0; j <= j1; ++j)
    for (double x : base)
      if (const double xj = x + j * period_; xj > a && xj < b) out.push_back(xj);
}

}  // namespace lsmbs
