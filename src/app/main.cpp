// lsmbs — command line of the level-set flexible-multibody testbed.
//
//   lsmbs simulate CASE.json -o OUT      generalized-α simulation (Algorithm 1 of the paper)
//   lsmbs static CASE.json -o OUT        static equilibrium at one time (measures, responses, VTU)
//   lsmbs geometry CASE.json -o OUT      level-set design mapped on the mesh (μ_e VTU + PNG, mass)
//   lsmbs sensitivity CASE.json --method NAME -o OUT   responses and design gradients (§4.3)
//   lsmbs optimize CASE.json -o OUT [--resume]         fully coupled optimization (NLopt MMA)
//   lsmbs verify CASE.json -o OUT                      verification report (methods, Δp, h, mesh)
//   lsmbs sweep CASE.json --axis k=50:400:8 -o OUT     responses over a grid or Latin hypercube
//   lsmbs bench CASE.json -o OUT                       step cost against the floor, sensitivity
//   overheads lsmbs --version
//
// Exit codes: 0 success; 1 numerical failure (message says when and why); 2 invalid input or
// usage (file, JSON path, what was expected). Nothing is written when the input is invalid.
//
// This file only parses the command line; each command is in commands/ (one file each).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/terminal.hpp"
#include "lsmbs/core/allocator.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/core/version.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/design_picture.hpp"
#include "lsmbs/io/output_folder.hpp"
#include "lsmbs/runs/mpi.hpp"

namespace {

// CLI11 converts an integer option with strtoull/strtoll in base 0: in an unsigned option "-1"
// wraps to 18446744073709551615, "010" is octal 8, "0x10" hexadecimal 16, and a number beyond
// the type's range becomes its largest value. Every integer option is checked here first:
// decimal digits only (leading zeros dropped, so that "010" is ten), a sign only where negative
// values exist, within [lo, hi].
CLI::Validator decimal_integer(long long lo, unsigned long long hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::string kind = lo >= 0 ? "a non-negative integer" : "an integer";
        const bool negative = !s.empty() && s[0] == '-';
        const size_t d = negative || (!s.empty() && s[0] == '+') ? 1 : 0;
        if (s.size() == d || s.find_first_not_of("0123456789", d) != std::string::npos)
          return "expected " + kind + " (decimal digits), got " + lsmbs::shown(s);
        std::string digits = s.substr(d);
        digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size() - 1));
        if (negative && lo >= 0 && s.find_first_not_of('0', 1) != std::string::npos)
          return "expected " + kind + ", got " + lsmbs::shown(s);
        unsigned long long v = 0;
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
        const bool beyond =
            ec != std::errc() ||
            (negative ? lo >= 0 || v > static_cast<unsigned long long>(-(lo + 1)) + 1 : v > hi);
        if (beyond)
          return "expected " + kind + " in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                 "], got " + lsmbs::shown(s);
        s = (negative && v != 0 ? "-" : "") + digits;
        return {};
      },
      "");
}

// The command line as summary.json records it: each argument quoted for a POSIX shell where it
// holds anything but plain characters, so that the recorded command, pasted into a shell, is the
// command that ran (a --set value '/name=a\n$(touch x)' is one argument again, and runs nothing).
std::string joined_args(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) {
    if (i) s += ' ';
    const std::string a = argv[i];
    const bool plain = !a.empty() && a.find_first_not_of(
                                         "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                         "0123456789_./=:,+@%-") == std::string::npos;
    if (plain) {
      s += a;
      continue;
    }
    s += '\'';
    for (char c : a) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
    s += '\'';
  }
  return s;
}

constexpr const char* kSetHelp =
    "override a value of the case by JSON path, /simulation/h=1e-3 or "
    "/bodies/1/material/E=70e9, or a design variable, name=value (repeatable; recorded in "
    "summary.json)";
constexpr const char* kOverwriteHelp =
    "reuse an output folder that holds an earlier run (its lsmbs files are removed first)";

