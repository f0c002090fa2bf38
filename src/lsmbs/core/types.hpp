#pragma once
// Eigen aliases used across lsmbs. Local (element / joint) blocks use fixed-maximum-size
// matrices so that per-step evaluation never touches the heap.
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <cstdint>

namespace lsmbs {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// Largest number of DOFs one local contribution (element, joint, force) may touch: a joint
/// between two spatial bodies in natural coordinates touches 2 × 12 (mbs/spatial.hpp).
inline constexpr int kMaxLocalDofs = 24;
/// Largest number of constraint equations in one local constraint block.
inline constexpr int kMaxLocalEqs = 3;

using LocalVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxLocalDofs, 1>;
using LocalMat =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLocalDofs, kMaxLocalDofs>;
using LocalEqVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxLocalEqs, 1>;
using LocalJac =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxLocalEqs, kMaxLocalDofs>;

/// Rotation matrix R(θ) and its derivative R'(θ) = dR/dθ.
inline Mat2 rotation(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat2 r;
  r << c, -s, s, c;
  return r;
}
inline Mat2 rotation_derivative(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat2 r;
  r << -s, -c, c, -s;
  return r;
}

}  // namespace lsmbs
