#include "ogm/poses_and_laser_scans.hpp"

#include <algorithm>

namespace builtscene {

PosesAndLaserScansEmitter::PosesAndLaserScansEmitter(const PinholeCamera& camera, const GroundFrame& ground,
                                                     PosesAndLaserScansOptions options)
    : scanner_(camera, options.scan), ground_(ground), options_(options) {}

std::vector<PosesAndLaserScans> PosesAndLaserScansEmitter::add_keyframe(double stamp, const SE3& T_wc,
                                                                        const cv::Mat& depth,
                                                                        const Trajectory& keyframes) {
  LaserScan scan = scanner_.scan(depth, ground_.camera_in_ground(T_wc), stamp);
  PosesAndLaserScans one;
  one.stamps = {stamp};
  one.T_wc = {T_wc};
  one.pairs = {PoseAndScan{ground_.to_2d(T_wc), scan}};
  scans_[stamp] = std::move(scan);
  std::vector<PosesAndLaserScans> out{std::move(one)};
  if (options_.full_batch_every > 0 && ++since_full_ >= options_.full_batch_every) out.push_back(full_batch(keyframes));
  return out;
}

PosesAndLaserScans PosesAndLaserScansEmitter::full_batch(const Trajectory& keyframes) {
  PosesAndLaserScans all;
  all.full = true;
  std::map<double, LaserScan> alive;
  // In time order, so a rebuild integrates scans in the order they were made and the same run
  // gives the same map whatever order the SLAM lists its keyframes in.
  Trajectory sorted = keyframes;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  for (const auto& kf : sorted) {
    auto it = scans_.find(kf.timestamp);
    if (it == scans_.end()) continue;  // a keyframe made before mapping started, or not ours
    all.stamps.push_back(kf.timestamp);
    all.T_wc.push_back(kf.pose);
    all.pairs.push_back({ground_.to_2d(kf.pose), it->second});
    alive.insert(scans_.extract(it));
  }
  scans_ = std::move(alive);  // culled keyframes' scans are freed
  since_full_ = 0;
  return all;
}

}  // namespace builtscene
