#include "lsmbs/mbs/time_law.hpp"

#include <cmath>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

TrapezoidLaw::TrapezoidLaw(double s0, double s1, double accel, double speed, double t_start)
    : s0_(s0), dir_(s1 >= s0 ? 1.0 : -1.0), a_(accel), v_(speed), t_start_(t_start) {
  if (!(accel > 0) || !(speed > 0))
    throw Error("trapezoid law: acceleration and speed must be positive");
  const double dist = std::abs(s1 - s0);
  ta_ = v_ / a_;
  if (a_ * ta_ * ta_ > dist) {  // triangular profile
    ta_ = std::sqrt(dist / a_);
    v_ = a_ * ta_;
    tc_ = 0;
  } else {
    tc_ = (dist - a_ * ta_ * ta_) / v_;
  }
}

void TrapezoidLaw::eval(double t, double& s, double& sd, double& sdd) const {
  const double tau = t - t_start_;
  const double d_acc = 0.5 * a_ * ta_ * ta_;
  double u, ud, udd;
  if (tau < 0) {  // at tau = 0 the accelerating phase's s̈ (right-sided, as at every switch)
    u = ud = udd = 0;
  } else if (tau < ta_) {
    u = 0.5 * a_ * tau * tau, ud = a_ * tau, udd = a_;
  } else if (tau < ta_ + tc_) {
    u = d_acc + v_ * (tau - ta_), ud = v_, udd = 0;
  } else if (tau < 2 * ta_ + tc_) {
    const double r = 2 * ta_ + tc_ - tau;
    u = 2 * d_acc + v_ * tc_ - 0.5 * a_ * r * r, ud = a_ * r, udd = -a_;
  } else {
    u = 2 * d_acc + v_ * tc_, ud = udd = 0;
  }
  s = s0_ + dir_ * u;
  sd = dir_ * ud;
  sdd = dir_ * udd;
}

std::vector<Phase> TrapezoidLaw::phases() const {
  return {{"accelerate", t_start_, t_start_ + ta_},
          {"constant", t_start_ + ta_, t_start_ + ta_ + tc_},
          {"decelerate", t_start_ + ta_ + tc_, t_start_ + 2 * ta_ + tc_}};
}

RampLaw::RampLaw(double s0, double speed, double ramp_time, double t_start)
    : s0_(s0), v_(speed), tr_(ramp_time), t_start_(t_start) {
  if (!(ramp_time > 0)) throw Error("ramp law: ramp_time must be positive");
}

void RampLaw::eval(double t, double& s, double& sd, double& sdd) const {
  const double tau = t - t_start_;
  if (tau < 0) {  // at tau = 0 the ramp's s̈ (right-sided)
    s = s0_, sd = sdd = 0;
  } else if (tau < tr_) {
    s = s0_ + 0.5 * v_ / tr_ * tau * tau, sd = v_ / tr_ * tau, sdd = v_ / tr_;
  } else {
    s = s0_ + 0.5 * v_ * tr_ + v_ * (tau - tr_), sd = v_, sdd = 0;
  }
}

std::vector<Phase> RampLaw::phases() const {
  return {{"ramp", t_start_, t_start_ + tr_}, {"constant", t_start_ + tr_, 1e300}};
}

}  // namespace lsmbs
