#pragma once
// SparseLU — KLU (SuiteSparse) behind a small C++ interface (DESIGN.md §Core interfaces 3):
// analyze(pattern) once per model, factor(values) per Newton iteration (klu_refactor reusing
// the pivot sequence when it stays well conditioned, a full klu_factor otherwise), and
// solve() on a block of right-hand sides in one call (sensitivity back-solves).
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "lsmbs/core/status.hpp"
#include "lsmbs/core/types.hpp"
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
  /// A + Aᵀ, KLU's user-ordering hook) — asymptotically less fill on large 2-D meshes — or
  /// COLAMD (SUNDIALS' SUNLinSol_KLU default, kept for the IDAS reference runs).
  enum class Ordering { kAmd, kNestedDissection, kColamd };
  void set_ordering(Ordering o) { ordering_ = o; }
  Ordering ordering() const { return ordering_; }
  static const char* ordering_name(Ordering o) {
    return o == Ordering::kAmd                ? "amd"
           : o == Ordering::kNestedDissection ? "nested_dissection"
                                              : "colamd";
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
  /// Numeric factorization of values laid out on the analyzed pattern.
  /// On a singular matrix returns kSingular with the offending column in singular_column().
  Status factor(std::span<const double> values);
  /// The steps of factor() on their own, for a caller with its own refactorization policy:
  /// refactor() reuses the last pivot sequence (false when KLU fails or there is none);
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
  std::unique_ptr<Impl> impl_;
  mutable Counters counters_;
  int singular_col_ = -1;
  Ordering ordering_ = Ordering::kAmd;
};

}  // namespace lsmbs
