#include "ogm/grid_resampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace builtscene {

Pose2D planar_part(const SE3& T) {
  const Eigen::Matrix3d R = T.rotation_matrix();
  return {T.translation().x(), T.translation().y(), std::atan2(R(1, 0), R(0, 0))};
}

namespace {

Eigen::Vector2d apply(const Pose2D& T, const Eigen::Vector2d& p) {
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  return {c * p.x() - s * p.y() + T.x, s * p.x() + c * p.y() + T.y};
}

Pose2D inverse(const Pose2D& T) {
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  return {-(c * T.x + s * T.y), s * T.x - c * T.y, -T.theta};
}

}  // namespace

OccupancyGrid resample_grid(const OccupancyGrid& src, const Pose2D& T_dst_src, const OccupancyGrid& lattice) {
  if (src.width() == 0 || src.height() == 0) return OccupancyGrid(0, 0, lattice.resolution(), lattice.origin());
  // The moved source's bounding box, snapped outwards to the lattice.
  const Eigen::Vector2d o = src.origin();
  const double w = src.width() * src.resolution(), h = src.height() * src.resolution();
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector2d& corner : {o, Eigen::Vector2d(o.x() + w, o.y()), Eigen::Vector2d(o.x(), o.y() + h),
                                       Eigen::Vector2d(o.x() + w, o.y() + h)}) {
    const Eigen::Vector2d q = apply(T_dst_src, corner);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double r = lattice.resolution();
  const Eigen::Vector2d first(lattice.origin().x() + std::floor((lo.x() - lattice.origin().x()) / r) * r,
                              lattice.origin().y() + std::floor((lo.y() - lattice.origin().y()) / r) * r);
  const int cols = static_cast<int>(std::ceil((hi.x() - first.x()) / r));
  const int rows = static_cast<int>(std::ceil((hi.y() - first.y()) / r));
  OccupancyGrid out(std::max(cols, 1), std::max(rows, 1), r, first);
  const Pose2D T_src_dst = inverse(T_dst_src);
  for (int row = 0; row < out.height(); ++row)
    for (int col = 0; col < out.width(); ++col)
      out.at({col, row}) = src.value_at(apply(T_src_dst, out.center_of({col, row})));
  return out;
}

}  // namespace builtscene
