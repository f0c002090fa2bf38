#include "lsmbs/linalg/block_amg.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <numeric>
#include <string>
#include <vector>

#include "lsmbs/linalg/sparse_lu.hpp"

#ifdef LSMBS_HAVE_HYPRE
#include <HYPRE.h>
#include <HYPRE_IJ_mv.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_mv.h>
#include <mpi.h>

#include "lsmbs/linalg/boomer_amg.hpp"
#endif

namespace lsmbs {

// The split of the unknowns and what follows from the pattern alone: the AMG block in rows (the
// CSR hypre takes, with each entry's position in S's values), the direct block's pattern and
// symbolic analysis, and the coupling A_cf.
struct BlockAmg::Split {
  int n = 0, nf = 0, nc = 0;
  CscPattern full;                      // S's pattern (the products)
  std::vector<int> f_global, c_global;  // local index → global unknown
  std::vector<double> rotations;        // 3 rigid-body rotations on the AMG block (3 × nf)
  double layers = 0;                    // elements across the block (Counters::layers)
  std::vector<int> ff_row_ptr, ff_col, ff_src;
  CscPattern cc;
  std::vector<int> cc_src;
  struct Coupling {
    int src, row_c, col_f;  // S(c_global[row_c], f_global[col_f]) = values[src]
  };
  struct CouplingFc {
    int src, row_f, col_c;  // S(f_global[row_f], c_global[col_c]) = values[src]
  };
  std::vector<Coupling> cf;
  std::vector<CouplingFc> fc;
  SparseLU cc_lu;  // symbolic analysis only; each factorization shares it
};

#ifdef LSMBS_HAVE_HYPRE

namespace {

std::mutex& hypre_mutex() {
  static std::mutex m;
  return m;
}

// hypre needs MPI: initialized here when nobody did (a process not started by mpirun), and then
// finalized at exit; under mpirun the run layer (runs/mpi.cpp) initialized and finalizes it.
void start_hypre() {
  static std::once_flag once;
  std::call_once(once, [] {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
      std::atexit([] {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Finalize();
      });
    }
    HYPRE_Init();
  });
}

bool mpi_finalized() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  return finalized != 0;
}

double* data_of(HYPRE_ParVector v) { return hypre_VectorData(hypre_ParVectorLocalVector(v)); }

}  // namespace

struct BlockAmg::Numeric {
  std::vector<double> values;  // S, kept for the products
  SparseLU cc_lu;
  std::vector<double> cc_values;
  HYPRE_IJMatrix A = nullptr;
  HYPRE_ParCSRMatrix pA = nullptr;
  std::vector<int> diag_src;  // hypre's storage of A_ff (diagonal first in each row) ← S's values
  HYPRE_IJVector B = nullptr, X = nullptr;
  HYPRE_ParVector pb = nullptr, px = nullptr;
  HYPRE_IJVector R[3] = {nullptr, nullptr, nullptr};  // the rotations (AMG keeps pointers)
  HYPRE_ParVector pr[3] = {nullptr, nullptr, nullptr};
  std::vector<double> row_scale, col_scale;  // equilibration of S and of Sᵀ
  double norm_s = 0, norm_st = 0;            // ‖D S‖∞, ‖D' Sᵀ‖∞
  HYPRE_Solver amg = nullptr;
  // GMRES and preconditioner workspace (sized once per analysis)
  mutable std::vector<double> V, H, cs, sn, g, y, r, w, z, zc, sz, bs, vs;
  ~Numeric() { release(); }
  void release() {
    if (!amg && !A && !B && !X && !R[0]) return;
    if (mpi_finalized()) return;  // at exit, after MPI: the process frees it
    std::lock_guard<std::mutex> lock(hypre_mutex());
    if (amg) HYPRE_BoomerAMGDestroy(amg);
    if (A) HYPRE_IJMatrixDestroy(A);
    if (B) HYPRE_IJVectorDestroy(B);
    if (X) HYPRE_IJVectorDestroy(X);
    for (auto*& r : R)
      if (r) HYPRE_IJVectorDestroy(r), r = nullptr;
    amg = nullptr, A = nullptr, B = nullptr, X = nullptr;
  }
};

bool BlockAmg::available() { return true; }

#else  // no hypre in this build

struct BlockAmg::Numeric {
  std::vector<double> values;
  SparseLU cc_lu;
  std::vector<double> cc_values;
  mutable std::vector<double> V, H, cs, sn, g, y, r, w, z, zc;
};

bool BlockAmg::available() { return false; }

#endif

