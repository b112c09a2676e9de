#include "slam/disparity_noise.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace builtscene::slam {

DisparityNoise estimate_disparity_noise(const BundleAdjustmentProblem& pb, int min_readings, int min_reads_per_point) {
  std::vector<int> reads;  // stereo measurements per point, counted only when asked for
  if (min_reads_per_point > 1) {
    reads.assign(pb.points.size(), 0);
    for (const auto& m : pb.measurements)
      if (m.o.stereo() && m.point >= 0 && static_cast<std::size_t>(m.point) < reads.size())
        ++reads[static_cast<std::size_t>(m.point)];
  }
  std::vector<double> residuals;
  for (const auto& m : pb.measurements) {
    if (!m.o.stereo()) continue;
    const auto c = static_cast<std::size_t>(m.camera), p = static_cast<std::size_t>(m.point);
    if (c >= pb.cameras.size() || p >= pb.points.size()) continue;
    if (min_reads_per_point > 1 && reads[p] < min_reads_per_point) continue;
    const Eigen::Vector3d pc = pb.cameras[c].T_cw * pb.points[p];
    if (!(pc.z() > 1e-6)) continue;
    residuals.push_back(std::abs(disparity_residual(pb.K, m.o, pc)));
  }
  DisparityNoise out;
  out.readings = static_cast<int>(residuals.size());
  if (out.readings < std::max(min_readings, 1)) return out;
  const auto mid = residuals.begin() + static_cast<std::ptrdiff_t>(residuals.size() / 2);
  std::nth_element(residuals.begin(), mid, residuals.end());
  out.sigma = 1.4826 * *mid;
  return out;
}

}  // namespace builtscene::slam
