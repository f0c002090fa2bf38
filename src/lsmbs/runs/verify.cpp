#include "lsmbs/runs/verify.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/responses/mesh_convergence.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {
namespace {

namespace fs = std::filesystem;
using Method = SensitivityOptions::Method;
using json = nlohmann::json;

Case make(const json& j, const std::string& file) {
  Case c = load_case_json(j, file, fs::path(file).parent_path().string());
  return c;
}

double scale_of(const Mat& g) { return g.size() ? g.cwiseAbs().maxCoeff() : 0.0; }

// Worst relative gradient difference, per response (GradientNorm::kPerResponse).
double worst(const SensitivityResult& a, const SensitivityResult& ref) {
  return compare_gradients(a.responses, ref.responses, GradientNorm::kPerResponse).worst;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// "worst 2.1e-07 < tolerance 1e-05" when it passes, "worst 6.2e-05 >= tolerance 1e-05" when not:
// the line states the comparison that holds
std::string below(double worst, double tolerance) {
  return "worst " + fmt("%.2e", worst) + (worst < tolerance ? " < " : " >= ") + "tolerance " +
         fmt("%.0e", tolerance);
}

// "within 1 ± 0.2" or "outside 1 ± 0.2", as the value lies
// User text (names of the case, variables, responses; the case file's path) as Markdown text of
// report.md: a '|' would split a table row, a line break a table or a list, '<' start HTML, and
// control characters reach whoever cats the file; each is written as an escape or an entity.
std::string md_text(const std::string& s) {
  std::string r;
  char b[8];
  for (unsigned char c : s) {
    switch (c) {
      case '|':
        r += "\\|";
        break;
      case '<':
        r += "&lt;";
        break;
      case '>':
        r += "&gt;";
        break;
      case '&':
        r += "&amp;";
        break;
      case '\\':
        r += "\\\\";
        break;
      case '`':
        r += "\\`";
        break;
      default:
        if (c < 0x20 || c == 0x7f) {
          std::snprintf(b, sizeof b, "\\x%02x", c);
          r += b;
        } else {
          r += static_cast<char>(c);
        }
    }
  }
  return r;
}

std::string within(bool ok, const std::string& range) {
  return (ok ? "within " : "outside ") + range;
}

// The smallest and largest of the errors that are numbers (a failed run's is NaN).
double finite_min(const std::vector<double>& e) {
  double m = std::numeric_limits<double>::infinity();
  for (double v : e)
    if (std::isfinite(v)) m = std::min(m, v);
  return m;
}
double finite_max(const std::vector<double>& e) {
  double m = 0;
  for (double v : e)
    if (std::isfinite(v)) m = std::max(m, v);
  return m;
}

}  // namespace

std::string VerifyOptions::validate() const {
  auto got = [](double v) { return ", got " + fmt("%g", v); };
  if (!(fd_delta > 0 && fd_delta < 1) && !fd_absolute)
    return "fd_delta: expected a relative step in (0, 1)" + got(fd_delta);
  if (!(fd_delta > 0) || !std::isfinite(fd_delta))
    return "fd_delta: expected a positive finite step" + got(fd_delta);
  if (!(tol_fd > 0) || !std::isfinite(tol_fd))
    return "tol_fd: expected a positive threshold" + got(tol_fd);
  if (!(tol_semi > 0) || !std::isfinite(tol_semi))
    return "tol_semi: expected a positive threshold" + got(tol_semi);
  if (!(tol_mesh > 0) || !std::isfinite(tol_mesh))
    return "tol_mesh: expected a positive threshold" + got(tol_mesh);
  if (!(idas_rtol >= 1e-14 && idas_rtol <= 1e-4))
    return "idas_rtol: expected a relative tolerance in [1e-14, 1e-4]" + got(idas_rtol);
  return {};
}

namespace {

using M = SensitivityOptions::Matrix;

// The verification of one case: each section of report.md is a method, run in order by
// run_verify; the state they share (the case, the design point, the report, the verdicts, the
// gradient runs, the IDAS reference) lives here.
class Verification {
 public:
  Verification(const std::string& file, const VerifyOptions& o) : file_(file), o_(o) {}
  VerifyResult run();

 private:
  struct Run {
    std::string name;
    SensitivityResult r;
  };
  void load();
  void header();
  void primal();
  void plan();
  void idas_reference();
  void gradient_runs();
  void gradient_table();
  void against_idas();
  void cost_table();
  void dp_study();
  void dp_plot(const std::vector<double>& dl, const std::vector<double>& ef,
               const std::vector<double>& ec);
  void dp_verdict(const char* what, const std::vector<double>& dl, const std::vector<double>& e,
                  double expected, double band);
  void h_study();
  std::vector<SensitivityResult> h_runs();
  struct Series {
    std::string name;
    std::vector<double> diff, self;
  };
  void h_table(const std::vector<Series>& series);
  void h_order(const Series& sr);
  void h_plot(const std::vector<Series>& series);
  void mesh_study();
  void finish();
  nlohmann::json summary(double wall) const;

  void verdict(bool ok, const std::string& what) {
    verdicts_.push_back(std::string(ok ? "PASS" : "FAIL") + " — " + what);
    vr_.pass &= ok;
  }
  // a check that could not decide (its reference is not accurate enough): said, not failed
  void note(const std::string& what) { verdicts_.push_back("NOTE — " + what); }
  void stage(const std::string& what);
  // a failed run has no numbers to compare: the verification stops, saying which run and why;
  // an interrupt ends the verification wherever it is (exit 130, the run flagged interrupted)
  SensitivityResult checked(SensitivityResult r, const std::string& what) const;
  SensitivityResult sens(Method m, double delta, bool absolute, M mx) const;
  SensitivityOptions options() const {
    SensitivityOptions so;
    so.progress = o_.on_progress;
    return so;
  }
  // a generalized-α result along the IDAS directions (gradients G W)
  SensitivityResult along(SensitivityResult r) const {
    if (W_.size())
      for (auto& x : r.responses) x.gradient = (x.gradient * W_).eval();
    return r;
  }

