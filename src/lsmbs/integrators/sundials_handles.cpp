#include "lsmbs/integrators/sundials_handles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lsmbs/linalg/sparse_lu.hpp"

namespace lsmbs::sun {

namespace {

struct SparseLuContent {
  SparseLU lu;
  CscPattern pattern;  // the analyzed one
  bool analyzed = false, fresh = true, fresh_each_setup = false;
  sunindextype last_flag = SUNLS_SUCCESS;
};

SparseLuContent& content(SUNLinearSolver S) { return *static_cast<SparseLuContent*>(S->content); }

int set_flag(SparseLuContent& c, int flag) {
  c.last_flag = flag;
  return flag;
}

// Whether the CSC arrays of A are those of `p`.
bool same_pattern(const CscPattern& p, sunindextype n, const sunindextype* cp,
                  const sunindextype* ri) {
  if (p.n != n || p.nnz() != cp[n]) return false;
  return std::equal(p.col_ptr.begin(), p.col_ptr.end(), cp) &&
         std::equal(p.row_ind.begin(), p.row_ind.end(), ri);
}

int setup(SUNLinearSolver S, SUNMatrix A) {
  auto& c = content(S);
  if (SUNMatGetID(A) != SUNMATRIX_SPARSE || SM_SPARSETYPE_S(A) != CSC_MAT ||
      SM_ROWS_S(A) != SM_COLUMNS_S(A))
    return set_flag(c, SUNLS_ILL_INPUT);
  const sunindextype n = SM_COLUMNS_S(A), *cp = SM_INDEXPTRS_S(A), *ri = SM_INDEXVALS_S(A);
  const std::span<const double> values(SM_DATA_S(A), static_cast<size_t>(cp[n]));
  if (!c.analyzed || !same_pattern(c.pattern, n, cp, ri)) {
    c.pattern.n = static_cast<int>(n);
    c.pattern.col_ptr.assign(cp, cp + n + 1);
    c.pattern.row_ind.assign(ri, ri + cp[n]);
    c.lu.analyze(c.pattern);
    c.analyzed = true;
    c.fresh = true;
  }
  if (c.fresh || c.fresh_each_setup) {
    c.lu.reset_pivoting();
    if (!c.lu.factor(values).ok()) return set_flag(c, SUNLS_PACKAGE_FAIL_UNREC);
    c.fresh = false;
    return set_flag(c, SUNLS_SUCCESS);
  }
  if (!c.lu.refactor(values)) return set_flag(c, SUNLS_PACKAGE_FAIL_REC);
  const auto rcond = c.lu.estimate_rcond();
  if (!rcond) return set_flag(c, SUNLS_PACKAGE_FAIL_REC);
  const double eps23 = std::pow(std::numeric_limits<double>::epsilon(), 2.0 / 3.0);
  if (*rcond < eps23) {  // the cheap estimate says ill-conditioned: ask the accurate one
    const auto cond = c.lu.estimate_condition(values);
    if (!cond) return set_flag(c, SUNLS_PACKAGE_FAIL_REC);
    if (*cond > 1.0 / eps23) {
      c.lu.reset_pivoting();
      if (!c.lu.factor(values).ok()) return set_flag(c, SUNLS_PACKAGE_FAIL_UNREC);
    }
  }
  return set_flag(c, SUNLS_SUCCESS);
}

int solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, realtype /*tol*/) {
  auto& c = content(S);
  if (!c.lu.factored() || SM_COLUMNS_S(A) != c.pattern.n)
    return set_flag(c, SUNLS_PACKAGE_FAIL_UNREC);
  N_VScale(1.0, b, x);
  c.lu.solve(std::span<double>(N_VGetArrayPointer(x), static_cast<size_t>(c.pattern.n)));
  return set_flag(c, SUNLS_SUCCESS);
}

int free_solver(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  delete static_cast<SparseLuContent*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

LinearSolver new_sparse_lu_solver(const Context& ctx, double pivot_tolerance,
                                  bool fresh_each_setup) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx.get());
  if (!S) return nullptr;
  auto* c = new SparseLuContent;
  c->lu.set_ordering(SparseLU::Ordering::kColamd);
  c->lu.set_solver(SparseLU::Solver::kKlu);  // SUNLinSol_KLU's policy, step by step
  c->lu.set_pivot_tolerance(pivot_tolerance);
  c->fresh_each_setup = fresh_each_setup;
  S->content = c;
  S->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  S->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  S->ops->initialize = [](SUNLinearSolver s) {
    content(s).fresh = true;  // the next setup factorizes with fresh pivoting
    return set_flag(content(s), SUNLS_SUCCESS);
  };
  S->ops->setup = setup;
  S->ops->solve = solve;
  S->ops->lastflag = [](SUNLinearSolver s) { return content(s).last_flag; };
  S->ops->free = free_solver;
  return LinearSolver(S);
}

}  // namespace lsmbs::sun
