#include "lsmbs/sensitivity/direct_observer.hpp"

#include <algorithm>
#include <cmath>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

AnalyticPseudoLoad::AnalyticPseudoLoad(const Model& m, const ModelParams& p,
                                       std::vector<ParamDirection> dirs)
    : m_(m), p_(p), dirs_(std::move(dirs)) {}

void AnalyticPseudoLoad::compute(const State& s, const Mat& dv_star, const Mat& dqdd_star, double,
                                 double, Mat& B, SensitivityCounts& counts) {
  const int nq = m_.nq(), nv = static_cast<int>(dirs_.size());
  B.setZero(m_.n(), nv);
  if (!dv_star.isZero(0.0) || !dqdd_star.isZero(0.0)) {
    m_.mass_damping_product(s, p_, dqdd_star, dv_star, MC_);
    B.topRows(nq) = MC_;
    ++counts.mass_damping_products;
  }
  for (int i = 0; i < nv; ++i) {
    if (dirs_[i].empty()) continue;
    m_.residual_param_derivative(s, p_, dirs_[i], col_);
    B.col(i) += col_;
    counts.element_pseudo_loads +=
        static_cast<long>(dirs_[i].fields.size() + dirs_[i].scalars.size());
  }
}

SemiAnalyticalPseudoLoad::SemiAnalyticalPseudoLoad(const Model& m, const ModelParams& p,
                                                   std::vector<ModelParams> plus,
                                                   std::vector<ModelParams> minus,
                                                   std::vector<double> delta, bool central,
                                                   const std::vector<ParamDirection>& dirs,
                                                   bool full_residual)
    : m_(m),
      p_(p),
      plus_(std::move(plus)),
      minus_(std::move(minus)),
      delta_(std::move(delta)),
      central_(central),
      full_(full_residual) {
  std::vector<int> nonlinear;
  for (size_t e = 0; e < m.forces().size(); ++e)
    if (!m.forces()[e]->linear_in_rates()) nonlinear.push_back(static_cast<int>(e));
  for (const auto& d : dirs) {
    auto t = m.forces_touched_by(d);
    t.insert(t.end(), nonlinear.begin(), nonlinear.end());
    std::sort(t.begin(), t.end());
    t.erase(std::unique(t.begin(), t.end()), t.end());
    evaluated_.push_back(std::move(t));
  }
}

void SemiAnalyticalPseudoLoad::compute(const State& s, const Mat& dv_star, const Mat& dqdd_star,
                                       double k, double zeta, Mat& B, SensitivityCounts& counts) {
  const int nv = static_cast<int>(delta_.size());
  B.setZero(m_.n(), nv);
  if (full_) {
    if (!central_) {  // eq. (30): the actual residual at p is subtracted, not assumed zero
      m_.residual(s, p_, k, zeta, R0_);
      ++counts.pseudo_load_residuals;
    }
    pert_ = s;
    for (int i = 0; i < nv; ++i) {
      const double d = delta_[i];
      pert_.v = s.v + d * dv_star.col(i);  // eq. (32)
      pert_.a = s.a + d * dqdd_star.col(i);
      m_.residual(pert_, plus_[i], k, zeta, Rp_);
      ++counts.pseudo_load_residuals;
      if (central_) {
        pert_.v = s.v - d * dv_star.col(i);
        pert_.a = s.a - d * dqdd_star.col(i);
        m_.residual(pert_, minus_[i], k, zeta, Rm_);
        ++counts.pseudo_load_residuals;
        B.col(i) = (Rp_ - Rm_) / (2 * d);
      } else {
        B.col(i) = (Rp_ - R0_) / d;
      }
    }
    return;
  }
  // element-local: exact M q̈* + C q̇* for the untouched rate-linear elements ...
  m_.mass_damping_product(s, p_, dqdd_star, dv_star, MC_);
  ++counts.mass_damping_products;
  B.topRows(m_.nq()) = MC_;
  // ... and perturbed element residuals for the others
  LocalVec rp, rm, r0, mc;
  pert_ = s;
  State minus = s;
  for (int i = 0; i < nv; ++i) {
    const double d = delta_[i];
    vi_ = dv_star.col(i);
    ai_ = dqdd_star.col(i);
    pert_.v = s.v + d * vi_;
    pert_.a = s.a + d * ai_;
    if (central_) {
      minus.v = s.v - d * vi_;
      minus.a = s.a - d * ai_;
    }
    for (int e : evaluated_[i]) {
      m_.element_mass_damping_product(e, s, p_, ai_, vi_, mc);
      m_.element_residual(e, pert_, plus_[i], rp);
      if (central_) {
        m_.element_residual(e, minus, minus_[i], rm);
        rp = (rp - rm) / (2 * d);
      } else {
        m_.element_residual(e, s, p_, r0);
        rp = (rp - r0) / d;
      }
      const auto dofs = m_.forces()[e]->dofs();
      for (size_t j = 0; j < dofs.size(); ++j) B(dofs[j], i) += rp[j] - mc[j];
    }
    counts.element_pseudo_loads += static_cast<long>(evaluated_[i].size());
  }
}

