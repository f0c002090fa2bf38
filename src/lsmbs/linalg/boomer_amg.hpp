#pragma once
// BoomerAMG (hypre) set up for 3D elasticity in nodal coordinates, one V-cycle per application:
// the preconditioner of BlockAmg (linalg/block_amg.hpp) and of the elastic-block benchmark
// (bench/amg_block.cpp), which share these settings. Only in builds with hypre
// (LSMBS_HAVE_HYPRE); the caller holds hypre's lock (BlockAmg) or is alone in the process.
#include <HYPRE_parcsr_ls.h>

namespace lsmbs {

struct ElasticityAmg {
  /// The rigid-body rotations of the nodes' positions as interpolation vectors (GM variant 2,
  /// with nodal coarsening by the blocks' row-sum norm and l1 Gauss–Seidel on the coarsest
  /// level), as hypre's elasticity examples and MFEM's SetElasticityOptions do; nullptr: the
  /// plain systems AMG (3 functions per node, unknown-based coarsening).
  HYPRE_ParVector* rotations = nullptr;
  /// Aggressive coarsening (HMIS, multipass interpolation) on the first level: about half the
  /// cost of a V-cycle on meshes several elements thick, divergent on plates one or two thick.
  bool aggressive = false;
};

/// A BoomerAMG solver object with these settings (the caller destroys it).
HYPRE_Solver make_elasticity_amg(const ElasticityAmg& variant);

}  // namespace lsmbs