  const std::string& file_;
  const VerifyOptions& o_;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  Case cs_;
  json base_;
  Vec p_;
  VerifyResult vr_;
  std::ostringstream md_;
  std::vector<std::string> verdicts_;
  std::vector<std::string> files_ = {"gradients.csv", "report.md", "summary.json"};
  double primal_ = 0;
  bool rect_ = false, state_from_data_ = false;
  int n_stages_ = 0, stage_no_ = 0;
  std::vector<double> steps_;  // the time-step study's h
  size_t at_h0_ = 0;           // the case's grid in steps_
  double rtol_tight_ = 0, rtol_loose_ = 0;
  Mat W_;  // n_v × k directions of the IDAS reference; empty: every variable
  std::vector<std::string> dir_names_;
  nlohmann::json cost_;
  std::vector<SensitivityResult> idas_tight_, idas_loose_;  // per grid of steps_
  std::vector<Run> runs_;
};

void Verification::stage(const std::string& what) {
  throw_if_interrupted("during verify, before: " + what);
  ++stage_no_;
  if (o_.on_stage)
    o_.on_stage(std::to_string(stage_no_) + "/" + std::to_string(n_stages_) + " " + what);
  signal_point(("verify:" + std::to_string(stage_no_)).c_str());
}

SensitivityResult Verification::checked(SensitivityResult r, const std::string& what) const {
  throw_if_interrupted("during verify: " + what);
  if (!r.ok)
    throw NumericalFailure("verify: " + what + " at the design point failed: " + r.message);
  return r;
}

SensitivityResult Verification::sens(Method m, double delta, bool absolute, M mx) const {
  SensitivityOptions so = options();
  so.method = m;
  so.delta = delta;
  so.relative = !absolute;
  so.matrix = mx;
  return checked(compute_sensitivities(cs_, p_, so), SensitivityOptions::name(m));
}

// The case as the file and the overrides give it (validated before anything is written), the
// design point, and which studies apply.
void Verification::load() {
  cs_ = load_case(file_, o_.case_overrides);
  base_ = cs_.raw;
  if (!cs_.design) throw Error(file_, "/design", "verification needs design variables");
  if (cs_.responses.empty())
    throw Error(file_, "/output/responses", "verification needs responses");
  const Design& d = *cs_.design;
  p_ = d.initial();
  for (const auto& [name, value] : o_.design_overrides) {
    const int k = d.variable_index(name);
    if (k < 0) throw Error("--set " + name + ": unknown design variable '" + name + "'");
    p_[k] = value;
  }
  if (o_.on_loaded) o_.on_loaded(cs_);
  fs::create_directories(o_.out_dir);
  d.apply(p_, cs_.model->params());  // the primal timing runs at p too
  // the mesh study: rectangle meshes only; an initial state from data belongs to the case's mesh
  rect_ = o_.mesh_study && !cs_.model->flexible_bodies().empty();
  for (const auto& b : base_.at("bodies"))
    if (b.value("type", "") == "flexible" && b.at("mesh").value("type", "") != "rectangle")
      rect_ = false;
  state_from_data_ = base_.contains("initial_state");
  rect_ = rect_ && !state_from_data_;
  n_stages_ = 2 + (o_.idas ? 2 : 0) + (rect_ ? 1 : 0);
}

void Verification::header() {
  const Design& d = *cs_.design;
  md_ << "# Verification report: " << md_text(cs_.name) << "\n\nCase `" << md_text(file_)
      << "` (SHA-256 " << cs_.sha256.substr(0, 16) << "…), " << d.size()
      << (d.size() == 1 ? " design variable, " : " design variables, ") << cs_.responses.size()
      << " responses, h = " << cs_.simulation.h << " s, t_end = " << cs_.simulation.t_end
      << " s. Produced by `" << o_.command_line << "`.\n\nDesign point:";
  for (int i = 0; i < d.size(); ++i)
    md_ << (i ? ", " : " ") << md_text(d.variables[i].name) << " = " << fmt("%.6g", p_[i]);
  md_ << (o_.design_overrides.empty() ? " (the case's initial design).\n\n" : ".\n\n");
}

void Verification::primal() {
  const auto t = std::chrono::steady_clock::now();
  const auto primal_run = run_simulation(cs_);
  throw_if_interrupted("during verify's primal run");
  if (!primal_run.integrator.ok)
    throw NumericalFailure("verify: the simulation at the design point failed: " +
                           primal_run.integrator.message);
  primal_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The IDAS reference (the directional derivatives of section 1 and the time-step study): one IDAS
// run with outputs on the finest grid of the study (h/2) gives every grid's responses
// (idas_on_grids), and a second one at ten times the tolerances estimates the reference's own
// error. With more than two design variables IDAS differentiates along two random combinations of
// all of them (fixed seed): its cost no longer grows with the number of variables, and fd-central
// checks each variable. What the rest costs is said after the primal run, in simulations of the
// case at h (a run at h/2 counts 2, a mesh with 4× the elements 4): the six gradient runs and
// fd-central's 2n, the Δp study's 21, the time-step study's Σ h0/h, the mesh study's 1/4 + 1 + 4.
// The IDAS reference has no such estimate (its steps adapt): it is said, and its progress shown.
void Verification::plan() {
  const Design& d = *cs_.design;
  const double h0 = cs_.simulation.h, span = cs_.simulation.t_end - cs_.initial.t;
  for (double f : {4.0, 2.0})  // h0·4, h0·2 when t_end stays a multiple of h; h0, h0/2
    if (std::abs(span / (f * h0) - std::round(span / (f * h0))) < 1e-9 * span / h0 &&
        span / (f * h0) >= 4)
      steps_.push_back(f * h0);
  steps_.push_back(h0);
  steps_.push_back(h0 / 2);
  at_h0_ = steps_.size() - 2;
  rtol_tight_ = o_.idas_rtol, rtol_loose_ = 10 * o_.idas_rtol;
  if (d.size() > 2) {
    std::mt19937_64 g(20261125);
    std::uniform_real_distribution<double> u(0.5, 1.0);
    W_.resize(d.size(), 2);
    for (Eigen::Index j = 0; j < W_.cols(); ++j)
      for (int i = 0; i < d.size(); ++i) {
        const double scale =
            std::max(std::abs(p_[i]), 1e-2 * (d.variables[i].upper - d.variables[i].lower));
        W_(i, j) = (g() % 2 ? 1.0 : -1.0) * u(g) * scale;
      }
    dir_names_ = {"w1", "w2"};
  } else {
    for (const auto& v : d.variables) dir_names_.push_back(v.name);
  }
  double planned = 6 + 2.0 * d.size() + 21;
  if (o_.idas)
    for (double h : steps_) planned += h0 / h;
  if (rect_) planned += 5.25;
  cost_ = {{"primal_seconds", primal_},
           {"simulations_planned_besides_idas", planned},
           {"estimated_seconds_besides_idas", planned * primal_},
           {"idas_runs", o_.idas ? 2 : 0},
           {"definition",
            "simulations of the case at its h and mesh (a run at h/2 counts 2, a mesh of 4x the "
            "elements 4); a sensitivity run by a direct or semi-analytical method counts 1, "
            "fd-central 1 per simulation; the IDAS reference is not estimated"}};
  if (o_.on_plan)
    o_.on_plan("one simulation took " + fmt("%.3g", primal_) + " s; the verification runs about " +
               fmt("%.0f", planned) + " simulations' worth (about " +
               fmt("%.3g", planned * primal_) + " s)" +
               (o_.idas ? " plus two IDAS runs with forward sensitivities (rtol " +
                              fmt("%.0e", rtol_tight_) + " and " + fmt("%.0e", rtol_loose_) +
                              "), whose cost is not known ahead and is shown as they run; "
                              "--no-idas skips them"
                        : ""));
}

void Verification::idas_reference() {
  if (!o_.idas) return;
  stage("IDAS reference (rtol " + fmt("%.0e", rtol_tight_) + " and " + fmt("%.0e", rtol_loose_) +
        ", " + std::to_string(dir_names_.size()) + (W_.size() ? " directions" : " variables") +
        ", outputs every h/2)");
  const double h0 = cs_.simulation.h;
  auto idas_runs = [&](double rtol) {
    SensitivityOptions so = options();
    so.idas.rtol = rtol;
    so.idas.atol = 1e-3 * rtol;  // in units of the model's length scale
    std::vector<int> strides;
    for (double h : steps_) strides.push_back(static_cast<int>(std::lround(h / (h0 / 2))));
    return idas_on_grids(cs_, p_, so, h0 / 2, strides, W_.size() ? &W_ : nullptr);
  };
  idas_tight_ = idas_runs(rtol_tight_);
  throw_if_interrupted("during verify's IDAS reference");
  idas_loose_ = idas_runs(rtol_loose_);
  throw_if_interrupted("during verify's IDAS reference");
  for (const auto* r : {&idas_tight_[0], &idas_loose_[0]})
    if (!r->ok)
      throw NumericalFailure("verify: the IDAS reference failed: " + r->message +
                             " (--idas-rtol with a looser tolerance may pass; --no-idas "
                             "verifies without IDAS)");
}

// The generalized-α methods share the exact matrix (refined), so that their columns differ only
// in the pseudo-loads; the paper's last-iteration matrix gets its own column; the last column is
// what a user gets without options, checked against fd-central like the reference.
void Verification::gradient_runs() {
  stage("gradients by every method");
  runs_.push_back({"direct-analytic", sens(Method::kDirectAnalytic, 1e-6, false, M::kRefined)});
  runs_.push_back({"semi-analytical", sens(Method::kSemiAnalytical, 1e-6, false, M::kRefined)});
  runs_.push_back(
      {"semi-analytical-central", sens(Method::kSemiAnalyticalCentral, 1e-6, false, M::kRefined)});
  runs_.push_back(
      {"fd-central", sens(Method::kFdCentral, o_.fd_delta, o_.fd_absolute, M::kLastIteration)});
  runs_.push_back({"direct-analytic (last-iteration matrix)",
                   sens(Method::kDirectAnalytic, 1e-6, false, M::kLastIteration)});
  runs_.push_back(
      {"default options (" + std::string(SensitivityOptions::name(SensitivityOptions{}.method)) +
           ", --matrix " + SensitivityOptions::matrix_name(SensitivityOptions{}.matrix) + ")",
       checked(compute_sensitivities(cs_, p_, options()), "the default method")});
}

// Section 1: the gradient of every method, relative to direct-analytic; gradients.csv.
void Verification::gradient_table() {
  const Design& d = *cs_.design;
  md_ << "## 1. Gradients\n\nReference: `direct-analytic` with the converged-state matrix "
         "(`refined`, as the two semi-analytical columns); the last-iteration-matrix column is "
         "the paper's Algorithm 2 matrix (for comparison, not checked); the last column is what "
         "`lsmbs sensitivity` gives without options, checked against fd-central like the "
         "reference. For the other methods the table gives the relative difference |g − g_ref| / "
         "‖g_ref‖∞ (per response value, over the variables; for a per-step response ‖g_ref‖∞ "
         "over all steps) and the agreeing digits −log10 of it. fd-central step: "
      << o_.fd_delta << (o_.fd_absolute ? " (absolute)" : " (relative)") << ".\n\n";
  // gradients.csv: one row per response and variable (a per-step response: its worst step, the
  // table's), one column per method; method names hold commas, hence csv_field
  std::ostringstream gcsv;
  gcsv << "response,variable,step";
  for (const auto& r : runs_) gcsv << "," << csv_field(r.name);
  gcsv << "\n";
  const auto& ref = runs_[0].r;
  for (size_t k = 0; k < ref.responses.size(); ++k) {
    const auto& rr = ref.responses[k];
    const bool per_step = !rr.times.empty();
    md_ << "### " << md_text(rr.name) << (per_step ? " (per step: worst step shown)" : "")
        << "\n\n| variable | direct-analytic |";
    for (size_t m = 1; m < runs_.size(); ++m) md_ << " " << md_text(runs_[m].name) << " |";
    md_ << "\n|---|---|";
    for (size_t m = 1; m < runs_.size(); ++m) md_ << "---|";
    md_ << "\n";
    // the row shown: the worst step of a per-step response (by fd-central difference), else 0
    Eigen::Index row = 0;
    if (per_step) {
      double w = -1;
      for (Eigen::Index i = 0; i < rr.gradient.rows(); ++i) {
        const double e =
            (runs_[3].r.responses[k].gradient.row(i) - rr.gradient.row(i)).cwiseAbs().maxCoeff();
        if (e > w) w = e, row = i;
      }
    }
    const double n = std::max(scale_of(rr.gradient), 1e-300);
    for (int i = 0; i < d.size(); ++i) {
      md_ << "| " << md_text(d.variables[i].name) << " | " << fmt("%.8e", rr.gradient(row, i))
          << " |";
      gcsv << csv_field(rr.name) << "," << csv_field(d.variables[i].name) << "," << row << ","
           << csv_number(rr.gradient(row, i));
      for (size_t m = 1; m < runs_.size(); ++m) {
        const double g = runs_[m].r.responses[k].gradient(row, i),
                     e = std::abs(g - rr.gradient(row, i)) / n;
        md_ << " " << fmt("%.1e", e) << " (" << fmt("%.1f", e > 0 ? -std::log10(e) : 16.0) << ") |";
        gcsv << "," << csv_number(g);
      }
      md_ << "\n";
      gcsv << "\n";
    }
    md_ << "\n";
  }
  write_file_atomic(o_.out_dir + "/gradients.csv", gcsv.str());
  const double e_fd = worst(ref, runs_[3].r), e_semi = worst(runs_[2].r, ref),
               e_def = worst(runs_.back().r, runs_[3].r);
  verdict(e_fd < o_.tol_fd, "direct-analytic vs fd-central: " + below(e_fd, o_.tol_fd));
  verdict(e_def < o_.tol_fd,
          "default sensitivity options vs fd-central: " + below(e_def, o_.tol_fd));
  verdict(e_semi < o_.tol_semi,
          "semi-analytical-central vs direct-analytic: " + below(e_semi, o_.tol_semi));
}

// Section 1b: against IDAS at the case's h (directional derivatives with many variables).
void Verification::against_idas() {
  if (!o_.idas) return;
  const auto ga = along(runs_[0].r);
  const auto& id = idas_tight_[at_h0_];
  md_ << "### Against IDAS at h = " << fmt("%.3e", cs_.simulation.h) << "\n\n"
      << (W_.size() ? "IDAS differentiates along two random combinations w1, w2 of all variables "
                      "(w_i = ±(0.5..1) × max(|p_i|, 1e-2 range_i), seed fixed; the columns of W "
                      "are in summary.json): the table compares the directional derivatives "
                      "∇f · w of direct-analytic with IDAS's. "
                    : "IDAS's forward sensitivities of every variable. ")
      << "IDAS: rtol " << fmt("%.0e", rtol_tight_) << ", atol " << fmt("%.0e", 1e-3 * rtol_tight_)
      << " (× the model's length scale). They differ by generalized-α's time-discretization "
         "error at this h; section 4 shows whether that error falls as h² (a per-step response: "
         "its worst step).\n\n| response | direction | direct-analytic | IDAS | relative "
         "difference |\n|---|---|---|---|---|\n";
  for (size_t k = 0; k < ga.responses.size(); ++k) {
    const auto &a = ga.responses[k], &b = id.responses[k];
    Eigen::Index row = 0;  // the worst step of a per-step response
    if (!a.times.empty())
      (a.gradient - b.gradient).rowwise().lpNorm<Eigen::Infinity>().maxCoeff(&row);
    const double n = std::max(scale_of(b.gradient), 1e-300);
    for (Eigen::Index j = 0; j < b.gradient.cols(); ++j)
      md_ << "| " << md_text(a.name)
          << (a.times.empty() ? "" : " (step " + std::to_string(row) + ")") << " | "
          << md_text(dir_names_[static_cast<size_t>(j)]) << " | " << fmt("%.8e", a.gradient(row, j))
          << " | " << fmt("%.8e", b.gradient(row, j)) << " | "
          << fmt("%.1e", std::abs(a.gradient(row, j) - b.gradient(row, j)) / n) << " |\n";
  }
  md_ << "\n";
}

// Section 2: what each method costs, against the primal simulation.
void Verification::cost_table() {
  md_ << "## 2. Cost\n\nPrimal simulation alone: " << fmt("%.3f", primal_)
      << " s.\n\n| method | wall [s] | / primal | simulations | factorizations | back-solve rhs | "
         "residual evals | pseudo-load residuals | element pseudo-loads |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : runs_) {
    const auto& c = r.r.counts;
    md_ << "| " << md_text(r.name) << " | " << fmt("%.3f", c.wall_seconds) << " | "
        << fmt("%.2f", c.wall_seconds / primal_) << " | " << c.simulations << " | "
        << c.factorizations << " | " << c.back_solve_rhs << " | " << c.residual_evaluations << " | "
        << c.pseudo_load_residuals << " | " << c.element_pseudo_loads << " |\n";
  }
  for (const auto* r : {&idas_tight_, &idas_loose_})  // one run each, all grids of section 4
    if (!r->empty()) {
      const auto& c = r->front().counts;
      md_ << "| IDAS reference, rtol " << fmt("%.0e", r == &idas_tight_ ? rtol_tight_ : rtol_loose_)
          << ", " << dir_names_.size() << (W_.size() ? " directions" : " variables")
          << ", outputs every h/2 | " << fmt("%.3f", c.wall_seconds) << " | "
          << fmt("%.2f", c.wall_seconds / primal_) << " | 1 | " << c.factorizations << " | — | "
          << c.residual_evaluations << " | — | — |\n";
    }
  md_ << "\n";
}

// Section 3: the Δp study of the semi-analytical methods (same matrix for all, refined; only the
// pseudo-load differs). A run that fails at a large Δp (its pseudo-load leaves the region where
// the steps converge, or its derivative is not finite) is a point of the study, not the end of the
// verification: NaN in the table, said in a NOTE.
void Verification::dp_study() {
  stage("Δp study of the semi-analytical methods (10 values of Δp)");
  const auto exact = sens(Method::kDirectAnalytic, 1e-6, false, M::kRefined);
  md_ << "## 3. Δp study\n\nError of the semi-analytical gradients against direct-analytic (same "
         "matrix, `refined`), relative Δp.\n\n| Δp | forward | central |\n|---|---|---|\n";
  const std::vector<double> dl = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
  std::vector<double> ef, ec;
  std::vector<std::string> failed_dp;
  auto error_at = [&](Method m, double x) {
    SensitivityOptions so = options();
    so.method = m;
    so.delta = x;
    so.relative = true;
    so.matrix = M::kRefined;
    std::string why;
    try {
      const SensitivityResult r = compute_sensitivities(cs_, p_, so);
      if (r.ok) return worst(r, exact);
      why = r.message;
    } catch (const NumericalFailure& e) {
      why = e.what();
    }
    throw_if_interrupted("during verify's Δp study");
    failed_dp.push_back(std::string(SensitivityOptions::name(m)) + " at Δp = " + fmt("%.0e", x) +
                        " (" + why + ")");
    return std::numeric_limits<double>::quiet_NaN();
  };
  auto cell = [&](double e) { return std::isnan(e) ? std::string("failed") : fmt("%.2e", e); };
  // written whole once the study is done (an interrupted study leaves no half table that no
  // summary lists: the next --overwrite refused the folder), registered as the run's own
  std::ostringstream c;
  c << "delta,forward,central\n";
  for (double x : dl) {
    ef.push_back(error_at(Method::kSemiAnalytical, x));
    ec.push_back(error_at(Method::kSemiAnalyticalCentral, x));
    c << fmt("%.1e", x) << "," << fmt("%.6e", ef.back()) << "," << fmt("%.6e", ec.back()) << "\n";
    md_ << "| " << fmt("%.0e", x) << " | " << cell(ef.back()) << " | " << cell(ec.back()) << " |\n";
  }
  write_file_atomic(o_.out_dir + "/dp_study.csv", c.str());
  files_.push_back("dp_study.csv");
  dp_plot(dl, ef, ec);
  dp_verdict("forward", dl, ef, 1, 0.2);
  dp_verdict("central", dl, ec, 2, 0.3);
  for (const auto& f : failed_dp)
    note("Δp study: " + f + "; the slopes are fitted on the runs that did not fail");
}

void Verification::dp_plot(const std::vector<double>& dl, const std::vector<double>& ef,
                           const std::vector<double>& ec) {
  PlotSpec ps;
  ps.png = o_.out_dir + "/dp_study.png";
  ps.title = "semi-analytical gradient error vs delta p";
  ps.xlabel = "relative delta p";
  ps.ylabel = "error vs direct-analytic";
  ps.logx = ps.logy = true;
  ps.series = {{dl, ef, "forward"}, {dl, ec, "central"}};
  ps.ymin = 0.1 * std::min(finite_min(ef), finite_min(ec));
  ps.ymax = 10 * std::max(finite_max(ef), finite_max(ec));
  // reference slopes through the errors at Δp = 1e-6 (forward) and 1e-5 (central)
  auto power_line = [&](double x_ref, double y_ref, int order, const char* title) {
    PlotSeries l{dl, {}, title, true, false, order, true};
    for (double x : dl) l.y.push_back(y_ref * std::pow(x / x_ref, order));
    ps.series.push_back(std::move(l));
  };
  if (std::isfinite(ef[4])) power_line(dl[4], ef[4], 1, "slope 1");
  if (std::isfinite(ec[3])) power_line(dl[3], ec[3], 2, "slope 2");
  const bool plotted = plot(ps);
  if (plotted) files_.push_back("dp_study.png");
  md_ << "\n"
      << (plotted ? "![dp study](dp_study.png)\n\n"
                  : "(no picture: no error is positive to draw on log axes; the numbers are in "
                    "dp_study.csv)\n\n");
}

// Slopes on the finest decade of Δp on the truncation side of the smallest error (the round-off
// floor; finer Δp only add round-off) whose two errors both stand 3× above that floor (round-off
// then moves the slope by at most log10(4/3) = 0.12): a fixed decade crossed into round-off on
// cases whose floor sits higher, and a coarser one is pre-asymptotic where the level-set map bends
// (the robot arm's central slope is 1.52 on 1e-3 → 1e-4, 1.99 on 1e-4 → 1e-5). Exact to round-off
// (no truncation error anywhere in the table: the error at the largest Δp within 10× of the
// smallest, a residual linear in the variable for forward differences, at most quadratic for
// central ones, or every error for Δp ≥ 1e-6 below 1e-9): no slope to fit, and none is asked for.
void Verification::dp_verdict(const char* what, const std::vector<double>& dl,
                              const std::vector<double>& e, double expected, double band) {
  const bool failed = std::any_of(e.begin(), e.end(), [](double v) { return std::isnan(v); });
  if (!failed) {
    const double lowest = *std::min_element(e.begin(), e.end());
    if (e.front() <= 10 * lowest || *std::max_element(e.begin(), e.begin() + 5) < 1e-9) {
      verdict(true, std::string(what) + " differences exact to round-off (error " +
                        fmt("%.1e", e.front()) + " at Δp = 1e-2, smallest " + fmt("%.1e", lowest) +
                        "): the residual is " + (expected == 1 ? "linear" : "at most quadratic") +
                        " in the perturbation");
      return;
    }
  }
  const double floor = finite_min(e);
  size_t k = 0;
  bool fitted = false;
  if (std::isfinite(floor)) {
    const auto lowest = std::find(e.begin(), e.end(), floor);
    for (auto i = static_cast<size_t>(lowest - e.begin()); i >= 1 && !fitted; --i)
      if (std::isfinite(e[i - 1]) && e[i - 1] > 3 * floor && e[i] > 3 * floor && e[i] < e[i - 1])
        k = i - 1, fitted = true;
  }
  const double slope = fitted ? std::log10(e[k] / e[k + 1]) : 0.0;
  const bool ok = fitted && std::abs(slope - expected) < band;
  const std::string range = fmt("%.0f", expected) + " ± " + fmt("%.1f", band);
  const std::string decade = " (" + fmt("%.0e", dl[k]) + " → " + fmt("%.0e", dl[k + 1]) + ")";
  verdict(ok, fitted ? std::string(what) + " slope " + fmt("%.2f", slope) + decade + " " +
                           within(ok, range)
                     : std::string(what) +
                           " differences: no decade of Δp above the round-off floor to fit a "
                           "slope on");
}

// Section 4: the time-step study against IDAS, response by response.
void Verification::h_study() {
  if (!o_.idas) {
    md_ << "## 4. Time-step study against IDAS\n\nSkipped (`--no-idas`).\n\n";
    return;
  }
  std::string at;
  for (double h : steps_) at += (at.empty() ? "" : ", ") + fmt("%g", h) + " s";
  stage("time-step study against IDAS (generalized-α at h = " + at + ")");
  md_ << "## 4. Time-step study against IDAS\n\nFor each h, generalized-α (direct-analytic, "
         "refined matrix, tol_r 1e-12) and IDAS (GGL, rtol "
      << fmt("%.0e", rtol_tight_) << ", atol " << fmt("%.0e", 1e-3 * rtol_tight_)
      << ") on the same output grid, for each scalar response: the relative difference of the "
         "values and of the gradients (along the directions of section 1, relative to IDAS's "
         "largest component). The IDAS values of every grid come from one run with outputs "
         "every h/2; its own error is estimated by a second run at rtol "
      << fmt("%.0e", rtol_loose_) << ", atol " << fmt("%.0e", 1e-3 * rtol_loose_)
      << " (\"IDAS self\": the difference of the two IDAS runs). An order is fitted on the "
         "finest halving whose two differences both exceed the reference's accuracy floor, "
         "max(100 × rtol, 4 × the largest IDAS self-difference of that quantity): 4× the "
         "self-difference is about 36× the tight run's error when IDAS's error is proportional "
         "to its tolerance, which moves a fitted order by less than 0.1; below the floor the "
         "differences are the reference's own error and carry no order.\n\n";
  const std::vector<SensitivityResult> ga = h_runs();
  // relative differences of response r: values, gradients
  auto value_diff = [](const ResponseSensitivity& x, const ResponseSensitivity& y) {
    return std::abs(x.values[0] - y.values[0]) / std::max(std::abs(y.values[0]), 1e-300);
  };
  auto gradient_diff = [](const ResponseSensitivity& x, const ResponseSensitivity& y) {
    const double n = std::max(y.gradient.row(0).cwiseAbs().maxCoeff(), 1e-300);
    return (x.gradient.row(0) - y.gradient.row(0)).cwiseAbs().maxCoeff() / n;
  };
  std::ostringstream c;  // h_study.csv: long form
  c << "response,quantity,h,difference,idas_self_difference\n";
  std::vector<Series> series;
  for (size_t r = 0; r < ga.front().responses.size(); ++r) {
    if (!ga.front().responses[r].times.empty()) continue;  // scalar responses
    for (int q = 0; q < 2; ++q) {
      Series sr{ga.front().responses[r].name + (q ? " gradient" : " value"), {}, {}};
      for (size_t k = 0; k < steps_.size(); ++k) {
        const auto &x = ga[k].responses[r], &y = idas_tight_[k].responses[r],
                   &z = idas_loose_[k].responses[r];
        sr.diff.push_back(q ? gradient_diff(x, y) : value_diff(x, y));
        sr.self.push_back(q ? gradient_diff(z, y) : value_diff(z, y));
        c << csv_field(x.name) << "," << (q ? "gradient" : "value") << "," << csv_number(steps_[k])
          << "," << csv_number(sr.diff.back()) << "," << csv_number(sr.self.back()) << "\n";
      }
      series.push_back(std::move(sr));
    }
  }
  write_file_atomic(o_.out_dir + "/h_study.csv", c.str());
  files_.push_back("h_study.csv");
  h_table(series);
  for (const auto& sr : series) h_order(sr);
  md_ << "\n";
  h_plot(series);
}

// The generalized-α runs of the time-step study, along the IDAS directions.
std::vector<SensitivityResult> Verification::h_runs() {
  std::vector<SensitivityResult> ga;
  for (double h : steps_) {
    json j = base_;
    j["simulation"]["h"] = h;
    j["simulation"]["tol_r"] = 1e-12;
    const Case a = make(j, file_);
    SensitivityOptions sa = options();
    sa.method = Method::kDirectAnalytic;
    sa.matrix = M::kRefined;
    auto ra = compute_sensitivities(a, p_, sa);
    throw_if_interrupted("during verify's time-step study");
    if (!ra.ok)
      throw NumericalFailure("verify: generalized-α at h = " + fmt("%.3e", h) +
                             " failed: " + ra.message);
    ga.push_back(along(std::move(ra)));
  }
  return ga;
}

// The differences per h, in report.md and h_study_plot.csv (one column per response and
// quantity).
void Verification::h_table(const std::vector<Series>& series) {
  if (series.empty())
    md_ << "The case has no scalar response (its per-step responses are compared with IDAS at "
           "the case's h in section 1 only): nothing to fit.\n\n";
  if (!series.empty()) {
    md_ << "| h |";
    for (const auto& sr : series) md_ << " " << md_text(sr.name) << " | IDAS self |";
    md_ << "\n|---|";
    for (size_t i = 0; i < series.size(); ++i) md_ << "---|---|";
    md_ << "\n";
  }
  std::ostringstream cw;
  cw << "h";
  for (const auto& sr : series) cw << "," << csv_field(sr.name);
  cw << "\n";
  for (size_t k = 0; k < steps_.size(); ++k) {
    if (!series.empty()) md_ << "| " << fmt("%.3e", steps_[k]) << " |";
    cw << csv_number(steps_[k]);
    for (const auto& sr : series) {
      md_ << " " << fmt("%.2e", sr.diff[k]) << " | " << fmt("%.1e", sr.self[k]) << " |";
      cw << "," << csv_number(sr.diff[k]);
    }
    if (!series.empty()) md_ << "\n";
    cw << "\n";
  }
  md_ << "\n";
  write_file_atomic(o_.out_dir + "/h_study_plot.csv", cw.str());
}

// An order from the finest halving above the reference's floor, or a statement of why there is
// none.
void Verification::h_order(const Series& sr) {
  const double self = *std::max_element(sr.self.begin(), sr.self.end());
  const double floor = std::max(1e2 * rtol_tight_, 4 * self);
  bool fitted = false;
  double order = 0, h_fit = 0;
  for (size_t k = sr.diff.size() - 1; k >= 1 && !fitted; --k)
    if (sr.diff[k - 1] > floor && sr.diff[k] > floor) {
      order = std::log2(sr.diff[k - 1] / sr.diff[k]);
      h_fit = steps_[k];
      fitted = true;
    }
  const double largest = *std::max_element(sr.diff.begin(), sr.diff.end());
  if (fitted) {
    const bool ok = order > 1.8 && order < 2.2;
    std::string line = sr.name + " converges to IDAS at order " + fmt("%.2f", order) +
                       " (halving to h = " + fmt("%.3e", h_fit) + "; " + within(ok, "1.8–2.2") +
                       ")";
    if (order < 1)
      line +=
          ": the differences barely fall with h, so these steps are not in the asymptotic range "
          "(e.g. undamped high-frequency vibration that each h damps differently); try smaller "
          "h, or a smoother load";
    else if (!ok)
      line +=
          ": the differences may still be pre-asymptotic at these h (a max or KS aggregate "
          "converges irregularly until its peak is resolved); a smaller case h "
          "(--set /simulation/h=…) may decide";
    verdict(ok, line);
    md_ << "- " << md_text(sr.name) << ": order " << fmt("%.2f", order)
        << " (halving to h = " << fmt("%.3e", h_fit) << ", floor " << fmt("%.1e", floor) << ").\n";
  } else if (largest <= 1e2 * rtol_tight_ && 1e2 * rtol_tight_ <= 1e-6) {
    verdict(true, sr.name +
                      " agrees with IDAS within 100 × its rtol at every h (largest "
                      "difference " +
                      fmt("%.1e", largest) + "; no order to fit)");
    md_ << "- " << md_text(sr.name)
        << ": every difference within 100 × IDAS's rtol (agreement, no order to fit).\n";
  } else {
    // what keeps the differences from an order: the reference's measured error, its tolerance,
    // or (a loose --idas-rtol) an agreement too coarse to call a pass
    const std::string why =
        4 * self >= 1e2 * rtol_tight_
            ? "IDAS's two runs differ by " + fmt("%.1e", self) + ", and the differences (up to " +
                  fmt("%.1e", largest) + ") do not stand above 4× that on two consecutive h"
            : "the differences (up to " + fmt("%.1e", largest) +
                  ") do not stand above 100 × IDAS's rtol = " + fmt("%.1e", floor) +
                  " on two consecutive h";
    note(sr.name + " against IDAS: inconclusive, " + why + "; a tighter --idas-rtol may decide");
    md_ << "- " << md_text(sr.name) << ": inconclusive, " << why << ".\n";
  }
}

void Verification::h_plot(const std::vector<Series>& series) {
  PlotSpec ps;
  ps.png = o_.out_dir + "/h_study.png";
  ps.title = "generalized-alpha vs IDAS";
  ps.xlabel = "h [s]";
  ps.ylabel = "relative difference";
  ps.logx = ps.logy = true;
  for (const auto& sr : series) ps.series.push_back({steps_, sr.diff, sr.name});
  // zero differences (a response IDAS and generalized-α get exactly, like a mass) have no place on
  // a log axis: they are not drawn
  const bool plotted = !series.empty() && plot(ps);
  files_.push_back("h_study_plot.csv");
  if (plotted) files_.push_back("h_study.png");
  if (!series.empty())
    md_ << (plotted ? "![h study](h_study.png)\n\n"
                    : "(no picture: no difference is positive to draw on log axes; the numbers "
                      "are in h_study.csv)\n\n");
}

// Section 5: the mesh study (rectangle meshes: element counts × 1/2, 1, 2). A response that has
// not converged in the mesh is not a verified response of the case, however exact its gradients:
// judged by the grid convergence index of the finest mesh.
void Verification::mesh_study() {
  if (!rect_) {
    md_ << "## 5. Mesh study\n\nSkipped ("
        << (!o_.mesh_study ? "`--no-mesh-study`"
            : state_from_data_
                ? "the case starts from an initial state given as data (`initial_state`), which "
                  "belongs to its mesh"
                : "it scales rectangle meshes of flexible bodies; the case has none")
        << ").\n\n";
    return;
  }
  stage("mesh study (element counts × 1/2, 1, 2)");
  md_ << "## 5. Mesh study\n\nElement counts of every rectangle mesh scaled by 1/2, 1, 2; scalar "
         "responses and the largest gradient component (direct-analytic).\n\n| scale | elements "
         "| ";
  for (const auto& r : cs_.responses)
    if (r.kind != ResponseSpec::Kind::kPerStep) md_ << md_text(r.name) << " | max |grad| | ";
  md_ << "\n|---|---|";
  for (const auto& r : cs_.responses)
    if (r.kind != ResponseSpec::Kind::kPerStep) md_ << "---|---|";
  md_ << "\n";
  std::vector<std::vector<double>> values(cs_.responses.size());  // per response: 3 meshes
  std::vector<double> sizes;  // characteristic size 1/sqrt(elements)
  for (double f : {0.5, 1.0, 2.0}) {
    json j = base_;
    for (auto& b : j["bodies"])
      if (b.value("type", "") == "flexible") {
        auto& el = b["mesh"]["elements"];
        el[0] = std::max(1, static_cast<int>(std::lround(el[0].get<double>() * f)));
        el[1] = std::max(1, static_cast<int>(std::lround(el[1].get<double>() * f)));
      }
    const Case c = make(j, file_);
    int ne = 0;
    for (const auto& b : c.model->flexible_bodies()) ne += b->mesh.num_elements();  // cells
    const auto r = checked(compute_sensitivities(c, p_, options()),
                           "the mesh study at " + std::to_string(ne) + " elements");
    md_ << "| " << f << " | " << ne << " | ";
    sizes.push_back(1 / std::sqrt(static_cast<double>(ne)));
    for (size_t k = 0; k < r.responses.size(); ++k)
      if (r.responses[k].times.empty()) {
        md_ << fmt("%.6e", r.responses[k].values[0]) << " | "
            << fmt("%.4e", r.responses[k].gradient.cwiseAbs().maxCoeff()) << " | ";
        values[k].push_back(r.responses[k].values[0]);
      }
    md_ << "\n";
  }
  md_ << "\nConvergence in the mesh (observed order and grid convergence index of the finest "
         "mesh, Celik et al. 2008; threshold --tol-mesh "
      << fmt("%g", o_.tol_mesh) << "):\n\n";
  for (size_t k = 0; k < cs_.responses.size(); ++k) {
    if (values[k].size() != 3) continue;
    const auto& v = values[k];
    const MeshConvergence mc =
        mesh_convergence(v[0], v[1], v[2], sizes[0], sizes[1], sizes[2], o_.tol_mesh);
    md_ << "- " << md_text(cs_.responses[k].name) << ": " << md_text(mc.explanation) << "\n";
    verdict(mc.pass(), "mesh study, " + cs_.responses[k].name + ": " + mc.explanation);
  }
  md_ << "\n";
}

// Section 6 and the files: the verdicts, report.md, summary.json.
void Verification::finish() {
  md_ << "## 6. Pass/fail\n\n";
  for (const auto& v : verdicts_) md_ << "- " << md_text(v) << "\n";
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  md_ << "\nWall time of the verification: " << fmt("%.1f", wall) << " s.\n";
  write_file_atomic(o_.out_dir + "/report.md", md_.str());
  vr_.summary = summary(wall);
  write_json_atomic(o_.out_dir + "/summary.json", vr_.summary);
}

nlohmann::json Verification::summary(double wall) const {
  const Design& d = *cs_.design;
  json S = provenance(o_.command_line, file_, cs_.sha256);
  if (!cs_.input_files.empty()) S["input_files_sha256"] = cs_.input_files;
  S["overrides"] = cs_.overrides;
  S["status"] = "complete";
  S["pass"] = vr_.pass;
  S["verdicts"] = verdicts_;
  S["options"] = {
      {"idas", o_.idas},        {"fd_delta", o_.fd_delta}, {"fd_absolute", o_.fd_absolute},
      {"tol_fd", o_.tol_fd},    {"tol_semi", o_.tol_semi}, {"mesh_study", rect_},
      {"tol_mesh", o_.tol_mesh}};
  if (o_.idas) {
    S["options"]["idas_rtol"] = rtol_tight_;
    S["options"]["idas_rtol_loose"] = rtol_loose_;
    S["options"]["idas_atol"] = 1e-3 * rtol_tight_;
    S["options"]["h_study_steps"] = steps_;
  }
  if (o_.idas && W_.size()) {
    json w = json::array();
    for (Eigen::Index j = 0; j < W_.cols(); ++j) {
      json col = json::object();
      for (int i = 0; i < d.size(); ++i) col[d.variables[i].name] = W_(i, j);
      w.push_back(col);
    }
    S["idas_directions"] = w;
  }
  S["wall_seconds"] = wall;
  S["cost"] = cost_;
  S["responses"] = json::object();  // at the design point (direct-analytic's run)
  for (const auto& r : runs_[0].r.responses)
    S["responses"][r.name] = r.times.empty() ? json(r.values[0]) : json(r.values);
  S["units"] = units_json(cs_);
  S["files"] = file_list(files_);
  return S;
}

VerifyResult Verification::run() {
  load();
  header();
  primal();
  plan();
  idas_reference();
  gradient_runs();
  gradient_table();
  against_idas();
  cost_table();
  dp_study();
  h_study();
  mesh_study();
  finish();
  return vr_;
}

}  // namespace

VerifyResult run_verify(const std::string& file, const VerifyOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("verify option " + msg);
  return Verification(file, o).run();
}

}  // namespace lsmbs