std::string BackSolveOptions::validate() const {
  if (max_refinement < 0) return "max_refinement: expected a non-negative number of iterations";
  if (!(accept > 0 && accept < 1)) return "accept: expected a relative correction in (0, 1)";
  if (!(round_off > 0 && round_off < 1)) return "round_off: expected a relative level in (0, 1)";
  return {};
}

DirectSensitivityObserver::DirectSensitivityObserver(const Model& m, const ModelParams& p, int nv,
                                                     PseudoLoad& load, ResponseTracker& tracker,
                                                     SensitivityCounts& counts,
                                                     BackSolveOptions back_solve)
    : m_(m), p_(p), nv_(nv), load_(load), tracker_(tracker), counts_(counts), bs_(back_solve) {
  if (auto msg = bs_.validate(); !msg.empty()) throw Error("back-solve option " + msg);
}

void DirectSensitivityObserver::on_start(const State& s0, const Vec&, const AlphaCoefficients&,
                                         double k, double zeta, const SparseLU* start_factor) {
  const int nq = m_.nq(), nc = m_.nc();
  tracker_.set_scaling(k);
  // q0 and q̇0 do not depend on p (constraints carry no design parameter)
  dq_.setZero(nq, nv_);
  dv_.setZero(nq, nv_);
  dqdd_.setZero(nq, nv_);
  dl_.setZero(nc, nv_);
  if (start_factor) {
    // consistent start: [M kΦ_qᵀ; kΦ_q 0][q̈0_,i; λ0_,i] = −[∂r/∂p_i ; 0]
    load_.compute(s0, dv_, dqdd_, k, 0.0, B_, counts_);
    B_ = -B_;
    start_factor->solve(B_);
    ++counts_.back_solves;
    counts_.back_solve_rhs += nv_;
    dqdd_ = B_.topRows(nq);
    dl_ = B_.bottomRows(nc);
  }
  (void)zeta;
  da_ = dqdd_;  // a0 = q̈0
  tracker_.record(s0, p_, &dq_, &dv_, &dqdd_, &dl_);
}

