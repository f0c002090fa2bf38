#include "lsmbs/linalg/sparsity.hpp"

#include <algorithm>
#include <stdexcept>

namespace lsmbs {

int CscPattern::find(int row, int col) const {
  const auto b = row_ind.begin() + col_ptr[col], e = row_ind.begin() + col_ptr[col + 1];
  const auto it = std::lower_bound(b, e, row);
  return (it != e && *it == row) ? static_cast<int>(it - row_ind.begin()) : -1;
}

int SparsityBuilder::add_block(std::span<const int> rows, std::span<const int> cols) {
  rows_.emplace_back(rows.begin(), rows.end());
  cols_.emplace_back(cols.begin(), cols.end());
  return static_cast<int>(rows_.size()) - 1;
}

void SparsityBuilder::add_diagonal() { diagonal_ = true; }

SparsityBuilder::Result SparsityBuilder::finalize() const {
  std::vector<std::vector<int>> col_rows(n_);
  for (size_t b = 0; b < rows_.size(); ++b)
    for (int c : cols_[b]) {
      if (c < 0) continue;
      for (int r : rows_[b])
        if (r >= 0) col_rows[c].push_back(r);
    }
  if (diagonal_)
    for (int i = 0; i < n_; ++i) col_rows[i].push_back(i);

  Result res;
  CscPattern& p = res.pattern;
  p.n = n_;
  p.col_ptr.assign(n_ + 1, 0);
  for (int c = 0; c < n_; ++c) {
    auto& v = col_rows[c];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    p.col_ptr[c + 1] = p.col_ptr[c] + static_cast<int>(v.size());
  }
  p.row_ind.reserve(p.col_ptr[n_]);
  for (int c = 0; c < n_; ++c)
    p.row_ind.insert(p.row_ind.end(), col_rows[c].begin(), col_rows[c].end());

  for (size_t b = 0; b < rows_.size(); ++b) {
    res.slot_offset.push_back(static_cast<int>(res.slots.size()));
    res.block_rows.push_back(static_cast<int>(rows_[b].size()));
    res.block_cols.push_back(static_cast<int>(cols_[b].size()));
    for (int c : cols_[b])
      for (int r : rows_[b]) res.slots.push_back((r < 0 || c < 0) ? -1 : p.find(r, c));
  }
  return res;
}

void BlockAssembler::build_diagonal_index() {
  const auto& p = r_.pattern;
  diag_slot_.resize(p.n);
  for (int i = 0; i < p.n; ++i) diag_slot_[i] = p.find(i, i);
}

void BlockAssembler::add_diagonal(std::span<double> values, int i, double v) const {
  if (diag_slot_.empty() || diag_slot_[i] < 0)
    throw std::logic_error("BlockAssembler::add_diagonal: diagonal not in pattern");
  values[diag_slot_[i]] += v;
}

void BlockAssembler::multiply(std::span<const double> values, const Mat& X, Mat& Y) const {
  const auto& p = r_.pattern;
  Y.setZero(p.n, X.cols());
  for (Eigen::Index k = 0; k < X.cols(); ++k)
    for (int c = 0; c < p.n; ++c) {
      const double xc = X(c, k);
      if (xc == 0) continue;
      for (int i = p.col_ptr[c]; i < p.col_ptr[c + 1]; ++i) Y(p.row_ind[i], k) += values[i] * xc;
    }
}

void BlockAssembler::multiply_transpose(std::span<const double> values, const Mat& X,
                                        Mat& Y) const {
  const auto& p = r_.pattern;
  Y.setZero(p.n, X.cols());
  for (Eigen::Index k = 0; k < X.cols(); ++k)
    for (int c = 0; c < p.n; ++c) {
      double y = 0;
      for (int i = p.col_ptr[c]; i < p.col_ptr[c + 1]; ++i) y += values[i] * X(p.row_ind[i], k);
      Y(c, k) = y;
    }
}

SpMat BlockAssembler::to_sparse(std::span<const double> values) const {
  const auto& p = r_.pattern;
  SpMat m(p.n, p.n);
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(p.nnz());
  for (int c = 0; c < p.n; ++c)
    for (int k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k)
      t.emplace_back(p.row_ind[k], c, values[k]);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace lsmbs