// The command line parsed: the common arguments, one argument struct per command, and the
// subcommands (the one given is the one that runs).
struct CommandLine {
  CLI::App app{"lsmbs — level-set structural optimization of flexible multibody system components"};
  CLI::Validator int_range =
      decimal_integer(std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  bool version = false, overwrite = false, no_check = false, no_idas = false, no_mesh = false;
  lsmbs::app::CommonArgs common;
  lsmbs::app::SimulateArgs sim_args;
  lsmbs::app::GeometryArgs geo_args;
  lsmbs::app::StaticArgs static_args;
  lsmbs::app::SensitivityArgs sen_args;
  lsmbs::app::OptimizeArgs opt_args;
  lsmbs::app::VerifyArgs ver_args;
  lsmbs::app::BenchArgs ben_args;
  lsmbs::app::SweepArgs swp_args;
  bool resume = false;  // sweep --resume
  CLI::App *sim = nullptr, *sta = nullptr, *geo = nullptr, *sen = nullptr, *opt = nullptr,
           *ver = nullptr, *ben = nullptr, *swp = nullptr;
};

// What every command takes: the case file, the output folder, --overwrite, -q.
CLI::App* add_command(CommandLine& cl, const char* name, const char* what, const char* case_help,
                      const char* out_help) {
  CLI::App* c = cl.app.add_subcommand(name, what);
  c->add_option("case", cl.common.case_file, case_help)->required()->check(CLI::ExistingFile);
  c->add_option("-o,--output", cl.common.out, out_help)->capture_default_str();
  c->add_flag("--overwrite", cl.overwrite, kOverwriteHelp);
  c->add_flag("-q,--quiet", cl.common.quiet, "print nothing but errors");
  return c;
}

void add_simulate(CommandLine& cl) {
  auto* sim = cl.sim =
      add_command(cl, "simulate", "simulate a case with the generalized-alpha scheme",
                  "case file (JSON)", "output folder (summary.json, history.csv, VTU)");
  auto& a = cl.sim_args;
  sim->add_flag("-v,--verbose", cl.common.verbose, "print model statistics");
  sim->add_option("--integrator", a.integrator,
                  "generalized-alpha (the paper's) or idas (SUNDIALS IDAS, GGL index 2)")
      ->check(CLI::IsMember({"generalized-alpha", "idas"}))
      ->capture_default_str();
  sim->add_option("--rtol", a.rtol, "IDAS relative tolerance")->capture_default_str();
  sim->add_option("--atol", a.atol,
                  "IDAS absolute tolerance on positions, in units of the model's length scale "
                  "(default: rtol)");
  sim->add_option("--max-order", a.max_order,
                  "IDAS maximum BDF order 1-5; 0 = auto (2, A-stable, for models with a "
                  "flexible body; 5 otherwise)")
      ->transform(cl.int_range)
      ->check(CLI::Range(0, 5))
      ->capture_default_str();
  sim->add_option("--error-test", a.error_test,
                  "IDAS error test: positions, positions+velocities, or auto (positions "
                  "for models with a flexible body)")
      ->check(CLI::IsMember({"auto", "positions", "positions+velocities"}))
      ->capture_default_str();
  sim->add_option("--set", cl.common.sets, kSetHelp);
}

void add_static_and_geometry(CommandLine& cl) {
  auto* sta = cl.sta = add_command(
      cl, "static", "static equilibrium at one time: measures, responses and VTU at equilibrium",
      "case file (JSON)", "output folder");
  sta->add_option("--set", cl.common.sets, kSetHelp);
  sta->add_option("--t", cl.static_args.t, "time at which drivers and loads are evaluated [s]")
      ->capture_default_str();
  sta->add_option("--max-iter", cl.static_args.max_iter, "Newton iterations")
      ->transform(cl.int_range)
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  auto* geo = cl.geo =
      add_command(cl, "geometry",
                  "map the level-set design onto the mesh: μ_e (VTU, PNG), mass and its gradient",
                  "case file (JSON) with a design section", "output folder");
  geo->add_option("--set", cl.common.sets, kSetHelp);
  geo->add_option("--width", cl.geo_args.width, "PNG width in pixels")
      ->transform(cl.int_range)
      ->capture_default_str()
      ->check(CLI::Range(lsmbs::DesignPictureLayout::kMinWidth, 20000));
}

void add_sensitivity(CommandLine& cl) {
  auto* sen = cl.sen = add_command(
      cl, "sensitivity",
      "responses and their design gradients (semi-analytical, direct, finite differences)",
      "case file (JSON) with design variables and responses", "output folder");
  auto& a = cl.sen_args;
  sen->add_option("--method", a.method,
                  "semi-analytical | semi-analytical-central | direct-analytic | adjoint (the "
                  "discrete adjoint: scalar responses, cost independent of the number of "
                  "variables) | adjoint-semi-analytical | fd-forward | fd-central | idas | "
                  "idas-adjoint (time-integral responses only); several separated by commas are "
                  "all run and compared (methods.csv, methods.png), the first one's results are "
                  "the gradients")
      ->capture_default_str();
  sen->add_option("--delta", a.delta, "perturbation Δp (semi-analytical) or finite-difference step")
      ->capture_default_str();
  sen->add_flag("--absolute", a.absolute,
                "Δp absolute instead of relative to max(|p_i|, 1e-2 (upper - lower))");
  a.matrix = lsmbs::SensitivityOptions::matrix_name(lsmbs::SensitivityOptions{}.matrix);
  sen->add_flag("--full-residual", a.full_residual,
                "semi-analytical pseudo-loads from whole-residual evaluations (Algorithm 2 "
                "literally) instead of element-local ones");
  sen->add_option("--matrix", a.matrix,
                  "matrix of the back-solves: converged (default: S_t refactorized at the "
                  "converged state, exact), refined (S_t at the converged state by iterative "
                  "refinement, exact), last (the last Newton iteration's, Algorithm 2 literally; "
                  "not exact where a step converged in one iteration)")
      ->capture_default_str();
  sen->add_option("--set", cl.common.sets, kSetHelp);
  sen->add_option("--rtol", a.rtol, "--method idas, idas-adjoint: IDAS relative tolerance")
      ->capture_default_str();
  sen->add_option("--atol", a.atol,
                  "--method idas, idas-adjoint: IDAS absolute tolerance in units of the length "
                  "scale (default: rtol)");
  sen->add_option("--adjoint-memory", a.adjoint_memory_mb,
                  "--method adjoint: bound on the memory of the stored trajectory in MB (0: no "
                  "bound); a trajectory that does not fit is stored at checkpoints and "
                  "recomputed in the backward pass (summary.json counts)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sen->add_option("--threads", a.threads,
                  "2: the sensitivity update of each step runs on a second thread while the next "
                  "step is computed; 1: one thread (the same results, bit for bit)")
      ->capture_default_str()
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 2));
  lsmbs::GradientCheckOptions& c = a.check_options;
  sen->add_flag("--check", a.check,
                "gradient check: central differences of 2 more simulations along a random "
                "direction against the gradient; per-response disagreement in summary.json (exit "
                "1 above --check-fail)");
  sen->add_option("--check-delta", c.delta, "--check: relative step along the direction")
      ->capture_default_str();
  sen->add_option("--check-seed", c.seed, "--check: seed of the random direction")
      ->capture_default_str()
      ->transform(decimal_integer(0, std::numeric_limits<unsigned>::max()));
  sen->add_option("--check-warn", c.warn, "--check: warn above this relative disagreement")
      ->capture_default_str();
  sen->add_option("--check-fail", c.fail, "--check: fail above this relative disagreement")
      ->capture_default_str();
}

