#include "lsmbs/linalg/sparse_lu.hpp"

#include <cholmod.h>
#include <klu.h>

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
}  // namespace

struct SparseLU::Impl {
  klu_common common{};
  std::shared_ptr<klu_symbolic> symbolic;
  klu_numeric* numeric = nullptr;
  std::shared_ptr<const std::vector<int>> ap, ai;
  int n = 0;
  Impl() { klu_defaults(&common); }
  ~Impl() {
    if (numeric) klu_free_numeric(&numeric, &common);
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

void SparseLU::analyze(const CscPattern& pattern) {
  auto& m = *impl_;
  if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
  m.symbolic.reset();
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
}

void SparseLU::share_analysis(const SparseLU& other) {
  const auto& o = *other.impl_;
  if (!o.symbolic)
    throw std::logic_error("SparseLU::share_analysis from an unanalyzed factorization");
  auto& m = *impl_;
  if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
  m.common = o.common;  // same options (ordering, pivot tolerance)
  m.symbolic = o.symbolic;
  m.ap = o.ap;
  m.ai = o.ai;
  m.n = o.n;
  ordering_ = other.ordering_;
  refactor_rcond_threshold = other.refactor_rcond_threshold;
}

Status SparseLU::factor(std::span<const double> values) {
  auto& m = *impl_;
  if (!m.symbolic) throw std::logic_error("SparseLU::factor before analyze");
  auto* vals = const_cast<double*>(values.data());  // KLU's API is not const-correct
  singular_col_ = -1;
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

void SparseLU::set_pivot_tolerance(double tol) { impl_->common.tol = tol; }

bool SparseLU::refactor(std::span<const double> values) {
  auto& m = *impl_;
  if (!m.symbolic || !m.numeric) return false;
  auto* vals = const_cast<double*>(values.data());  // KLU's API is not const-correct
  if (!klu_refactor(m.Ap(), m.Ai(), vals, m.symbolic.get(), m.numeric, &m.common)) return false;
  ++counters_.refactorizations;
  return true;
}

std::optional<double> SparseLU::estimate_rcond() {
  auto& m = *impl_;
  if (!m.numeric || !klu_rcond(m.symbolic.get(), m.numeric, &m.common)) return std::nullopt;
  return m.common.rcond;
}

std::optional<double> SparseLU::estimate_condition(std::span<const double> values) {
  auto& m = *impl_;
  auto* vals = const_cast<double*>(values.data());
  if (!m.numeric || !klu_condest(m.Ap(), vals, m.symbolic.get(), m.numeric, &m.common))
    return std::nullopt;
  return m.common.condest;
}

void SparseLU::solve(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!m.numeric) throw std::logic_error("SparseLU::solve without a factorization");
  klu_solve(m.symbolic.get(), m.numeric, m.n, nrhs, b.data(), &m.common);
  auto& c = counters_;
  ++c.solves;
  c.rhs += nrhs;
}

void SparseLU::solve_transpose(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!m.numeric) throw std::logic_error("SparseLU::solve_transpose without a factorization");
  klu_tsolve(m.symbolic.get(), m.numeric, m.n, nrhs, b.data(), &m.common);
  auto& c = counters_;
  ++c.solves;
  c.rhs += nrhs;
}

void SparseLU::reset_pivoting() {
  auto& m = *impl_;
  if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
}

bool SparseLU::factored() const { return impl_->numeric != nullptr; }
double SparseLU::rcond() const { return impl_->common.rcond; }

long SparseLU::factor_nonzeros() const {
  const auto& m = *impl_;
  return m.numeric ? static_cast<long>(m.numeric->lnz) + static_cast<long>(m.numeric->unz) : 0;
}

}  // namespace lsmbs
