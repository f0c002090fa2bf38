#pragma once
// BlockAmg — the iterative linear solver behind SparseLU::Solver::kAmg: restarted GMRES on the
// whole iteration matrix S_t (eq. 13), right-preconditioned by a symmetric block Gauss–Seidel
// sweep whose large block is taken by V-cycles of hypre's BoomerAMG and whose small block by KLU.
//
// The unknowns are split in two. F: the coordinates of solid bodies' nodes that no constraint row
// touches, three per node (x, y, z consecutive) — an elastic block, symmetric positive definite,
// made for an AMG (3 functions per node, the systems approach, with the rigid-body rotations of
// the nodes' positions as interpolation vectors: thin plates need them). C: everything else — the
// multipliers, the rigid bodies' coordinates, the nodes tied to them by rigid connections — a
// saddle point of a few hundred unknowns that a direct LU takes exactly. With S = [A_ff A_fc;
// A_cf A_cc] one application of the preconditioner is
//   z_f = AMG(r_f),  z_c = A_cc⁻¹ (r_c − A_cf z_f),  z_f += AMG(r_f − A_ff z_f − A_fc z_c),
// the second V-cycle carrying the direct block's correction (a rigid body's motion) into the
// flexible body: a payload hanging on a thin plate (solid_arm.json) took 205 GMRES(60) iterations
// with the first two steps alone, 58 with all three. For Sᵀ the same sweep on Sᵀ's blocks.
// Where the block is several elements thick across (Options::Shape), the sweep is C, F instead
// — z_c = A_cc⁻¹ r_c, z_f = AMG(r_f − A_fc z_c) — with aggressive coarsening: one cheaper V-cycle.
// GMRES iterates on the true (equilibrated) matrix, so the solution is S⁻¹b to the tolerance
// whatever the quality of the preconditioner: a relative residual of `rtol` (1e-12) on the
// equilibrated system, or of `attainable` (1e-10) — or a backward error of 1e-14 — where
// round-off stalls it above rtol, as it
// stalls a direct LU's (docs/performance.md, "Linear solvers on 3D meshes").
//
// hypre is a Debian package (libhypre-dev) built with MPI: available() is false in a build without
// it. hypre keeps global state: every call into it holds one process-wide lock, so two threads
// solving at once take turns in hypre (and run the rest of their GMRES side by side).
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/status.hpp"
#include "lsmbs/linalg/sparsity.hpp"

namespace lsmbs {

class BlockAmg {
 public:
  struct Options {
    double rtol = 1e-12;  ///< ‖D(b − S x)‖ ≤ rtol ‖D b‖, D the equilibration
    /// or, where round-off stalls the residual above rtol, ≤ attainable ‖D b‖
    double attainable = 1e-10;
    /// or, stalled, the normwise backward error ‖D(b − S x)‖∞ / (‖D S‖∞ ‖x‖∞ + ‖D b‖∞) is at
    /// most this, as a stable direct solver's: where b nearly cancels against S x (a
    /// sensitivity's right-hand side 1e-9 of ‖S‖‖x‖), round-off stalls the relative residual
    /// far above rtol (1e-8) at a backward error near 1e-17
    double backward_error = 1e-14;
    int restart = 60;  ///< GMRES(m) Krylov basis size
    bool equilibrate = true;
    int max_iterations = 2000;
    /// The AMG block's shape, which sets the preconditioner (kAuto: kBulky where the block is at
    /// least `bulky_layers` elements thick, kThin elsewhere). kThin: standard coarsening and the
    /// sweep F, C, F (two V-cycles); kBulky: aggressive coarsening on the first level and the
    /// sweep C, F (one V-cycle), about half the cost on meshes several elements thick, but slow
    /// or divergent on plates one or two elements thick (docs/performance.md).
    enum class Shape { kAuto, kThin, kBulky };
    Shape shape = Shape::kAuto;
    double bulky_layers = 4;
    /// A solve with the bulky preconditioner that has not converged after this many iterations
    /// starts again from zero with the thin one, which the solver keeps until the next analysis
    /// (a curved shell that looks bulky from afar).
    int fallback_iterations = 150;
  };
  /// Counts since analyze(), for summaries and the benchmarks.
  struct Counters {
    long setups = 0, solves = 0, iterations = 0;
    int max_iterations = 0;     ///< the most GMRES iterations one solve took
    double worst_residual = 0;  ///< the largest final relative residual of a solve
    int block_unknowns = 0, direct_unknowns = 0;
    /// How many elements thick the solids are (the AMG block's nodes and the held ones): per
    /// connected part of their node graph, the extent across the thinnest principal direction of
    /// its nodes over the median of the nodes' largest neighbour spacing along it; the thinnest
    /// part's figure, which decides for the whole block (nx × ny × nz bricks: min(nx, ny, nz)).
    double layers = 0;
    bool bulky = false;  ///< the preconditioner in use (Options::Shape)
    int fallbacks = 0;   ///< bulky solves that started again as thin
  };