void add_optimize(CommandLine& cl) {
  auto* opt = cl.opt = add_command(
      cl, "optimize", "fully coupled optimization of the case's design (NLopt MMA/CCSAQ/SLSQP)",
      "case file (JSON) with design, responses and an optimization section",
      "output folder (history.csv, checkpoint.json, final_design/, summary.json)");
  auto& a = cl.opt_args;
  opt->add_flag("--resume", a.resume, "continue an interrupted run from OUT/checkpoint.json");
  opt->add_option("--starts", a.starts,
                  "multi-start: N optimizations from N feasible random initial designs (uniform "
                  "within the bounds, seeded), in OUT/start_1 … OUT/start_N, 2 at a time; "
                  "OUT/starts.csv and summary.json rank them")
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 1000));
  opt->add_option("--seed", a.seed, "multi-start: seed of the random initial designs")
      ->capture_default_str()
      ->transform(decimal_integer(0, std::numeric_limits<unsigned long>::max()));
  opt->add_option("--optimizer", a.optimizer, "override the case's optimizer")
      ->check(CLI::IsMember({"mma", "ccsaq", "slsqp", "mma-svanberg"}));
  opt->add_option("--set", cl.common.sets,
                  "override a value of the case by JSON path, /simulation/h=1e-3 (repeatable); "
                  "name=value sets a design variable's initial value");
  opt->add_flag(
      "--no-check", cl.no_check,
      "skip the gradient check at the initial design (default: central differences along a random "
      "direction, 2 simulations; warns above --check-warn, refuses above --check-fail)");
  opt->add_option("--check-warn", a.check_options.warn,
                  "gradient check: warn above this relative disagreement")
      ->capture_default_str();
  opt->add_option("--check-fail", a.check_options.fail,
                  "gradient check: refuse above this relative disagreement")
      ->capture_default_str();
  opt->add_flag(
      "-v,--verbose", cl.common.verbose,
      "a row per evaluation also when not on a terminal (default there: final summary only)");
}

