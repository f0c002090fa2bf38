#include "lsmbs/mbs/linear_solver_setup.hpp"

namespace lsmbs {

void amg_split(const Model& m, std::vector<int>& node_of, std::vector<int>& direction_of,
               std::vector<double>& positions) {
  const int n = m.n(), nq = m.nq();
  node_of.assign(n, -1);
  direction_of.assign(n, -1);
  positions.clear();
  // coordinates a constraint row reaches (Φ_q, and through it the penalty ζ Φ_qᵀΦ_q of eq. 7)
  std::vector<char> held(n, 0);
  const CscPattern& P = m.pattern();
  for (int j = 0; j < nq; ++j)
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (P.row_ind[p] >= nq) held[j] = 1;
  int next = 0;
  for (const auto& body : m.solid_bodies())
    for (int k = 0; k < body->mesh.num_nodes(); ++k, ++next) {
      const int d0 = body->node_dof(k);
      for (int d = 0; d < 3; ++d) positions.push_back(body->mesh.nodes[k][d]);
      // a held node goes to the direct block (3 + d) and counts in the solid's shape
      const bool held_node = held[d0] || held[d0 + 1] || held[d0 + 2];
      for (int d = 0; d < 3; ++d) {
        node_of[d0 + d] = next;
        direction_of[d0 + d] = held_node ? 3 + d : d;
      }
    }
}

void analyze_model_matrix(SparseLU& lu, const Model& m, SparseLU::Solver solver,
                          SparseLU::Ordering ordering) {
  lu.set_ordering(ordering);
  lu.set_solver(solver);
  if (solver == SparseLU::Solver::kAmg ||
      (solver == SparseLU::Solver::kAuto && SparseLU::amg_available() &&
       !m.solid_bodies().empty())) {
    std::vector<int> node_of, direction_of;
    std::vector<double> positions;
    amg_split(m, node_of, direction_of, positions);
    lu.set_amg_split(std::move(node_of), std::move(direction_of), std::move(positions));
  }
  lu.analyze(m.pattern());
}

}  // namespace lsmbs
