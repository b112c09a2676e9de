#pragma once
// An RGB-D frame as tracking sees it: ORB keypoints (raw and undistorted), descriptors, the
// depth of each keypoint and its virtual right-image coordinate u_R = u - bf / depth (the
// "stereo" view ORB-SLAM gives RGB-D keypoints), a grid for fast area queries, the pose and
// the map points matched to each keypoint.
//
// Ownership: a Frame belongs to the tracking thread alone and needs no lock. Its features
// (FrameFeatures) never change after construction and are shared read-only with the keyframe
// made from it. Its `points` may refer to map points whose mutable state is guarded by the
// map lock (see map.hpp).
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "features/descriptor.hpp"
#include "features/orb_extractor.hpp"
#include "slam/observation.hpp"

namespace builtscene::slam {

class MapPoint;
class KeyFrame;

// What every frame of one sequence shares: camera, depth settings, scale pyramid, metric.
struct FrameContext {
  PinholeCamera camera;
  double bf = 40.0;        // baseline times fx (pixels * metres)
  double th_depth = 3.0;   // metres: closer keypoints are "close" (reliable depth)
  double disparity_sigma = 0;  // pixels; 0 = ORB-SLAM's u_right residual (see RgbdCameraSettings)
  double global_ba_disparity_sigma = 0;  // pixels, in global bundle adjustment; 0 = disparity_sigma
  double local_ba_disparity_sigma = 0;   // pixels, in local bundle adjustment, fixed; 0 = disparity_sigma or local_ba_disparity.hpp's rule
  double max_depth = 0;        // metres: keypoint depth readings beyond are not used (0 = no limit)
  double far_depth = 0;        // metres: readings beyond place points but give no disparity residual (0 = none)
  ScalePyramid pyramid;
  DescriptorMetric metric = DescriptorMetric::orb();
  // Undistorted image bounds (the image corners undistorted), for projection checks.
  float min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  static constexpr int kGridCols = 64;
  static constexpr int kGridRows = 48;
  float grid_scale_x = 0, grid_scale_y = 0;  // cells per pixel

  static std::shared_ptr<const FrameContext> make(const RgbdCameraSettings& settings, const ScalePyramid& pyramid,
                                                  const DescriptorMetric& metric);
  bool in_image(double u, double v) const { return u >= min_x && u < max_x && v >= min_y && v < max_y; }
};

// The immutable per-frame measurements.
struct FrameFeatures {
  std::shared_ptr<const FrameContext> ctx;
  std::vector<cv::KeyPoint> keys;     // as detected (distorted image)
  std::vector<cv::KeyPoint> keys_un;  // undistorted
  cv::Mat descriptors;                // one row per keypoint
  std::vector<float> depth;           // metres, <= 0 when unknown
  std::vector<float> u_right;         // virtual right coordinate of every depth reading, < 0 when none
  // Keypoints binned by undistorted position: cell c holds grid_items[grid_start[c] .. grid_start[c+1]).
  std::vector<int> grid_start, grid_items;

  std::size_t size() const { return keys_un.size(); }
  bool has_depth(std::size_t i) const { return depth[i] > 0; }
  bool is_close(std::size_t i) const { return depth[i] > 0 && depth[i] < ctx->th_depth; }
  // Beyond ctx->far_depth (FarDepth): the reading places points but is a disparity measurement
  // only where `keep_far` (a keyframe the depth-odometry bridge made: KeyFrame::keeps_far_readings).
  bool is_far(std::size_t i) const { return ctx->far_depth > 0 && depth[i] > ctx->far_depth; }
  float measured_u_right(std::size_t i, bool keep_far = false) const { return keep_far || !is_far(i) ? u_right[i] : -1.f; }
  // Keypoint i as the optimizers measure it (pixel, level information, disparity where measured).
  Observation observation(std::size_t i, bool keep_far = false) const {
    Observation o;
    o.uv = {keys_un[i].pt.x, keys_un[i].pt.y};
    o.inv_sigma2 = ctx->pyramid.inv_sigma2[static_cast<std::size_t>(keys_un[i].octave)];
    o.u_right = measured_u_right(i, keep_far);
    return o;
  }
  // Keypoint indices within radius r of (u, v) (square window), octave in [min_level, max_level]
  // (negative = any).
  std::vector<int> in_area(float u, float v, float r, int min_level = -1, int max_level = -1) const;
  // Camera-frame point of keypoint i from its depth (undistorted coordinates).
  Eigen::Vector3d unproject(std::size_t i) const;
};

// Fills the area-query grid from keys_un (needs ctx); used when features are loaded from a file.
void build_feature_grid(FrameFeatures& f);

// Extracts ORB from `gray` and reads depth (metres, CV_32F, same size) at each keypoint.
std::shared_ptr<const FrameFeatures> make_rgbd_features(const cv::Mat& gray, const cv::Mat& depth_m,
                                                        std::shared_ptr<const FrameContext> ctx, FeatureExtractor& extractor);

class Frame {
 public:
  Frame(long id, double timestamp, std::shared_ptr<const FrameFeatures> features);

  long id = 0;
  double timestamp = 0;
  std::shared_ptr<const FrameFeatures> f;
  std::vector<std::shared_ptr<MapPoint>> points;  // per keypoint, null when unmatched
  std::vector<char> outlier;                      // set by pose optimization

  bool has_pose = false;
  SE3 T_cw;  // world -> camera
  std::shared_ptr<KeyFrame> reference;

  void set_pose(const SE3& T) {
    T_cw = T;
    has_pose = true;
  }
  Eigen::Vector3d camera_center() const { return T_cw.inverse().translation(); }
  std::size_t size() const { return f->size(); }
  int matched_count() const;
  void clear_matches();
  // Drops the matches pose optimization marked as outliers; returns the inliers left.
  int keep_inlier_matches();
};

}  // namespace builtscene::slam
