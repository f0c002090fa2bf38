#include "lsmbs/linalg/sparse_lu.hpp"

#include <klu.h>

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

SparseLU::SparseLU() : impl_(std::make_unique<Impl>()) {}
SparseLU::~SparseLU() = default;

void SparseLU::analyze(const CscPattern& pattern) {
  auto& m = *impl_;
  if (m.numeric) klu_free_numeric(&m.numeric, &m.common);
  if (m.symbolic) klu_free_symbolic(&m.symbolic, &m.common);
  m.n = pattern.n;
  m.ap = pattern.col_ptr;
  m.ai = pattern.row_ind;
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

}  // namespace lsmbs