namespace {

// How many elements thick the solids are (Counters::layers): per connected part of the graph of
// solid nodes (node_of, any direction: the AMG block's and the held ones, coupled through S's
// pattern), the extent of its nodes across their thinnest principal direction e (the covariance's
// smallest eigenvector) over the median of the nodes' largest neighbour spacing along e — the
// element size across; the thinnest part's figure, snapped to an integer within 1e-6 (a box's
// round-off). On nx × ny × nz bricks it is min(nx, ny, nz).
double element_layers(const CscPattern& P, std::span<const int> node_of,
                      std::span<const double> positions) {
  const int nodes = static_cast<int>(positions.size() / 3);
  std::vector<int> parent(nodes, -1);  // −1: no unknown of the node in the split
  for (int i = 0; i < P.n; ++i)
    if (node_of[i] >= 0) parent[node_of[i]] = node_of[i];
  auto find = [&](int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (int j = 0; j < P.n; ++j)
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (node_of[j] >= 0 && node_of[P.row_ind[p]] >= 0) {
        const int ra = find(node_of[j]), rb = find(node_of[P.row_ind[p]]);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }
  auto at = [&](int a) {
    return Eigen::Vector3d(positions[3 * a], positions[3 * a + 1], positions[3 * a + 2]);
  };
  // per part (by its root): the thinnest direction, the extent across it
  std::vector<int> part(nodes, -1), count(nodes, 0);
  std::vector<Eigen::Vector3d> mean(nodes, Eigen::Vector3d::Zero()), dir(nodes);
  std::vector<Eigen::Matrix3d> cov(nodes, Eigen::Matrix3d::Zero());
  for (int a = 0; a < nodes; ++a)
    if (parent[a] >= 0) part[a] = find(a), mean[part[a]] += at(a), ++count[part[a]];
  for (int r = 0; r < nodes; ++r)
    if (count[r] > 0) mean[r] /= count[r];
  for (int a = 0; a < nodes; ++a)
    if (part[a] >= 0) cov[part[a]] += (at(a) - mean[part[a]]) * (at(a) - mean[part[a]]).transpose();
  std::vector<double> lo(nodes, INFINITY), hi(nodes, -INFINITY), spacing(nodes, 0.0);
  for (int r = 0; r < nodes; ++r)
    if (count[r] > 0)
      dir[r] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov[r]).eigenvectors().col(0);
  for (int a = 0; a < nodes; ++a)
    if (part[a] >= 0) {
      const double pa = dir[part[a]].dot(at(a));
      lo[part[a]] = std::min(lo[part[a]], pa), hi[part[a]] = std::max(hi[part[a]], pa);
    }
  for (int j = 0; j < P.n; ++j)
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p) {
      const int a = node_of[j], b = node_of[P.row_ind[p]];
      if (a >= 0 && b >= 0)
        spacing[a] = std::max(spacing[a], std::abs(dir[part[a]].dot(at(b) - at(a))));
    }
  double thinnest = INFINITY;
  std::vector<double> h;
  for (int r = 0; r < nodes; ++r) {
    if (count[r] == 0) continue;
    h.clear();
    for (int a = 0; a < nodes; ++a)
      if (part[a] == r) h.push_back(spacing[a]);
    std::nth_element(h.begin(), h.begin() + h.size() / 2, h.end());
    const double median = h[h.size() / 2];
    const double layers = median > 0 ? (hi[r] - lo[r]) / median : 0.0;
    const double whole = std::round(layers);
    thinnest = std::min(thinnest,
                        std::abs(layers - whole) <= 1e-6 * std::max(1.0, whole) ? whole : layers);
  }
  return std::isfinite(thinnest) ? thinnest : 0.0;
}

}  // namespace

BlockAmg::BlockAmg() = default;
BlockAmg::~BlockAmg() = default;

