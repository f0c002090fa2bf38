// AdjointSensitivity: the discrete adjoint of the generalized-α solution (adjoint_method.hpp;
// the derivation, term by term, in docs/methods.md "Discrete adjoint").
//
// Forward (Algorithm 2, direct_observer.hpp), per step n → n+1 with x = (q, q̇, q̈, a, λ)_,p:
//   a*  = c₁ a_n + c₂ q̇_n + c₃ q_n,   c₁ = −(½−β)/β, c₂ = −1/(βh), c₃ = −1/(βh²)        (35)
//   q̇* = q̇_n + h(1−γ) a_n + hγ a*                                                       (33)
//   q̈* = ((1−α_m) a* + α_m a_n − α_f q̈_n) / (1−α_f)                                    (34)
//   S_t [q; λ]_{n+1} = −[M q̈* + C q̇* + ∂r/∂p ; 0]                                        (37)
//   q̇_{n+1} = q̇* + γ' q_{n+1},  q̈_{n+1} = q̈* + β' q_{n+1},  a_{n+1} = a* + q_{n+1}/(βh²)  (38)–(40)
// Backward, with the adjoint (Q, V, D, A, L) of (q, q̇, q̈, a, λ) at n+1 (sources added):
//   S_tᵀ μ = [Q + γ'V + β'D + A/(βh²) ; L]
//   dψ/dp −= μᵀ ∂R/∂p,   D* = D − Mᵀμ_q,   V* = V − Cᵀμ_q
//   A* = A + (1−α_m)/(1−α_f) D* + hγ V*
//   Q_n = c₃ A*,  V_n = V* + c₂ A*,  D_n = −α_f/(1−α_f) D*,
//   A_n = α_m/(1−α_f) D* + h(1−γ) V* + c₁ A*,  L_n = 0
// and at the consistent start [M kΦ_qᵀ; kΦ_q 0]ᵀ μ₀ = [D₀ + A₀ ; L₀], dψ/dp −= μ₀ᵀ ∂R/∂p.
// The sources at a grid step n are w_n ∂f/∂(q, q̇, q̈, λ) of each response's measure, w_n the
// aggregation's weights (aggregation.hpp).
#include "lsmbs/sensitivity/adjoint_method.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/mbs/linear_solver_setup.hpp"
#include "lsmbs/sensitivity/method.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

namespace {

// One converged state of the trajectory and the coefficients of the step that reached it.
struct Entry {
  State s;
  AlphaCoefficients c;
  bool grid = false;
  long record = -1;  // its index among the tracker's grid records (grid entries)
};

double entry_bytes(const Model& m) { return 8.0 * (3.0 * m.nq() + m.nc() + 1) + sizeof(Entry); }

// Stores the steps of a run: every entry (a segment, or the whole trajectory), and optionally
// a checkpoint at every `stride`-th grid step. Also records the response values (the tracker).
class TrajectoryRecorder : public StepObserver {
 public:
  TrajectoryRecorder(ResponseTracker* tracker, const ModelParams& p, bool keep_entries, long stride,
                     long first_record)
      : tracker_(tracker), p_(p), keep_(keep_entries), stride_(stride), record_(first_record) {}
  void on_start(const State& s0, const Vec& a0, const AlphaCoefficients& c, double k, double zeta,
                const SparseLU*) override {
    k_ = k;
    zeta_ = zeta;
    if (tracker_) {
      tracker_->set_scaling(k);
      tracker_->record(s0, p_, nullptr, nullptr, nullptr, nullptr);
    }
    if (keep_) entries.push_back({s0, c, true, record_});
    if (stride_ > 0) checkpoint(s0, a0);
  }
  bool on_step(const StepInfo& i) override {
    if (i.grid_point) {
      ++record_;
      ++grid_;
      if (tracker_) tracker_->record(*i.state, p_, nullptr, nullptr, nullptr, nullptr);
    }
    if (keep_) entries.push_back({*i.state, i.coef, i.grid_point, i.grid_point ? record_ : -1});
    if (stride_ > 0 && i.grid_point && grid_ % stride_ == 0) checkpoint(*i.state, *i.acc_like);
    return true;
  }
  long grid_reached() const { return grid_; }
  std::vector<Entry> entries;
  std::vector<GridCheckpoint> checkpoints;
  double k_ = 1, zeta_ = 0;

