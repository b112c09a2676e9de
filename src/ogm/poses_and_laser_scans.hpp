#pragma once
// PosesAndLaserScans: the batches that connect the SLAM to occupancy grid mapping (the
// source's Figure 2.4). The SLAM emits a batch of one (the new keyframe's pose and its virtual
// scan) for every new keyframe, and a batch of all historical keyframes with their poses after
// optimization every N keyframes and after every loop closure. The mapper updates
// incrementally on a batch of one and erases and rebuilds on a larger one.
//
// A keyframe's scan is cut from its depth image once, when the keyframe is created, with the
// camera's tilt at that moment; later batches carry the same scan with the keyframe's newer
// pose (a scan's points relative to the floor below the camera do not change when the pose
// is corrected, only where the scan lies on the map).
#include <cstddef>
#include <map>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "io/trajectory.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/occupancy_grid_mapper.hpp"
#include "ogm/virtual_laser_scanner.hpp"

namespace builtscene {

struct PosesAndLaserScans {
  bool full = false;               // all historical keyframes (rebuild) rather than one new one
  std::vector<double> stamps;      // keyframe timestamps, one per pair
  std::vector<SE3> T_wc;           // keyframe poses in the SLAM's world
  std::vector<PoseAndScan> pairs;  // 2D pose in the ground frame and the scan
};

struct PosesAndLaserScansOptions {
  VirtualLaserScanOptions scan;
  int full_batch_every = 10;  // keyframes between full batches (0 = never, only after loops)
};

// Turns keyframes into PosesAndLaserScans batches. Not thread-safe: call it from the thread
// that runs the SLAM's tracking (the keyframe decision is made there).
class PosesAndLaserScansEmitter {
 public:
  PosesAndLaserScansEmitter(const PinholeCamera& camera, const GroundFrame& ground,
                            PosesAndLaserScansOptions options = {});

  // A new keyframe: cuts its scan from `depth` (CV_32F metres) and returns the batch of one;
  // when this keyframe completes N since the last full batch, `keyframes` (all keyframes now
  // in the map, after optimization) also yields a full batch, returned second.
  std::vector<PosesAndLaserScans> add_keyframe(double stamp, const SE3& T_wc, const cv::Mat& depth,
                                               const Trajectory& keyframes);

  // All historical keyframes still in `keyframes` (culled ones are dropped for good), with
  // the poses given there: after a loop closure, and every N keyframes.
  PosesAndLaserScans full_batch(const Trajectory& keyframes);

  const GroundFrame& ground() const { return ground_; }
  std::size_t keyframes_kept() const { return scans_.size(); }

 private:
  VirtualLaserScanner scanner_;
  GroundFrame ground_;
  PosesAndLaserScansOptions options_;
  std::map<double, LaserScan> scans_;  // by keyframe timestamp
  int since_full_ = 0;
};

}  // namespace builtscene