void BlockAmg::analyze(const CscPattern& P, std::span<const int> node_of,
                       std::span<const int> direction_of, std::span<const double> positions) {
  if (!available())
    throw std::logic_error("BlockAmg: this build of lsmbs has no hypre (libhypre-dev)");
  const int n = P.n;
  if (static_cast<int>(node_of.size()) != n || static_cast<int>(direction_of.size()) != n)
    throw std::logic_error("BlockAmg::analyze: the split does not match the pattern");
  const int max_node_of = node_of.empty() ? -1 : *std::max_element(node_of.begin(), node_of.end());
  if (static_cast<long>(positions.size()) < 3L * (max_node_of + 1))
    throw std::logic_error("BlockAmg::analyze: a node has no position");
  auto s = std::make_shared<Split>();
  s->n = n;
  s->full = P;
  // nodes with all three coordinates marked enter the AMG block, in the order of their smallest
  // unknown, x y z consecutive (the systems AMG's interleaved functions)
  int max_node = -1;
  for (int i = 0; i < n; ++i) max_node = std::max(max_node, node_of[i]);
  std::vector<std::array<int, 3>> coords(max_node + 1, {-1, -1, -1});
  for (int i = 0; i < n; ++i)
    if (node_of[i] >= 0 && direction_of[i] >= 0 && direction_of[i] < 3)
      coords[node_of[i]][direction_of[i]] = i;
  std::vector<int> first(coords.size());
  std::vector<int> order;
  for (size_t k = 0; k < coords.size(); ++k)
    if (std::all_of(coords[k].begin(), coords[k].end(), [](int i) { return i >= 0; })) {
      order.push_back(static_cast<int>(k));
      first[k] = *std::min_element(coords[k].begin(), coords[k].end());
    }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return first[a] < first[b]; });
  std::vector<int> local(n, -1);
  std::vector<char> in_f(n, 0);
  for (int k : order)
    for (int d = 0; d < 3; ++d) {
      const int i = coords[k][d];
      in_f[i] = 1;
      local[i] = static_cast<int>(s->f_global.size());
      s->f_global.push_back(i);
    }
  // rotations about z, x and y through the origin: u = ω × X at each node of the block
  const size_t nf = s->f_global.size();
  s->rotations.assign(3 * nf, 0.0);
  for (size_t a = 0; a < order.size(); ++a) {
    const double* X = positions.data() + 3 * static_cast<size_t>(order[a]);
    double* rz = s->rotations.data() + 3 * a;
    double* rx = rz + nf;
    double* ry = rx + nf;
    rz[0] = -X[1], rz[1] = X[0];
    rx[1] = -X[2], rx[2] = X[1];
    ry[0] = X[2], ry[2] = -X[0];
  }
  for (int i = 0; i < n; ++i)
    if (!in_f[i]) {
      local[i] = static_cast<int>(s->c_global.size());
      s->c_global.push_back(i);
    }
  s->nf = static_cast<int>(s->f_global.size());
  s->nc = static_cast<int>(s->c_global.size());
  // A_ff by rows (row i of A_ff holds the entries (i, j), j in F: column j of the CSC), the
  // direct block by columns, and the coupling A_cf
  s->ff_row_ptr.assign(s->nf + 1, 0);
  s->cc.n = s->nc;
  s->cc.col_ptr.assign(1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (in_f[P.row_ind[p]] && in_f[j]) ++s->ff_row_ptr[local[P.row_ind[p]] + 1];
  std::partial_sum(s->ff_row_ptr.begin(), s->ff_row_ptr.end(), s->ff_row_ptr.begin());
  s->ff_col.resize(s->ff_row_ptr.back());
  s->ff_src.resize(s->ff_row_ptr.back());
  std::vector<int> next(s->ff_row_ptr.begin(), s->ff_row_ptr.end() - 1);
  for (int jl = 0; jl < s->nf; ++jl) {  // columns in local order: rows come out sorted
    const int j = s->f_global[jl];
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p) {
      const int i = P.row_ind[p];
      if (!in_f[i]) continue;
      const int k = next[local[i]]++;
      s->ff_col[k] = jl;
      s->ff_src[k] = p;
    }
  }
  for (int jl = 0; jl < s->nc; ++jl) {
    const int j = s->c_global[jl];
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (!in_f[P.row_ind[p]]) {
        s->cc.row_ind.push_back(local[P.row_ind[p]]);
        s->cc_src.push_back(p);
      }
    s->cc.col_ptr.push_back(static_cast<int>(s->cc.row_ind.size()));
  }
  for (int jl = 0; jl < s->nf; ++jl) {
    const int j = s->f_global[jl];
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (!in_f[P.row_ind[p]]) s->cf.push_back({p, local[P.row_ind[p]], jl});
  }
  for (int jl = 0; jl < s->nc; ++jl) {
    const int j = s->c_global[jl];
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (in_f[P.row_ind[p]]) s->fc.push_back({p, local[P.row_ind[p]], jl});
  }
  if (s->nc > 0) {
    s->cc_lu.set_solver(SparseLU::Solver::kKlu);
    s->cc_lu.analyze(s->cc);
  }
  s->layers = element_layers(P, node_of, positions);
  split_ = std::move(s);
  num_.reset();
  reset_counters();
}

void BlockAmg::share_analysis(const BlockAmg& other) {
  if (!other.split_) throw std::logic_error("BlockAmg::share_analysis from an unanalyzed solver");
  split_ = other.split_;
  options = other.options;
  num_.reset();
  reset_counters();
}

void BlockAmg::reset_counters() {
  counters_ = Counters{};
  counters_.block_unknowns = split_->nf;
  counters_.direct_unknowns = split_->nc;
  counters_.layers = split_->layers;
  fell_back_ = false;
}

