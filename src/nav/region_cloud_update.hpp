#pragma once
// Location-aware point-cloud update (the source's section 2.6.3): a coloured cloud is built
// from posed RGB-D frames in the ground frame; given a region on the map, only frames whose 2D
// pose lies inside it are integrated, their points are clipped to the region, and the points
// of an existing cloud inside the region are replaced by them. Everything outside the region
// is kept as it was.
#include <optional>
#include <vector>

#include "core/stage_timer.hpp"
#include "io/point_cloud.hpp"
#include "io/tum_dataset.hpp"
#include "nav/region.hpp"
#include "ogm/ground_frame.hpp"

namespace builtscene {

struct CloudBuildOptions {
  double voxel = 0.02;        // metres
  int pixel_stride = 2;
  double max_depth = 4.0;     // metres: Kinect depth beyond this is too noisy for a cloud
  double keyframe_translation = 0.10;
  double keyframe_rotation_deg = 10.0;
};

struct PosedFrame {
  std::size_t frame = 0;  // dataset index
  SE3 T_gc;               // camera in the ground frame
};

struct CloudUpdateResult {
  PointCloud cloud;
  std::size_t frames_integrated = 0, frames_outside_region = 0, frames_skipped = 0;
  std::size_t points_kept = 0, points_removed = 0, points_added = 0;
  StageTimer timer;
};

CloudUpdateResult update_cloud_in_region(const TumDataset& dataset, const std::vector<PosedFrame>& frames,
                                         const std::optional<Region>& region, const PointCloud* existing,
                                         const CloudBuildOptions& options);

}  // namespace builtscene
