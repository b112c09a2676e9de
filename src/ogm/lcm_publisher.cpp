#include "ogm/lcm_publisher.hpp"

#include <algorithm>
#include <chrono>

#include <lcm/lcm-cpp.hpp>

#include "builtscene/loop_event_t.hpp"
#include "builtscene/poi_event_t.hpp"
#include "builtscene/poses_and_laser_scans_t.hpp"
#include "core/errors.hpp"

namespace builtscene {
namespace {

int64_t utime_now() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

builtscene::pose2d_t to_msg(const Pose2D& p) {
  builtscene::pose2d_t m;
  m.x = p.x;
  m.y = p.y;
  m.theta = p.theta;
  return m;
}

builtscene::laser_scan_t to_msg(const LaserScan& s) {
  builtscene::laser_scan_t m;
  m.stamp = s.stamp;
  m.angle_min = s.angle_min;
  m.angle_max = s.angle_max;
  m.angle_increment = s.angle_increment;
  m.time_increment = s.time_increment;
  m.scan_time = s.scan_time;
  m.range_min = s.range_min;
  m.range_max = s.range_max;
  m.num_ranges = static_cast<int32_t>(s.ranges.size());
  m.ranges = s.ranges;
  return m;
}

// A pose as the messages carry it: tx ty tz qx qy qz qw (TUM order).
std::vector<double> tum7(const SE3& T) {
  const Eigen::Vector3d t = T.translation();
  const Eigen::Quaterniond q = T.rotation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

}  // namespace

struct LcmPublisher::Impl {
  explicit Impl(const std::string& url) : lcm(url) {}
  lcm::LCM lcm;
};

LcmPublisher::LcmPublisher(const std::string& url) : impl_(std::make_unique<Impl>(url)) {
  if (!impl_->lcm.good()) throw InputError("--lcm " + url + ": LCM cannot open this URL");
}

LcmPublisher::~LcmPublisher() = default;

void LcmPublisher::publish(const PosesAndLaserScans& batch, const std::string& channel) {
  builtscene::poses_and_laser_scans_t m;
  m.utime = utime_now();
  m.full = batch.full;
  m.num_keyframes = static_cast<int32_t>(batch.pairs.size());
  for (std::size_t i = 0; i < batch.pairs.size(); ++i) {
    m.stamps.push_back(batch.stamps[i]);
    m.poses.push_back(tum7(batch.T_wc[i]));
    m.poses2d.push_back(to_msg(batch.pairs[i].pose));
    m.scans.push_back(to_msg(batch.pairs[i].scan));
  }
  if (impl_->lcm.publish(channel, &m) != 0) throw Failure("LCM publish on " + channel + " failed");
  ++published_;
}

void LcmPublisher::publish(const LcmPoiEvent& e, const std::string& channel) {
  builtscene::poi_event_t m;
  m.utime = utime_now();
  m.time = e.time;
  m.frame = e.frame;
  m.pose = to_msg(e.pose);
  m.poi = e.poi;
  m.distance = e.distance;
  if (impl_->lcm.publish(channel, &m) != 0) throw Failure("LCM publish on " + channel + " failed");
  ++published_;
}

void LcmPublisher::publish(const LcmLoopEvent& e, const std::string& channel) {
  builtscene::loop_event_t m;
  m.utime = utime_now();
  m.stage = e.stage;
  m.loop = e.loop;
  m.frame = e.frame;
  m.time = e.time;
  m.keyframe = e.keyframe;
  m.matched_keyframe = e.matched_keyframe;
  m.inliers = e.inliers;
  const auto c = tum7(e.correction);
  std::copy(c.begin(), c.end(), m.correction);
  m.num_keyframes = static_cast<int32_t>(e.T_wc.size());
  for (std::size_t i = 0; i < e.T_wc.size(); ++i) {
    m.keyframe_ids.push_back(i < e.keyframe_ids.size() ? e.keyframe_ids[i] : -1);
    m.stamps.push_back(i < e.stamps.size() ? e.stamps[i] : 0.0);
    m.poses.push_back(tum7(e.T_wc[i]));
  }
  if (impl_->lcm.publish(channel, &m) != 0) throw Failure("LCM publish on " + channel + " failed");
  ++published_;
}

}  // namespace builtscene
