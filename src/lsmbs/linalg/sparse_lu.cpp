#include "lsmbs/linalg/sparse_lu.hpp"

#include <cholmod.h>
#include <klu.h>
#include <umfpack.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace lsmbs {

namespace {
// The symbolic analysis is read-only once computed, so factorizations may share it
// (SparseLU::share_analysis); it is freed with the last of them.
struct SymbolicDeleter {
  void operator()(klu_symbolic* s) const {
    klu_common c;
    klu_defaults(&c);
    klu_free_symbolic(&s, &c);
  }
};
struct UmfpackSymbolicDeleter {
  void operator()(void* s) const { umfpack_dl_free_symbolic(&s); }
};
}  // namespace

struct SparseLU::Impl {
  klu_common common{};
  std::shared_ptr<klu_symbolic> symbolic;  // always analyzed: the fill estimate, diagnostics
  klu_numeric* numeric = nullptr;
  // UMFPACK (Solver::kUmfpack): its symbolic analysis (read-only, shared like KLU's), numeric
  // factorization, options and the last call's statistics, and the workspace of wsolve (one
  // right-hand side at a time, allocated once in analyze). The long-integer interface (dl): the
  // int one (di) indexes its numeric workspace with int and runs out of it on 3D meshes of
  // 150k DOFs with memory to spare. The pattern's long copy is shared like the pattern.
  bool umfpack = false;
  std::shared_ptr<const std::vector<SuiteSparse_long>> apl, ail;
  std::shared_ptr<void> umf_symbolic;
  void* umf_numeric = nullptr;
  double umf_control[UMFPACK_CONTROL] = {};
  mutable double umf_info[UMFPACK_INFO] = {};
  mutable std::vector<SuiteSparse_long> umf_wi;
  mutable std::vector<double> umf_w, umf_rhs;
  std::shared_ptr<const std::vector<int>> ap, ai;
  int n = 0;
  Impl() { klu_defaults(&common); }
  ~Impl() { free_numeric(); }
  void free_numeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (umf_numeric) umfpack_dl_free_numeric(&umf_numeric);
  }
  void umfpack_workspace() {
    umf_wi.assign(n, 0);
    umf_w.assign(5 * static_cast<size_t>(n), 0.0);
    umf_rhs.assign(n, 0.0);
  }
  // one UMFPACK solve per column: sys is UMFPACK_A or UMFPACK_At; no iterative refinement
  // (Control[IRSTEP] = 0, as KLU), so the matrix values are not needed
  void umfpack_solve(int sys, std::span<double> b, int nrhs) const {
    for (int j = 0; j < nrhs; ++j) {
      double* x = b.data() + static_cast<size_t>(j) * n;
      std::copy(x, x + n, umf_rhs.begin());
      umfpack_dl_wsolve(sys, apl->data(), ail->data(), nullptr, x, umf_rhs.data(), umf_numeric,
                        umf_control, umf_info, umf_wi.data(), umf_w.data());
    }
  }
  int* Ap() const { return const_cast<int*>(ap->data()); }  // KLU's API is not const-correct
  int* Ai() const { return const_cast<int*>(ai->data()); }
};

namespace {

// KLU user ordering (Common.ordering = 3): nested dissection of the symmetrized pattern
// S = A + Aᵀ by METIS through CHOLMOD (cholmod_metis, postordered). Returns 0 on failure (KLU
// then reports an error), otherwise -1 ("no fill estimate").
int nested_dissection_order(int n, int Ap[], int Ai[], int Perm[], klu_common*) {
  if (n <= 0) return 0;
  if (n < 3) {  // METIS needs a graph; a tiny block needs no ordering
    for (int k = 0; k < n; ++k) Perm[k] = k;
    return -1;
  }
  // upper triangle of the pattern of A + Aᵀ, diagonal excluded, as a CSC matrix
  std::vector<std::vector<int>> cols(n);
  for (int j = 0; j < n; ++j)
    for (int p = Ap[j]; p < Ap[j + 1]; ++p) {
      const int i = Ai[p];
      if (i < j)
        cols[j].push_back(i);
      else if (i > j)
        cols[i].push_back(j);
    }
  std::vector<int> sp(n + 1, 0), si;
  for (int j = 0; j < n; ++j) {
    auto& c = cols[j];
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    si.insert(si.end(), c.begin(), c.end());
    sp[j + 1] = static_cast<int>(si.size());
  }
  if (si.empty()) {
    for (int k = 0; k < n; ++k) Perm[k] = k;
    return -1;
  }
  cholmod_common cm;
  cholmod_start(&cm);
  cm.print = 0;
  cholmod_sparse S{};
  S.nrow = S.ncol = static_cast<size_t>(n);
  S.nzmax = si.size();
  S.p = sp.data();
  S.i = si.data();
  S.stype = 1;  // symmetric, upper triangle stored
  S.itype = CHOLMOD_INT;
  S.xtype = CHOLMOD_PATTERN;
  S.dtype = CHOLMOD_DOUBLE;
  S.sorted = 1;
  S.packed = 1;
  const int ok = cholmod_metis(&S, nullptr, 0, 1, Perm, &cm);
  cholmod_finish(&cm);
  return ok ? -1 : 0;
}

}  // namespace

