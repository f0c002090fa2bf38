#pragma once
// How a model's Newton matrices (Model::pattern(), eq. 13) are solved: the one place that sets up
// a SparseLU for them, so that every user — the integrator, the static solver, the sensitivity
// methods, the benchmarks — gets the same solver with the same split.
#include <vector>

#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

/// The AMG solver's split (BlockAmg::analyze): the three coordinates of every solid-body node that
/// no constraint row touches go to the AMG block (node_of: a number of the node's own,
/// direction_of: 0, 1, 2); every other unknown — multipliers, rigid bodies, planar bodies, nodes
/// tied by rigid connections or joints — to the direct block (−1; a tied node's coordinates keep
/// their node number with direction 3 + d, to count in the solid's shape). `positions`: each
/// node's position at t = 0.
void amg_split(const Model& m, std::vector<int>& node_of, std::vector<int>& direction_of,
               std::vector<double>& positions);

/// Sets the ordering and solver of `lu` (with the AMG split when the solver is kAmg) and analyzes
/// the model's pattern.
void analyze_model_matrix(SparseLU& lu, const Model& m, SparseLU::Solver solver,
                          SparseLU::Ordering ordering);

}  // namespace lsmbs