 private:
  void checkpoint(const State& s, const Vec& a) {
    GridCheckpoint c;
    c.state = s;
    c.acc_like = a;
    c.k = k_;
    c.zeta = zeta_;
    c.grid = grid_;
    checkpoints.push_back(std::move(c));
  }
  ResponseTracker* tracker_;
  const ModelParams& p_;
  bool keep_;
  long stride_;
  long record_, grid_ = 0;
};

// adjoint-semi-analytical: the perturbed parameter sets μ(p + Δp_i), the steps, and the force
// elements each variable touches.
struct SemiAnalyticalContraction {
  std::vector<ModelParams> plus;
  std::vector<double> delta;
  std::vector<std::vector<int>> touched;
};

// The backward pass: adjoint state, accumulated contractions, workspace (sized once).
class Backward {
 public:
  Backward(const Study& cs, const ModelParams& p, ResponseTracker& tracker,
           const std::vector<std::vector<double>>& weights, const ParamDirection& support, double k,
           double zeta, const AdjointTerms& terms, SensitivityCounts& counts,
           const SemiAnalyticalContraction* semi)
      : cs_(cs),
        m_(*cs.model),
        p_(p),
        tracker_(tracker),
        weights_(weights),
        support_(support),
        k_(k),
        zeta_(zeta),
        terms_(terms),
        counts_(counts),
        semi_(semi),
        nq_(m_.nq()),
        nc_(m_.nc()),
        nr_(static_cast<int>(weights.size())) {
    Q_.setZero(nq_, nr_);
    V_ = D_ = A_ = Q_;
    L_.setZero(nc_, nr_);
    fields_.setZero(static_cast<Eigen::Index>(support.fields.size()), nr_);
    scalars_.setZero(static_cast<Eigen::Index>(support.scalars.size()), nr_);
    explicit_.setZero(nr_, cs.design->size());
    semi_sum_.setZero(nr_, cs.design->size());
    analyze_model_matrix(lu_, m_, cs.simulation.linear_solver, cs.simulation.ordering);
  }

  // w_n ∂f/∂(q, q̇, q̈, λ) of every response at grid record n, and w_n ∂f/∂p.
  void add_sources(const Entry& e) {
    if (!e.grid) return;
    for (int r = 0; r < nr_; ++r) {
      const auto& w = weights_[r];
      if (e.record < 0 || e.record >= static_cast<long>(w.size())) continue;
      const double wn = w[e.record];
      if (wn == 0) continue;
      tracker_.response_partials(r, e.s, p_, g_, gp_);
      for (const auto& [j, v] : g_.dq) Q_(j, r) += wn * v;
      for (const auto& [j, v] : g_.dv) V_(j, r) += wn * v;
      for (const auto& [j, v] : g_.da) D_(j, r) += wn * v;
      if (terms_.multipliers)
        for (const auto& [j, v] : g_.dl) L_(j, r) += wn * v;
      explicit_.row(r) += wn * gp_;
    }
  }

