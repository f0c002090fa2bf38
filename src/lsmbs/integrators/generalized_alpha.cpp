#include "lsmbs/integrators/generalized_alpha.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "lsmbs/integrators/initial_state.hpp"

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
  if (!(h > 0)) return "h: expected a positive time step";
  if (!(t_end > 0)) return "t_end: expected a positive final time";
  if (!(rho_inf >= 0 && rho_inf <= 1)) return "rho_inf: expected a value in [0, 1]";
  if (!(tol_r > 0)) return "tol_r: expected a positive tolerance";
  if (!(tol_phi > 0)) return "tol_phi: expected a positive tolerance";
  if (!(tol_q > 0)) return "tol_q: expected a positive tolerance";
  if (!(force_floor >= 0)) return "force_floor: expected a non-negative force";
  if (max_iter < 1) return "max_iter: expected at least 1";
  if (min_iter < 0 || min_iter > max_iter) return "min_iter: expected 0 <= min_iter <= max_iter";
  if (max_halvings < 0 || max_halvings > 30) return "max_halvings: expected 0..30";
  if (threads < 1 || threads > 2) return "threads: expected 1 or 2";
  if (k < 0 || zeta < 0) return "k, zeta: expected non-negative values (0 = automatic)";
  return {};
}

nlohmann::json GeneralizedAlphaOptions::to_json() const {
  return {{"h", h}, {"t_end", t_end}, {"rho_inf", rho_inf}, {"tol_r", tol_r}, {"tol_phi", tol_phi}, {"tol_q", tol_q},
          {"force_floor", force_floor}, {"max_iter", max_iter}, {"min_iter", min_iter},
          {"consistent_start", consistent_start}, {"project_initial", project_initial},
          {"newton", newton_name(newton)}, {"max_halvings", max_halvings},
          {"ordering", SparseLU::ordering_name(ordering)},
          {"sensitivity_matrix", refactor_converged ? "converged" : "last_iteration"}, {"threads", threads},
          {"k", k}, {"zeta", zeta}};
}

const char* GeneralizedAlphaOptions::newton_name(Newton n) {
  return n == Newton::kFull ? "full" : n == Newton::kModified ? "modified" : "modified_across_steps";
}

