#include "lsmbs/io/verify_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/io/simulation_run.hpp"
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
std::string within(bool ok, const std::string& range) {
  return (ok ? "within " : "outside ") + range;
}

}  // namespace

std::string VerifyOptions::validate() const {
  if (!(fd_delta > 0 && fd_delta < 1) && !fd_absolute)
    return "fd_delta: expected a relative step in (0, 1)";
  if (!(fd_delta > 0) || !std::isfinite(fd_delta))
    return "fd_delta: expected a positive finite step";
  if (!(tol_fd > 0) || !std::isfinite(tol_fd)) return "tol_fd: expected a positive threshold";
  if (!(tol_semi > 0) || !std::isfinite(tol_semi)) return "tol_semi: expected a positive threshold";
  return {};
}

VerifyResult run_verify(const std::string& file, const VerifyOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("verify option " + msg);
  const auto t0 = std::chrono::steady_clock::now();
  Case cs = load_case(file, o.case_overrides);  // validates everything (nesting depth included)
                                                // before anything is written
  const json base = cs.raw;
  if (!cs.design) throw Error(file, "/design", "verification needs design variables");
  if (cs.responses.empty()) throw Error(file, "/output/responses", "verification needs responses");
  fs::create_directories(o.out_dir);
  const Design& d = *cs.design;
  Vec p = d.initial();
  for (const auto& [name, value] : o.design_overrides) {
    const int k = d.variable_index(name);
    if (k < 0) throw Error("--set " + name + ": unknown design variable '" + name + "'");
    p[k] = value;
  }
  d.apply(p, cs.model->params());  // the primal timing runs at p too
  VerifyResult vr;
  std::ostringstream md;
  std::vector<std::string> verdicts;
  auto verdict = [&](bool ok, const std::string& what) {
    verdicts.push_back(std::string(ok ? "PASS" : "FAIL") + " — " + what);
    vr.pass &= ok;
  };
  md << "# Verification report: " << cs.name << "\n\nCase `" << file << "` (SHA-256 "
     << cs.sha256.substr(0, 16) << "…), " << d.size() << " design variables, "
     << cs.responses.size() << " responses, h = " << cs.simulation.h
     << " s, t_end = " << cs.simulation.t_end << " s. Produced by `" << o.command_line
     << "`.\n\nDesign point:";
  for (int i = 0; i < d.size(); ++i)
    md << (i ? ", " : " ") << d.variables[i].name << " = " << fmt("%.6g", p[i]);
  md << (o.design_overrides.empty() ? " (the case's initial design).\n\n" : ".\n\n");

  // ---- primal and all methods
  auto t_primal = std::chrono::steady_clock::now();
  run_simulation(cs);
  const double primal =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_primal).count();
  struct Run {
    std::string name;
    SensitivityResult r;
  };
  std::vector<Run> runs;
  auto sens = [&](Method m, double delta, bool absolute, SensitivityOptions::Matrix mx) {
    Case c = load_case(file, o.case_overrides);
    SensitivityOptions so;
    so.method = m;
    so.delta = delta;
    so.relative = !absolute;
    so.matrix = mx;
    return compute_sensitivities(c, p, so);
  };
  using M = SensitivityOptions::Matrix;
  // the generalized-α methods share the exact matrix (refined), so that their columns differ only
  // in the pseudo-loads; the paper's last-iteration matrix gets its own column
  auto stage = [&](const std::string& what) {
    if (o.on_stage) o.on_stage(what);
  };
  stage("1/4 gradients by every method" + std::string(o.idas ? " (IDAS included)" : ""));
  runs.push_back({"direct-analytic", sens(Method::kDirectAnalytic, 1e-6, false, M::kRefined)});
  runs.push_back({"semi-analytical", sens(Method::kSemiAnalytical, 1e-6, false, M::kRefined)});
  runs.push_back(
      {"semi-analytical-central", sens(Method::kSemiAnalyticalCentral, 1e-6, false, M::kRefined)});
  runs.push_back(
      {"fd-central", sens(Method::kFdCentral, o.fd_delta, o.fd_absolute, M::kLastIteration)});
  runs.push_back({"direct-analytic (last-iteration matrix)",
                  sens(Method::kDirectAnalytic, 1e-6, false, M::kLastIteration)});
  if (o.idas) runs.push_back({"idas", sens(Method::kIdas, 1e-6, false, M::kLastIteration)});
  {  // what a user gets without options: checked against fd-central like the reference
    Case c = load_case(file, o.case_overrides);
    runs.push_back(
        {"default options (" + std::string(SensitivityOptions::name(SensitivityOptions{}.method)) +
             ", --matrix " + SensitivityOptions::matrix_name(SensitivityOptions{}.matrix) + ")",
         compute_sensitivities(c, p, SensitivityOptions{})});
  }
  const auto& defaults = runs.back().r;
  const auto& ref = runs[0].r;

  // ---- 1. gradient table
  md << "## 1. Gradients\n\nReference: `direct-analytic` with the converged-state matrix "
        "(`refined`, as the two "
        "semi-analytical columns); the last-iteration-matrix column is the paper's Algorithm 2 "
        "matrix (for "
        "comparison, not checked); the last column is what `lsmbs sensitivity` gives without "
        "options, checked "
        "against fd-central like the reference. For the other "
        "methods the table gives the relative difference |g − g_ref| / ‖g_ref‖∞ (per response "
        "value, over the "
        "variables; for a per-step response ‖g_ref‖∞ over all steps) and the agreeing digits "
        "−log10 of it. fd-central step: "
     << o.fd_delta << (o.fd_absolute ? " (absolute)" : " (relative)") << ".\n\n";
  // gradients.csv: one row per response and variable (a per-step response: its worst step, the
  // table's), one column per method; method names hold commas, hence csv_field
  std::ostringstream gcsv;
  gcsv << "response,variable,step";
  for (const auto& r : runs) gcsv << "," << csv_field(r.name);
  gcsv << "\n";
  std::vector<std::string> files = {"gradients.csv", "report.md", "summary.json"};
  for (size_t k = 0; k < ref.responses.size(); ++k) {
    const auto& rr = ref.responses[k];
    const bool per_step = !rr.times.empty();
    md << "### " << rr.name << (per_step ? " (per step: worst step shown)" : "")
       << "\n\n| variable | direct-analytic |";
    for (size_t m = 1; m < runs.size(); ++m) md << " " << runs[m].name << " |";
    md << "\n|---|---|";
    for (size_t m = 1; m < runs.size(); ++m) md << "---|";
    md << "\n";
    // the row shown: the worst step of a per-step response (by fd-central difference), else 0
    Eigen::Index row = 0;
    if (per_step) {
      double w = -1;
      for (Eigen::Index i = 0; i < rr.gradient.rows(); ++i) {
        const double e =
            (runs[3].r.responses[k].gradient.row(i) - rr.gradient.row(i)).cwiseAbs().maxCoeff();
        if (e > w) w = e, row = i;
      }
    }
    const double n = std::max(scale_of(rr.gradient), 1e-300);
    for (int i = 0; i < d.size(); ++i) {
      md << "| " << d.variables[i].name << " | " << fmt("%.8e", rr.gradient(row, i)) << " |";
      gcsv << csv_field(rr.name) << "," << csv_field(d.variables[i].name) << "," << row << ","
           << csv_number(rr.gradient(row, i));
      for (size_t m = 1; m < runs.size(); ++m) {
        const double g = runs[m].r.responses[k].gradient(row, i),
                     e = std::abs(g - rr.gradient(row, i)) / n;
        md << " " << fmt("%.1e", e) << " (" << fmt("%.1f", e > 0 ? -std::log10(e) : 16.0) << ") |";
        gcsv << "," << csv_number(g);
      }
      md << "\n";
      gcsv << "\n";
    }
    md << "\n";
  }
  write_file_atomic(o.out_dir + "/gradients.csv", gcsv.str());
  const double e_fd = worst(ref, runs[3].r), e_semi = worst(runs[2].r, ref),
               e_def = worst(defaults, runs[3].r);
  verdict(e_fd < o.tol_fd, "direct-analytic vs fd-central: " + below(e_fd, o.tol_fd));
  verdict(e_def < o.tol_fd, "default sensitivity options vs fd-central: " + below(e_def, o.tol_fd));
  verdict(e_semi < o.tol_semi,
          "semi-analytical-central vs direct-analytic: " + below(e_semi, o.tol_semi));

  // ---- 2. cost table
  md << "## 2. Cost\n\nPrimal simulation alone: " << fmt("%.3f", primal)
     << " s.\n\n| method | wall [s] | / primal | simulations | factorizations | back-solve rhs | "
        "residual evals "
        "| pseudo-load residuals | element pseudo-loads |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : runs) {
    const auto& c = r.r.counts;
    md << "| " << r.name << " | " << fmt("%.3f", c.wall_seconds) << " | "
       << fmt("%.2f", c.wall_seconds / primal) << " | " << c.simulations << " | "
       << c.factorizations << " | " << c.back_solve_rhs << " | " << c.residual_evaluations << " | "
       << c.pseudo_load_residuals << " | " << c.element_pseudo_loads << " |\n";
  }
  md << "\n";

  // ---- 3. Δp study (same matrix for all: refined; only the pseudo-load differs)
  {
    stage("2/4 Δp study of the semi-analytical methods (10 values of Δp)");
    const auto exact = sens(Method::kDirectAnalytic, 1e-6, false, M::kRefined);
    std::ofstream c(o.out_dir + "/dp_study.csv");
    c << "delta,forward,central\n";
    md << "## 3. Δp study\n\nError of the semi-analytical gradients against direct-analytic (same "
          "matrix, `refined`), "
          "relative Δp.\n\n| Δp | forward | central |\n|---|---|---|\n";
    std::vector<double> dl = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
    std::vector<double> ef, ec;
    for (double x : dl) {
      ef.push_back(worst(sens(Method::kSemiAnalytical, x, false, M::kRefined), exact));
      ec.push_back(worst(sens(Method::kSemiAnalyticalCentral, x, false, M::kRefined), exact));
      c << fmt("%.1e", x) << "," << fmt("%.6e", ef.back()) << "," << fmt("%.6e", ec.back()) << "\n";
      md << "| " << fmt("%.0e", x) << " | " << fmt("%.2e", ef.back()) << " | "
         << fmt("%.2e", ec.back()) << " |\n";
    }
    c.close();
    files.push_back("dp_study.csv");
    const double slope_f = std::log10(ef[3] / ef[4]), slope_c = std::log10(ec[2] / ec[3]);
    PlotSpec ps;
    ps.png = o.out_dir + "/dp_study.png";
    ps.title = "semi-analytical gradient error vs delta p";
    ps.xlabel = "relative delta p";
    ps.ylabel = "error vs direct-analytic";
    ps.logx = ps.logy = true;
    ps.series = {{o.out_dir + "/dp_study.csv", 1, 2, "forward"},
                 {o.out_dir + "/dp_study.csv", 1, 3, "central"}};
    ps.ymin = 0.1 * std::min(*std::min_element(ef.begin(), ef.end()),
                             *std::min_element(ec.begin(), ec.end()));
    ps.ymax = 10 * std::max(*std::max_element(ef.begin(), ef.end()),
                            *std::max_element(ec.begin(), ec.end()));
    ps.functions = {fmt("%.6e", ef[4] / 1e-6) + "*x with lines dt 2 title 'slope 1'",
                    fmt("%.6e", ec[3] / 1e-10) + "*x**2 with lines dt 3 title 'slope 2'"};
    const bool plotted = plot(ps);
    if (plotted) files.push_back("dp_study.png");
    md << "\n"
       << (plotted ? "![dp study](dp_study.png)\n\n"
                   : "(gnuplot unavailable: see dp_study.csv)\n\n");
    const bool ok_f = std::abs(slope_f - 1) < 0.2;
    verdict(ok_f,
            "forward slope " + fmt("%.2f", slope_f) + " (1e-5 → 1e-6) " + within(ok_f, "1 ± 0.2"));
    if (ec[2] < 1e-9 && ec[3] < 1e-9)
      verdict(true, "central differences exact to round-off (" + fmt("%.1e", ec[2]) + ", " +
                        fmt("%.1e", ec[3]) +
                        "): the residual is at most quadratic in the perturbation");
    else
      verdict(std::abs(slope_c - 2) < 0.3, "central slope " + fmt("%.2f", slope_c) +
                                               " (1e-4 → 1e-5) " +
                                               within(std::abs(slope_c - 2) < 0.3, "2 ± 0.3"));
  }

  // ---- 4. h study against IDAS
  if (o.idas) {
    stage("3/4 time-step study against IDAS (4h, 2h, h, h/2)");
    md << "## 4. Time-step study against IDAS\n\nFor each h, generalized-α (direct-analytic, "
          "refined matrix) and IDAS "
          "(reference tolerances) on the same output grid; largest relative difference over the "
          "scalar responses "
          "and over their gradients.\n\n| h | response | gradient |\n|---|---|---|\n";
    std::ofstream c(o.out_dir + "/h_study.csv");
    c << "h,response,gradient\n";
    std::vector<double> hs, dr, dg;
    // h0·4, h0·2 (when t_end stays a multiple of h), h0, h0/2: differences at IDAS's accuracy
    // floor (≈ its rtol) carry no order; coarser steps lift them above it
    const double h0 = cs.simulation.h, span = cs.simulation.t_end - cs.initial.t;
    std::vector<double> steps;
    for (double f : {4.0, 2.0})
      if (std::abs(span / (f * h0) - std::round(span / (f * h0))) < 1e-9 * span / h0 &&
          span / (f * h0) >= 4)
        steps.push_back(f * h0);
    steps.push_back(h0);
    steps.push_back(h0 / 2);
    constexpr double kIdasRtol = 1e-10;
    for (double h : steps) {
      json j = base;
      j["simulation"]["h"] = h;
      j["simulation"]["tol_r"] = 1e-12;
      Case a = make(j, file), b = make(j, file);
      SensitivityOptions sa, sb;
      sa.method = Method::kDirectAnalytic;
      sa.matrix = M::kRefined;
      sb.method = Method::kIdas;
      sb.idas.rtol = kIdasRtol;
      sb.idas.atol = 1e-13;
      const auto ra = compute_sensitivities(a, p, sa), rb = compute_sensitivities(b, p, sb);
      double er = 0, eg = 0;
      for (size_t r = 0; r < ra.responses.size(); ++r) {
        if (!ra.responses[r].times.empty()) continue;  // scalar responses
        er = std::max(er, std::abs(ra.responses[r].values[0] - rb.responses[r].values[0]) /
                              std::max(std::abs(rb.responses[r].values[0]), 1e-300));
        const double n = std::max(rb.responses[r].gradient.row(0).cwiseAbs().maxCoeff(), 1e-300);
        eg = std::max(eg, (ra.responses[r].gradient.row(0) - rb.responses[r].gradient.row(0))
                                  .cwiseAbs()
                                  .maxCoeff() /
                              n);
      }
      hs.push_back(h), dr.push_back(er), dg.push_back(eg);
      c << h << "," << er << "," << eg << "\n";
      md << "| " << fmt("%.3e", h) << " | " << fmt("%.2e", er) << " | " << fmt("%.2e", eg)
         << " |\n";
    }
    c.close();
    files.push_back("h_study.csv");
    // order from the finest halving whose two differences both stand 1000× above IDAS's rtol
    const double fit_floor = 1e3 * kIdasRtol;
    auto fit = [&](const std::vector<double>& e, double& order, double& h_fit) {
      for (size_t k = e.size() - 1; k >= 1; --k)
        if (e[k - 1] > fit_floor && e[k] > fit_floor) {
          order = std::log2(e[k - 1] / e[k]);
          h_fit = hs[k];
          return true;
        }
      return false;
    };
    double order_r = 0, order_g = 0, h_r = 0, h_g = 0;
    const bool fit_r = fit(dr, order_r, h_r), fit_g = fit(dg, order_g, h_g);
    md << "\nOrders are fitted on the finest halving whose differences both exceed "
       << fmt("%.0e", fit_floor) << " (1000 × IDAS's rtol " << fmt("%.0e", kIdasRtol)
       << "): below that the differences are the reference's own error and carry no order.\n\n";
    md << "Fitted order: responses "
       << (fit_r ? fmt("%.2f", order_r) + " (halving to h = " + fmt("%.3e", h_r) + ")"
                 : std::string("not fitted (at the reference's accuracy)"))
       << ", gradients "
       << (fit_g ? fmt("%.2f", order_g) + " (halving to h = " + fmt("%.3e", h_g) + ")"
                 : std::string("not fitted (at the reference's accuracy)"))
       << ".\n\n";
    PlotSpec ps;
    ps.png = o.out_dir + "/h_study.png";
    ps.title = "generalized-alpha vs IDAS";
    ps.xlabel = "h [s]";
    ps.ylabel = "relative difference";
    ps.logx = ps.logy = true;
    ps.series = {{o.out_dir + "/h_study.csv", 1, 2, "responses"},
                 {o.out_dir + "/h_study.csv", 1, 3, "gradients"}};
    const bool plotted = plot(ps);
    if (plotted) files.push_back("h_study.png");
    md << (plotted ? "![h study](h_study.png)\n\n" : "(gnuplot unavailable: see h_study.csv)\n\n");
    const bool ok_r = order_r > 1.8 && order_r<2.2, ok_g = order_g> 1.8 && order_g < 2.2;
    if (fit_r)
      verdict(ok_r, "responses converge to IDAS at order " + fmt("%.2f", order_r) + " (" +
                        within(ok_r, "1.8–2.2") + ")");
    else
      md << "Responses: every difference is within 1000 × IDAS's tolerance — agreement, no order "
            "to fit.\n\n";
    if (fit_g)
      verdict(ok_g, "gradients converge to IDAS at order " + fmt("%.2f", order_g) + " (" +
                        within(ok_g, "1.8–2.2") + ")");
    else
      md << "Gradients: every difference is within 1000 × IDAS's tolerance — agreement, no order "
            "to fit.\n\n";
  } else {
    md << "## 4. Time-step study against IDAS\n\nSkipped (`--no-idas`).\n\n";
  }

  // ---- 5. mesh study (rectangle meshes: element counts × 1/2, 1, 2)
  bool rect = o.mesh_study;
  for (const auto& b : base.at("bodies"))
    if (b.value("type", "") == "flexible" && b.at("mesh").value("type", "") != "rectangle")
      rect = false;
  if (rect && !cs.model->flexible_bodies().empty()) {
    stage("4/4 mesh study (element counts × 1/2, 1, 2)");
    md << "## 5. Mesh study\n\nElement counts of every rectangle mesh scaled by 1/2, 1, 2; scalar "
          "responses and the "
          "largest gradient component (direct-analytic).\n\n| scale | elements | ";
    for (const auto& r : cs.responses)
      if (r.kind != ResponseSpec::Kind::kPerStep) md << r.name << " | max |grad| | ";
    md << "\n|---|---|";
    for (const auto& r : cs.responses)
      if (r.kind != ResponseSpec::Kind::kPerStep) md << "---|---|";
    md << "\n";
    for (double f : {0.5, 1.0, 2.0}) {
      json j = base;
      int ne = 0;
      for (auto& b : j["bodies"])
        if (b.value("type", "") == "flexible") {
          auto& el = b["mesh"]["elements"];
          el[0] = std::max(1, static_cast<int>(std::lround(el[0].get<double>() * f)));
          el[1] = std::max(1, static_cast<int>(std::lround(el[1].get<double>() * f)));
          ne += el[0].get<int>() * el[1].get<int>();
        }
      Case c = make(j, file);
      SensitivityOptions so;
      const auto r = compute_sensitivities(c, p, so);
      md << "| " << f << " | " << ne << " | ";
      for (size_t k = 0; k < r.responses.size(); ++k)
        if (r.responses[k].times.empty())
          md << fmt("%.6e", r.responses[k].values[0]) << " | "
             << fmt("%.4e", r.responses[k].gradient.cwiseAbs().maxCoeff()) << " | ";
      md << "\n";
    }
    md << "\n";
  }

  // ---- 6. verdicts
  md << "## 6. Pass/fail\n\n";
  for (const auto& v : verdicts) md << "- " << v << "\n";
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  md << "\nWall time of the verification: " << fmt("%.1f", wall) << " s.\n";
  write_file_atomic(o.out_dir + "/report.md", md.str());
  json S = provenance(o.command_line, file, cs.sha256);
  S["overrides"] = cs.overrides;
  S["status"] = "complete";
  S["pass"] = vr.pass;
  S["verdicts"] = verdicts;
  S["options"] = {{"idas", o.idas},     {"fd_delta", o.fd_delta}, {"fd_absolute", o.fd_absolute},
                  {"tol_fd", o.tol_fd}, {"tol_semi", o.tol_semi}, {"mesh_study", rect}};
  S["wall_seconds"] = wall;
  S["responses"] = json::object();
  S["units"] = units_json(cs);
  S["files"] = file_list(std::move(files));
  write_json_atomic(o.out_dir + "/summary.json", S);
  vr.summary = S;
  return vr;
}

}  // namespace lsmbs