  // From the adjoint at n+1 (entry `e`, sources added) to the adjoint at n.
  void step_back(const Entry& e) {
    const auto& c = e.c;
    const double h = c.h, bh2 = c.beta * h * h;
    const double c1 = -(0.5 - c.beta) / c.beta, c2 = -1 / (c.beta * h), c3 = -1 / bh2;
    // S_tᵀ μ = [Q + γ'V + β'D + A/(βh²) ; L]
    mu_.resize(nq_ + nc_, nr_);
    mu_.topRows(nq_) = Q_ + (terms_.velocity_update ? c.gamma_p : 0.0) * V_ +
                       (terms_.acceleration_update ? c.beta_p : 0.0) * D_ + A_ / bh2;
    mu_.bottomRows(nc_) = L_;
    m_.iteration_matrix(e.s, p_, Coefficients{c.beta_p, c.gamma_p, 1.0}, k_, zeta_, vals_);
    factor("t = " + std::to_string(e.s.t) + ": the iteration matrix at the converged state");
    solve_transpose();
    contract(e.s);
    muq_ = mu_.topRows(nq_);
    m_.mass_damping_transpose_product(e.s, p_, muq_, MtY_, CtY_);
    if (terms_.mass) D_ -= MtY_;
    if (terms_.damping) V_ -= CtY_;
    // D_ = D*, V_ = V*; A* into A_
    A_ += ((1 - c.alpha_m) / (1 - c.alpha_f)) * D_ + (h * c.gamma) * V_;
    tmp_ = A_;  // A*
    A_ = (terms_.alpha_m ? c.alpha_m / (1 - c.alpha_f) : 0.0) * D_ + (h * (1 - c.gamma)) * V_ +
         c1 * tmp_;
    D_ *= terms_.alpha_f ? -c.alpha_f / (1 - c.alpha_f) : 0.0;
    V_ += c2 * tmp_;
    Q_ = c3 * tmp_;
    L_.setZero();
  }

  // The consistent start: [M kΦ_qᵀ; kΦ_q 0]ᵀ μ₀ = [D₀ + A₀ ; L₀].
  void start(const State& s0) {
    if (!terms_.start) return;
    mu_.resize(nq_ + nc_, nr_);
    mu_.topRows(nq_) = D_ + A_;
    mu_.bottomRows(nc_) = L_;
    State z = s0;  // the matrix as consistent_accelerations assembles it: q̈ = 0, λ = 0
    z.a.setZero();
    z.lambda.setZero();
    m_.iteration_matrix(z, p_, Coefficients{1, 0, 0}, k_, 0.0, vals_);
    lu_.reset_pivoting();
    factor("the consistent-start system");
    solve_transpose();
    contract(s0);
  }

  // dψ_r/dp_i = ∂ψ_r/∂p_i − Σ_steps μᵀ ∂R/∂p_i, assembled per direction from the per-entry sums.
  Mat gradient(const std::vector<ParamDirection>& dirs) const {
    std::map<std::pair<int, int>, Eigen::Index> field_row;
    for (size_t k = 0; k < support_.fields.size(); ++k)
      field_row[{support_.fields[k].field, support_.fields[k].element}] =
          static_cast<Eigen::Index>(k);
    std::map<int, Eigen::Index> scalar_row;
    for (size_t k = 0; k < support_.scalars.size(); ++k)
      scalar_row[support_.scalars[k].first] = static_cast<Eigen::Index>(k);
    Mat G = explicit_;
    if (semi_) return G - semi_sum_;
    for (size_t i = 0; i < dirs.size(); ++i) {
      for (const auto& f : dirs[i].fields)
        G.col(static_cast<Eigen::Index>(i)) -=
            f.value * fields_.row(field_row.at({f.field, f.element})).transpose();
      for (const auto& [j, v] : dirs[i].scalars)
        G.col(static_cast<Eigen::Index>(i)) -= v * scalars_.row(scalar_row.at(j)).transpose();
    }
    return G;  // nr × n_v
  }

