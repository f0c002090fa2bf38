// lsmbs — command line of the level-set flexible-multibody testbed.
//
//   lsmbs simulate CASE.json -o OUT      generalized-α simulation (Algorithm 1 of the paper)
//   lsmbs static CASE.json -o OUT        static equilibrium at one time (measures, responses, VTU)
//   lsmbs geometry CASE.json -o OUT      level-set design mapped on the mesh (μ_e VTU + PNG, mass)
//   lsmbs sensitivity CASE.json --method NAME -o OUT   responses and design gradients (§4.3)
//   lsmbs optimize CASE.json -o OUT [--resume]         fully coupled optimization (NLopt MMA)
//   lsmbs verify CASE.json -o OUT                      verification report (methods, Δp, h, mesh)
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

}  // namespace

int main(int argc, char** argv) {
  lsmbs::keep_freed_memory();
  // SIGINT and SIGTERM from the start: every phase polls the flag and ends with exit 130 and its
  // results flagged (core/interrupt.hpp); a second signal ends the process at once
  lsmbs::install_interrupt_handlers();
  // names from the case reach the terminal in messages and reports: as text, never as control
  lsmbs::app::filter_control_characters();
  static const char* kSetHelp =
      "override a value of the case by JSON path, /simulation/h=1e-3 or "
      "/bodies/1/material/E=70e9, or a design variable, name=value (repeatable; recorded in "
      "summary.json)";
  const CLI::Validator kInt =
      decimal_integer(std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  CLI::App app{"lsmbs — level-set structural optimization of flexible multibody system components"};
  app.require_subcommand(0, 1);
  bool version = false;
  app.add_flag("--version", version, "print version and git commit");

  lsmbs::app::CommonArgs common;
  std::string& case_file = common.case_file;
  std::string& out = common.out;
  bool& quiet = common.quiet;
  bool& verbose = common.verbose;
  bool overwrite = false;
  std::vector<std::string>& sets = common.sets;
  lsmbs::app::SimulateArgs sim_args;
  lsmbs::app::GeometryArgs geo_args;
  lsmbs::app::StaticArgs static_args;
  lsmbs::app::SensitivityArgs sen_args;
  lsmbs::app::OptimizeArgs opt_args;
  lsmbs::app::VerifyArgs ver_args;
  lsmbs::app::BenchArgs ben_args;
  auto* sim = app.add_subcommand("simulate", "simulate a case with the generalized-alpha scheme");
  sim->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  sim->add_option("-o,--output", out, "output folder (summary.json, history.csv, VTU)")
      ->capture_default_str();
  sim->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  sim->add_flag("-q,--quiet", quiet, "print nothing but errors");
  sim->add_flag("-v,--verbose", verbose, "print model statistics");
  sim->add_option("--integrator", sim_args.integrator,
                  "generalized-alpha (the paper's) or idas (SUNDIALS IDAS, GGL index 2)")
      ->check(CLI::IsMember({"generalized-alpha", "idas"}))
      ->capture_default_str();
  sim->add_option("--rtol", sim_args.rtol, "IDAS relative tolerance")->capture_default_str();
  sim->add_option("--atol", sim_args.atol,
                  "IDAS absolute tolerance on positions, in units of the model's length scale "
                  "(default: rtol)");
  sim->add_option("--max-order", sim_args.max_order,
                  "IDAS maximum BDF order 1-5; 0 = auto (2, A-stable, for models with a "
                  "flexible body; 5 otherwise)")
      ->transform(kInt)
      ->check(CLI::Range(0, 5))
      ->capture_default_str();
  sim->add_option("--error-test", sim_args.error_test,
                  "IDAS error test: positions, positions+velocities, or auto (positions "
                  "for models with a flexible body)")
      ->check(CLI::IsMember({"auto", "positions", "positions+velocities"}))
      ->capture_default_str();

  sim->add_option("--set", sets, kSetHelp);
  auto* sta = app.add_subcommand(
      "static", "static equilibrium at one time: measures, responses and VTU at equilibrium");
  sta->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  sta->add_option("-o,--output", out, "output folder")->capture_default_str();
  sta->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  sta->add_option("--set", sets, kSetHelp);
  sta->add_option("--t", static_args.t, "time at which drivers and loads are evaluated [s]")
      ->capture_default_str();
  sta->add_option("--max-iter", static_args.max_iter, "Newton iterations")
      ->transform(kInt)
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sta->add_flag("-q,--quiet", quiet, "print nothing but errors");
  auto* geo = app.add_subcommand(
      "geometry", "map the level-set design onto the mesh: μ_e (VTU, PNG), mass and its gradient");
  geo->add_option("case", case_file, "case file (JSON) with a design section")
      ->required()
      ->check(CLI::ExistingFile);
  geo->add_option("-o,--output", out, "output folder")->capture_default_str();
  geo->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  geo->add_option("--set", sets, kSetHelp);
  geo->add_option("--width", geo_args.width, "PNG width in pixels")
      ->transform(kInt)
      ->capture_default_str()
      ->check(CLI::Range(lsmbs::DesignPictureLayout::kMinWidth, 20000));
  geo->add_flag("-q,--quiet", quiet, "print nothing but errors");

  auto* sen = app.add_subcommand(
      "sensitivity",
      "responses and their design gradients (semi-analytical, direct, finite differences)");
  sen->add_option("case", case_file, "case file (JSON) with design variables and responses")
      ->required()
      ->check(CLI::ExistingFile);
  sen->add_option("-o,--output", out, "output folder")->capture_default_str();
  sen->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  sen->add_option("--method", sen_args.method,
                  "semi-analytical | semi-analytical-central | direct-analytic | adjoint (the "
                  "discrete adjoint: scalar responses, cost independent of the number of "
                  "variables) | adjoint-semi-analytical | fd-forward | fd-central | idas | "
                  "idas-adjoint (time-integral responses only); several separated by commas are "
                  "all run and compared (methods.csv, methods.png), the first one's results are "
                  "the gradients")
      ->capture_default_str();
  sen->add_option("--delta", sen_args.delta,
                  "perturbation Δp (semi-analytical) or finite-difference step")
      ->capture_default_str();
  sen->add_flag("--absolute", sen_args.absolute,
                "Δp absolute instead of relative to max(|p_i|, 1e-2 (upper - lower))");
  sen_args.matrix = lsmbs::SensitivityOptions::matrix_name(lsmbs::SensitivityOptions{}.matrix);
  sen->add_flag("--full-residual", sen_args.full_residual,
                "semi-analytical pseudo-loads from whole-residual evaluations (Algorithm 2 "
                "literally) instead of element-local ones");
  sen->add_option(
         "--matrix", sen_args.matrix,
         "matrix of the back-solves: converged (default: S_t refactorized at the converged state, "
         "exact), "
         "refined (S_t at the converged state by iterative refinement, exact), last (the last "
         "Newton "
         "iteration's, Algorithm 2 literally; not exact where a step converged in one iteration)")
      ->capture_default_str();
  sen->add_option("--set", sets, kSetHelp);
  sen->add_option("--rtol", sen_args.rtol, "--method idas, idas-adjoint: IDAS relative tolerance")
      ->capture_default_str();
  sen->add_option("--atol", sen_args.atol,
                  "--method idas, idas-adjoint: IDAS absolute tolerance in units of the length "
                  "scale (default: rtol)");
  sen->add_option("--adjoint-memory", sen_args.adjoint_memory_mb,
                  "--method adjoint: bound on the memory of the stored trajectory in MB (0: no "
                  "bound); a trajectory that does not fit is stored at checkpoints and "
                  "recomputed in the backward pass (summary.json counts)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sen->add_option("--threads", sen_args.threads,
                  "2: the sensitivity update of each step runs on a second thread while the next "
                  "step is computed; "
                  "1: one thread (same results to round-off)")
      ->capture_default_str()
      ->transform(kInt)
      ->check(CLI::Range(1, 2));
  sen->add_flag("-q,--quiet", quiet, "print nothing but errors");
  lsmbs::GradientCheckOptions& check_opt = sen_args.check_options;
  sen->add_flag("--check", sen_args.check,
                "gradient check: central differences of 2 more simulations along a random "
                "direction against the "
                "gradient; per-response disagreement in summary.json (exit 1 above --check-fail)");
  sen->add_option("--check-delta", check_opt.delta, "--check: relative step along the direction")
      ->capture_default_str();
  sen->add_option("--check-seed", check_opt.seed, "--check: seed of the random direction")
      ->capture_default_str()
      ->transform(decimal_integer(0, std::numeric_limits<unsigned>::max()));
  sen->add_option("--check-warn", check_opt.warn, "--check: warn above this relative disagreement")
      ->capture_default_str();
  sen->add_option("--check-fail", check_opt.fail, "--check: fail above this relative disagreement")
      ->capture_default_str();

  auto* opt = app.add_subcommand(
      "optimize", "fully coupled optimization of the case's design (NLopt MMA/CCSAQ/SLSQP)");
  opt->add_option("case", case_file,
                  "case file (JSON) with design, responses and an optimization section")
      ->required()
      ->check(CLI::ExistingFile);
  opt->add_option("-o,--output", out,
                  "output folder (history.csv, checkpoint.json, final_design/, summary.json)")
      ->capture_default_str();
  opt->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  opt->add_flag("--resume", opt_args.resume,
                "continue an interrupted run from OUT/checkpoint.json");
  opt->add_option("--starts", opt_args.starts,
                  "multi-start: N optimizations from N feasible random initial designs (uniform "
                  "within the bounds, seeded), in OUT/start_1 … OUT/start_N, 2 at a time; "
                  "OUT/starts.csv and summary.json rank them")
      ->transform(kInt)
      ->check(CLI::Range(1, 1000));
  opt->add_option("--seed", opt_args.seed, "multi-start: seed of the random initial designs")
      ->capture_default_str()
      ->transform(decimal_integer(0, std::numeric_limits<unsigned long>::max()));
  opt->add_option("--optimizer", opt_args.optimizer, "override the case's optimizer")
      ->check(CLI::IsMember({"mma", "ccsaq", "slsqp", "mma-svanberg"}));
  opt->add_flag("-q,--quiet", quiet, "print nothing but errors");
  opt->add_option("--set", sets,
                  "override a value of the case by JSON path, /simulation/h=1e-3 (repeatable); "
                  "name=value sets a design variable's initial value");
  bool no_check = false;
  lsmbs::GradientCheckOptions& opt_check = opt_args.check_options;
  opt->add_flag(
      "--no-check", no_check,
      "skip the gradient check at the initial design (default: central differences along a random "
      "direction, 2 simulations; warns above --check-warn, refuses above --check-fail)");
  opt->add_option("--check-warn", opt_check.warn,
                  "gradient check: warn above this relative disagreement")
      ->capture_default_str();
  opt->add_option("--check-fail", opt_check.fail,
                  "gradient check: refuse above this relative disagreement")
      ->capture_default_str();
  opt->add_flag(
      "-v,--verbose", verbose,
      "a row per evaluation also when not on a terminal (default there: final summary only)");

  lsmbs::VerifyOptions& vo = ver_args.options;
  bool no_idas = false, no_mesh = false;
  auto* ver =
      app.add_subcommand("verify",
                         "verification report: every sensitivity method, costs, delta-p study, "
                         "time-step study against IDAS, mesh study, pass/fail");
  ver->add_option("case", case_file, "case file (JSON) with design variables and responses")
      ->required()
      ->check(CLI::ExistingFile);
  ver->add_option("-o,--output", out, "output folder (report.md, CSV, PNG)")->capture_default_str();
  ver->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  ver->add_flag("--no-idas", no_idas,
                "skip IDAS (too slow for long runs of stiff flexible models)");
  ver->add_flag("--no-mesh-study", no_mesh, "skip the mesh study");
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
  ver->add_option("--set", sets, kSetHelp);

  lsmbs::BenchOptions& bo = ben_args.options;
  auto* ben = app.add_subcommand("bench",
                                 "whole-run benchmark: step cost against the KLU/assembly floor, "
                                 "sensitivity overheads, peak memory");
  ben->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  ben->add_option("-o,--output", out, "output folder (bench.json, summary.json)")
      ->capture_default_str();
  ben->add_flag(
      "--overwrite", overwrite,
      "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  ben->add_option("--methods", ben_args.methods,
                  "sensitivity methods to time (default: direct-analytic "
                  "semi-analytical-central; 'none' for none)");
  ben->add_option("--matrices", bo.matrices,
                  "back-solve matrices timed besides the default for the direct methods "
                  "(last, converged, refined; 'none' for none)")
      ->capture_default_str();
  ben->add_option("--repetitions", bo.repetitions, "repetitions of the floor measurements")
      ->capture_default_str()
      ->transform(kInt)
      ->check(CLI::Range(1, 100000));
  ben->add_option("--threads", bo.threads,
                  "threads of the sensitivity runs (see sensitivity --threads)")
      ->capture_default_str()
      ->transform(kInt)
      ->check(CLI::Range(1, 2));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  if (version) {
    std::printf("lsmbs %s (commit %s)\n", lsmbs::kVersion, lsmbs::git_commit());
    return 0;
  }
  bool started = false;  // the output folder is ours: a failure from here on is flagged in it
  lsmbs::ReplacedRun replaced;  // an earlier run --overwrite replaces: back in place on bad input
  try {
    if (*opt && opt->count("--seed") && !opt->count("--starts"))
      throw lsmbs::Error("--seed: the seed of --starts' random initial designs; give --starts N");
    // an option of a part that does not run would be ignored without a word
    for (const char* o : {"--check-delta", "--check-seed", "--check-warn", "--check-fail"})
      if (*sen && sen->count(o) && !sen_args.check)
        throw lsmbs::Error(std::string(o) + ": an option of the gradient check; give --check");
    for (const char* o : {"--check-warn", "--check-fail"})
      if (*opt && opt->count(o) && no_check)
        throw lsmbs::Error(std::string(o) +
                           ": an option of the gradient check, which --no-check skips");
    // an option of sensitivity methods none of which runs (--delta 0.5 with direct-analytic left
    // gradients.csv byte for byte as it was, and summary.json recorded it as if used)
    if (*sen) {
      std::vector<std::string> methods;
      for (size_t b = 0; b <= sen_args.method.size();) {
        const size_t e = std::min(sen_args.method.find(',', b), sen_args.method.size());
        methods.push_back(sen_args.method.substr(b, e - b));
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
        if (!sen->count(u.option)) continue;
        const bool used = std::any_of(methods.begin(), methods.end(), [&](const std::string& m) {
          return std::find(u.by.begin(), u.by.end(), m) != u.by.end();
        });
        if (!used) {
          std::string list;
          for (const auto& m : u.by) list += (list.empty() ? "" : ", ") + m;
          throw lsmbs::Error(std::string(u.option) + ": an option of the methods " + list +
                             ", and --method " + sen_args.method + " does not use it");
        }
      }
    }
    if (*sim && sim_args.integrator != "idas")
      for (const char* o : {"--rtol", "--atol", "--max-order", "--error-test"})
        if (sim->count(o))
          throw lsmbs::Error(std::string(o) +
                             ": an option of IDAS (--integrator idas); generalized-alpha does not "
                             "use it");
    // summary.json records the case file's name, and JSON text is UTF-8: a name that is not
    // would fail only when the summary is written, after the run
    if (lsmbs::invalid_utf8_at(case_file) != std::string::npos)
      throw lsmbs::Error(lsmbs::shown(case_file, 4096) +  // a path is shown whole (PATH_MAX)

                         ": the case file's name is not valid UTF-8 (summary.json records it); "
                         "rename the file");
    // every argument is recorded in summary.json as UTF-8 text: the case file's name and --set
    // are checked above and when parsed (naming the byte), -o with the folder; anything else
    for (int i = 1; i < argc; ++i)
      if (!lsmbs::valid_utf8(argv[i]) && argv[i] != case_file && argv[i] != out &&
          std::string(argv[i - 1]) != "--set")
        throw lsmbs::Error(std::string(argv[i - 1]) + " " + lsmbs::shown(argv[i]) +
                           ": not valid UTF-8 text (summary.json records the command line)");
    if (*sim || *sta || *geo || *opt || *ben || *ver || *sen) {
      // checked now, claimed by the command once its case has loaded (commands/common.hpp)
      lsmbs::check_output_folder(out);
      common.overwrite = overwrite;
      common.resume = *opt && opt_args.resume;
      common.replaced = &replaced;
      started = true;
    }
    common.command_line = joined_args(argc, argv);
    if (*sim) return lsmbs::app::simulate_command(common, sim_args);
    if (*geo) return lsmbs::app::geometry_command(common, geo_args);
    if (*sta) return lsmbs::app::static_command(common, static_args);
    if (*opt) {
      opt_args.check = !no_check;
      opt_args.overwrite = overwrite;
      return lsmbs::app::optimize_command(common, opt_args);
    }
    if (*ben) return lsmbs::app::bench_command(common, ben_args);
    if (*ver) {
      vo.idas = !no_idas;
      vo.mesh_study = !no_mesh;
      return lsmbs::app::verify_command(common, ver_args);
    }
    if (*sen) return lsmbs::app::sensitivity_command(common, sen_args);
    std::cout << app.help();
    return 2;
  } catch (
      const lsmbs::SetupError& e) {  // the library names the subject; the case file has the path
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
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file, e.what(), "interrupted");
    return 130;
  } catch (const lsmbs::NumericalFailure& e) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", e.what());
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file,
                                  std::string("numerical failure: ") + e.what());
    return 1;
  } catch (const lsmbs::OutputError& e) {  // the disk filled, a quota, an I/O error
    std::fprintf(stderr, "lsmbs: cannot write the output: %s; the results are partial\n", e.what());
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file,
                                  std::string("cannot write the output: ") + e.what());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "lsmbs: cannot write the output (-o %s): %s; the results are partial\n",
                 out.c_str(), e.code().message().c_str());
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file,
                                  std::string("cannot write the output: ") + e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "lsmbs: out of memory (the model or a table or mesh of the case is too large for "
                 "this machine)\n");
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file, "out of memory");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lsmbs: internal error: %s\n", e.what());
    if (started)
      lsmbs::app::flag_failed_run(out, joined_args(argc, argv), case_file,
                                  std::string("internal error: ") + e.what());
    return 1;
  }
}