void add_verify_and_bench(CommandLine& cl) {
  lsmbs::VerifyOptions& vo = cl.ver_args.options;
  auto* ver = cl.ver = add_command(
      cl, "verify",
      "verification report: every sensitivity method, costs, delta-p study, time-step study "
      "against IDAS, mesh study, pass/fail",
      "case file (JSON) with design variables and responses",
      "output folder (report.md, CSV, PNG)");
  ver->add_flag("--no-idas", cl.no_idas,
                "skip IDAS (too slow for long runs of stiff flexible models)");
  ver->add_flag("--no-mesh-study", cl.no_mesh, "skip the mesh study");
  ver->add_option("--fd-delta", vo.fd_delta, "fd-central step")->capture_default_str();
  ver->add_flag("--fd-absolute", vo.fd_absolute, "fd-central step absolute instead of relative");
  ver->add_option("--tol-fd", vo.tol_fd, "threshold direct-analytic vs fd-central")
      ->capture_default_str();
  ver->add_option("--tol-semi", vo.tol_semi, "threshold semi-analytical-central vs direct-analytic")
      ->capture_default_str();
  ver->add_option("--tol-mesh", vo.tol_mesh,
                  "mesh study: largest grid convergence index of a response on the finest mesh")
      ->capture_default_str();
  ver->add_option("--idas-rtol", vo.idas_rtol,
                  "IDAS reference tolerance (atol 1e-3 of it, in units of the length scale); a "
                  "second run at ten times both estimates the reference's own error")
      ->capture_default_str();
  ver->add_option("--set", cl.common.sets, kSetHelp);
  lsmbs::BenchOptions& bo = cl.ben_args.options;
  auto* ben = cl.ben = add_command(cl, "bench",
                                   "whole-run benchmark: step cost against the KLU/assembly "
                                   "floor, sensitivity overheads, peak memory",
                                   "case file (JSON)", "output folder (bench.json, summary.json)");
  ben->add_option("--methods", cl.ben_args.methods,
                  "sensitivity methods to time (default: direct-analytic "
                  "semi-analytical-central; 'none' for none)");
  ben->add_option("--matrices", bo.matrices,
                  "back-solve matrices timed besides the default for the direct methods "
                  "(last, converged, refined; 'none' for none)")
      ->capture_default_str();
  ben->add_option("--repetitions", bo.repetitions, "repetitions of the floor measurements")
      ->capture_default_str()
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 100000));
  ben->add_option("--threads", bo.threads,
                  "threads of the sensitivity runs (see sensitivity --threads)")
      ->capture_default_str()
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 2));
  ben->add_option("--set", cl.common.sets, kSetHelp);
}