bool BlockAmg::factored() const { return num_ != nullptr; }

#ifdef LSMBS_HAVE_HYPRE

// Without the rotations a thin plate (solid_arm.json, 2 bricks through 10 mm) took 149 CG
// iterations, with them 57; a chunky block 28 against 19 (docs/performance.md).
HYPRE_Solver make_elasticity_amg(const ElasticityAmg& variant) {
  HYPRE_Solver amg = nullptr;
  HYPRE_BoomerAMGCreate(&amg);
  HYPRE_BoomerAMGSetNumFunctions(amg, 3);       // x, y, z of each node (the systems approach)
  HYPRE_BoomerAMGSetStrongThreshold(amg, 0.5);  // hypre's advice for 3D problems
  HYPRE_BoomerAMGSetCoarsenType(amg, 10);       // HMIS
  HYPRE_BoomerAMGSetInterpType(amg, 6);         // extended+i
  HYPRE_BoomerAMGSetPMaxElmts(amg, 4);
  HYPRE_BoomerAMGSetAggNumLevels(amg, variant.aggressive ? 1 : 0);
  HYPRE_BoomerAMGSetRelaxType(amg, 6);  // symmetric hybrid Gauss–Seidel: a symmetric V-cycle
  HYPRE_BoomerAMGSetNumSweeps(amg, 1);
  if (variant.rotations) {
    HYPRE_BoomerAMGSetNodal(amg, 4);  // strength between nodes by the row-sum norm of blocks
    HYPRE_BoomerAMGSetNodalDiag(amg, 1);
    HYPRE_BoomerAMGSetCycleRelaxType(amg, 8, 3);  // l1 Gauss–Seidel on the coarsest level
    HYPRE_BoomerAMGSetInterpVecVariant(amg, 2);
    HYPRE_BoomerAMGSetInterpVecQMax(amg, 4);
    HYPRE_BoomerAMGSetInterpVectors(amg, 3, variant.rotations);
  }
  HYPRE_BoomerAMGSetMaxIter(amg, 1);
  HYPRE_BoomerAMGSetTol(amg, 0.0);
  HYPRE_BoomerAMGSetPrintLevel(amg, 0);
  return amg;
}

Status BlockAmg::factor(std::span<const double> values) {
  if (!split_) throw std::logic_error("BlockAmg::factor before analyze");
  const Split& s = *split_;
  start_hypre();
  singular_ = -1;
  if (!num_) {
    num_ = std::make_unique<Numeric>();
    if (s.nc > 0) num_->cc_lu.share_analysis(s.cc_lu);
    const int m = options.restart;
    num_->V.assign(static_cast<size_t>(s.n) * (m + 1), 0.0);
    num_->H.assign(static_cast<size_t>(m + 1) * m, 0.0);
    num_->cs.assign(m, 0.0), num_->sn.assign(m, 0.0);
    num_->g.assign(m + 1, 0.0), num_->y.assign(m, 0.0);
    num_->r.assign(s.n, 0.0), num_->w.assign(s.n, 0.0), num_->z.assign(s.n, 0.0);
    num_->zc.assign(s.nc, 0.0);
    num_->sz.assign(s.n, 0.0), num_->bs.assign(s.n, 0.0), num_->vs.assign(s.n, 0.0);
    num_->row_scale.assign(s.n, 1.0), num_->col_scale.assign(s.n, 1.0);
    num_->cc_values.assign(s.cc_src.size(), 0.0);
    num_->values.assign(s.full.row_ind.size(), 0.0);
    bulky_ = !fell_back_ &&
             (options.shape == Options::Shape::kBulky ||
              (options.shape == Options::Shape::kAuto && s.layers >= options.bulky_layers));
    if (s.nf > 0) create_block(*num_, s);
  }
  Numeric& nm = *num_;
  std::copy(values.begin(), values.end(), nm.values.begin());
  // equilibration: each row's and each column's largest entry
  std::fill(nm.row_scale.begin(), nm.row_scale.end(), 0.0);
  std::fill(nm.col_scale.begin(), nm.col_scale.end(), 0.0);
  for (int j = 0; j < s.n; ++j)
    for (int p = s.full.col_ptr[j]; p < s.full.col_ptr[j + 1]; ++p) {
      const double a = std::abs(values[p]);
      nm.row_scale[s.full.row_ind[p]] = std::max(nm.row_scale[s.full.row_ind[p]], a);
      nm.col_scale[j] = std::max(nm.col_scale[j], a);
    }
  for (auto* sc : {&nm.row_scale, &nm.col_scale})
    for (double& d : *sc) d = d > 0 && options.equilibrate ? 1 / d : 1.0;
  // ‖D S‖∞ and ‖D' Sᵀ‖∞ (the backward error's scale): the largest scaled row (column) sum
  std::fill(nm.sz.begin(), nm.sz.end(), 0.0);
  nm.norm_st = 0;
  for (int j = 0; j < s.n; ++j) {
    double column = 0;
    for (int p = s.full.col_ptr[j]; p < s.full.col_ptr[j + 1]; ++p) {
      const double a = std::abs(values[p]);
      nm.sz[s.full.row_ind[p]] += a * nm.row_scale[s.full.row_ind[p]];
      column += a;
    }
    nm.norm_st = std::max(nm.norm_st, column * nm.col_scale[j]);
  }
  nm.norm_s = *std::max_element(nm.sz.begin(), nm.sz.end());
  for (size_t k = 0; k < s.cc_src.size(); ++k) nm.cc_values[k] = values[s.cc_src[k]];
  if (s.nc > 0) {
    const Status st = nm.cc_lu.factor(nm.cc_values);
    if (!st.ok()) {
      singular_ = nm.cc_lu.singular_column() >= 0 ? s.c_global[nm.cc_lu.singular_column()] : -1;
      num_.reset();
      return Status::Fail(Status::Code::kSingular,
                          "singular iteration matrix (column " + std::to_string(singular_) + ")");
    }
  }
  if (s.nf > 0) {
    double* a = hypre_CSRMatrixData(hypre_ParCSRMatrixDiag(nm.pA));
    for (size_t k = 0; k < nm.diag_src.size(); ++k) a[k] = values[nm.diag_src[k]];
    setup_amg();
  }
  ++counters_.setups;
  return Status::Ok();
}