SparseLU::SparseLU() : impl_(std::make_unique<Impl>()) {}
SparseLU::~SparseLU() = default;

// Where UMFPACK starts to pay (docs/performance.md, "Linear solvers on 3D meshes"): below a
// million estimated nonzeros in L + U KLU's refactorization (no pivot search, no frontal
// matrices) is as fast or faster — the planar cases, 0.6M on the slider crank's rod — and above
// it UMFPACK's dense frontal arithmetic wins, by 1.1x on the 3D robot-arm plate (1.2M) and 9x on
// a 3D block of 15k DOFs.
double SparseLU::auto_fill_threshold() { return 1.0e6; }

// Where the AMG solver takes over (docs/performance.md, "Linear solvers on 3D meshes"): on the
// solid block, AMG's primal step overtakes UMFPACK's near 4·10⁷ estimated nonzeros in L + U
// (37k DOFs) and its sensitivity steps near 10⁸ (74k DOFs); past it UMFPACK's factors, n^1.44,
// cost more time and memory than AMG's hierarchy at every size measured.
double SparseLU::auto_amg_fill_threshold() { return 1.0e8; }

void SparseLU::analyze(const CscPattern& pattern) {
  auto& m = *impl_;
  m.free_numeric();
  amg_.reset();
  if (solver_ == Solver::kAmg) {
    analyze_amg(pattern);
    return;
  }
  m.symbolic.reset();
  m.umf_symbolic.reset();
  m.n = pattern.n;
  m.ap = std::make_shared<const std::vector<int>>(pattern.col_ptr);
  m.ai = std::make_shared<const std::vector<int>>(pattern.row_ind);
  if (ordering_ == Ordering::kNestedDissection) {
    m.common.ordering = 3;
    m.common.user_order = nested_dissection_order;
  } else {
    m.common.ordering = ordering_ == Ordering::kColamd ? 1 : 0;
    m.common.user_order = nullptr;
  }
  klu_symbolic* sym = klu_analyze(m.n, m.Ap(), m.Ai(), &m.common);
  if (!sym)
    throw std::runtime_error("KLU symbolic analysis failed (status " +
                             std::to_string(m.common.status) + ")");
  m.symbolic.reset(sym, SymbolicDeleter{});
  ++counters_.symbolic;
  if (solver_ == Solver::kAuto && amg_suits(pattern.n)) {
    analyze_amg(pattern);
    return;
  }
  used_ = solver_ != Solver::kAuto                              ? solver_
          : estimated_factor_nonzeros() > auto_fill_threshold() ? Solver::kUmfpack
                                                                : Solver::kKlu;
  m.umfpack = used_ == Solver::kUmfpack;
  if (!m.umfpack) return;
  umfpack_dl_defaults(m.umf_control);
  m.apl = std::make_shared<const std::vector<SuiteSparse_long>>(m.ap->begin(), m.ap->end());
  m.ail = std::make_shared<const std::vector<SuiteSparse_long>>(m.ai->begin(), m.ai->end());
  m.umf_control[UMFPACK_IRSTEP] = 0;
  // The iteration matrices are structurally symmetric (blocks and their transposes): the
  // symmetric strategy (ordering of A + Aᵀ, diagonal pivots preferred down to 0.001 of the
  // column). The automatic choice needs values, which analyze() has not; without them it takes
  // the unsymmetric strategy (COLAMD), whose pivots grew the residual of a 3-D Laplacian a
  // thousandfold (1.6e-10 against 8.7e-14 relative to b, sparse_lu_test).
  m.umf_control[UMFPACK_STRATEGY] = UMFPACK_STRATEGY_SYMMETRIC;
  m.umf_control[UMFPACK_ORDERING] =
      ordering_ == Ordering::kNestedDissection ? UMFPACK_ORDERING_METIS : UMFPACK_ORDERING_AMD;
  void* us = nullptr;
  const auto st = umfpack_dl_symbolic(m.n, m.n, m.apl->data(), m.ail->data(), nullptr, &us,
                                      m.umf_control, m.umf_info);
  if (st != UMFPACK_OK || !us)
    throw std::runtime_error("UMFPACK symbolic analysis failed (status " + std::to_string(st) +
                             ")");
  m.umf_symbolic.reset(us, UmfpackSymbolicDeleter{});
  m.umfpack_workspace();
}

