#pragma once
// A feature frame (geometry/level_set_3d.hpp) from its origin, its w axis and a u direction
// (made unit; v = w × u completes the right-handed frame).
#include <Eigen/Geometry>

#include "lsmbs/geometry/level_set_3d.hpp"

namespace lsmbs::test {

inline Frame3 frame(const Vec3& origin, const Vec3& w, const Vec3& u) {
  Frame3 f;
  f.origin = origin;
  f.axes.col(0) = u.normalized();
  f.axes.col(2) = w.normalized();
  f.axes.col(1) = f.axes.col(2).cross(f.axes.col(0));
  return f;
}

}  // namespace lsmbs::test