bool DirectSensitivityObserver::on_step(const StepInfo& info) {
  const auto& c = info.coef;
  const double h = c.h, bh2 = c.beta * h * h;
  const int nq = m_.nq(), nc = m_.nc();
  // predictors (35), (33), (34)
  das_ = -((0.5 - c.beta) * h * h * da_ + h * dv_ + dq_) / bh2;
  dvs_ = dv_ + h * (1 - c.gamma) * da_ + h * c.gamma * das_;
  dqdds_ = ((1 - c.alpha_m) * das_ + c.alpha_m * da_ - c.alpha_f * dqdd_) / (1 - c.alpha_f);
  // pseudo-loads and one back-solve for all variables (37)
  load_.compute(*info.state, dvs_, dqdds_, info.k, info.zeta, B_, counts_);
  B_ = -B_;
  if (info.newton_iterations <= 1) ++counts_.predictor_matrix_steps;
  if (bs_.mode == BackSolveOptions::Mode::kExact) {
    exact_solve(info);
  } else {
    info.factor->solve(B_);
    ++counts_.back_solves;
    counts_.back_solve_rhs += nv_;
  }
  // updates (38)–(40)
  dq_ = B_.topRows(nq);
  dl_ = B_.bottomRows(nc);
  dv_ = dvs_ + c.gamma_p * dq_;
  dqdd_ = dqdds_ + c.beta_p * dq_;
  da_ = das_ + dq_ / bh2;
  if (info.grid_point) tracker_.record(*info.state, p_, &dq_, &dv_, &dqdd_, &dl_);
  return true;
}

namespace {
// max over columns of ‖D_j‖∞ / ‖X_j‖∞ (columns with X_j = 0: ‖D_j‖∞)
double relative_correction(const Mat& D, const Mat& X) {
  double r = 0;
  for (Eigen::Index j = 0; j < D.cols(); ++j) {
    const double x = X.col(j).lpNorm<Eigen::Infinity>(), d = D.col(j).lpNorm<Eigen::Infinity>();
    r = std::max(r, x > 0 ? d / x : d);
  }
  return r;
}
}  // namespace

// Solves S_t(converged) X = B_ (rhs in B_, solution left in B_). The step's factorization was
// computed at an earlier Newton iterate (the predictor when the step took one iteration), so it
// is used as the preconditioner of iterative refinement X ← X + S_f⁻¹ (b − S_t X), which
// converges to the solution with the converged-state matrix at the rate ‖I − S_f⁻¹ S_t‖. When
// that rate is poor, S_t is factorized (the shared symbolic analysis, a numeric factorization of
// the observer's own), which is exact whatever the step's iterations were.
void DirectSensitivityObserver::exact_solve(const StepInfo& info) {
  const auto& c = info.coef;
  rhs_ = B_;
  m_.iteration_matrix(*info.state, p_, Coefficients{c.beta_p, c.gamma_p, 1.0}, info.k, info.zeta,
                      svals_);
  ++counts_.sensitivity_matrix_assemblies;
  const SparseLU* lu = info.factor;
  bool accepted = false;
  {
    lu->solve(B_);
    ++counts_.back_solves;
    counts_.back_solve_rhs += nv_;
    double prev = INFINITY;
    for (int it = 0; it < bs_.max_refinement; ++it) {
      m_.assembler().multiply(svals_, B_, SX_);
      SX_ = rhs_ - SX_;
      lu->solve(SX_);
      B_ += SX_;
      ++counts_.refinement_solves;
      counts_.back_solve_rhs += nv_;
      const double r = relative_correction(SX_, B_);
      if (!(r == r)) break;  // NaN: factorize
      if (r <= bs_.accept || (r > 0.5 * prev && r <= bs_.round_off)) {
        accepted = true;
        break;
      }
      if (r > 0.5 * prev) break;  // not contracting: factorize
      prev = r;
    }
  }
  if (accepted) return;
  if (!own_lu_shares_) {
    own_lu_.share_analysis(*lu);
    own_lu_shares_ = true;
  }
  if (!own_lu_.factor(svals_).ok())
    throw NumericalFailure(
        "t = " + std::to_string(info.state->t) +
        ": the iteration matrix at the converged state is singular (sensitivity back-solve)");
  ++counts_.sensitivity_factorizations;
  B_ = rhs_;
  own_lu_.solve(B_);
  ++counts_.back_solves;
  counts_.back_solve_rhs += nv_;
  // one step of classical refinement with the exact factorization
  m_.assembler().multiply(svals_, B_, SX_);
  SX_ = rhs_ - SX_;
  own_lu_.solve(SX_);
  B_ += SX_;
  ++counts_.refinement_solves;
  counts_.back_solve_rhs += nv_;
}

}  // namespace lsmbs
