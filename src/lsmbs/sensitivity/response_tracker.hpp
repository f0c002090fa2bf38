#pragma once
// ResponseTracker — evaluates the case's response measures at every grid step and, when
// state derivatives are available, their total derivatives (eq. 24):
//   df_n/dp_i = ∂f/∂q q_,i + ∂f/∂q̇ q̇_,i + ∂f/∂q̈ q̈_,i + ∂f/∂λ λ_,i + ∂f/∂p_i,
// then aggregates them into the responses' values and gradients.
#include <vector>

#include "lsmbs/sensitivity/sensitivity.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

class ResponseTracker {
 public:
  /// directions[i] = ∂(ModelParams)/∂p_i (for the explicit ∂f/∂p); empty for values only.
  /// `params`: the parameters of the run (the design's), which record() is given.
  ResponseTracker(const Study& cs, std::vector<ParamDirection> directions,
                  const ModelParams& params);
  /// Records the columns used by responses at a grid step; derivatives may be null.
  void record(const State& s, const ModelParams& p, const Mat* dq, const Mat* dv, const Mat* da,
              const Mat* dl);
  std::vector<ResponseSensitivity> results() const;
  /// Response r aggregated from the recorded values (no gradient): its value and the weights
  /// ∂(value)/∂f_n of the recorded grid steps (aggregation.hpp).
  Aggregate aggregate_response(size_t r) const;
  /// Number of grid steps recorded.
  size_t recorded() const { return times_.size(); }
  /// The run's constraint scaling k (constraint forces are kλ; 1 for physical multipliers).
  void set_scaling(double k) { k_ = k; }
  /// Value of response r's measure component at s and, with the state derivatives, its total
  /// derivative (eq. 24) in `grad` (1 × n_v). Not recorded.
  double response_measure(size_t r, const State& s, const ModelParams& p, const Mat* dq,
                          const Mat* dv, const Mat* da, const Mat* dl, Eigen::RowVectorXd* grad);
  /// Value of response r's measure component at s, its state partials in `g` and its explicit
  /// ∂f/∂p in `gp` (1 × n_v) — the pieces of an adjoint source term. Not recorded.
  double response_partials(size_t r, const State& s, const ModelParams& p, MeasureGradient& g,
                           Eigen::RowVectorXd& gp);

 private:
  const Study& cs_;
  std::vector<ParamDirection> dirs_;
  struct Column {
    const Measure* measure;
    int component;
    std::vector<double> values;
    std::vector<Eigen::RowVectorXd> grads;
  };
  double evaluate(const Measure* measure, int component, const State& s, const ModelParams& p,
                  const Mat* dq, const Mat* dv, const Mat* da, const Mat* dl,
                  Eigen::RowVectorXd* grad);
  // the measure's values and state partials, constraint forces with this run's k
  void values(const Measure* measure, const State& s, const ModelParams& p, double* out) const;
  void partials(const Measure* measure, const State& s, const ModelParams& p, int component,
                MeasureGradient& g) const;
  std::vector<Column> cols_;
  MeasureGradient grad_;
  std::vector<int> response_column_;
  std::vector<double> times_;
  ModelParams scratch_;
  double k_ = 1;
  Mat zero_q_, zero_l_;  // zero state derivatives: the explicit ∂f/∂p alone
  mutable std::vector<double> buf_;
  Vec df_dmu_;  ///< ∂f/∂μ_e of a measure that gives it exactly
};

}  // namespace lsmbs
