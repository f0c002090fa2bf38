#pragma once
// Table1D — tabulated function y(x) with smooth (cubic spline, C²) or linear interpolation,
// first and second derivatives, optional periodic wrap of x. Used for tabulated driver laws,
// forces and pressure curves. Without a period the cubic spline is natural (zero second
// derivative at both ends); with a period it is the periodic spline (equal first and second
// derivatives at x0 and x0 + period), so that the wrapped function is C² everywhere.
#include <string>
#include <vector>

namespace lsmbs {

class Table1D {
 public:
  enum class Interp { kCubic, kLinear };
  Table1D() = default;
  /// x strictly increasing, at least 2 points. period > 0 wraps x into [x0, x0 + period): the
  /// points must then lie within one period; the last point may be x0 + period (within 1e-9 of
  /// the period), in which case its value must equal y0 (within 1e-9 of the largest |y|),
  /// otherwise the point (x0 + period, y0) is appended. Violations throw Error.
  Table1D(std::vector<double> x, std::vector<double> y, Interp interp = Interp::kCubic,
          double period = 0);
  /// Reads two columns (x, y) from a CSV file; '#' starts a comment; an optional header line.
  static Table1D read_csv(const std::string& path, Interp interp = Interp::kCubic,
                          double period = 0, double x_scale = 1, double y_scale = 1);

  double value(double x) const {
    double v, d1, d2;
    eval(x, v, d1, d2);
    return v;
  }
  /// Beyond the ends (without period) the value is held constant and derivatives are zero. At a
  /// knot (the first point included) the derivatives are right-sided: those of the interval that
  /// starts there.
  void eval(double x, double& v, double& d1, double& d2) const;
  bool empty() const { return x_.empty(); }
  double x_min() const { return x_.front(); }
  double x_max() const { return x_.back(); }
  /// Appends the x in (a, b) where the interpolant is not C² (the knots of a linear table, the
  /// ends of a non-periodic one where it is held constant), repeated over periods.
  void kinks(double a, double b, std::vector<double>& out) const;

 private:
  std::vector<double> x_, y_, m_;  // m_: second derivatives at the knots
  Interp interp_ = Interp::kCubic;
  double period_ = 0;
};

}  // namespace lsmbs