nlohmann::json IntegratorSummary::to_json() const {
  return {{"ok", ok}, {"aborted", aborted}, {"message", message}, {"t_reached", t_reached},
          {"steps", steps}, {"newton_iterations", newton_iterations}, {"factorizations", factorizations},
          {"residual_evaluations", residual_evaluations}, {"matrix_evaluations", matrix_evaluations},
          {"halvings", halvings}, {"halving_times", halving_times},
          {"fresh_factor_retries", fresh_factor_retries}, {"increment_rejections", increment_rejections},
          {"seconds", {{"setup", seconds.setup}, {"residual", seconds.residual}, {"matrix", seconds.matrix},
                       {"factor", seconds.factor}, {"solve", seconds.solve}}},
          {"k", k}, {"zeta", zeta},
          {"residual_floor_N", force_floor},
          {"wall_seconds", wall_seconds}};
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

namespace {

// Column of the first NaN or Inf among the values of a matrix on `pat`, or −1.
int first_non_finite_column(const CscPattern& pat, const std::vector<double>& vals) {
  for (int col = 0; col < pat.n; ++col)
    for (int at = pat.col_ptr[col]; at < pat.col_ptr[col + 1]; ++at)
      if (!std::isfinite(vals[at])) return col;
  return -1;
}

struct Workspace {
  State cur, prev;
  Vec a_cur, a_prev;
  Vec R, r_abs, dx;
  Vec row_floor;  // per-row round-off floor [N] from the last assembled iteration matrix
  std::vector<double> vals;
};

// Round-off floor of each residual row (positions only). A position known to ε·x_j (x_j =
// max(|q_j|, L)) perturbs row i by about Σ_j |S_ij| ε x_j through the iteration matrix (β′M, K_t,
// ζΦ_qᵀΦ_q: this is where the h⁻² of β′ and ζ enters, row by row rather than as one global
// bound); the sum of the row's force terms s_i adds its own ε s_i. No Newton iteration gets the
// row below this, and the test never asks it to.
// Newton corrections up to this multiple of tol_q·L that stop halving are round-off (accepted).
constexpr double kRoundOffIncrement = 100;

void row_round_off_floor(const CscPattern& pat, const std::vector<double>& vals, const Vec& q, double L, int nq,
                         Vec& floor) {
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

}  // namespace

IntegratorSummary GeneralizedAlpha::run(const Model& model, const ModelParams& p, State s0,
                                        std::vector<StepObserver*> observers, State* final_state) {
  const auto t_start = std::chrono::steady_clock::now();
  IntegratorSummary sum;
  std::optional<ObserverWorker> worker;
  auto finish = [&](IntegratorSummary& s) -> IntegratorSummary& {
    if (worker && !worker->wait_idle()) s.aborted = true;  // the last step's observers complete
    s.wall_seconds = seconds_since(t_start);
    return s;
  };
  if (auto msg = opt_.validate(); !msg.empty()) {
    sum.ok = false;
    sum.message = "invalid integrator option " + msg;
    return finish(sum);
  }
  const int nq = model.nq(), nc = model.nc(), n = model.n();
  s0.v.conservativeResize(nq);
  if (s0.a.size() != nq) s0.a.setZero(nq);
  if (s0.lambda.size() != nc) s0.lambda.setZero(nc);

  SparseLU lu;
  lu.set_ordering(opt_.ordering);
  lu.analyze(model.pattern());
  const AlphaCoefficients c0 = AlphaCoefficients::make(opt_.rho_inf, opt_.h);

  if (opt_.project_initial) {
    if (auto st = project_initial_state(model, p, s0, lu, 1e-13 * model.length_scale()); !st.ok()) {
      sum.ok = false;
      sum.message = "t = " + std::to_string(s0.t) + ": " + st.message;
      return finish(sum);
    }
  }
  const double stiffness_scale = automatic_scaling(model, p, s0, c0);
  sum.k = opt_.k > 0 ? opt_.k : stiffness_scale;
  sum.zeta = opt_.zeta > 0 ? opt_.zeta : sum.k;
  const double k = sum.k, zeta = sum.zeta;

  if (opt_.consistent_start) {
    if (auto st = consistent_accelerations(model, p, k, s0, lu); !st.ok()) {
      sum.ok = false;
      sum.message = "t = " + std::to_string(s0.t) + ": " + st.message;
      return finish(sum);
    }
  } else {
    s0.a.setZero(nq);
    s0.lambda.setZero(nc);
  }

  Workspace w;
  w.cur = s0;
  w.prev = s0;
  w.a_cur = s0.a;  // a_0 = q̈_0
  w.a_prev = w.a_cur;
  w.R.resize(n);
  w.r_abs.resize(nq);
  w.dx.resize(n);
  for (auto* o : observers) o->on_start(s0, w.a_cur, c0, k, zeta, opt_.consistent_start ? &lu : nullptr);
  lu.reset_pivoting();  // the first Newton iteration factorizes with fresh pivoting

  // Concurrent observers: a second numeric factorization of the same symbolic analysis, so that
  // step n+1 is factorized into one while the worker back-solves with step n's in the other.
  std::vector<StepObserver*> sync_observers, concurrent_observers;
  for (auto* o : observers) (opt_.threads > 1 && o->concurrent() ? concurrent_observers : sync_observers).push_back(o);
  SparseLU lu_alt;
  SparseLU* step_lu = &lu;  // the factorization the current step writes
  if (!concurrent_observers.empty()) {
    lu_alt.share_analysis(lu);
    worker.emplace(std::move(concurrent_observers));
  }

  const double tol_phi = opt_.tol_phi * model.length_scale();
  const double L = model.length_scale();
  w.row_floor.setZero(nq);
  // Convergence measure: the largest |r_i| / (tol_r s_i + floor_i + force_floor) with s_i the sum of
  // the absolute force terms of row i (inertia, internal, applied, constraint forces), and
  // ‖Φ‖∞ / tol_phi. Both ≤ 1: converged (docs/methods.md, "Convergence test").
  // Newton correction (17)–(18): Δq̇ = γ′Δq, Δq̈ = β′Δq
  auto apply_correction = [&](State& x, const AlphaCoefficients& c) {
    x.q += w.dx.head(nq);
    x.v += c.gamma_p * w.dx.head(nq);
    x.a += c.beta_p * w.dx.head(nq);
    x.lambda += w.dx.tail(nc);
  };
  auto residual_measure = [&]() {
    double m = 0;
    for (int i = 0; i < nq; ++i) {
      const double r = std::abs(w.R[i]);
      if (r == 0) continue;
      const double tol = opt_.tol_r * w.r_abs[i] + w.row_floor[i] + opt_.force_floor;
      m = std::max(m, tol > 0 ? r / tol : INFINITY);
    }
    return m;
  };
  const long n_steps = std::lround(std::ceil((opt_.t_end - s0.t) / opt_.h - 1e-9));
  long grid = 0;
  double h_try = opt_.h;
  int depth = 0;  // halvings active for the current grid interval
  double t_grid_next = s0.t + opt_.h;
  using Newton = GeneralizedAlphaOptions::Newton;
  // Factorization in step_lu that a step may start from (modified_across_steps): its h, and
  // whether a failed step should be retried with a fresh one.
  bool have_factor = false, retried_fresh = false;
  double factor_h = 0;

  sum.seconds.setup = seconds_since(t_start);
  while (grid < n_steps) {
    const double t_n = w.prev.t;
    const AlphaCoefficients c = AlphaCoefficients::make(opt_.rho_inf, h_try);
    State& x = w.cur;
    // ---- predictor (Algorithm 1): q̈_{n+1} = 0, λ_{n+1} = 0, a_{n+1} from (8)
    x.t = t_n + h_try;
    w.a_cur = (c.alpha_f * w.prev.a - c.alpha_m * w.a_prev) / (1 - c.alpha_m);
    x.q = w.prev.q + h_try * w.prev.v + h_try * h_try * ((0.5 - c.beta) * w.a_prev + c.beta * w.a_cur);
    x.v = w.prev.v + h_try * ((1 - c.gamma) * w.a_prev + c.gamma * w.a_cur);
    x.a.setZero();
    x.lambda.setZero();
    // ---- Newton
    if (opt_.newton != Newton::kModifiedAcrossSteps || factor_h != h_try) have_factor = false;
    const bool started_with_old_factor = have_factor;
    bool converged = false;
    std::string why;
    int it = 0;
    double rn = 0, pn = 0, prev_err = INFINITY, prev_inc = INFINITY;
    const Coefficients coeffs{c.beta_p, c.gamma_p, 1.0};
    for (;; ++it) {
      if (std::any_of(observers.begin(), observers.end(), [](const StepObserver* o) { return o->stop_requested(); })) {
        sum.ok = false;  // abandon the step in progress: the run ends at the last converged step
        sum.aborted = true;
        sum.message = "stopped during the step from t = " + std::to_string(t_n) + " s";
        sum.t_reached = w.prev.t;
        if (final_state) *final_state = w.prev;
        return finish(sum);
      }
      timed(sum.seconds.residual, [&] { model.residual(x, p, k, zeta, w.R, &w.r_abs); });
      ++sum.residual_evaluations;
      if (!w.R.allFinite()) {
        why = "non-finite residual (NaN or Inf)";
        break;
      }
      rn = nq ? w.R.head(nq).lpNorm<Eigen::Infinity>() : 0.0;
      pn = nc ? w.R.tail(nc).lpNorm<Eigen::Infinity>() / k : 0.0;
      // convergence measure: residual rows and constraints relative to their tolerances
      const double err = std::max(residual_measure(), pn / tol_phi);
      const bool residual_ok = err <= 1 && it >= opt_.min_iter;
      bool slow_chord = false;
      if (residual_ok && have_factor) {
        // Increment test: the residual alone can be below tol_r·s_i while the positions are not
        // converged (the rows carry the constraint forces, large next to the forces that move a
        // light body along its free directions). The next Newton correction, back-solved with
        // the factorization at hand (no new one), must be within tol_q·L on every position; it is
        // then applied. A small correction that no longer halves is round-off: accepted too.
        w.dx = -w.R;
        timed(sum.seconds.solve, [&] { step_lu->solve(w.dx); });
        const double inc = nq ? w.dx.head(nq).lpNorm<Eigen::Infinity>() / (opt_.tol_q * L) : 0.0;
        if (!std::isfinite(inc)) {
          why = "non-finite Newton correction";
          break;
        }
        if (inc <= 1 || (inc > 0.5 * prev_inc && inc <= kRoundOffIncrement)) {
          apply_correction(x, c);
          converged = true;
          break;
        }
        ++sum.increment_rejections;
        slow_chord = inc > 0.25 * prev_inc;
        prev_inc = inc;
        if (it >= opt_.max_iter) {
          why = "Newton did not converge in " + std::to_string(opt_.max_iter) + " iterations (position corrections)";
          break;
        }
        if (!slow_chord) {  // a chord step with the factorization at hand
          apply_correction(x, c);
          ++sum.newton_iterations;
          prev_err = err;
          continue;
        }
      } else if (it >= opt_.max_iter) {
        why = "Newton did not converge in " + std::to_string(opt_.max_iter) + " iterations";
        break;
      }
      const bool refactor = opt_.newton == Newton::kFull || !have_factor || err > 0.25 * prev_err || slow_chord;
      if (refactor) {
        timed(sum.seconds.matrix, [&] {
          model.iteration_matrix(x, p, coeffs, k, zeta, w.vals);
          row_round_off_floor(model.pattern(), w.vals, x.q, L, nq, w.row_floor);
        });
        sum.force_floor = std::max(sum.force_floor, nq ? w.row_floor.maxCoeff() : 0.0);
        ++sum.matrix_evaluations;
        if (const int bad = first_non_finite_column(model.pattern(), w.vals); bad >= 0) {
          // an overflow, not a singular motion: say so instead of blaming the factorization
          why = "non-finite iteration matrix (NaN or Inf) in the equations of " + model.describe_unknown(bad);
          have_factor = false;
          break;
        }
        const Status st = timed(sum.seconds.factor, [&] { return step_lu->factor(w.vals); });
        ++sum.factorizations;
        if (!st.ok()) {
          why = "singular iteration matrix: the motion of " + model.describe_unknown(step_lu->singular_column()) +
                " is not determined";
          have_factor = false;
          break;
        }
        have_factor = true;
        factor_h = h_try;
      }
      prev_err = err;
      w.dx = -w.R;
      timed(sum.seconds.solve, [&] { step_lu->solve(w.dx); });
      apply_correction(x, c);
      ++sum.newton_iterations;
    }
    if (!converged) {
      if (started_with_old_factor && !retried_fresh && why.rfind("singular", 0) != 0) {
        retried_fresh = true;  // an old factorization may be what failed: redo the step once
        have_factor = false;
        ++sum.fresh_factor_retries;
        x = w.prev;
        continue;
      }
      retried_fresh = false;
      if (depth < opt_.max_halvings && why.rfind("singular", 0) != 0) {
        ++depth;
        ++sum.halvings;
        sum.halving_times.push_back(t_n);
        h_try *= 0.5;
        x = w.prev;
        continue;
      }
      // worst residual / constraint entry
      int worst = 0;
      double wv = -1;
      for (int i = 0; i < n; ++i) {
        const double v = std::abs(w.R[i]) / (i < nq ? 1.0 : k);
        if (std::isfinite(v) ? v > wv : true) {
          wv = v;
          worst = i;
        }
      }
      std::ostringstream os;
      os << "t = " << x.t << " (step " << sum.steps + 1 << ", h = " << h_try << "): " << why
         << "; ‖r‖∞ = " << rn << " N, ‖Φ‖∞ = " << pn << "; worst: " << model.describe_unknown(worst);
      sum.ok = false;
      sum.message = os.str();
      sum.t_reached = w.prev.t;
      if (final_state) *final_state = w.prev;
      return finish(sum);
    }
    if (opt_.refactor_converged && !observers.empty()) {
      timed(sum.seconds.matrix, [&] { model.iteration_matrix(x, p, coeffs, k, zeta, w.vals); });
      ++sum.matrix_evaluations;
      ++sum.factorizations;
      if (!timed(sum.seconds.factor, [&] { return step_lu->factor(w.vals); }).ok()) {
        sum.ok = false;
        sum.message = "t = " + std::to_string(x.t) + ": singular iteration matrix at the converged state";
        sum.t_reached = w.prev.t;
        if (final_state) *final_state = w.prev;
        return finish(sum);
      }
    }
    retried_fresh = false;
    // ---- accept: a_{n+1} += (1−α_f)/(1−α_m) q̈_{n+1}   (Algorithm 1, last line)
    w.a_cur += (1 - c.alpha_f) / (1 - c.alpha_m) * x.a;
    ++sum.steps;
    const bool on_grid = std::abs(x.t - t_grid_next) <= 1e-9 * opt_.h;
    if (on_grid) x.t = t_grid_next;  // remove round-off drift
    StepInfo info;
    info.step = static_cast<int>(sum.steps);
    info.grid_point = on_grid;
    info.prev = &w.prev;
    info.prev_acc_like = &w.a_prev;
    info.state = &x;
    info.acc_like = &w.a_cur;
    info.coef = c;
    info.k = k;
    info.zeta = zeta;
    info.factor = step_lu;
    info.newton_iterations = it;
    bool stop = false;
    for (auto* o : sync_observers) stop |= !o->on_step(info);
    if (worker) {
      stop |= !worker->wait_idle();  // step n's observers are done with the other factorization
      worker->post(info);
      step_lu = step_lu == &lu ? &lu_alt : &lu;
      have_factor = false;  // the worker solves with the last one; the other is two steps old
    }
    std::swap(w.prev, w.cur);
    std::swap(w.a_prev, w.a_cur);
    if (stop) {
      sum.aborted = true;
      break;
    }
    if (on_grid) {
      ++grid;
      t_grid_next = s0.t + (grid + 1) * opt_.h;
      h_try = opt_.h;
      depth = 0;
    } else {
      h_try = std::min(h_try, t_grid_next - w.prev.t);
    }
  }
  sum.t_reached = w.prev.t;
  if (final_state) *final_state = w.prev;
  return finish(sum);
}

}  // namespace lsmbs