void add_sweep(CommandLine& cl) {
  auto* swp = cl.swp = add_command(
      cl, "sweep",
      "responses (and gradients) over a grid or a Latin hypercube of design variables, model "
      "parameters or case values",
      "case file (JSON)", "output folder (sweep.csv, sweep.json, summary.json)");
  auto& a = cl.swp_args;
  swp->add_option("--axis", a.axes,
                  "a quantity swept: name=lower:upper:points (a grid axis) or, with --lhs, "
                  "name=lower:upper; name: a design variable, a model parameter (spring.stiffness) "
                  "or a JSON pointer (/simulation/h); repeatable")
      ->required();
  swp->add_option("--lhs", a.lhs, "a Latin hypercube of N points instead of the grid")
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 1000000));
  swp->add_option("--seed", a.seed, "--lhs: seed of the hypercube")
      ->capture_default_str()
      ->transform(decimal_integer(0, std::numeric_limits<unsigned long>::max()));
  swp->add_flag("--gradients", a.gradients,
                "also the gradients of the responses with respect to the design variables");
  swp->add_option("--method", a.method, "--gradients: the sensitivity method")
      ->capture_default_str();
  swp->add_option("--jobs", a.jobs, "points at once on this machine (under mpirun: one per rank)")
      ->capture_default_str()
      ->transform(cl.int_range)
      ->check(CLI::Range(1, 1024));
  swp->add_flag("--resume", cl.resume, "run the points an interrupted sweep in OUT did not finish");
  swp->add_flag("-v,--verbose", cl.common.verbose,
                "a line per finished point (always on a terminal)");
  swp->add_option("--set", cl.common.sets, kSetHelp);
}

// An option of sensitivity methods none of which runs (--delta 0.5 with direct-analytic left
// gradients.csv byte for byte as it was, and summary.json recorded it as if used).
void check_method_options(const CommandLine& cl) {
  const std::string& list = cl.sen_args.method;
  std::vector<std::string> methods;
  for (size_t b = 0; b <= list.size();) {
    const size_t e = std::min(list.find(',', b), list.size());
    methods.push_back(list.substr(b, e - b));
    b = e + 1;
  }
  struct Use {
    const char* option;
    std::vector<std::string> by;
  };
  const std::vector<std::string> semi = {"semi-analytical", "semi-analytical-central",
                                         "adjoint-semi-analytical"};
  std::vector<std::string> steps = semi;
  steps.insert(steps.end(), {"fd-forward", "fd-central"});
  const Use uses[] = {
      {"--delta", steps},
      {"--absolute", steps},
      {"--full-residual", semi},
      {"--matrix", {"semi-analytical", "semi-analytical-central", "direct-analytic"}},
      {"--rtol", {"idas", "idas-adjoint"}},
      {"--atol", {"idas", "idas-adjoint"}},
      {"--adjoint-memory", {"adjoint", "adjoint-semi-analytical"}},
  };
  for (const Use& u : uses) {
    if (!cl.sen->count(u.option)) continue;
    const bool used = std::any_of(methods.begin(), methods.end(), [&](const std::string& m) {
      return std::find(u.by.begin(), u.by.end(), m) != u.by.end();
    });
    if (used) continue;
    std::string names;
    for (const auto& m : u.by) names += (names.empty() ? "" : ", ") + m;
    throw lsmbs::Error(std::string(u.option) + ": an option of the methods " + names +
                       ", and --method " + list + " does not use it");
  }
}