 private:
  void factor(const std::string& what) {
    if (!lu_.factor(vals_).ok()) throw NumericalFailure(what + " is singular (adjoint back-solve)");
    ++counts_.sensitivity_factorizations;
    ++counts_.sensitivity_matrix_assemblies;
  }
  // μ ← S⁻ᵀ μ with one step of iterative refinement, as the direct method's back-solves
  void solve_transpose() {
    rhs_ = mu_;
    lu_.solve_transpose(std::span<double>(mu_.data(), mu_.size()), nr_);
    m_.assembler().multiply_transpose(vals_, mu_, res_);
    res_ = rhs_ - res_;
    lu_.solve_transpose(std::span<double>(res_.data(), res_.size()), nr_);
    mu_ += res_;
    ++counts_.adjoint_solves;
    counts_.back_solve_rhs += 2 * nr_;
  }
  void contract(const State& s) {
    if (semi_) {
      semi_contract(s);
      return;
    }
    m_.residual_param_contraction(s, p_, support_, mu_, fk_, sk_);
    fields_ += fk_;
    scalars_ += sk_;
    counts_.element_pseudo_loads += static_cast<long>(support_.fields.size());
  }

  // μᵀ ∂R/∂p_i ≈ μᵀ (r(s, p + Δp_i) − r(s, p)) / Δp_i over the elements design variable i
  // touches (the semi-analytical pseudo-load of eq. (30) at the converged state, in adjoint form)
  void semi_contract(const State& s) {
    const auto& sc = *semi_;
    for (size_t i = 0; i < sc.plus.size(); ++i) {
      for (int e : sc.touched[i]) {
        m_.element_residual(e, s, sc.plus[i], rp_);
        m_.element_residual(e, s, p_, r0_);
        const auto d = m_.forces()[static_cast<size_t>(e)]->dofs();
        for (size_t j = 0; j < d.size(); ++j) {
          const double g =
              (rp_[static_cast<Eigen::Index>(j)] - r0_[static_cast<Eigen::Index>(j)]) / sc.delta[i];
          if (g != 0) semi_sum_.col(static_cast<Eigen::Index>(i)) += g * mu_.row(d[j]).transpose();
        }
      }
      counts_.element_pseudo_loads += static_cast<long>(sc.touched[i].size());
    }
  }

  const Study& cs_;
  const Model& m_;
  const ModelParams& p_;
  ResponseTracker& tracker_;
  const std::vector<std::vector<double>>& weights_;
  const ParamDirection& support_;
  const double k_, zeta_;
  const AdjointTerms& terms_;
  SensitivityCounts& counts_;
  const SemiAnalyticalContraction* semi_;
  const int nq_, nc_, nr_;
  LocalVec rp_, r0_;
  Mat semi_sum_;
  Mat Q_, V_, D_, A_, L_, mu_, rhs_, res_, muq_, MtY_, CtY_, tmp_, fk_, sk_;
  Mat fields_, scalars_, explicit_;
  MeasureGradient g_;
  Eigen::RowVectorXd gp_;
  std::vector<double> vals_;
  SparseLU lu_;
};

// The union of the directions' entries (values irrelevant): what ∂R/∂p is contracted over.
ParamDirection support_of(const std::vector<ParamDirection>& dirs) {
  std::map<std::pair<int, int>, bool> fields;
  std::map<int, bool> scalars;
  for (const auto& d : dirs) {
    for (const auto& f : d.fields) fields[{f.field, f.element}] = true;
    for (const auto& [j, v] : d.scalars) scalars[j] = true;
  }
  ParamDirection s;
  for (const auto& [fe, b] : fields) s.fields.push_back({fe.first, fe.second, 1.0});
  for (const auto& [j, b] : scalars) s.scalars.emplace_back(j, 1.0);
  return s;
}

}  // namespace