// hypre's objects of a factorization, made once (the matrix's values are then written in place):
// A_ff from its rows, the two vectors of the V-cycle, the rotations; and where each entry of
// hypre's storage of A_ff (one process: all in the "diagonal" part, the diagonal entry first in
// each row) takes its value from S.
void BlockAmg::create_block(Numeric& nm, const Split& s) {
  std::lock_guard<std::mutex> lock(hypre_mutex());
  const int nf = s.nf;
  HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, nf - 1, 0, nf - 1, &nm.A);
  HYPRE_IJMatrixSetObjectType(nm.A, HYPRE_PARCSR);
  std::vector<HYPRE_Int> sizes(nf);
  std::vector<HYPRE_BigInt> rows(nf), cols(s.ff_col.begin(), s.ff_col.end());
  for (int i = 0; i < nf; ++i) sizes[i] = s.ff_row_ptr[i + 1] - s.ff_row_ptr[i], rows[i] = i;
  std::vector<double> zeros(s.ff_col.size(), 0.0);
  HYPRE_IJMatrixSetRowSizes(nm.A, sizes.data());
  HYPRE_IJMatrixInitialize(nm.A);
  HYPRE_IJMatrixSetValues(nm.A, nf, sizes.data(), rows.data(), cols.data(), zeros.data());
  HYPRE_IJMatrixAssemble(nm.A);
  HYPRE_IJMatrixGetObject(nm.A, reinterpret_cast<void**>(&nm.pA));
  hypre_CSRMatrix* diag = hypre_ParCSRMatrixDiag(nm.pA);
  const HYPRE_Int* I = hypre_CSRMatrixI(diag);
  const HYPRE_Int* J = hypre_CSRMatrixJ(diag);
  if (hypre_CSRMatrixNumNonzeros(diag) != static_cast<HYPRE_Int>(s.ff_col.size()) ||
      hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixOffd(nm.pA)) != 0)
    throw std::logic_error("BlockAmg: hypre stored A_ff with other entries than given");
  nm.diag_src.resize(s.ff_col.size());
  for (int i = 0; i < nf; ++i)
    for (HYPRE_Int k = I[i]; k < I[i + 1]; ++k) {
      const auto b = s.ff_col.begin() + s.ff_row_ptr[i], e = s.ff_col.begin() + s.ff_row_ptr[i + 1];
      const auto it = std::lower_bound(b, e, static_cast<int>(J[k]));
      if (it == e || *it != J[k]) throw std::logic_error("BlockAmg: an entry hypre added");
      nm.diag_src[k] = s.ff_src[it - s.ff_col.begin()];
    }
  for (auto* V : {&nm.B, &nm.X}) {
    HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, nf - 1, V);
    HYPRE_IJVectorSetObjectType(*V, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(*V);
    HYPRE_IJVectorAssemble(*V);
  }
  HYPRE_IJVectorGetObject(nm.B, reinterpret_cast<void**>(&nm.pb));
  HYPRE_IJVectorGetObject(nm.X, reinterpret_cast<void**>(&nm.px));
  std::fill_n(data_of(nm.pb), nf, 0.0);
  std::fill_n(data_of(nm.px), nf, 0.0);
  for (int r = 0; r < 3; ++r) {
    HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, nf - 1, &nm.R[r]);
    HYPRE_IJVectorSetObjectType(nm.R[r], HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(nm.R[r]);
    HYPRE_IJVectorAssemble(nm.R[r]);
    HYPRE_IJVectorGetObject(nm.R[r], reinterpret_cast<void**>(&nm.pr[r]));
    std::copy_n(s.rotations.data() + static_cast<size_t>(r) * nf, nf, data_of(nm.pr[r]));
  }
}

