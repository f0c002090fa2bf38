#pragma once
// Fixed sparsity pattern with index maps. Every contributor (element, joint, force) registers
// the dense local blocks it will write once, when the model is built; the pattern is then
// frozen in compressed-column (CSC) form and each block keeps the positions of its entries in
// the value array. Assembly is a scatter through these maps: no triplets, no search, no
// allocation per Newton iteration (DESIGN.md).
#include <span>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

struct CscPattern {
  int n = 0;                 ///< square dimension
  std::vector<int> col_ptr;  ///< size n + 1
  std::vector<int> row_ind;  ///< size nnz, sorted within each column
  int nnz() const { return static_cast<int>(row_ind.size()); }
  /// Position of entry (row, col) in the value array, or -1 when structurally zero.
  int find(int row, int col) const;
};

class SparsityBuilder {
 public:
  explicit SparsityBuilder(int n) : n_(n) {}
  /// Registers the dense block rows × cols; returns its id. Indices < 0 are skipped (ground).
  int add_block(std::span<const int> rows, std::span<const int> cols);
  /// Adds the whole diagonal (KLU needs structural diagonal entries for pivoting freedom).
  void add_diagonal();
  int n() const { return n_; }

  struct Result {
    CscPattern pattern;
    std::vector<int> slot_offset;  ///< block b's slots are slots[slot_offset[b] .. +rows*cols]
    std::vector<int> slots;        ///< column-major local order; -1 for skipped indices
    std::vector<int> block_rows, block_cols;
  };
  Result finalize() const;

 private:
  int n_;
  std::vector<std::vector<int>> rows_, cols_;
  bool diagonal_ = false;
};

/// Value array over a CscPattern with block scatter.
class BlockAssembler {
 public:
  BlockAssembler() = default;
  explicit BlockAssembler(SparsityBuilder::Result r) : r_(std::move(r)) { build_diagonal_index(); }
  const CscPattern& pattern() const { return r_.pattern; }
  int num_blocks() const { return static_cast<int>(r_.slot_offset.size()); }

  /// values[slot(b, i, j)] += scale * local(i, j) for every registered entry of block b.
  template <class Derived>
  void add(std::span<double> values, int block, const Eigen::MatrixBase<Derived>& local,
           double scale = 1.0) const {
    const int nr = r_.block_rows[block], nc = r_.block_cols[block];
    const int* s = r_.slots.data() + r_.slot_offset[block];
    for (int j = 0; j < nc; ++j)
      for (int i = 0; i < nr; ++i) {
        const int k = s[i + nr * j];
        if (k >= 0) values[k] += scale * local(i, j);
      }
  }
  /// Adds to the diagonal entry of row i (must be in the pattern).
  void add_diagonal(std::span<double> values, int i, double v) const;
  /// Y = A X for a block of columns, A given by values on the pattern.
  void multiply(std::span<const double> values, const Mat& X, Mat& Y) const;
  /// Y = Aᵀ X (the discrete adjoint's refinement of its transposed solves).
  void multiply_transpose(std::span<const double> values, const Mat& X, Mat& Y) const;
  /// Converts values to an Eigen sparse matrix (tests, small models, output).
  SpMat to_sparse(std::span<const double> values) const;

 private:
  void build_diagonal_index();
  SparsityBuilder::Result r_;
  std::vector<int> diag_slot_;
};

}  // namespace lsmbs