// The automatic choice of the AMG solver: a build with hypre, a split given, an AMG block of at
// least half the unknowns (a solid mesh, not a few nodes on a mechanism), and factors that would
// fill past auto_amg_fill_threshold() — where UMFPACK's time and memory grow as n^1.5 and more
// (docs/performance.md, "Linear solvers on 3D meshes").
bool SparseLU::amg_suits(int n) const {
  if (!amg_available() || static_cast<int>(amg_node_.size()) != n) return false;
  long block = 0;  // coordinates of the AMG block (a held node's are marked 3 + d)
  for (int i = 0; i < n; ++i)
    block += amg_node_[i] >= 0 && amg_direction_[i] >= 0 && amg_direction_[i] < 3;
  return 2 * block >= n && estimated_factor_nonzeros() > auto_amg_fill_threshold();
}

void SparseLU::analyze_amg(const CscPattern& pattern) {
  auto& m = *impl_;
  m.symbolic.reset();  // no LU of the whole matrix: the split's small block only
  m.umf_symbolic.reset();
  m.n = pattern.n;
  if (static_cast<int>(amg_node_.size()) != pattern.n)
    throw std::logic_error("SparseLU: the AMG solver needs set_amg_split() before analyze()");
  amg_ = std::make_unique<BlockAmg>();
  amg_->analyze(pattern, amg_node_, amg_direction_, amg_positions_);
  used_ = Solver::kAmg;
  ++counters_.symbolic;
}

double SparseLU::estimated_factor_nonzeros() const {
  const auto& m = *impl_;
  return m.symbolic ? m.symbolic->lnz + m.symbolic->unz : 0.0;
}

void SparseLU::share_analysis(const SparseLU& other) {
  if (other.amg_) {
    amg_ = std::make_unique<BlockAmg>();
    amg_->share_analysis(*other.amg_);
    impl_->free_numeric();
    impl_->n = other.impl_->n;
    solver_ = other.solver_;
    used_ = other.used_;
    return;
  }
  amg_.reset();
  const auto& o = *other.impl_;
  if (!o.symbolic)
    throw std::logic_error("SparseLU::share_analysis from an unanalyzed factorization");
  auto& m = *impl_;
  m.free_numeric();
  m.common = o.common;  // same options (ordering, pivot tolerance)
  m.symbolic = o.symbolic;
  m.ap = o.ap;
  m.ai = o.ai;
  m.n = o.n;
  m.umfpack = o.umfpack;
  m.umf_symbolic = o.umf_symbolic;
  m.apl = o.apl;
  m.ail = o.ail;
  std::copy(std::begin(o.umf_control), std::end(o.umf_control), m.umf_control);
  if (m.umfpack) m.umfpack_workspace();
  ordering_ = other.ordering_;
  solver_ = other.solver_;
  used_ = other.used_;
  refactor_rcond_threshold = other.refactor_rcond_threshold;
}

Status SparseLU::factor(std::span<const double> values) {
  if (amg_) {
    singular_col_ = -1;
    Status st = amg_->factor(values);
    ++counters_.full_factorizations;
    if (!st.ok()) singular_col_ = amg_->singular_unknown();
    return st;
  }
  auto& m = *impl_;
  if (!m.symbolic) throw std::logic_error("SparseLU::factor before analyze");
  auto* vals = const_cast<double*>(values.data());  // KLU's API is not const-correct
  singular_col_ = -1;
  if (m.umfpack) return factor_umfpack(values);
  if (m.numeric) {
    if (klu_refactor(m.Ap(), m.Ai(), vals, m.symbolic.get(), m.numeric, &m.common)) {
      klu_rcond(m.symbolic.get(), m.numeric, &m.common);
      if (m.common.rcond > refactor_rcond_threshold && std::isfinite(m.common.rcond)) {
        ++counters_.refactorizations;
        return Status::Ok();
      }
    }
    klu_free_numeric(&m.numeric, &m.common);
  }
  m.numeric = klu_factor(m.Ap(), m.Ai(), vals, m.symbolic.get(), &m.common);
  ++counters_.full_factorizations;
  if (!m.numeric || m.common.status == KLU_SINGULAR) {
    singular_col_ = m.common.singular_col;
    if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
    return Status::Fail(Status::Code::kSingular,
                        "singular iteration matrix (column " + std::to_string(singular_col_) + ")");
  }
  klu_rcond(m.symbolic.get(), m.numeric, &m.common);
  return Status::Ok();
}