// BoomerAMG's hierarchy for A_ff's current values, with the preconditioner of the block's shape.
void BlockAmg::setup_amg() const {
  Numeric& nm = *num_;
  std::lock_guard<std::mutex> lock(hypre_mutex());
  if (nm.amg) HYPRE_BoomerAMGDestroy(nm.amg);
  nm.amg = make_elasticity_amg({nm.pr, bulky_});
  HYPRE_BoomerAMGSetup(nm.amg, nm.pA, nm.pb, nm.px);
  counters_.bulky = bulky_;
}

namespace {

double dot(const double* a, const double* b, int n) {
  double s = 0;
  for (int i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

}  // namespace

// z = P⁻¹ v for S (or for Sᵀ, with its blocks). Thin: a symmetric block Gauss–Seidel sweep
// F, C, F — one V-cycle on the AMG block, the direct block's LU with the AMG block's update, and a
// second V-cycle on the AMG block's remaining residual, which carries the direct block's
// correction (a rigid body's motion) into the flexible body's interior. Bulky: C, F — the direct
// block's LU, then one V-cycle on the AMG block's residual after that correction.
void BlockAmg::precondition(const double* v, double* z, bool transpose) const {
  const Split& s = *split_;
  Numeric& nm = *num_;
  double* bf = s.nf > 0 ? data_of(nm.pb) : nullptr;
  double* xf = s.nf > 0 ? data_of(nm.px) : nullptr;
  auto v_cycle = [&] {  // xf = AMG(bf)
    std::lock_guard<std::mutex> lock(hypre_mutex());
    std::fill_n(xf, s.nf, 0.0);
    HYPRE_BoomerAMGSolve(nm.amg, nm.pA, nm.pb, nm.px);
  };
  std::fill_n(z, s.n, 0.0);
  if (bulky_) {
    if (s.nc > 0) {
      for (int k = 0; k < s.nc; ++k) nm.zc[k] = v[s.c_global[k]];
      auto zc = std::span<double>(nm.zc.data(), nm.zc.size());
      transpose ? nm.cc_lu.solve_transpose(zc) : nm.cc_lu.solve(zc);
      for (int k = 0; k < s.nc; ++k) z[s.c_global[k]] = nm.zc[k];
    }
    if (s.nf > 0) {
      for (int k = 0; k < s.nf; ++k) bf[k] = v[s.f_global[k]];
      if (!transpose)  // − A_fc z_c
        for (const auto& e : s.fc) bf[e.row_f] -= nm.values[e.src] * nm.zc[e.col_c];
      else  // − (Sᵀ)_fc z_c = − A_cfᵀ z_c
        for (const auto& e : s.cf) bf[e.col_f] -= nm.values[e.src] * nm.zc[e.row_c];
      v_cycle();
      for (int k = 0; k < s.nf; ++k) z[s.f_global[k]] = xf[k];
    }
    return;
  }
  if (s.nf > 0) {
    for (int k = 0; k < s.nf; ++k) bf[k] = v[s.f_global[k]];
    v_cycle();
    for (int k = 0; k < s.nf; ++k) z[s.f_global[k]] = xf[k];
  }
  if (s.nc > 0) {
    for (int k = 0; k < s.nc; ++k) nm.zc[k] = v[s.c_global[k]];
    if (!transpose)  // − A_cf z_f
      for (const auto& e : s.cf) nm.zc[e.row_c] -= nm.values[e.src] * z[s.f_global[e.col_f]];
    else  // − (Sᵀ)_cf z_f = − A_fcᵀ z_f
      for (const auto& e : s.fc) nm.zc[e.col_c] -= nm.values[e.src] * z[s.f_global[e.row_f]];
    auto zc = std::span<double>(nm.zc.data(), nm.zc.size());
    transpose ? nm.cc_lu.solve_transpose(zc) : nm.cc_lu.solve(zc);
    for (int k = 0; k < s.nc; ++k) z[s.c_global[k]] = nm.zc[k];
  }
  if (s.nf > 0 && s.nc > 0) {  // z_f += AMG(v_f − (S z)_f)
    multiply(z, nm.sz.data(), transpose);
    for (int k = 0; k < s.nf; ++k) bf[k] = v[s.f_global[k]] - nm.sz[s.f_global[k]];
    v_cycle();
    for (int k = 0; k < s.nf; ++k) z[s.f_global[k]] += xf[k];
  }
}

// y = S x or Sᵀ x (S in compressed columns).
void BlockAmg::multiply(const double* x, double* y, bool transpose) const {
  const CscPattern& P = split_->full;
  const double* v = num_->values.data();
  if (!transpose) {
    std::fill_n(y, P.n, 0.0);
    for (int j = 0; j < P.n; ++j) {
      const double xj = x[j];
      for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p) y[P.row_ind[p]] += v[p] * xj;
    }
  } else {
    for (int j = 0; j < P.n; ++j) {
      double sum = 0;
      for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p) sum += v[p] * x[P.row_ind[p]];
      y[j] = sum;
    }
  }
}