// An option of a part that does not run would be ignored without a word: refused.
void check_unused_options(const CommandLine& cl) {
  if (*cl.opt && cl.opt->count("--seed") && !cl.opt->count("--starts"))
    throw lsmbs::Error("--seed: the seed of --starts' random initial designs; give --starts N");
  for (const char* o : {"--check-delta", "--check-seed", "--check-warn", "--check-fail"})
    if (*cl.sen && cl.sen->count(o) && !cl.sen_args.check)
      throw lsmbs::Error(std::string(o) + ": an option of the gradient check; give --check");
  for (const char* o : {"--check-warn", "--check-fail"})
    if (*cl.opt && cl.opt->count(o) && cl.no_check)
      throw lsmbs::Error(std::string(o) +
                         ": an option of the gradient check, which --no-check skips");
  if (*cl.sen) check_method_options(cl);
  if (*cl.sim && cl.sim_args.integrator != "idas")
    for (const char* o : {"--rtol", "--atol", "--max-order", "--error-test"})
      if (cl.sim->count(o))
        throw lsmbs::Error(std::string(o) +
                           ": an option of IDAS (--integrator idas); generalized-alpha does not "
                           "use it");
}

// summary.json records the case file's name and every argument as UTF-8 text: a name that is not
// would fail only when the summary is written, after the run. The case file's name and --set are
// checked here and when parsed (naming the byte), -o with the folder; anything else here.
void check_utf8(int argc, char** argv, const lsmbs::app::CommonArgs& c) {
  if (lsmbs::invalid_utf8_at(c.case_file) != std::string::npos)
    throw lsmbs::Error(lsmbs::shown(c.case_file, 4096) +  // a path is shown whole (PATH_MAX)
                       ": the case file's name is not valid UTF-8 (summary.json records it); "
                       "rename the file");
  for (int i = 1; i < argc; ++i)
    if (!lsmbs::valid_utf8(argv[i]) && argv[i] != c.case_file && argv[i] != c.out &&
        std::string(argv[i - 1]) != "--set")
      throw lsmbs::Error(std::string(argv[i - 1]) + " " + lsmbs::shown(argv[i]) +
                         ": not valid UTF-8 text (summary.json records the command line)");
}

// The command given, with its options complete.
int dispatch(CommandLine& cl) {
  using namespace lsmbs::app;
  if (*cl.sim) return simulate_command(cl.common, cl.sim_args);
  if (*cl.geo) return geometry_command(cl.common, cl.geo_args);
  if (*cl.sta) return static_command(cl.common, cl.static_args);
  if (*cl.opt) {
    cl.opt_args.check = !cl.no_check;
    cl.opt_args.overwrite = cl.overwrite;
    return optimize_command(cl.common, cl.opt_args);
  }
  if (*cl.ben) return bench_command(cl.common, cl.ben_args);
  if (*cl.ver) {
    cl.ver_args.options.idas = !cl.no_idas;
    cl.ver_args.options.mesh_study = !cl.no_mesh;
    return verify_command(cl.common, cl.ver_args);
  }
  if (*cl.sen) return sensitivity_command(cl.common, cl.sen_args);
  if (*cl.swp) return sweep_command(cl.common, cl.swp_args);
  std::cout << cl.app.help();
  return 2;
}

