#pragma once
// SparseLU — a sparse direct LU (SuiteSparse) behind a small C++ interface (DESIGN.md §Core
// interfaces 3): analyze(pattern) once per model, factor(values) per Newton iteration, and
// solve() on a block of right-hand sides in one call (sensitivity back-solves).
// Two factorizations stand behind it (Solver): KLU (klu_refactor reusing the pivot sequence when
// it stays well conditioned, a full klu_factor otherwise), made for matrices that fill little —
// every planar model — and UMFPACK's multifrontal LU (dense frontal matrices through BLAS 3, a
// fresh threshold-pivoting factorization each time), for the matrices of 3D solid meshes whose
// factors fill ten times and more (docs/performance.md, "Linear solvers on 3D meshes").
// A third solver is iterative (Solver::kAmg, linalg/block_amg.hpp): GMRES preconditioned by
// hypre's BoomerAMG on the solid bodies' elastic block and KLU on the rest, solved to a relative
// residual of 1e-12; factor() is then the AMG setup and the small LU, solve() the GMRES.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/core/types.hpp"
#include "lsmbs/linalg/block_amg.hpp"
#include "lsmbs/linalg/sparsity.hpp"

namespace lsmbs {

class SparseLU {
 public:
  SparseLU();
  ~SparseLU();
  SparseLU(const SparseLU&) = delete;
  SparseLU& operator=(const SparseLU&) = delete;

  /// Fill-reducing ordering of the symbolic analysis (of each block of KLU's block triangular
  /// form): KLU's default AMD, nested dissection (METIS through CHOLMOD on the pattern of
  /// A + Aᵀ, KLU's user-ordering hook) — asymptotically less fill on large 2-D and 3-D meshes —
  /// or COLAMD (SUNDIALS' SUNLinSol_KLU default, kept for the IDAS reference runs). UMFPACK
  /// orders A + Aᵀ by AMD, or by METIS for kNestedDissection.
  enum class Ordering { kAmd, kNestedDissection, kColamd };
  void set_ordering(Ordering o) { ordering_ = o; }
  Ordering ordering() const { return ordering_; }
  static const char* ordering_name(Ordering o) {
    return o == Ordering::kAmd                ? "amd"
           : o == Ordering::kNestedDissection ? "nested_dissection"
                                              : "colamd";
  }
  /// Which factorization: kAuto decides at analyze() from KLU's fill estimate of the pattern
  /// (UMFPACK above auto_fill_threshold() nonzeros in L + U), kKlu and kUmfpack force one. The
  /// decision depends only on the pattern, so the same model always gets the same solver. kAmg
  /// (set_amg_split() first; needs a build with hypre) is kAuto's choice when the split's AMG block
  /// holds at least half the unknowns and the estimated fill passes auto_amg_fill_threshold().
  enum class Solver { kAuto, kKlu, kUmfpack, kAmg };
  static double auto_amg_fill_threshold();
  /// Whether this build has the AMG solver (hypre).
  static bool amg_available() { return BlockAmg::available(); }
  /// The AMG solver's split of the unknowns and the nodes' positions (BlockAmg::analyze), read
  /// by analyze() with kAmg.
  void set_amg_split(std::vector<int> node_of, std::vector<int> direction_of,
                     std::vector<double> positions) {
    amg_node_ = std::move(node_of);
    amg_direction_ = std::move(direction_of);
    amg_positions_ = std::move(positions);
  }
  /// The AMG solver after analyze() with kAmg (options, counters); nullptr otherwise.
  BlockAmg* amg() { return amg_.get(); }
  const BlockAmg* amg() const { return amg_.get(); }
  static double auto_fill_threshold();
  void set_solver(Solver s) { solver_ = s; }
  Solver solver() const { return solver_; }
  /// The factorization analyze() chose (kKlu or kUmfpack; kAuto before analyze()).
  Solver solver_used() const { return used_; }
  static const char* solver_name(Solver s) {
    return s == Solver::kAuto  ? "auto"
           : s == Solver::kKlu ? "klu"
           : s == Solver::kAmg ? "amg"
                               : "umfpack";
  }
  /// KLU's partial-pivoting threshold (Common.tol, default 0.001): a diagonal entry is kept as
  /// pivot down to this fraction of its column's largest entry; 1 is plain partial pivoting.
  void set_pivot_tolerance(double tol);

  /// Symbolic analysis (ordering); the pattern must outlive the factorization.
  void analyze(const CscPattern& pattern);
  /// Uses `other`'s symbolic analysis (shared, read-only; not recomputed) for a second, independent
  /// numeric factorization of the same pattern — e.g. one a worker thread solves with while the
  /// integrator factorizes the next step into the other.
  void share_analysis(const SparseLU& other);
  /// Nonzeros of the last factorization's L and U (fill-in).
  long factor_nonzeros() const;
  /// KLU's estimate of the nonzeros of L and U from the symbolic analysis (AMD or the chosen
  /// ordering; what kAuto decides on).
  double estimated_factor_nonzeros() const;
  /// Numeric factorization of values laid out on the analyzed pattern.
  /// On a singular matrix returns kSingular with the offending column in singular_column() (with
  /// UMFPACK, the column is found by a KLU factorization of the same values: the diagnostics do
  /// not depend on the solver).
  Status factor(std::span<const double> values);
  /// The steps of factor() on their own, for a caller with its own refactorization policy:
  /// refactor() reuses the last pivot sequence (false when KLU fails or there is none; UMFPACK
  /// has no such step and factorizes afresh);
  /// estimate_rcond() is KLU's cheap reciprocal condition estimate of the factorization, and
  /// estimate_condition() its 1-norm condition estimate (klu_condest) with the values factorized
  /// (nullopt when KLU fails).
  bool refactor(std::span<const double> values);
  std::optional<double> estimate_rcond();
  std::optional<double> estimate_condition(std::span<const double> values);
  /// Solves A X = B in place; B is column-major n × nrhs.
  void solve(std::span<double> b, int nrhs = 1) const;
  void solve(Vec& b) const { solve(std::span<double>(b.data(), b.size()), 1); }
  /// Solves for every column of B (n × nrhs, column-major) in one call.
  void solve(Mat& b) const {
    solve(std::span<double>(b.data(), b.size()), static_cast<int>(b.cols()));
  }
  /// Solves Aᵀ X = B in place.
  void solve_transpose(std::span<double> b, int nrhs = 1) const;

  bool factored() const;
  /// Forgets the pivot sequence: the next factor() does a full klu_factor (used when the
  /// matrix changes character, e.g. from the initialization system to the iteration matrix).
  void reset_pivoting();
  int singular_column() const { return singular_col_; }
  /// Reciprocal condition estimate of the last factorization (cheap, KLU's klu_rcond).
  double rcond() const;

  struct Counters {
    long symbolic = 0, full_factorizations = 0, refactorizations = 0, solves = 0, rhs = 0;
  };
  const Counters& counters() const { return counters_; }

  /// Threshold on klu_rcond under which a refactorization is redone with fresh pivoting.
  double refactor_rcond_threshold = 1e-12;

 private:
  struct Impl;
  Status factor_umfpack(std::span<const double> values);
  bool amg_suits(int n) const;
  void analyze_amg(const CscPattern& pattern);
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<BlockAmg> amg_;
  std::vector<int> amg_node_, amg_direction_;
  std::vector<double> amg_positions_;
  mutable Counters counters_;
  int singular_col_ = -1;
  Ordering ordering_ = Ordering::kAmd;
  Solver solver_ = Solver::kAuto;
  Solver used_ = Solver::kAuto;
};

}  // namespace lsmbs
