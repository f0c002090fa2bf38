// lsmbs — command line of the level-set flexible-multibody testbed.
//
//   lsmbs simulate CASE.json -o OUT      generalized-α simulation (Algorithm 1 of the paper)
//   lsmbs --version
//
// Exit codes: 0 success; 1 numerical failure (message says when and why); 2 invalid input or
// usage (file, JSON path, what was expected). Nothing is written when the input is invalid.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/version.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/simulation_run.hpp"

namespace {

std::string joined_args(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) s += (i ? " " : "") + std::string(argv[i]);
  return s;
}

int simulate(const std::string& case_file, const std::string& out, bool quiet, bool verbose,
             const std::string& cmdline) {
  lsmbs::Case cs = lsmbs::load_case(case_file);  // validates everything before writing
  lsmbs::RunOptions ro;
  ro.out_dir = out;
  ro.progress = !quiet && ::isatty(STDERR_FILENO);
  ro.command_line = cmdline;
  if (verbose)
    std::fprintf(stderr, "lsmbs: case '%s': %d DOFs, %d constraint equations, %d nonzeros\n", cs.name.c_str(),
                 cs.model->nq(), cs.model->nc(), cs.model->pattern().nnz());
  const auto res = lsmbs::run_simulation(cs, ro);
  const auto& s = res.integrator;
  if (!quiet) {
    std::printf("lsmbs simulate: %s — %ld steps, %ld Newton iterations, %ld factorizations, %.3f s\n",
                s.ok ? "complete" : "FAILED", s.steps, s.newton_iterations, s.factorizations, s.wall_seconds);
    if (s.halvings) std::printf("  step halvings: %ld (first at t = %g s)\n", s.halvings, s.halving_times.front());
    for (const auto& [name, v] : res.responses) std::printf("  %-28s %.10g\n", name.c_str(), v);
    std::printf("  results in %s\n", out.c_str());
  }
  if (!s.ok) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n  (partial results in %s, flagged in summary.json)\n",
                 s.message.c_str(), out.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lsmbs — level-set structural optimization of flexible multibody system components"};
  app.require_subcommand(0, 1);
  bool version = false;
  app.add_flag("--version", version, "print version and git commit");

  std::string case_file, out = "out";
  bool quiet = false, verbose = false;
  auto* sim = app.add_subcommand("simulate", "simulate a case with the generalized-alpha scheme");
  sim->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  sim->add_option("-o,--output", out, "output folder (summary.json, history.csv, VTU)")->capture_default_str();
  sim->add_flag("-q,--quiet", quiet, "print nothing but errors");
  sim->add_flag("-v,--verbose", verbose, "print model statistics");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  if (version) {
    std::printf("lsmbs %s (commit %s)\n", lsmbs::kVersion, lsmbs::kGitCommit);
    return 0;
  }
  try {
    if (*sim) return simulate(case_file, out, quiet, verbose, joined_args(argc, argv));
    std::cout << app.help();
    return 2;
  } catch (const lsmbs::Error& e) {
    std::fprintf(stderr, "lsmbs: error: %s\n", e.what());
    return 2;
  } catch (const lsmbs::NumericalFailure& e) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lsmbs: internal error: %s\n", e.what());
    return 1;
  }
}