// Restarted GMRES(m), right-preconditioned (x = P⁻¹ u, the residual GMRES minimizes is the true
// one), modified Gram–Schmidt and Givens rotations, on the equilibrated system D S x = D b (D the
// reciprocal of each row's largest entry, of each column's for Sᵀ: a multiplier row scaled by k
// and a node's mass row then weigh alike in the residual's norm). Each restart starts from the true
// residual, and a solve ends only when, for the x it returns, ‖D(b − S x)‖ ≤ rtol ‖D b‖; or, once
// round-off stops the residual from falling (a restart cycle gains less than a factor 2), when it
// is at most `attainable` ‖D b‖ — on the solid arm the LU's own residual is 5e-11 ‖b‖ — or its
// normwise backward error is at most `backward_error` (b nearly cancelling against S x). Stalled
// solves end at backward errors of 1e-17 to 5e-16; the backward error is not a reason to stop
// earlier (on the solid arm, stopping at 1e-14 whenever reached doubled the gradients' distance
// from the LU's).
//
// Returns the iterations; the solution is left in the workspace w, b is not changed.
BlockAmg::Outcome BlockAmg::gmres(const double* b, bool transpose, int max_iterations) const {
  const Split& s = *split_;
  Numeric& nm = *num_;
  const int n = s.n, m = options.restart;
  const double* D = transpose ? nm.col_scale.data() : nm.row_scale.data();
  double* x = nm.w.data();  // the solution, copied into b at the end
  std::fill_n(x, n, 0.0);
  for (int i = 0; i < n; ++i) nm.bs[i] = D[i] * b[i];
  const double bnorm = std::sqrt(dot(nm.bs.data(), nm.bs.data(), n));
  Outcome o;
  if (bnorm == 0) return o;
  double binf = 0;
  for (int i = 0; i < n; ++i) binf = std::max(binf, std::abs(nm.bs[i]));
  const double anorm = transpose ? nm.norm_st : nm.norm_s;
  const double target = options.rtol * bnorm;
  auto V = [&](int j) { return nm.V.data() + static_cast<size_t>(j) * n; };
  auto H = [&](int i, int j) -> double& { return nm.H[static_cast<size_t>(j) * (m + 1) + i]; };
  // z = P⁻¹ D⁻¹ v: the preconditioner of the equilibrated matrix
  auto precondition_scaled = [&](const double* v, double* z) {
    for (int i = 0; i < n; ++i) nm.vs[i] = v[i] / D[i];
    precondition(nm.vs.data(), z, transpose);
  };
  int its = 0;
  double previous = INFINITY;
  for (;;) {
    multiply(x, nm.r.data(), transpose);
    for (int i = 0; i < n; ++i) nm.r[i] = D[i] * (b[i] - nm.r[i]);
    const double beta = std::sqrt(dot(nm.r.data(), nm.r.data(), n));
    double rinf = 0, xinf = 0;
    for (int i = 0; i < n; ++i)
      rinf = std::max(rinf, std::abs(nm.r[i])), xinf = std::max(xinf, std::abs(x[i]));
    o.rel = beta / bnorm;
    o.eta = rinf / (anorm * xinf + binf);
    // stalled: a restart cycle gained less than a factor 2 — round-off's floor, where the
    // residual is judged by what a direct solver would leave
    o.stalled = beta > 0.5 * previous;
    o.converged = o.rel <= options.rtol ||
                  (o.stalled && (o.rel <= options.attainable || o.eta <= options.backward_error));
    previous = beta;
    if (o.converged || !std::isfinite(beta) || its >= max_iterations) break;
    for (int i = 0; i < n; ++i) V(0)[i] = nm.r[i] / beta;
    std::fill(nm.g.begin(), nm.g.end(), 0.0);
    nm.g[0] = beta;
    int k = 0;
    while (k < m && its < max_iterations) {
      precondition_scaled(V(k), nm.z.data());
      double* w = V(k + 1);
      multiply(nm.z.data(), w, transpose);
      for (int l = 0; l < n; ++l) w[l] *= D[l];
      for (int i = 0; i <= k; ++i) {
        const double h = dot(w, V(i), n);
        H(i, k) = h;
        for (int l = 0; l < n; ++l) w[l] -= h * V(i)[l];
      }
      const double hn = std::sqrt(dot(w, w, n));
      H(k + 1, k) = hn;
      if (hn > 0)
        for (int l = 0; l < n; ++l) w[l] /= hn;
      for (int i = 0; i < k; ++i) {  // the earlier rotations on the new column
        const double a = H(i, k), c = H(i + 1, k);
        H(i, k) = nm.cs[i] * a + nm.sn[i] * c;
        H(i + 1, k) = -nm.sn[i] * a + nm.cs[i] * c;
      }
      const double a = H(k, k), c = H(k + 1, k), rho = std::hypot(a, c);
      nm.cs[k] = rho > 0 ? a / rho : 1.0;
      nm.sn[k] = rho > 0 ? c / rho : 0.0;
      H(k, k) = rho;
      H(k + 1, k) = 0;
      nm.g[k + 1] = -nm.sn[k] * nm.g[k];
      nm.g[k] *= nm.cs[k];
      ++k, ++its;
      if (std::abs(nm.g[k]) <= target || hn == 0) break;
      // stalled in round-off (|g| no longer halves in 10 iterations): the restart's true residual
      // and backward error decide
      if (k >= 10 && std::abs(nm.g[k]) > 0.5 * std::abs(nm.g[k - 10]) &&
          std::abs(nm.g[k]) <= 1e-8 * bnorm)
        break;
    }
    for (int i = k - 1; i >= 0; --i) {  // H y = g, upper triangular
      double sum = nm.g[i];
      for (int j = i + 1; j < k; ++j) sum -= H(i, j) * nm.y[j];
      nm.y[i] = H(i, i) != 0 ? sum / H(i, i) : 0.0;
    }
    std::fill(nm.r.begin(), nm.r.end(), 0.0);  // x += P⁻¹ D⁻¹ (V y)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < n; ++l) nm.r[l] += nm.y[j] * V(j)[l];
    precondition_scaled(nm.r.data(), nm.z.data());
    for (int l = 0; l < n; ++l) x[l] += nm.z[l];
  }
  o.iterations = its;
  return o;
}