  BlockAmg();
  ~BlockAmg();
  BlockAmg(const BlockAmg&) = delete;
  BlockAmg& operator=(const BlockAmg&) = delete;

  /// Whether this build has hypre.
  static bool available();

  /// The split: `node_of[i]` is the solid node (any numbering that gives each node its own
  /// number) whose coordinate unknown i is, with `direction_of[i]` ∈ {0, 1, 2}; −1 for an unknown
  /// the direct block takes. A node enters the AMG block only with its three coordinates.
  /// `direction_of[i]` = 3 + d marks coordinate d of a solid node that a constraint holds: the
  /// direct block takes it, and it counts in the solids' shape (Counters::layers: a face clamped
  /// across a block's thinnest direction is one of its element layers).
  /// `positions` holds each node's reference position (3 per node number): the rotations that
  /// AMG's interpolation must reproduce. Throws std::logic_error when hypre is not available.
  void analyze(const CscPattern& pattern, std::span<const int> node_of,
               std::span<const int> direction_of, std::span<const double> positions);
  /// Shares `other`'s split and the direct block's symbolic analysis (read-only).
  void share_analysis(const BlockAmg& other);
  /// AMG setup on A_ff and LU of A_cc from the values on the pattern (kept for the products).
  /// kSingular names the unknown (global numbering) where A_cc's LU broke down.
  Status factor(std::span<const double> values);
  bool factored() const;
  /// Solves S X = B (or Sᵀ X = B) in place, B column-major n × nrhs. A solve that does not reach
  /// the tolerance throws LinearSolveError (numerical failure: the caller reports it).
  void solve(std::span<double> b, int nrhs, bool transpose) const;
  int singular_unknown() const { return singular_; }

  Options options;
  const Counters& counters() const { return counters_; }

 private:
  struct Split;
  struct Numeric;
  void precondition(const double* v, double* z, bool transpose) const;
  void multiply(const double* x, double* y, bool transpose) const;
  void solve_one(double* b, bool transpose) const;
  struct Outcome {
    int iterations = 0;
    double rel = 0, eta = 0;  // relative residual (2-norm), normwise backward error (∞-norms)
    bool stalled = false, converged = true;
  };
  Outcome gmres(const double* b, bool transpose, int max_iterations) const;
  void setup_amg() const;
  static void create_block(Numeric& nm, const Split& s);
  void reset_counters();
  std::shared_ptr<const Split> split_;
  std::unique_ptr<Numeric> num_;
  mutable Counters counters_;
  int singular_ = -1;
  mutable bool bulky_ = false, fell_back_ = false;
};

/// An iterative solve that missed its tolerance: a numerical failure (exit code 1, the results
/// flagged partial), not an input error. The message says how far it got.
class LinearSolveError : public NumericalFailure {
 public:
  using NumericalFailure::NumericalFailure;
};

}  // namespace lsmbs
