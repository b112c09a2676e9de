#pragma once
// A map built directly (no images): random keyframes on a circle, random keypoints and
// descriptors, points observed by several keyframes, covisibility and spanning tree from
// KeyFrame::update_connections. Seeded, so the serializer tests and benchmark are repeatable.
#include <memory>
#include <random>

#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam::test {

inline RgbdCameraSettings kinect_settings() {
  RgbdCameraSettings s;
  s.camera.fx = s.camera.fy = 525;
  s.camera.cx = 319.5;
  s.camera.cy = 239.5;
  s.camera.width = 640;
  s.camera.height = 480;
  return s;
}

inline std::shared_ptr<const FrameContext> kinect_context() {
  return FrameContext::make(kinect_settings(), ScalePyramid::make(1.2f, 8), DescriptorMetric::orb());
}

// Fills `map` (caller holds the lock) with `n_kfs` keyframes of `n_keys` keypoints each; every
// keypoint of keyframe k with an even index is shared with keyframes k+1 and k+2.
inline void build_random_map(Map& map, const std::shared_ptr<const FrameContext>& ctx, int n_kfs, int n_keys,
                             unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(0, 639), uy(0, 479), ua(0, 360), ud(0.5f, 6.0f);
  std::uniform_int_distribution<int> level(0, 7), byte(0, 255);
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int k = 0; k < n_kfs; ++k) {
    auto f = std::make_shared<FrameFeatures>();
    f->ctx = ctx;
    for (int i = 0; i < n_keys; ++i) {
      cv::KeyPoint kp(ux(rng), uy(rng), 31.0f, ua(rng), 0.01f * static_cast<float>(i), level(rng));
      f->keys.push_back(kp);
      const float d = (i % 5 == 0) ? -1.0f : ud(rng);
      f->depth.push_back(d);
      f->u_right.push_back(d > 0 ? kp.pt.x - static_cast<float>(ctx->bf) / d : -1.0f);
    }
    f->keys_un = f->keys;
    f->descriptors.create(n_keys, 32, CV_8U);
    for (int r = 0; r < n_keys; ++r)
      for (int c = 0; c < 32; ++c) f->descriptors.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(rng));
    build_feature_grid(*f);
    Frame frame(10 * k, 1.0 + k / 30.0, f);
    const double a = 0.05 * k;
    frame.set_pose(SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY())),
                       Eigen::Vector3d(std::cos(a), 0.1 * std::sin(3 * a), std::sin(a))));
    auto kf = std::make_shared<KeyFrame>(map.next_keyframe_id(), frame);
    kf->keep = k == 0;
    map.add_keyframe(kf);
    kfs.push_back(kf);
  }
  for (int k = 0; k < n_kfs; ++k) {
    for (int i = 0; i < n_keys; ++i) {
      if (kfs[static_cast<std::size_t>(k)]->points[static_cast<std::size_t>(i)]) continue;
      auto& kf = kfs[static_cast<std::size_t>(k)];
      const Eigen::Vector3d pc(ux(rng) / 300.0 - 1, uy(rng) / 300.0 - 0.8, ud(rng));
      auto p = std::make_shared<MapPoint>(map.next_point_id(), kf->pose_inverse() * pc, kf.get(), kf->id);
      for (int o = 0; o < 3 && k + o < n_kfs; ++o) {
        if (o > 0 && i % 2 != 0) break;
        auto& okf = kfs[static_cast<std::size_t>(k + o)];
        if (okf->points[static_cast<std::size_t>(i)]) break;
        okf->add_point(i, p);
        p->add_observation(okf.get(), i);
      }
      p->update_descriptor();
      p->update_normal_and_depth();
      p->visible = 3 + i % 7;
      p->found = 1 + i % 3;
      map.add_point(p);
    }
  }
  for (auto& kf : kfs) kf->update_connections(15);
  // All points exist before the connections here, so update_connections could pick a newer
  // parent and close a cycle; a chain is what tracking would have built.
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    if (kfs[k]->parent) kfs[k]->parent->children.erase(kfs[k].get());
    kfs[k]->parent = k > 0 ? kfs[k - 1] : nullptr;
    if (k > 0) kfs[k - 1]->children.insert(kfs[k].get());
    kfs[k]->has_parent_link = k > 0;
  }
}

}  // namespace builtscene::slam::test