// One solve: GMRES with the block's preconditioner; a bulky one that has not converged after
// fallback_iterations starts again from zero with the thin one, kept from then on.
void BlockAmg::solve_one(double* b, bool transpose) const {
  Outcome o = gmres(b, transpose,
                    bulky_ ? std::min(options.fallback_iterations, options.max_iterations)
                           : options.max_iterations);
  int its = o.iterations;
  if (bulky_ && !o.converged) {
    bulky_ = false, fell_back_ = true;
    ++counters_.fallbacks;
    setup_amg();
    o = gmres(b, transpose, options.max_iterations);
    its += o.iterations;
  }
  counters_.iterations += its;
  counters_.max_iterations = std::max(counters_.max_iterations, its);
  counters_.worst_residual = std::max(counters_.worst_residual, o.rel);
  if (!o.converged) {
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "the AMG-preconditioned GMRES stopped after %d iterations at a relative "
                  "residual of %.3g and a backward error of %.3g (tolerance %.3g, or a backward "
                  "error of %.3g, or %.3g where round-off stalls the residual)",
                  its, o.rel, o.eta, options.rtol, options.backward_error, options.attainable);
    throw LinearSolveError(msg);
  }
  std::copy_n(num_->w.data(), split_->n, b);
}

void BlockAmg::solve(std::span<double> b, int nrhs, bool transpose) const {
  if (!num_) throw std::logic_error("BlockAmg::solve without a factorization");
  const int n = split_->n;
  for (int j = 0; j < nrhs; ++j) {
    solve_one(b.data() + static_cast<size_t>(j) * n, transpose);
    ++counters_.solves;
  }
}

#else

Status BlockAmg::factor(std::span<const double>) {
  throw std::logic_error("BlockAmg: this build of lsmbs has no hypre (libhypre-dev)");
}
void BlockAmg::solve(std::span<double>, int, bool) const {
  throw std::logic_error("BlockAmg: this build of lsmbs has no hypre (libhypre-dev)");
}

#endif

}  // namespace lsmbs
