#include "lsmbs/linalg/sparse_lu.hpp"

#include <cholmod.h>
#include <klu.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace lsmbs {

struct SparseLU::Impl {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  std::vector<int> ap, ai;
  int n = 0;
  Impl() { klu_defaults(&common); }
  ~Impl() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
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
      if (i < j) cols[j].push_back(i);
      else if (i > j) cols[i].push_back(j);
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
  if (m.symbolic) klu_free_symbolic(&m.symbolic, &m.common);
  m.n = pattern.n;
  m.ap = pattern.col_ptr;
  m.ai = pattern.row_ind;
  if (ordering_ == Ordering::kNestedDissection) {
    m.common.ordering = 3;
    m.common.user_order = nested_dissection_order;
  } else {
    m.common.ordering = 0;
    m.common.user_order = nullptr;
  }
  m.symbolic = klu_analyze(m.n, m.ap.data(), m.ai.data(), &m.common);
  if (!m.symbolic) throw std::runtime_error("KLU symbolic analysis failed (status " +
                                            std::to_string(m.common.status) + ")");
  ++counters_.symbolic;
}

Status SparseLU::factor(std::span<const double> values) {
  auto& m = *impl_;
  if (!m.symbolic) throw std::logic_error("SparseLU::factor before analyze");
  auto* vals = const_cast<double*>(values.data());  // KLU's API is not const-correct
  singular_col_ = -1;
  if (m.numeric) {
    if (klu_refactor(m.ap.data(), m.ai.data(), vals, m.symbolic, m.numeric, &m.common)) {
      klu_rcond(m.symbolic, m.numeric, &m.common);
      if (m.common.rcond > refactor_rcond_threshold && std::isfinite(m.common.rcond)) {
        ++counters_.refactorizations;
        return Status::Ok();
      }
    }
    klu_free_numeric(&m.numeric, &m.common);
  }
  m.numeric = klu_factor(m.ap.data(), m.ai.data(), vals, m.symbolic, &m.common);
  ++counters_.full_factorizations;
  if (!m.numeric || m.common.status == KLU_SINGULAR) {
    singular_col_ = m.common.singular_col;
    if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
    return Status::Fail(Status::Code::kSingular,
                        "singular iteration matrix (column " + std::to_string(singular_col_) + ")");
  }
  klu_rcond(m.symbolic, m.numeric, &m.common);
  return Status::Ok();
}

void SparseLU::solve(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!m.numeric) throw std::logic_error("SparseLU::solve without a factorization");
  klu_solve(m.symbolic, m.numeric, m.n, nrhs, b.data(), &m.common);
  auto& c = counters_;
  ++c.solves;
  c.rhs += nrhs;
}

void SparseLU::solve_transpose(std::span<double> b, int nrhs) const {
  auto& m = *impl_;
  if (!m.numeric) throw std::logic_error("SparseLU::solve_transpose without a factorization");
  klu_tsolve(m.symbolic, m.numeric, m.n, nrhs, b.data(), &m.common);
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
