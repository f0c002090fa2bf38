#include "lsmbs/sensitivity/response_tracker.hpp"

#include <algorithm>
#include <cmath>

namespace lsmbs {

ResponseTracker::ResponseTracker(const Study& cs, std::vector<ParamDirection> directions,
                                 const ModelParams& params)
    : cs_(cs), dirs_(std::move(directions)), scratch_(params) {
  // flattened measure columns → (measure, component)
  std::vector<std::pair<const Measure*, int>> flat;
  for (const auto& m : cs.measures)
    for (int c = 0; c < static_cast<int>(m->components().size()); ++c)
      flat.emplace_back(m.get(), c);
  for (const auto& r : cs.responses) {
    int found = -1;
    for (size_t k = 0; k < cols_.size(); ++k)
      if (cols_[k].measure == flat[r.column].first && cols_[k].component == flat[r.column].second)
        found = static_cast<int>(k);
    if (found < 0) {
      cols_.push_back({flat[r.column].first, flat[r.column].second, {}, {}});
      found = static_cast<int>(cols_.size()) - 1;
    }
    response_column_.push_back(found);
  }
}

void ResponseTracker::values(const Measure* measure, const State& s, const ModelParams& p,
                             double* out) const {
  if (const auto* cf = dynamic_cast<const ConstraintForceMeasure*>(measure))
    cf->evaluate_scaled(*cs_.model, s, p, k_, out);
  else
    measure->evaluate(*cs_.model, s, p, out);
}

void ResponseTracker::partials(const Measure* measure, const State& s, const ModelParams& p,
                               int component, MeasureGradient& g) const {
  if (const auto* cf = dynamic_cast<const ConstraintForceMeasure*>(measure))
    cf->gradient_scaled(*cs_.model, s, p, component, k_, g);
  else
    measure->gradient(*cs_.model, s, p, component, g);
}

void ResponseTracker::record(const State& s, const ModelParams& p, const Mat* dq, const Mat* dv,
                             const Mat* da, const Mat* dl) {
  times_.push_back(s.t);
  const int nv = static_cast<int>(dirs_.size());
  for (auto& c : cols_) {
    Eigen::RowVectorXd row;
    if (dq) row.setZero(nv);
    c.values.push_back(evaluate(c.measure, c.component, s, p, dq, dv, da, dl, dq ? &row : nullptr));
    if (dq) c.grads.push_back(row);
  }
}

double ResponseTracker::response_measure(size_t r, const State& s, const ModelParams& p,
                                         const Mat* dq, const Mat* dv, const Mat* da, const Mat* dl,
                                         Eigen::RowVectorXd* grad) {
  const auto& c = cols_[response_column_[r]];
  if (grad) grad->setZero(static_cast<Eigen::Index>(dirs_.size()));
  return evaluate(c.measure, c.component, s, p, dq, dv, da, dl, grad);
}

double ResponseTracker::response_partials(size_t r, const State& s, const ModelParams& p,
                                          MeasureGradient& g, Eigen::RowVectorXd& gp) {
  const auto& c = cols_[response_column_[r]];
  const auto nv = static_cast<Eigen::Index>(dirs_.size());
  double value;
  gp.setZero(nv);
  if (c.measure->depends_on_params()) {
    if (zero_q_.rows() != s.q.size())
      zero_q_.setZero(s.q.size(), nv), zero_l_.setZero(s.lambda.size(), nv);
    value = evaluate(c.measure, c.component, s, p, &zero_q_, &zero_q_, &zero_q_, &zero_l_, &gp);
  } else {
    value = evaluate(c.measure, c.component, s, p, nullptr, nullptr, nullptr, nullptr, nullptr);
  }
  g.clear();
  partials(c.measure, s, p, c.component, g);
  return value;
}

double ResponseTracker::evaluate(const Measure* measure, int component, const State& s,
                                 const ModelParams& p, const Mat* dq, const Mat* dv, const Mat* da,
                                 const Mat* dl, Eigen::RowVectorXd* grad) {
  buf_.resize(measure->components().size());
  values(measure, s, p, buf_.data());
  const double value = buf_[component];
  if (!grad) return value;
  Eigen::RowVectorXd& row = *grad;
  const int nv = static_cast<int>(dirs_.size());
  MeasureGradient& g = grad_;
  g.clear();
  partials(measure, s, p, component, g);
  for (const auto& [j, w] : g.dq) row += w * dq->row(j);
  for (const auto& [j, w] : g.dv) row += w * dv->row(j);
  for (const auto& [j, w] : g.da) row += w * da->row(j);
  for (const auto& [j, w] : g.dl) row += w * dl->row(j);
  if (measure->depends_on_params()) {
    // explicit ∂f/∂p_i: ∂f/∂μ exactly where the measure gives it (stress), otherwise a central
    // difference along the parameter direction; the measures without exact partials (mass,
    // energies) are linear in μ and in most parameters
    int field = -1;
    const bool exact_mu = measure->field_partials(*cs_.model, s, p, component, field, df_dmu_);
    for (int i = 0; i < nv; ++i) {
      const auto& d = dirs_[i];
      if (d.empty()) continue;
      if (exact_mu)
        for (const auto& f : d.fields)
          if (f.field == field) row[i] += f.value * df_dmu_[f.element];
      // step: 1e-3 of μ (the measures are linear in μ, so any step is exact and a large one
      // avoids round-off) and 1e-6 relative for scalar parameters
      double t = 1e300;
      if (!exact_mu)
        for (const auto& f : d.fields)
          if (f.value != 0) t = std::min(t, 1e-3 / std::abs(f.value));
      for (const auto& [j, v] : d.scalars)
        if (v != 0) t = std::min(t, 1e-6 * std::max(std::abs(p.scalars[j]), 1e-300) / std::abs(v));
      if (!(t < 1e300)) continue;
      auto step = [&](double tt) {
        if (!exact_mu)
          for (const auto& f : d.fields) scratch_.fields[f.field][f.element] += tt * f.value;
        for (const auto& [j, v] : d.scalars) scratch_.scalars[j] += tt * v;
      };
      step(t);
      values(measure, s, scratch_, buf_.data());
      const double fp = buf_[component];
      step(-2 * t);
      values(measure, s, scratch_, buf_.data());
      const double fm = buf_[component];
      // restore the touched entries exactly (no copy of the whole parameter set per step)
      for (const auto& f : d.fields)
        scratch_.fields[f.field][f.element] = p.fields[f.field][f.element];
      for (const auto& [j, v] : d.scalars) scratch_.scalars[j] = p.scalars[j];
      row[i] += (fp - fm) / (2 * t);
    }
  }
  return value;
}

Aggregate ResponseTracker::aggregate_response(size_t r) const {
  return aggregate(cs_.responses[r], times_, cols_[response_column_[r]].values);
}

std::vector<ResponseSensitivity> ResponseTracker::results() const {
  std::vector<ResponseSensitivity> out;
  const int nv = static_cast<int>(dirs_.size());
  for (size_t r = 0; r < cs_.responses.size(); ++r) {
    const auto& c = cols_[response_column_[r]];
    Mat G(static_cast<Eigen::Index>(c.values.size()), nv);
    for (size_t n = 0; n < c.grads.size(); ++n) G.row(static_cast<Eigen::Index>(n)) = c.grads[n];
    if (c.grads.empty()) G.setZero(static_cast<Eigen::Index>(c.values.size()), nv);
    Aggregate a = aggregate(cs_.responses[r], times_, c.values, &G);
    ResponseSensitivity rs;
    rs.name = cs_.responses[r].name;
    rs.values = std::move(a.values);
    rs.times = std::move(a.times);
    rs.gradient = std::move(a.gradient);
    rs.extreme_time = a.extreme_time;
    out.push_back(std::move(rs));
  }
  return out;
}

}  // namespace lsmbs