// UMFPACK's numeric factorization (threshold partial pivoting afresh each time). A singular
// matrix is factorized once more by KLU, for the column the diagnostics name.
Status SparseLU::factor_umfpack(std::span<const double> values) {
  auto& m = *impl_;
  if (m.umf_numeric) umfpack_dl_free_numeric(&m.umf_numeric);
  const auto st =
      umfpack_dl_numeric(m.apl->data(), m.ail->data(), values.data(), m.umf_symbolic.get(),
                         &m.umf_numeric, m.umf_control, m.umf_info);
  ++counters_.full_factorizations;
  if (st == UMFPACK_OK) return Status::Ok();
  if (m.umf_numeric) umfpack_dl_free_numeric(&m.umf_numeric);
  if (st != UMFPACK_WARNING_singular_matrix)
    return Status::Fail(Status::Code::kSingular,
                        "UMFPACK numeric factorization failed (status " + std::to_string(st) +
                            (st == UMFPACK_ERROR_out_of_memory ? ": out of memory)" : ")"));
  auto* vals = const_cast<double*>(values.data());
  if (klu_numeric* kn = klu_factor(m.Ap(), m.Ai(), vals, m.symbolic.get(), &m.common)) {
    singular_col_ = m.common.status == KLU_SINGULAR ? m.common.singular_col : -1;
    klu_free_numeric(&kn, &m.common);
  } else {
    singular_col_ = m.common.singular_col;
  }
  return Status::Fail(Status::Code::kSingular,
                      "singular iteration matrix (column " + std::to_string(singular_col_) + ")");
}

void SparseLU::set_pivot_tolerance(double tol) { impl_->common.tol = tol; }

bool SparseLU::refactor(std::span<const double> values) {
  if (amg_) return factor(values).ok();
  auto& m = *impl_;
  if (m.umfpack) return m.umf_symbolic && factor(values).ok();
  if (!m.symbolic || !m.numeric) return false;
  auto* vals = const_cast<double*>(values.data());  // KLU's API is not const-correct
  if (!klu_refactor(m.Ap(), m.Ai(), vals, m.symbolic.get(), m.numeric, &m.common)) return false;
  ++counters_.refactorizations;
  return true;
}

std::optional<double> SparseLU::estimate_rcond() {
  if (amg_) return std::nullopt;  // no factors to estimate from
  auto& m = *impl_;
  if (m.umfpack) return m.umf_numeric ? std::optional<double>(rcond()) : std::nullopt;
  if (!m.numeric || !klu_rcond(m.symbolic.get(), m.numeric, &m.common)) return std::nullopt;
  return m.common.rcond;
}

std::optional<double> SparseLU::estimate_condition(std::span<const double> values) {
  if (amg_) return std::nullopt;
  auto& m = *impl_;
  auto* vals = const_cast<double*>(values.data());
  if (m.umfpack) return std::nullopt;  // UMFPACK has no condition estimator
  if (!m.numeric || !klu_condest(m.Ap(), vals, m.symbolic.get(), m.numeric, &m.common))
    return std::nullopt;
  return m.common.condest;
}

void SparseLU::solve(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!factored()) throw std::logic_error("SparseLU::solve without a factorization");
  if (amg_)
    amg_->solve(b, nrhs, false);
  else if (m.umfpack)
    m.umfpack_solve(UMFPACK_A, b, nrhs);
  else
    klu_solve(m.symbolic.get(), m.numeric, m.n, nrhs, b.data(), &m.common);
  auto& c = counters_;
  ++c.solves;
  c.rhs += nrhs;
}

void SparseLU::solve_transpose(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!factored()) throw std::logic_error("SparseLU::solve_transpose without a factorization");
  if (amg_)
    amg_->solve(b, nrhs, true);
  else if (m.umfpack)
    m.umfpack_solve(UMFPACK_At, b, nrhs);
  else
    klu_tsolve(m.symbolic.get(), m.numeric, m.n, nrhs, b.data(), &m.common);
  auto& c = counters_;
  ++c.solves;
  c.rhs += nrhs;
}

void SparseLU::reset_pivoting() { impl_->free_numeric(); }  // the AMG solver has no pivots

bool SparseLU::factored() const {
  return amg_ ? amg_->factored() : impl_->numeric || impl_->umf_numeric;
}
double SparseLU::rcond() const {
  if (amg_) return 0;  // no factors: no estimate
  const auto& m = *impl_;
  return m.umfpack ? m.umf_info[UMFPACK_RCOND] : m.common.rcond;
}

long SparseLU::factor_nonzeros() const {
  const auto& m = *impl_;
  if (m.umf_numeric) {
    SuiteSparse_long lnz = 0, unz = 0, nr = 0, nc = 0, nzud = 0;
    umfpack_dl_get_lunz(&lnz, &unz, &nr, &nc, &nzud, m.umf_numeric);
    return static_cast<long>(lnz + unz);
  }
  return m.numeric ? static_cast<long>(m.numeric->lnz) + static_cast<long>(m.numeric->unz) : 0;
}

}  // namespace lsmbs
