#pragma once
// TimeLaw — a prescribed motion s(t) with ṡ and s̈ for drivers: constant-acceleration
// trapezoid (accelerate / constant speed / decelerate, the robot joints of §6), speed ramp
// then constant speed (the crank of §5), or a tabulated law (cubic spline). Laws expose named
// phases so that responses can be aggregated "over the constant-speed phase" (eq. 45).
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/mbs/table.hpp"

namespace lsmbs {

struct Phase {
  std::string name;
  double t0 = 0, t1 = 0;
};

class TimeLaw {
 public:
  virtual ~TimeLaw() = default;
  /// s(t), ṡ(t), s̈(t). Where a derivative jumps (a phase switch, a table knot, the start of the
  /// law) it is the right-sided one, the value after t: the initial velocities and accelerations
  /// of a run starting there are those of the motion that follows.
  virtual void eval(double t, double& s, double& sd, double& sdd) const = 0;
  virtual std::vector<Phase> phases() const { return {}; }
  /// Appends the times in (t0, t1) where s̈ is discontinuous (phase boundaries, table knots):
  /// IDAS stops there instead of stepping across.
  virtual void kinks(double t0, double t1, std::vector<double>& out) const {
    for (const Phase& p : phases())
      for (double t : {p.t0, p.t1})
        if (t > t0 && t < t1) out.push_back(t);
  }
  double value(double t) const {
    double s, sd, sdd;
    eval(t, s, sd, sdd);
    return s;
  }
};

/// From s0 to s1 with |acceleration| = accel and cruise speed = speed, starting at t_start.
/// If the distance is too short to reach the cruise speed the profile is triangular.
class TrapezoidLaw : public TimeLaw {
 public:
  TrapezoidLaw(double s0, double s1, double accel, double speed, double t_start = 0);
  void eval(double t, double& s, double& sd, double& sdd) const override;
  std::vector<Phase> phases() const override;
  double end_time() const { return t_start_ + 2 * ta_ + tc_; }

 private:
  double s0_, dir_, a_, v_, t_start_, ta_, tc_;
};

/// Speed ramps linearly from 0 to `speed` in `ramp_time`, then stays constant.
class RampLaw : public TimeLaw {
 public:
  RampLaw(double s0, double speed, double ramp_time, double t_start = 0);
  void eval(double t, double& s, double& sd, double& sdd) const override;
  std::vector<Phase> phases() const override;

 private:
  double s0_, v_, tr_, t_start_;
};

class TabulatedLaw : public TimeLaw {
 public:
  explicit TabulatedLaw(Table1D table) : table_(std::move(table)) {}
  void eval(double t, double& s, double& sd, double& sdd) const override {
    table_.eval(t, s, sd, sdd);
  }
  void kinks(double t0, double t1, std::vector<double>& out) const override {
    table_.kinks(t0, t1, out);
  }

 private:
  Table1D table_;
};

/// Another law shifted by a constant, s(t) = law(t) + shift, with its phases and kinks: a
/// planar law of absolute angles driving a spatial joint's angle, which is zero at assembly.
class ShiftedLaw : public TimeLaw {
 public:
  ShiftedLaw(std::shared_ptr<const TimeLaw> law, double shift)
      : law_(std::move(law)), shift_(shift) {}
  void eval(double t, double& s, double& sd, double& sdd) const override {
    law_->eval(t, s, sd, sdd);
    s += shift_;
  }
  std::vector<Phase> phases() const override { return law_->phases(); }
  void kinks(double t0, double t1, std::vector<double>& out) const override {
    law_->kinks(t0, t1, out);
  }

 private:
  std::shared_ptr<const TimeLaw> law_;
  double shift_;
};

class ConstantLaw : public TimeLaw {
 public:
  explicit ConstantLaw(double s0) : s0_(s0) {}
  void eval(double, double& s, double& sd, double& sdd) const override {
    s = s0_;
    sd = sdd = 0;
  }

 private:
  double s0_;
};

}  // namespace lsmbs
