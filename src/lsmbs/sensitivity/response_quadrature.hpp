#pragma once
// ResponseQuadrature — the case's time-integral responses as IDAS quadratures: for a
// response of kind integral, average, average_eq45 or rms over the window [a, b] of measure f,
//   Q(t) = ∫ f dt (f² for rms),  integral = Q(b) − Q(a),  average = (Q(b) − Q(a)) / (b − a),
//   rms = sqrt((Q(b) − Q(a)) / (b − a)),
// with dQ/dp from IDAQuadSensInit (eq. 24 inside the integral). These are the continuous-time
// values that the generalized-α grid aggregates approximate: the trapezoidal `integral` at
// O(h²), the sample means `average`/`rms` (eq. 45 is a sum over steps) at O(h).
#include <map>
#include <string>
#include <vector>

#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

class ResponseQuadrature : public IdasQuadrature {
 public:
  /// directions: ∂(ModelParams)/∂p_i (empty for values only); params: the run's model parameters.
  /// Run from t_start to t_end.
  ResponseQuadrature(const Study& cs, std::vector<ParamDirection> directions,
                     const ModelParams& params, double t_start, double t_end);
  /// Whether the case has any time-integral response.
  bool empty() const { return responses_.empty(); }

  int size() const override { return static_cast<int>(responses_.size()); }
  std::vector<double> breakpoints() const override;
  void integrand(const State& s, const ModelParams& p, double* g) override;
  void integrand_sensitivity(const State& s, const ModelParams& p, const Mat& dq, const Mat& dv,
                             const Mat& da, const Mat& dl, Mat& dg) override;
  void on_breakpoint(double t, const Vec& Q, const Mat* dQ) override;
  /// Adjoint path: ∂g/∂q, ∂g/∂q̇ (2 f ∂f for rms) and the explicit ∂g/∂p; refuses measures of
  /// accelerations or multipliers (constraint forces).
  bool integrand_gradient(int k, const State& s, const ModelParams& p, Vec& gq, Vec& gv,
                          Eigen::RowVectorXd& gp, std::string& why) override;
  /// dQ_k/dp at the window's ends (not at the run's start, where Q = 0).
  bool needs_gradient(int k, double t) const override;

  /// The responses from the recorded Q (call after the run).
  std::vector<QuadratureResponse> results() const;

 private:
  struct Item {
    size_t response;  ///< index in cs.responses
    bool square;      ///< rms: ∫ f²
    double a, b;      ///< window clipped to [t_start, t_end]
  };
  const Study& cs_;
  ResponseTracker tracker_;
  std::vector<Item> responses_;
  double t_start_, t_end_;
  int nv_;
  std::map<double, std::pair<Vec, Mat>> at_;  ///< t → (Q, dQ/dp)
  Eigen::RowVectorXd row_;
  MeasureGradient partials_;
};

}  // namespace lsmbs
