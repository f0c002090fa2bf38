#include "lsmbs/mbs/table.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

Table1D::Table1D(std::vector<double> x, std::vector<double> y, Interp interp, double period)
    : x_(std::move(x)), y_(std::move(y)), interp_(interp), period_(period) {
  const size_t n = x_.size();
  if (n < 2 || y_.size() != n) throw Error("table: expected at least two (x, y) points of equal count");
  for (size_t i = 0; i + 1 < n; ++i)
    if (!(x_[i + 1] > x_[i])) throw Error("table: x values must be strictly increasing");
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(x_[i]) || !std::isfinite(y_[i])) throw Error("table: non-finite value");
  m_.assign(n, 0.0);
  if (interp_ == Interp::kCubic && n > 2) {  // natural spline: tridiagonal solve (Thomas)
    std::vector<double> a(n, 0), b(n, 1), c(n, 0), d(n, 0);
    for (size_t i = 1; i + 1 < n; ++i) {
      const double h0 = x_[i] - x_[i - 1], h1 = x_[i + 1] - x_[i];
      a[i] = h0 / 6;
      b[i] = (h0 + h1) / 3;
      c[i] = h1 / 6;
      d[i] = (y_[i + 1] - y_[i]) / h1 - (y_[i] - y_[i - 1]) / h0;
    }
    for (size_t i = 1; i < n; ++i) {
      const double w = a[i] / b[i - 1];
      b[i] -= w * c[i - 1];
      d[i] -= w * d[i - 1];
    }
    m_[n - 1] = d[n - 1] / b[n - 1];
    for (size_t i = n - 1; i-- > 0;) m_[i] = (d[i] - c[i] * m_[i + 1]) / b[i];
  }
}

Table1D Table1D::read_csv(const std::string& path, Interp interp, double period, double xs, double ys) {
  std::ifstream f(path);
  if (!f) throw Error(path, "", "cannot open table file");
  std::vector<double> x, y;
  std::string line;
  int ln = 0;
  while (std::getline(f, line)) {
    ++ln;
    if (auto h = line.find('#'); h != std::string::npos) line.resize(h);
    for (char& ch : line)
      if (ch == ',' || ch == ';' || ch == '\t') ch = ' ';
    std::istringstream is(line);
    double a, b;
    if (!(is >> a)) {
      if (line.find_first_not_of(" \r") == std::string::npos || (x.empty() && ln == 1)) continue;  // blank/header
      throw Error(path, "line " + std::to_string(ln), "expected two numbers");
    }
    if (!(is >> b)) throw Error(path, "line " + std::to_string(ln), "expected two numbers");
    x.push_back(a * xs);
    y.push_back(b * ys);
  }
  try {
    return Table1D(std::move(x), std::move(y), interp, period);
  } catch (const Error& e) {
    throw Error(path, "", e.what());
  }
}

void Table1D::eval(double x, double& v, double& d1, double& d2) const {
  if (period_ > 0) x = x_.front() + std::fmod(std::fmod(x - x_.front(), period_) + period_, period_);
  if (x <= x_.front() || x >= x_.back()) {
    v = x <= x_.front() ? y_.front() : y_.back();
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
  v = A * y_[i] + B * y_[i + 1] + ((A * A * A - A) * m_[i] + (B * B * B - B) * m_[i + 1]) * h * h / 6;
  d1 = (y_[i + 1] - y_[i]) / h - (3 * A * A - 1) / 6 * h * m_[i] + (3 * B * B - 1) / 6 * h * m_[i + 1];
  d2 = A * m_[i] + B * m_[i + 1];
}

}  // namespace lsmbs
