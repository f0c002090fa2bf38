#include "lsmbs/integrators/generalized_alpha.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/mbs/linear_solver_setup.hpp"
#include "lsmbs/mbs/spatial.hpp"

namespace lsmbs {

AlphaCoefficients AlphaCoefficients::make(double rho, double h) {
  AlphaCoefficients c;
  c.rho_inf = rho;
  c.alpha_m = (2 * rho - 1) / (rho + 1);
  c.alpha_f = rho / (rho + 1);
  c.gamma = 0.5 - c.alpha_m + c.alpha_f;
  c.beta = 0.25 * (c.gamma + 0.5) * (c.gamma + 0.5);
  c.h = h;
  c.beta_p = (1 - c.alpha_m) / ((1 - c.alpha_f) * c.beta * h * h);
  c.gamma_p = c.gamma / (c.beta * h);
  return c;
}

std::string GeneralizedAlphaOptions::validate() const {
  if (!(h > 0) || !std::isfinite(h)) return "h: expected a positive time step";
  if (!(t_end > 0) || !std::isfinite(t_end)) return "t_end: expected a positive final time";
  // the output grid t = 0, h, 2h, … must end on t_end: no silent overshoot, no run without a step
  if (t_end / h > 1e8) return "h: more than 1e8 steps requested";
  char msg[320];
  if (h > t_end * (1 + 1e-9)) {  // zero steps: the run would end at t = 0 and report it complete
    std::snprintf(msg, sizeof msg,
                  "h: h = %g is longer than t_end = %g (the run would have no step)", h, t_end);
    return msg;
  }
  if (const double n = t_end / h; std::abs(n - std::round(n)) > 1e-9 * std::max(1.0, n)) {
    std::snprintf(msg, sizeof msg,
                  "h: t_end = %.10g is not a multiple of h = %.10g (%.6g steps): the run would end "
                  "after t_end; use h = %.10g (%ld steps) or t_end = %.10g",
                  t_end, h, n, t_end / std::ceil(n), static_cast<long>(std::ceil(n)),
                  std::ceil(n) * h);
    return msg;
  }
  if (!(rho_inf >= 0 && rho_inf <= 1)) return "rho_inf: expected a value in [0, 1]";
  if (!(tol_r > 0)) return "tol_r: expected a positive tolerance";
  if (!(tol_phi > 0)) return "tol_phi: expected a positive tolerance";
  if (!(tol_q > 0)) return "tol_q: expected a positive tolerance";
  if (!(force_floor >= 0)) return "force_floor: expected a non-negative force";
  if (max_iter < 1) return "max_iter: expected at least 1";
  // the case file's bound of every integer (io/json_reader.cpp), for options set in code
  if (max_iter > 100000000) return "max_iter: expected at most 100000000";
  if (min_iter < 0 || min_iter > max_iter) return "min_iter: expected 0 <= min_iter <= max_iter";
  if (max_halvings < 0 || max_halvings > 30) return "max_halvings: expected 0..30";
  if (!(k >= 0) || !std::isfinite(k)) return "k: expected a non-negative value (0 = automatic)";
  if (!(zeta >= 0) || !std::isfinite(zeta))
    return "zeta: expected a non-negative value (0 = automatic)";
  return {};
}

const char* GeneralizedAlphaOptions::newton_name(Newton n) {
  return n == Newton::kFull       ? "full"
         : n == Newton::kModified ? "modified"
                                  : "modified_across_steps";
}

double GeneralizedAlpha::automatic_scaling(const Model& model, const ModelParams& p, const State& s,
                                           const AlphaCoefficients& c) {
  std::vector<double> vals;
  model.iteration_matrix(s, p, Coefficients{c.beta_p, c.gamma_p, 1.0}, 0.0, 0.0, vals);
  const auto& pat = model.pattern();
  double sum = 0;
  int cnt = 0;
  for (int j = 0; j < model.nq(); ++j) {
    const int k = pat.find(j, j);
    if (k >= 0 && vals[k] != 0) {
      sum += std::abs(vals[k]);
      ++cnt;
    }
  }
  return cnt ? sum / cnt : 1.0;
}

// Round-off floor of each residual row (positions only). A position known to ε·x_j (x_j =
// max(|q_j|, L)) perturbs row i by about Σ_j |S_ij| ε x_j through the iteration matrix (β′M, K_t,
// ζΦ_qᵀΦ_q: this is where the h⁻² of β′ and ζ enters, row by row rather than as one global
// bound); the sum of the row's force terms s_i adds its own ε s_i. No Newton iteration gets the
// row below this, and the test never asks it to.
void row_round_off_floor(const CscPattern& pat, const std::vector<double>& vals, const Vec& q,
                         double L, int nq, Vec& floor) {
  constexpr double kFactor = 16 * 2.2204460492503131e-16;
  floor.setZero(nq);
  for (int j = 0; j < nq; ++j) {
    const double xj = std::max(std::abs(q[j]), L);
    for (int k = pat.col_ptr[j]; k < pat.col_ptr[j + 1]; ++k) {
      const int i = pat.row_ind[k];
      if (i < nq) floor[i] += std::abs(vals[k]) * xj;
    }
  }
  floor *= kFactor;
}

namespace {

// Column of the first NaN or Inf among the values of a matrix on `pat`, or −1.
int first_non_finite_column(const CscPattern& pat, const std::vector<double>& vals) {
  for (int col = 0; col < pat.n; ++col)
    for (int at = pat.col_ptr[col]; at < pat.col_ptr[col + 1]; ++at)
      if (!std::isfinite(vals[at])) return col;
  return -1;
}

// Newton corrections up to this multiple of tol_q·L that stop halving are round-off (accepted).
constexpr double kRoundOffIncrement = 100;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Returns f() and adds its wall time to `acc` (IntegratorSummary::seconds).
template <class F>
decltype(auto) timed(double& acc, F&& f) {
  struct AddOnExit {
    double& acc;
    std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
    ~AddOnExit() { acc += seconds_since(t0); }
  } add{acc};
  return f();
}

// Runs the concurrent observers on one worker thread, one step behind the integrator. One job
// slot: post() copies the step (no allocation once the slot has its sizes) after wait_idle()
// has seen the previous job finish, so at most one step is in flight.
class ObserverWorker {
 public:
  explicit ObserverWorker(std::vector<StepObserver*> observers)
      : observers_(std::move(observers)), thread_([this] { loop(); }) {}
  ~ObserverWorker() {
    {
      std::lock_guard<std::mutex> lk(mu_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  ObserverWorker(const ObserverWorker&) = delete;
  ObserverWorker& operator=(const ObserverWorker&) = delete;

  /// Waits for the job in flight; false when an observer asked to stop. Rethrows an observer's
  /// exception on the integrator's thread.
  bool wait_idle() {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [&] { return !pending_; });
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return !stop_;
  }
  /// Copies the step and hands it to the worker (call after wait_idle()).
  void post(const StepInfo& info) {
    job_.prev = *info.prev;
    job_.prev_acc = *info.prev_acc_like;
    job_.state = *info.state;
    job_.acc = *info.acc_like;
    job_.info = info;
    job_.info.prev = &job_.prev;
    job_.info.prev_acc_like = &job_.prev_acc;
    job_.info.state = &job_.state;
    job_.info.acc_like = &job_.acc;
    {
      std::lock_guard<std::mutex> lk(mu_);
      pending_ = true;
    }
    cv_.notify_all();
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lk(mu_);
    for (;;) {
      cv_.wait(lk, [&] { return pending_ || quit_; });
      if (!pending_) return;
      lk.unlock();
      bool go_on = true;
      std::exception_ptr err;
      try {
        for (auto* o : observers_) go_on &= o->on_step(job_.info);
      } catch (...) {
        err = std::current_exception();
      }
      lk.lock();
      if (!go_on) stop_ = true;
      if (err && !error_) error_ = err;
      pending_ = false;
      cv_.notify_all();
    }
  }
  struct Job {
    State prev, state;
    Vec prev_acc, acc;
    StepInfo info;
  } job_;
  std::vector<StepObserver*> observers_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool pending_ = false, quit_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once everything above exists
};

// How the corrector of one step ended.
enum class NewtonStatus {
  kConverged,
  kStopped,  ///< an observer asked to stop (stop_requested): the step is abandoned
  kNonFiniteResidual,
  kNonFiniteCorrection,
  kLinearSolve,  ///< the iterative linear solver missed its tolerance (linear_failure_ says how)
  kNonFiniteMatrix,        ///< NaN or Inf in S_t: an overflow, not a singular motion
  kSingular,               ///< S_t singular: the motion of an unknown is not determined
  kNotConverged,           ///< max_iter iterations, residual test not met
  kNotConvergedPositions,  ///< max_iter iterations, residual test met, position corrections not
  kInverted,               ///< converged to a state with an inverted element (a spurious solution)
  kFolded,  ///< converged to a state where an element folded within the step (retried)
};

// One run of GeneralizedAlpha: its named steps (the boxes of Algorithm 1), the workspace (sized
// in start(), so that the steps allocate nothing), the factorizations, the step-size control and
// the summary.
class AlphaRun {
 public:
  AlphaRun(const GeneralizedAlphaOptions& opt, const StepObserverOptions& served,
           const Model& model, const ModelParams& p, std::vector<StepObserver*> observers,
           State* final_state)
      : opt_(opt),
        served_(served),
        model_(model),
        p_(p),
        observers_(std::move(observers)),
        final_state_(final_state),
        nq_(model.nq()),
        nc_(model.nc()),
        L_(model.length_scale()) {}

  bool start(State s0);
  bool start_from(const GridCheckpoint& from, long grid_end);
  bool done() const { return grid_ >= n_steps_; }
  double step_size() const { return h_; }
  void predict(const AlphaCoefficients& c);
  NewtonStatus newton(const AlphaCoefficients& c);
  bool halve_or_fail(NewtonStatus st);
  bool factor_for_observers(const AlphaCoefficients& c);
  void accept(const AlphaCoefficients& c);
  bool notify_observers(const AlphaCoefficients& c);
  void next_step();
  IntegratorSummary finish();

 private:
  bool fail(std::string message);
  bool stop_requested() const;
  void start_observers();
  void evaluate_residual();
  double residual_measure() const;
  bool factor_iteration_matrix(const Coefficients& coeffs, NewtonStatus& failure);
  bool solve_correction();  // false: the iterative solver failed (linear_failure_)
  void apply_correction(const AlphaCoefficients& c);

  const GeneralizedAlphaOptions& opt_;
  const StepObserverOptions& served_;
  const Model& model_;
  const ModelParams& p_;
  std::vector<StepObserver*> observers_, sync_observers_;
  State* final_state_;
  const int nq_, nc_;
  const double L_;           // model length scale
  double tol_phi_ = 0;       // tol_phi · L
  double k_ = 1, zeta_ = 0;  // scaling and penalty of eq. (7)
  const std::chrono::steady_clock::time_point t_start_ = std::chrono::steady_clock::now();
  IntegratorSummary sum_;
  bool started_ = false;

  // Step-size control: steps of opt.h on the output grid, each grid interval halved up to
  // max_halvings times.
  double t0_ = 0, h_ = 0, t_grid_next_ = 0;
  int spinning_body_ = -1;  // the spatial body of the largest ωh so far
  long n_steps_ = 0, grid_ = 0;
  int depth_ = 0;         // halvings active for the current grid interval
  bool on_grid_ = false;  // the accepted step ends on the grid

  // The step from prev (t_n) to cur (t_{n+1}).
  State cur_, prev_;
  Vec a_cur_, a_prev_;  // acceleration-like a_{n+1}, a_n of eq. (8)
  Vec R_, r_abs_, dx_;
  Vec row_floor_;  // per-row round-off floor [N] from the last assembled iteration matrix
  std::vector<double> vals_;

  // The last Newton iteration (StepInfo, failure reports).
  int iterations_ = 0;
  double rn_ = 0, pn_ = 0;      // ‖r‖∞ [N], ‖Φ‖∞ [length]
  int bad_column_ = -1;         // kNonFiniteMatrix: the first column with NaN or Inf
  std::string linear_failure_;  // kLinearSolve: the solver's message
  Model::Inversion inversion_;  // kInverted: the element with the smallest det F
  bool prev_folded_ = false;    // the last accepted state has a folded element

  // Factorizations. Concurrent observers: a second numeric factorization of the same symbolic
  // analysis, so that step n+1 is factorized into one while the worker back-solves with step n's
  // in the other; step_lu_ is the one the current step writes. A factorization in it that a step
  // may start from (modified_across_steps) has its h; a failed step that started from an old one
  // is retried once with a fresh one.
  SparseLU lu_, lu_alt_;
  SparseLU* step_lu_ = &lu_;
  bool alternate_ = false;  // steps alternate between lu_ and lu_alt_ (start_observers)
  bool have_factor_ = false, started_with_old_factor_ = false, retried_fresh_ = false;
  double factor_h_ = 0;
  std::optional<ObserverWorker> worker_;  // last: joined before the factorizations it reads go
};

bool AlphaRun::fail(std::string message) {
  sum_.ok = false;
  sum_.message = std::move(message);
  return false;
}

// The observers that may run on the worker thread (threads > 1) go to it, the others run in the
// step. With any such observer the steps alternate between the two factorizations whatever the
// threads: KLU's refactorization reuses the pivot sequence of the factorization it writes into,
// so one thread alternating as the worker mode does gives the same bits as two.
void AlphaRun::start_observers() {
  std::vector<StepObserver*> concurrent;
  sync_observers_.clear();
  alternate_ = false;
  for (auto* o : observers_) {
    alternate_ |= o->concurrent();
    (served_.threads > 1 && o->concurrent() ? concurrent : sync_observers_).push_back(o);
  }
  if (alternate_) lu_alt_.share_analysis(lu_);
  if (!concurrent.empty()) worker_.emplace(std::move(concurrent));
}

bool AlphaRun::stop_requested() const {
  return std::any_of(observers_.begin(), observers_.end(),
                     [](const StepObserver* o) { return o->stop_requested(); });
}

// Consistent start: q0, q̇0 projected on the constraints, k and ζ of eq. (7), then q̈0 and λ0 from
// the acceleration-level system (consistent_start = false: q̈0 = a0 = 0, λ0 = 0 as Algorithm 1),
// a_0 = q̈_0, and the observers' on_start.
bool AlphaRun::start(State s0) {
  if (auto msg = opt_.validate(); !msg.empty()) return fail("invalid integrator option " + msg);
  if (auto msg = served_.validate(); !msg.empty()) return fail("invalid observer option " + msg);
  s0.v.conservativeResize(nq_);
  if (s0.a.size() != nq_) s0.a.setZero(nq_);
  if (s0.lambda.size() != nc_) s0.lambda.setZero(nc_);

  analyze_model_matrix(lu_, model_, opt_.linear_solver, opt_.ordering);
  sum_.linear_solver = SparseLU::solver_name(lu_.solver_used());
  const AlphaCoefficients c0 = AlphaCoefficients::make(opt_.rho_inf, opt_.h);
  if (opt_.project_initial)
    if (auto st = project_initial_state(model_, p_, s0, lu_, 1e-13 * L_); !st.ok())
      return fail("t = " + std::to_string(s0.t) + ": " + st.message);
  const double stiffness_scale = GeneralizedAlpha::automatic_scaling(model_, p_, s0, c0);
  sum_.k = k_ = opt_.k > 0 ? opt_.k : stiffness_scale;
  sum_.zeta = zeta_ = opt_.zeta > 0 ? opt_.zeta : k_;
  if (opt_.consistent_start) {
    if (auto st = consistent_accelerations(model_, p_, k_, s0, lu_); !st.ok())
      return fail("t = " + std::to_string(s0.t) + ": " + st.message);
  } else {
    s0.a.setZero(nq_);
    s0.lambda.setZero(nc_);
  }

  cur_ = s0;
  prev_ = s0;
  prev_folded_ = model_.most_compressed_element(s0.q, p_).folded();
  a_cur_ = s0.a;  // a_0 = q̈_0
  a_prev_ = a_cur_;
  R_.resize(model_.n());
  r_abs_.resize(nq_);
  dx_.resize(model_.n());
  row_floor_.setZero(nq_);
  for (auto* o : observers_)
    o->on_start(s0, a_cur_, c0, k_, zeta_, opt_.consistent_start ? &lu_ : nullptr);
  lu_.reset_pivoting();  // the first Newton iteration factorizes with fresh pivoting

  start_observers();

  tol_phi_ = opt_.tol_phi * L_;
  t0_ = s0.t;
  n_steps_ = std::lround(std::ceil((opt_.t_end - s0.t) / opt_.h - 1e-9));
  h_ = opt_.h;
  t_grid_next_ = s0.t + opt_.h;
  started_ = true;
  sum_.seconds.setup = seconds_since(t_start_);
  return true;
}

// A start at a checkpoint of an earlier run on the same grid: that run's state, a_n, k and ζ.
bool AlphaRun::start_from(const GridCheckpoint& from, long grid_end) {
  if (auto msg = opt_.validate(); !msg.empty()) return fail("invalid integrator option " + msg);
  if (auto msg = served_.validate(); !msg.empty()) return fail("invalid observer option " + msg);
  if (from.state.q.size() != nq_ || from.state.v.size() != nq_ || from.state.a.size() != nq_ ||
      from.state.lambda.size() != nc_ || from.acc_like.size() != nq_ || !(from.k > 0))
    return fail("resume: the checkpoint does not belong to this model");
  analyze_model_matrix(lu_, model_, opt_.linear_solver, opt_.ordering);
  sum_.linear_solver = SparseLU::solver_name(lu_.solver_used());
  sum_.k = k_ = from.k;
  sum_.zeta = zeta_ = from.zeta;
  cur_ = from.state;
  prev_ = from.state;
  prev_folded_ = model_.most_compressed_element(from.state.q, p_).folded();
  a_cur_ = from.acc_like;
  a_prev_ = a_cur_;
  R_.resize(model_.n());
  r_abs_.resize(nq_);
  dx_.resize(model_.n());
  row_floor_.setZero(nq_);
  const AlphaCoefficients c0 = AlphaCoefficients::make(opt_.rho_inf, opt_.h);
  for (auto* o : observers_) o->on_start(from.state, a_cur_, c0, k_, zeta_, nullptr);
  start_observers();
  tol_phi_ = opt_.tol_phi * L_;
  t0_ = from.t_origin;
  grid_ = from.grid;
  n_steps_ = grid_end;
  h_ = opt_.h;
  t_grid_next_ = t0_ + (grid_ + 1) * opt_.h;
  started_ = true;
  sum_.seconds.setup = seconds_since(t_start_);
  return true;
}

// Predictor (Algorithm 1): q̈_{n+1} = 0, λ_{n+1} = 0; a_{n+1} from (8), q_{n+1} and q̇_{n+1} from
// (9)–(10).
void AlphaRun::predict(const AlphaCoefficients& c) {
  State& x = cur_;
  x.t = prev_.t + h_;
  a_cur_ = (c.alpha_f * prev_.a - c.alpha_m * a_prev_) / (1 - c.alpha_m);
  x.q = prev_.q + h_ * prev_.v + h_ * h_ * ((0.5 - c.beta) * a_prev_ + c.beta * a_cur_);
  x.v = prev_.v + h_ * ((1 - c.gamma) * a_prev_ + c.gamma * a_cur_);
  x.a.setZero();
  x.lambda.setZero();
}

void AlphaRun::evaluate_residual() {
  timed(sum_.seconds.residual, [&] { model_.residual(cur_, p_, k_, zeta_, R_, &r_abs_); });
  ++sum_.residual_evaluations;
}

// The largest |r_i| / (tol_r s_i + floor_i + force_floor) over the position rows, s_i the sum of
// the absolute force terms of row i (inertia, internal, applied, constraint forces).
double AlphaRun::residual_measure() const {
  double m = 0;
  for (int i = 0; i < nq_; ++i) {
    const double r = std::abs(R_[i]);
    if (r == 0) continue;
    const double tol = opt_.tol_r * r_abs_[i] + row_floor_[i] + opt_.force_floor;
    m = std::max(m, tol > 0 ? r / tol : INFINITY);
  }
  return m;
}

// S_t (20) at the current iterate, its round-off floors, and its numeric factorization.
bool AlphaRun::factor_iteration_matrix(const Coefficients& coeffs, NewtonStatus& failure) {
  timed(sum_.seconds.matrix, [&] {
    model_.iteration_matrix(cur_, p_, coeffs, k_, zeta_, vals_);
    row_round_off_floor(model_.pattern(), vals_, cur_.q, L_, nq_, row_floor_);
  });
  sum_.force_floor = std::max(sum_.force_floor, nq_ ? row_floor_.maxCoeff() : 0.0);
  ++sum_.matrix_evaluations;
  have_factor_ = false;
  if (const int bad = first_non_finite_column(model_.pattern(), vals_); bad >= 0) {
    bad_column_ =
        bad;  // an overflow, not a singular motion: say so instead of blaming the factorization
    failure = NewtonStatus::kNonFiniteMatrix;
    return false;
  }
  const Status st = timed(sum_.seconds.factor, [&] { return step_lu_->factor(vals_); });
  ++sum_.factorizations;
  if (!st.ok()) {
    failure = NewtonStatus::kSingular;
    return false;
  }
  have_factor_ = true;
  factor_h_ = h_;
  return true;
}

// [Δq; Δλ] = −S_t⁻¹ [r; kΦ] (19) with the factorization at hand.
bool AlphaRun::solve_correction() {
  dx_ = -R_;
  try {
    timed(sum_.seconds.solve, [&] { step_lu_->solve(dx_); });
  } catch (const LinearSolveError& e) {
    linear_failure_ = e.what();
    return false;
  }
  return true;
}

// Increments (12)–(15) with Δq̇ = γ′Δq, Δq̈ = β′Δq (17)–(18).
void AlphaRun::apply_correction(const AlphaCoefficients& c) {
  cur_.q += dx_.head(nq_);
  cur_.v += c.gamma_p * dx_.head(nq_);
  cur_.a += c.beta_p * dx_.head(nq_);
  cur_.lambda += dx_.tail(nc_);
}

// Corrector: Newton on [r; kΦ] = 0 of eq. (7) from the predicted state. Converged when the
// residual measure and ‖Φ‖∞ / tol_phi are both ≤ 1 after at least min_iter iterations and the
// next correction is within tol_q·L (docs/methods.md, "Convergence test"). S_t is refactorized
// at every iteration (full Newton) or while convergence is slow (modified Newton).
NewtonStatus AlphaRun::newton(const AlphaCoefficients& c) {
  using Newton = GeneralizedAlphaOptions::Newton;
  if (opt_.newton != Newton::kModifiedAcrossSteps || factor_h_ != h_) have_factor_ = false;
  started_with_old_factor_ = have_factor_;
  const Coefficients coeffs{c.beta_p, c.gamma_p, 1.0};
  double prev_err = INFINITY, prev_inc = INFINITY;
  rn_ = pn_ = 0;
  for (iterations_ = 0;; ++iterations_) {
    if (stop_requested()) return NewtonStatus::kStopped;
    evaluate_residual();
    if (!R_.allFinite()) return NewtonStatus::kNonFiniteResidual;
    rn_ = nq_ ? R_.head(nq_).lpNorm<Eigen::Infinity>() : 0.0;
    pn_ = nc_ ? R_.tail(nc_).lpNorm<Eigen::Infinity>() / k_ : 0.0;
    const double err = std::max(residual_measure(), pn_ / tol_phi_);
    const bool residual_ok = err <= 1 && iterations_ >= opt_.min_iter;
    bool slow_chord = false;
    if (residual_ok && have_factor_) {
      // Increment test: the residual alone can be below tol_r·s_i while the positions are not
      // converged (the rows carry the constraint forces, large next to the forces that move a
      // light body along its free directions). The next Newton correction, back-solved with
      // the factorization at hand (no new one), must be within tol_q·L on every position; it is
      // then applied. A small correction that no longer halves is round-off: accepted too.
      if (!solve_correction()) return NewtonStatus::kLinearSolve;
      const double inc = nq_ ? dx_.head(nq_).lpNorm<Eigen::Infinity>() / (opt_.tol_q * L_) : 0.0;
      if (!std::isfinite(inc)) return NewtonStatus::kNonFiniteCorrection;
      if (inc <= 1 || (inc > 0.5 * prev_inc && inc <= kRoundOffIncrement)) {
        apply_correction(c);
        // A reflected element is stress-free (E = ½(FᵀF − I)): Newton can converge to such a
        // far solution of the step equations from the predictor of a long step. Reject it; the
        // step is redone with h/2, whose predictor lies closer to the physical solution.
        inversion_ = model_.most_compressed_element(cur_.q, p_);
        if (inversion_.inverted()) {
          ++sum_.inverted_element_rejections;
          return NewtonStatus::kInverted;
        }
        // An element that folds within one step (det F ≤ 0 at a corner only) is retried with
        // h/2 like an inverted one: on a soft block indented by a sudden load Newton converged
        // from a 1 ms predictor to a far, folded state that h/2 avoids. A fold that remains at the
        // smallest step, or that the previous state already had, is the discrete solution of a
        // mesh too coarse for the deformation: accepted and reported.
        if (inversion_.folded()) {
          if (!prev_folded_ && depth_ < opt_.max_halvings) {
            ++sum_.folded_element_rejections;
            return NewtonStatus::kFolded;
          }
          if (!sum_.folded_element_steps++)
            sum_.folded_first =
                "t = " + std::to_string(cur_.t) + " s, " + inversion_.describe_fold();
        }
        return NewtonStatus::kConverged;
      }
      ++sum_.increment_rejections;
      slow_chord = inc > 0.25 * prev_inc;
      prev_inc = inc;
      if (iterations_ >= opt_.max_iter) return NewtonStatus::kNotConvergedPositions;
      if (!slow_chord) {  // a chord step with the factorization at hand
        apply_correction(c);
        ++sum_.newton_iterations;
        prev_err = err;
        continue;
      }
    } else if (iterations_ >= opt_.max_iter) {
      return NewtonStatus::kNotConverged;
    }
    const bool refactor =
        opt_.newton == Newton::kFull || !have_factor_ || err > 0.25 * prev_err || slow_chord;
    NewtonStatus failure{};
    if (refactor && !factor_iteration_matrix(coeffs, failure)) return failure;
    prev_err = err;
    if (!solve_correction()) return NewtonStatus::kLinearSolve;
    apply_correction(c);
    ++sum_.newton_iterations;
  }
}

// A step whose corrector failed is redone: once with a fresh factorization when it started from
// an old one (modified_across_steps), then with h/2, up to max_halvings times per grid interval.
// A singular S_t is not retried. Otherwise the run ends at the last converged step, and the
// summary says where and why (with the worst residual or constraint entry). True: redo the step.
bool AlphaRun::halve_or_fail(NewtonStatus st) {
  if (st == NewtonStatus::kStopped) {
    sum_.aborted = true;
    return fail("stopped during the step from t = " + std::to_string(prev_.t) + " s");
  }
  const bool singular = st == NewtonStatus::kSingular;
  if (started_with_old_factor_ && !retried_fresh_ && !singular) {
    retried_fresh_ = true;  // an old factorization may be what failed: redo the step once
    have_factor_ = false;
    ++sum_.fresh_factor_retries;
    cur_ = prev_;
    return true;
  }
  retried_fresh_ = false;
  if (depth_ < opt_.max_halvings && !singular) {
    ++depth_;
    ++sum_.halvings;
    sum_.halving_times.push_back(prev_.t);
    h_ *= 0.5;
    cur_ = prev_;
    return true;
  }
  std::string why;
  switch (st) {
    case NewtonStatus::kNonFiniteResidual:
      why = "non-finite residual (NaN or Inf)";
      break;
    case NewtonStatus::kNonFiniteCorrection:
      why = "non-finite Newton correction";
      break;
    case NewtonStatus::kLinearSolve:
      why = "the linear solve of a Newton iteration failed: " + linear_failure_;
      break;
    case NewtonStatus::kNonFiniteMatrix:
      why = "non-finite iteration matrix (NaN or Inf) in the equations of " +
            model_.describe_unknown(bad_column_);
      break;
    case NewtonStatus::kSingular:
      why = "singular iteration matrix: the motion of " +
            model_.describe_unknown(step_lu_->singular_column()) + " is not determined";
      break;
    case NewtonStatus::kFolded:  // not reached: the smallest step accepts a fold
      why = "an element folded within the step, " + inversion_.describe_fold();
      break;
    case NewtonStatus::kInverted:
      why = "the step converged to a state with an inverted element, " + inversion_.describe() +
            ", after " + std::to_string(opt_.max_halvings) +
            " halvings: a reflected St Venant–Kirchhoff element is stress-free, a spurious "
            "solution of the step equations (more halvings, simulation.max_halvings, a smaller h "
            "or ρ∞, or a finer mesh may avoid it)";
      break;
    case NewtonStatus::kNotConvergedPositions:
      why = "Newton did not converge in " + std::to_string(opt_.max_iter) +
            " iterations (position corrections)";
      break;
    default:
      why = "Newton did not converge in " + std::to_string(opt_.max_iter) + " iterations";
      break;
  }
  int worst = 0;
  double wv = -1;
  for (int i = 0; i < model_.n(); ++i) {
    const double v = std::abs(R_[i]) / (i < nq_ ? 1.0 : k_);
    if (std::isfinite(v) ? v > wv : true) {
      wv = v;
      worst = i;
    }
  }
  std::ostringstream os;
  os << "t = " << cur_.t << " (step " << sum_.steps + 1 << ", h = " << h_ << "): " << why;
  if (st != NewtonStatus::kInverted && st != NewtonStatus::kFolded)  // converged: no residual
    os << "; ‖r‖∞ = " << rn_ << " N, ‖Φ‖∞ = " << pn_
       << "; worst: " << model_.describe_unknown(worst);
  return fail(os.str());
}

// StepObserverOptions::Factor::kConverged: S_t re-assembled and factorized at the converged state
// for the observers (the exact Jacobian of the step) instead of the last iteration's.
bool AlphaRun::factor_for_observers(const AlphaCoefficients& c) {
  if (served_.factor != StepObserverOptions::Factor::kConverged || observers_.empty()) return true;
  timed(sum_.seconds.matrix, [&] {
    model_.iteration_matrix(cur_, p_, Coefficients{c.beta_p, c.gamma_p, 1.0}, k_, zeta_, vals_);
  });
  ++sum_.matrix_evaluations;
  ++sum_.factorizations;
  if (!timed(sum_.seconds.factor, [&] { return step_lu_->factor(vals_); }).ok())
    return fail("t = " + std::to_string(cur_.t) +
                ": singular iteration matrix at the converged state");
  return true;
}

// Accepts the converged step: a_{n+1} += (1−α_f)/(1−α_m) q̈_{n+1} (Algorithm 1, last line, cf.
// (8)); a step that ends on the output grid is put exactly on it (no round-off drift).
void AlphaRun::accept(const AlphaCoefficients& c) {
  retried_fresh_ = false;
  for (size_t b = 0; b < model_.spatial_bodies().size(); ++b) {
    const int d0 = model_.spatial_bodies()[b].dof0;
    const double wh = SpatialPose::body_angular_velocity(d0, cur_.q, cur_.v).norm() * h_;
    if (wh > sum_.max_omega_h) {
      sum_.max_omega_h = wh, sum_.max_omega_h_t = cur_.t;
      spinning_body_ = static_cast<int>(b);
    }
  }
  a_cur_ += (1 - c.alpha_f) / (1 - c.alpha_m) * cur_.a;
  prev_folded_ = inversion_.folded();
  ++sum_.steps;
  on_grid_ = std::abs(cur_.t - t_grid_next_) <= 1e-9 * opt_.h;
  if (on_grid_) cur_.t = t_grid_next_;
}

// Hands the step to the observers: the synchronous ones here, the concurrent ones to the worker
// (which then owns this step's factorization; the next step writes the other one). False when an
// observer asked to stop: the run then ends, reported as aborted.
bool AlphaRun::notify_observers(const AlphaCoefficients& c) {
  StepInfo info;
  info.step = static_cast<int>(sum_.steps);
  info.grid_point = on_grid_;
  info.prev = &prev_;
  info.prev_acc_like = &a_prev_;
  info.state = &cur_;
  info.acc_like = &a_cur_;
  info.coef = c;
  info.k = k_;
  info.zeta = zeta_;
  info.factor = step_lu_;
  info.newton_iterations = iterations_;
  bool stop = false;
  for (auto* o : sync_observers_) stop |= !o->on_step(info);
  if (worker_) {
    stop |= !worker_->wait_idle();  // step n's observers are done with the other factorization
    worker_->post(info);
  }
  if (alternate_) {
    step_lu_ = step_lu_ == &lu_ ? &lu_alt_ : &lu_;
    have_factor_ = false;  // the worker solves with the last one; the other is two steps old
  }
  if (stop) sum_.aborted = true;
  return !stop;
}

// n ← n + 1. The next step is the next grid step (h), or the rest of a halved grid interval.
void AlphaRun::next_step() {
  std::swap(prev_, cur_);
  std::swap(a_prev_, a_cur_);
  if (on_grid_) {
    ++grid_;
    t_grid_next_ = t0_ + (grid_ + 1) * opt_.h;
    h_ = opt_.h;
    depth_ = 0;
  } else {
    h_ = std::min(h_, t_grid_next_ - prev_.t);
  }
}

// The summary, the last converged state, and the concurrent observers of the last step completed.
IntegratorSummary AlphaRun::finish() {
  sum_.rho_inf = opt_.rho_inf;
  if (spinning_body_ >= 0)
    sum_.max_omega_h_body = model_.spatial_bodies()[static_cast<size_t>(spinning_body_)].name;
  if (started_) {
    sum_.t_reached = prev_.t;
    if (final_state_) *final_state_ = prev_;
  }
  if (worker_ && !worker_->wait_idle()) sum_.aborted = true;
  for (const SparseLU* lu : {&lu_, &lu_alt_})
    if (const BlockAmg* amg = lu->amg()) {
      sum_.linear_iterations += amg->counters().iterations;
      sum_.max_linear_iterations =
          std::max<long>(sum_.max_linear_iterations, amg->counters().max_iterations);
      const auto& c = amg->counters();
      const std::string used = c.fallbacks > 0 ? "bulky, then thin" : c.bulky ? "bulky" : "thin";
      if (sum_.linear_preconditioner.empty() || c.fallbacks > 0) sum_.linear_preconditioner = used;
    }
  sum_.wall_seconds = seconds_since(t_start_);
  return std::move(sum_);
}

}  // namespace

namespace {
// Algorithm 1's loop over the steps of a started run (with the departures listed in the header).
IntegratorSummary integrate(AlphaRun& run, const GeneralizedAlphaOptions& opt) {
  while (!run.done()) {
    const AlphaCoefficients c = AlphaCoefficients::make(opt.rho_inf, run.step_size());  // (11)
    run.predict(c);                         // q̈_{n+1} = 0, λ_{n+1} = 0; a, q, q̇ by (8)–(10)
    const NewtonStatus st = run.newton(c);  // S_t [Δq; Δλ] = −[r; kΦ] (19) until converged
    if (st != NewtonStatus::kConverged) {
      if (run.halve_or_fail(st)) continue;  // redo the step (fresh factorization or h/2)
      break;
    }
    if (!run.factor_for_observers(c)) break;
    run.accept(c);  // a_{n+1} += (1−α_f)/(1−α_m) q̈_{n+1}
    const bool go_on = run.notify_observers(c);
    run.next_step();
    if (!go_on) break;
  }
  return run.finish();
}
}  // namespace

IntegratorSummary GeneralizedAlpha::run(const Model& model, const ModelParams& p, State s0,
                                        std::vector<StepObserver*> observers, State* final_state) {
  AlphaRun run(opt_, served_, model, p, std::move(observers), final_state);
  if (!run.start(std::move(s0))) return run.finish();
  return integrate(run, opt_);
}

IntegratorSummary GeneralizedAlpha::resume(const Model& model, const ModelParams& p,
                                           const GridCheckpoint& from, long grid_end,
                                           std::vector<StepObserver*> observers,
                                           State* final_state) {
  AlphaRun run(opt_, served_, model, p, std::move(observers), final_state);
  if (!run.start_from(from, grid_end)) return run.finish();
  return integrate(run, opt_);
}

RunStatus IntegratorSummary::status() const {
  if (aborted) return RunStatus::kInterrupted;
  return ok ? RunStatus::kComplete : RunStatus::kFailed;
}

std::string IntegratorSummary::report() const {
  char b[320];
  std::snprintf(b, sizeof b,
                "generalized-alpha: %s at t = %.9g s: %ld steps, %ld Newton iterations, %ld "
                "factorizations, %ld "
                "residual evaluations, %ld step halvings, %.3f s",
                run_status_name(status()), t_reached, steps, newton_iterations, factorizations,
                residual_evaluations, halvings, wall_seconds);
  std::string r = b;
  for (const auto& w : warnings()) r += "\n  warning: " + w;
  return message.empty() ? r : r + "\n  " + message;
}

double IntegratorSummary::omega_h_limit(double rho_inf) {
  return rho_inf <= 0.6 ? 0.2 : rho_inf <= 0.8 ? 0.1 : rho_inf <= 0.9 ? 0.05 : 0.03;
}

std::vector<std::string> IntegratorSummary::warnings() const {
  std::vector<std::string> w;
  if (max_omega_h > omega_h_limit(rho_inf)) {
    char b[400];
    std::snprintf(b, sizeof b,
                  "spatial body '%s' turned at omega h = %.3g (t = %.6g s), beyond %.2g, where "
                  "generalized-alpha with rho_inf = %.2g is stable for a spinning body in natural "
                  "coordinates (docs/methods.md, \"Spatial rigid bodies\"): a smaller h or rho_inf "
                  "keeps it stable; compare with IDAS",
                  max_omega_h_body.c_str(), max_omega_h, max_omega_h_t, omega_h_limit(rho_inf),
                  rho_inf);
    w.emplace_back(b);
  }
  if (folded_element_steps > 0)
    w.push_back(std::to_string(folded_element_steps) +
                " steps ended with a folded element (det F <= 0 at a corner, positive at the "
                "integration points), first at " +
                folded_first +
                ": the mesh is too coarse for this deformation, or the step converged to a far "
                "solution; compare with a smaller h or with IDAS");
  return w;
}

}  // namespace lsmbs