namespace {

SensitivityResult adjoint_with(const Study& cs, const Vec& p, ModelParams& params,
                               const SensitivityOptions& o, const AdjointTerms& terms) {
  const Design& d = *cs.design;
  SensitivityResult res;
  for (size_t i = 0; i < cs.responses.size(); ++i)
    if (const auto& r = cs.responses[i];
        r.kind == ResponseSpec::Kind::kPerStep && !o.adjoint_skip_per_step)
      throw SetupError("responses." + std::to_string(i),
                       "response \"" + r.name +
                           "\" is per_step (one value per grid step): the adjoint method takes "
                           "scalar responses (one backward pass each); use --method "
                           "direct-analytic for per-step responses");
  const auto dirs = d.apply_with_directions(p, params);
  ResponseTracker tracker(cs, dirs, params);
  const Model& m = *cs.model;

  // memory: the whole trajectory, or checkpoints every `stride` grid steps and one segment
  const double per_entry = entry_bytes(m);
  const long n_grid = std::lround(std::ceil(cs.simulation.t_end / cs.simulation.h - 1e-9));
  const double budget = o.adjoint_memory_mb * 1e6;
  long stride = 0;
  if (budget > 0 && (n_grid + 1) * per_entry > budget) {
    const double capacity = budget / per_entry;  // states that fit
    long fewest = n_grid + 1;                    // the fewest states any stride needs
    for (long k = 1; k <= n_grid; ++k) {
      const long states = (n_grid + k - 1) / k + 1 + k;  // checkpoints and one segment
      fewest = std::min(fewest, states);
      if (stride == 0 && states <= capacity) stride = k;
    }
    if (stride == 0) {
      // the least memory, rounded up to 3 significant digits: the value stated works
      const double mb = fewest * per_entry / 1e6,
                   unit = std::pow(10.0, std::floor(std::log10(mb)) - 2);
      char need[32];
      std::snprintf(need, sizeof need, "%.3g", std::ceil(mb / unit) * unit);
      char given[32];
      std::snprintf(given, sizeof given, "%.3g", o.adjoint_memory_mb);
      throw SetupError("optimization.sensitivity.adjoint_memory_mb",
                       "the adjoint of " + std::to_string(n_grid) + " steps of " +
                           std::to_string(m.n()) + " unknowns needs at least " + need +
                           " MB with checkpoints; the bound is " + given + " MB");
    }
  }

  // forward: the primal run, the response values, the trajectory or its checkpoints
  TrajectoryRecorder rec(&tracker, params, stride == 0, stride, 0);
  StepObserverOptions served;  // the observers only read states: no factorization for them
  ProgressObserver prog(o.progress, cs.simulation.t_end);
  InterruptObserver stop;
  res.primal = GeneralizedAlpha(cs.simulation, served)
                   .run(*cs.model, params, cs.initial, {&rec, &prog, &stop});
  res.counts.add_run(res.primal);
  res.counts.primal_wall_seconds = res.primal.wall_seconds;  // the forward pass, recording
  res.ok = res.primal.ok && !res.primal.aborted;
  res.message = res.primal.aborted && res.primal.message.empty()
                    ? "stopped at t = " + std::to_string(res.primal.t_reached) + " s"
                    : res.primal.message;
  res.responses = tracker.results();
  if (o.method == SensitivityOptions::Method::kAdjointSemiAnalytical)
    res.warnings.push_back(
        "adjoint-semi-analytical contracts the adjoint with forward differences of the element "
        "residuals (Δp = delta): not exact, O(Δp); the method adjoint is");
  const int nr = static_cast<int>(cs.responses.size());
  const int nv = d.size();
  if (res.primal.aborted) {  // interrupted: no backward pass
    for (auto& r : res.responses) r.gradient.setConstant(1, nv, NAN);
    return res;
  }

  // weights of the aggregation: ∂ψ_r/∂f_n
  std::vector<std::vector<double>> weights(nr);
  for (int r = 0; r < nr; ++r) weights[r] = tracker.aggregate_response(r).weights;  // per_step: {}
  const ParamDirection support = support_of(dirs);
  std::optional<SemiAnalyticalContraction> semi;
  if (o.method == SensitivityOptions::Method::kAdjointSemiAnalytical) {
    semi.emplace();
    for (int i = 0; i < nv; ++i) {
      semi->delta.push_back(o.step(d, p, i));
      Vec pp = p;
      pp[i] += semi->delta.back();
      semi->plus.push_back(params);
      d.apply(pp, semi->plus.back());
      semi->touched.push_back(m.forces_touched_by(dirs[static_cast<size_t>(i)]));
    }
  }
  Backward back(cs, params, tracker, weights, support, rec.k_, rec.zeta_, terms, res.counts,
                semi ? &*semi : nullptr);

  double peak = static_cast<double>(rec.entries.size()) * per_entry +
                static_cast<double>(rec.checkpoints.size()) * per_entry;
  // An interrupt (SIGINT/SIGTERM) ends the backward pass at the next step: the result is
  // reported as interrupted (SensitivityMethod::compute), its gradients NaN
  auto stop_backward = [&](double t) {
    res.ok = false;
    res.message = "stopped during the adjoint's backward pass at t = " + std::to_string(t) + " s";
    for (auto& r : res.responses) r.gradient.setConstant(1, nv, NAN);
    return res;
  };
  auto sweep = [&](std::vector<Entry>& entries) {  // entries[0]: the segment's first state
    for (size_t e = entries.size() - 1; e >= 1; --e) {
      if (interrupted()) return false;
      back.add_sources(entries[e]);
      back.step_back(entries[e]);
    }
    return true;
  };
  State s0;
  signal_point("adjoint-backward");
  if (stride == 0) {
    if (!sweep(rec.entries)) return stop_backward(rec.entries.back().s.t);
    s0 = rec.entries.front().s;
    back.add_sources(rec.entries.front());
  } else {
    // the segments between checkpoints, last first, each recomputed from its checkpoint
    GeneralizedAlpha ga(cs.simulation);
    for (size_t j = rec.checkpoints.size(); j-- > 0;) {
      const auto& ck = rec.checkpoints[j];
      const long end = std::min(ck.grid + stride, rec.grid_reached());
      if (end <= ck.grid) continue;
      TrajectoryRecorder seg(nullptr, params, true, 0, ck.grid);
      signal_point("adjoint-recompute");
      const auto sum = ga.resume(*cs.model, params, ck, end, {&seg, &stop});
      res.counts.adjoint_recomputed_steps += sum.steps;
      if (sum.aborted && interrupted()) return stop_backward(ck.state.t);
      if (!sum.ok || sum.aborted)
        throw NumericalFailure("adjoint: recomputing the steps from t = " +
                               std::to_string(ck.state.t) + " s failed: " + sum.message);
      peak = std::max(peak,
                      static_cast<double>(seg.entries.size() + rec.checkpoints.size()) * per_entry);
      if (!sweep(seg.entries)) return stop_backward(seg.entries.back().s.t);
    }
    s0 = rec.checkpoints.front().state;
    Entry first{s0, {}, true, 0};
    back.add_sources(first);
  }
  if (cs.simulation.consistent_start) back.start(s0);
  res.counts.adjoint_memory_bytes = peak;

  const Mat G = back.gradient(dirs);
  for (int r = 0; r < nr; ++r) {
    auto& rs = res.responses[r];
    if (cs.responses[r].kind == ResponseSpec::Kind::kPerStep) {  // skipped (adjoint_skip_per_step)
      rs.gradient.setConstant(static_cast<Eigen::Index>(rs.values.size()), nv, NAN);
      continue;
    }
    rs.gradient = G.row(r);
    if (rs.values.empty() || !std::isfinite(rs.values[0])) rs.gradient.setConstant(1, nv, NAN);
  }
  return res;
}

}  // namespace

SensitivityResult adjoint_sensitivities(const Study& cs, const Vec& p, const SensitivityOptions& o,
                                        const AdjointTerms& terms) {
  ModelParams params = cs.model->params();  // adjoint_with maps the design at p
  return adjoint_with(cs, p, params, o, terms);
}

SensitivityResult AdjointSensitivity::run(const Study& cs, const Vec& p,
                                          ModelParams& params) const {
  return adjoint_with(cs, p, params, options(), AdjointTerms{});
}

}  // namespace lsmbs
