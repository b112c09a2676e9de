#include "nav/region_cloud_update.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "ogm/trajectory_mapping.hpp"

namespace builtscene {

CloudUpdateResult update_cloud_in_region(const TumDataset& ds, const std::vector<PosedFrame>& frames,
                                         const std::optional<Region>& region, const PointCloud* existing,
                                         const CloudBuildOptions& o) {
  CloudUpdateResult r;
  auto inside = [&](const Eigen::Vector3f& p) { return !region || region->contains({p.x(), p.y()}); };
  PointCloud fresh;
  const PinholeCamera& cam = ds.settings().camera;
  const int stride = std::max(1, o.pixel_stride);
  std::optional<SE3> last_used;
  Progress progress("cloud", frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    progress.update(k + 1);
    const auto& f = frames[k];
    const Eigen::Vector3d c = f.T_gc.translation();
    if (region && !region->contains({c.x(), c.y()})) {
      ++r.frames_outside_region;
      continue;
    }
    // Thin to keyframes by motion: nearby frames add only duplicates.
    if (last_used && !moved_enough(*last_used, f.T_gc, o.keyframe_translation, o.keyframe_rotation_deg)) continue;
    cv::Mat rgb, depth;
    try {
      auto t = r.timer.scope("load");
      rgb = ds.load_rgb(f.frame);
      depth = ds.load_depth(f.frame);
    } catch (const InputError& e) {
      ++r.frames_skipped;
      spdlog::warn("skipping frame {}: {}", f.frame, e.what());
      continue;
    }
    if (rgb.size() != depth.size()) cv::resize(rgb, rgb, depth.size());
    last_used = f.T_gc;
    ++r.frames_integrated;
    auto t = r.timer.scope("backproject");
    const Eigen::Matrix3f R = f.T_gc.rotation_matrix().cast<float>();
    const Eigen::Vector3f tr = f.T_gc.translation().cast<float>();
    for (int v = 0; v < depth.rows; v += stride)
      for (int u = 0; u < depth.cols; u += stride) {
        const float z = depth.at<float>(v, u);
        if (!(z > 0.0f) || z > o.max_depth) continue;
        const Eigen::Vector3f p = R * cam.unproject({u, v}, z).cast<float>() + tr;
        if (!inside(p)) continue;
        const cv::Vec3b bgr = rgb.at<cv::Vec3b>(v, u);
        fresh.push_back({p, {bgr[2], bgr[1], bgr[0]}});
      }
  }
  {
    auto t = r.timer.scope("voxel");
    fresh = voxel_downsample(fresh, o.voxel);
  }
  r.points_added = fresh.size();
  if (existing) {
    for (const auto& p : *existing) {
      if (inside(p.position)) {
        ++r.points_removed;
      } else {
        r.cloud.push_back(p);
      }
    }
    r.points_kept = r.cloud.size();
  }
  r.cloud.insert(r.cloud.end(), fresh.begin(), fresh.end());
  return r;
}

}  // namespace builtscene