// The exit code and message of a command that threw: 2 bad input (an earlier run that
// --overwrite set aside is put back), 130 interrupted, 1 a numerical or output failure (the output
// folder, once ours, is flagged partial).
int failed(std::exception_ptr thrown, const CommandLine& cl, lsmbs::ReplacedRun& replaced,
           bool started, const std::string& command_line) {
  const std::string& out = cl.common.out;
  const std::string& case_file = cl.common.case_file;
  auto flag = [&](const std::string& what, const char* status = "partial") {
    if (started) lsmbs::app::flag_failed_run(out, command_line, case_file, what, status);
  };
  try {
    std::rethrow_exception(thrown);
  } catch (const lsmbs::SetupError& e) {  // the library names the subject; the case file the path
    std::fprintf(stderr, "lsmbs: error: %s\n", lsmbs::locate(case_file, e).what());
    replaced.restore();
    return 2;
  } catch (const lsmbs::Error& e) {
    std::fprintf(stderr, "lsmbs: error: %s\n", e.what());
    replaced.restore();
    return 2;
  } catch (const lsmbs::Interrupted& e) {  // a phase that has no partial result to return
    std::fprintf(stderr, "lsmbs: %s; what was finished is in %s (status interrupted)\n", e.what(),
                 out.c_str());
    flag(e.what(), "interrupted");
    return 130;
  } catch (const lsmbs::NumericalFailure& e) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", e.what());
    flag(std::string("numerical failure: ") + e.what());
    return 1;
  } catch (const lsmbs::OutputError& e) {  // the disk filled, a quota, an I/O error
    std::fprintf(stderr, "lsmbs: cannot write the output: %s; the results are partial\n", e.what());
    flag(std::string("cannot write the output: ") + e.what());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "lsmbs: cannot write the output (-o %s): %s; the results are partial\n",
                 out.c_str(), e.code().message().c_str());
    flag(std::string("cannot write the output: ") + e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "lsmbs: out of memory (the model or a table or mesh of the case is too large for "
                 "this machine)\n");
    flag("out of memory");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lsmbs: internal error: %s\n", e.what());
    flag(std::string("internal error: ") + e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  lsmbs::keep_freed_memory();
  // under mpirun/srun (src/lsmbs/runs/mpi.hpp): optimize and sensitivity run on every rank, their
  // service conditions and starts split over the ranks; rank 0 prints and writes
  try {
    lsmbs::mpi::init(&argc, &argv);
  } catch (const lsmbs::Error& e) {
    std::fprintf(stderr, "lsmbs: error: %s\n", e.what());
    return 2;
  }
  const bool worker = lsmbs::mpi::world().rank > 0;
  if (worker && !std::freopen("/dev/null", "w", stdout)) return 1;
  // SIGINT and SIGTERM from the start: every phase polls the flag and ends with exit 130 and its
  // results flagged (core/interrupt.hpp); a second signal ends the process at once
  lsmbs::install_interrupt_handlers();
  // names from the case reach the terminal in messages and reports: as text, never as control
  lsmbs::app::filter_control_characters();
  CommandLine cl;
  cl.app.require_subcommand(0, 1);
  cl.app.add_flag("--version", cl.version, "print version and git commit");
  add_simulate(cl);
  add_static_and_geometry(cl);
  add_sensitivity(cl);
  add_optimize(cl);
  add_verify_and_bench(cl);
  add_sweep(cl);
  try {
    cl.app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = cl.app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  if (cl.version) {
    std::printf("lsmbs %s (commit %s; %s)\n", lsmbs::kVersion, lsmbs::git_commit(),
                lsmbs::mpi::built() ? "with MPI" : "without MPI");
    return 0;
  }
  bool started = false;  // the output folder is ours: a failure from here on is flagged in it
  lsmbs::ReplacedRun replaced;  // an earlier run --overwrite replaces: back in place on bad input
  const std::string command_line = joined_args(argc, argv);
  try {
    check_unused_options(cl);
    check_utf8(argc, argv, cl.common);
    // every rank but 0 takes part in optimize, sensitivity and sweep only, and writes nothing
    if (worker && !*cl.opt && !*cl.sen && !*cl.swp) return 0;
    if (worker) cl.common.quiet = true;
    if (!worker &&
        (*cl.sim || *cl.sta || *cl.geo || *cl.opt || *cl.ben || *cl.ver || *cl.sen || *cl.swp)) {
      // checked now, claimed by the command once its case has loaded (commands/common.hpp)
      lsmbs::check_output_folder(cl.common.out);
      cl.common.overwrite = cl.overwrite;
      cl.common.resume = (*cl.opt && cl.opt_args.resume) || (*cl.swp && cl.resume);
      cl.common.replaced = &replaced;
      started = true;
    }
    cl.common.overwrite = cl.overwrite;
    cl.common.resume = (*cl.opt && cl.opt_args.resume) || (*cl.swp && cl.resume);
    cl.common.command_line = command_line;
    return dispatch(cl);
  } catch (...) {
    return failed(std::current_exception(), cl, replaced, started, command_line);
  }
}
