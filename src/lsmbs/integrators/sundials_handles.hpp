#pragma once
// RAII owners of the SUNDIALS objects of an IDAS run (used by integrators/idas_*.cpp only): the
// context, serial N_Vectors and arrays of them, the sparse SUNMatrix, the linear solver, and the
// IDAS memory. Each frees its object with the matching SUNDIALS call; an object that failed to be
// created is null and frees nothing. The linear solver is the project's SparseLU behind the
// SUNLinearSolver interface (new_sparse_lu_solver).
#include <idas/idas.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <memory>
#include <type_traits>
#include <utility>

#include "lsmbs/core/types.hpp"

namespace lsmbs::sun {

/// SUNContext: create() before any other object, destroyed after all of them.
class Context {
 public:
  Context() = default;
  ~Context() {
    if (ctx_) SUNContext_Free(&ctx_);
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  bool create() { return SUNContext_Create(nullptr, &ctx_) == 0; }
  SUNContext get() const { return ctx_; }

 private:
  SUNContext ctx_ = nullptr;
};

struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
inline Vector new_vector(sunindextype n, const Context& ctx) {
  return Vector(N_VNew_Serial(n, ctx.get()));
}

/// Eigen view of a serial N_Vector.
inline Eigen::Map<Vec> map(N_Vector v) {
  return {N_VGetArrayPointer(v), static_cast<Eigen::Index>(N_VGetLength(v))};
}

/// An array of n clones of a vector (N_VCloneVectorArray), as IDAS's sensitivity functions take.
class VectorArray {
 public:
  VectorArray() = default;
  VectorArray(int n, N_Vector like) : v_(N_VCloneVectorArray(n, like)), n_(n) {}
  ~VectorArray() {
    if (v_) N_VDestroyVectorArray(v_, n_);
  }
  VectorArray(VectorArray&& o) noexcept : v_(std::exchange(o.v_, nullptr)), n_(o.n_) {}
  VectorArray& operator=(VectorArray&& o) noexcept {
    std::swap(v_, o.v_);
    std::swap(n_, o.n_);
    return *this;
  }
  N_Vector* get() const { return v_; }
  N_Vector operator[](int i) const { return v_[i]; }
  int size() const { return n_; }

 private:
  N_Vector* v_ = nullptr;
  int n_ = 0;
};

struct MatrixDeleter {
  void operator()(SUNMatrix A) const { SUNMatDestroy(A); }
};
using Matrix = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;

struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
using LinearSolver = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;

/// A direct, matrix-based SUNLinearSolver that factorizes the CSC SUNMatrix of IDAS with
/// SparseLU, following SUNLinSol_KLU's policy step by step so that the runs are the same to the
/// bit: COLAMD ordering and the given pivot tolerance; one symbolic analysis (the pattern is
/// fixed; a changed pattern is analyzed again); a factorization with fresh pivoting after
/// initialize (IDAS calls it at the start and after each IDAReInit), otherwise a refactorization
/// with the last pivot sequence, redone with fresh pivoting when KLU's cheap rcond is below
/// ε^(2/3) and its condest confirms a condition number above ε^(−2/3). A failed refactorization
/// or estimate is recoverable (IDAS retries with a smaller step), a failed fresh factorization is
/// not. `fresh_each_setup`: every setup factorizes with fresh pivoting (history-free solves).
LinearSolver new_sparse_lu_solver(const Context& ctx, double pivot_tolerance,
                                  bool fresh_each_setup);

/// Copies a compressed CSC matrix into a SUNDIALS sparse matrix (CSC_MAT), growing its storage
/// when needed.
inline void copy_to(const SpMat& A, SUNMatrix J) {
  if (SM_NNZ_S(J) < A.nonZeros()) SUNSparseMatrix_Reallocate(J, A.nonZeros());
  sunindextype* cp = SM_INDEXPTRS_S(J);
  sunindextype* ri = SM_INDEXVALS_S(J);
  realtype* d = SM_DATA_S(J);
  for (int c = 0; c <= A.cols(); ++c) cp[c] = A.outerIndexPtr()[c];
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k)
    ri[k] = A.innerIndexPtr()[k], d[k] = A.valuePtr()[k];
}

/// The IDAS memory (IDACreate / IDAFree). IDAFree also frees the memories of the backward
/// problems of an adjoint run; their vectors and solvers must outlive it.
class IdaMemory {
 public:
  IdaMemory() = default;
  ~IdaMemory() {
    if (mem_) IDAFree(&mem_);
  }
  IdaMemory(const IdaMemory&) = delete;
  IdaMemory& operator=(const IdaMemory&) = delete;
  bool create(const Context& ctx) { return (mem_ = IDACreate(ctx.get())) != nullptr; }
  void* get() const { return mem_; }

 private:
  void* mem_ = nullptr;
};

}  // namespace lsmbs::sun
