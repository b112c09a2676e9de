// Local mapping's triangulation against known points. Two keyframes 0.6 m apart along the
// view (a robot driving down a corridor), a grazing side wall without depth readings, keypoints
// with 1 px noise: every created point is compared with the wall point it came from.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "map_test_fixture.hpp"
#include "slam/local_mapping.hpp"

namespace builtscene::slam {
namespace {

struct TriangulatedWall {
  int created = 0;
  double mean_range_error = 0;  // relative, (estimated - true) / true, over the created points
};

// Keyframe A at the origin looking along +z, keyframe B 0.6 m ahead. 40 anchor points with
// depth, seen by both, make them covisible; `n` wall points at x = -1.5 m, 2.5-9 m ahead, have
// no depth and unique descriptors, so each can only be matched to itself.
TriangulatedWall triangulate_a_grazing_wall(double min_parallax_sigmas, int n, unsigned seed) {
  const auto ctx = test::kinect_context();
  const Intrinsics K = intrinsics_of(*ctx);
  Map map;
  std::mt19937 rng(seed);
  std::normal_distribution<double> pixel_noise(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::uniform_int_distribution<int> byte(0, 255);
  const SE3 T_a;                                              // world -> camera A
  const SE3 T_b(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -0.6));  // camera B at z = 0.6

  struct Truth {
    Eigen::Vector3d p;
    bool anchor;
  };
  std::vector<Truth> truth;
  for (int i = 0; i < 40; ++i)
    truth.push_back({Eigen::Vector3d(-0.8 + 1.6 * u01(rng), -0.6 + 1.2 * u01(rng), 2.0 + u01(rng)), true});
  for (int i = 0; i < n; ++i)
    truth.push_back({Eigen::Vector3d(-1.5, -0.7 + 1.4 * u01(rng), 2.5 + 6.5 * u01(rng)), false});
  cv::Mat desc(static_cast<int>(truth.size()), 32, CV_8U);
  for (int r = 0; r < desc.rows; ++r)
    for (int c = 0; c < 32; ++c) desc.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(rng));

  // Features of one keyframe: every truth point inside the image, with pixel noise; index map
  // truth -> keypoint.
  auto features = [&](const SE3& T, std::vector<int>& key_of) {
    auto f = std::make_shared<FrameFeatures>();
    f->ctx = ctx;
    std::vector<int> rows;
    key_of.assign(truth.size(), -1);
    for (std::size_t t = 0; t < truth.size(); ++t) {
      const Eigen::Vector3d pc = T * truth[t].p;
      const double u = K.fx * pc.x() / pc.z() + K.cx + pixel_noise(rng);
      const double v = K.fy * pc.y() / pc.z() + K.cy + pixel_noise(rng);
      if (pc.z() <= 0.1 || u < 0 || v < 0 || u > 639 || v > 479) continue;
      key_of[t] = static_cast<int>(f->keys.size());
      f->keys.emplace_back(static_cast<float>(u), static_cast<float>(v), 31.0f, 0.0f, 0.0f, 0);
      const float d = truth[t].anchor ? static_cast<float>(pc.z()) : -1.0f;
      f->depth.push_back(d);
      f->u_right.push_back(d > 0 ? f->keys.back().pt.x - static_cast<float>(K.bf) / d : -1.0f);
      rows.push_back(static_cast<int>(t));
    }
    f->keys_un = f->keys;
    f->descriptors.create(static_cast<int>(rows.size()), 32, CV_8U);
    for (std::size_t r = 0; r < rows.size(); ++r) desc.row(rows[r]).copyTo(f->descriptors.row(static_cast<int>(r)));
    build_feature_grid(*f);
    return f;
  };
  std::vector<int> key_a, key_b;
  Frame fa(0, 1.0, features(T_a, key_a)), fb(20, 1.7, features(T_b, key_b));
  fa.set_pose(T_a);
  fb.set_pose(T_b);
  std::shared_ptr<KeyFrame> a, b;
  {
    std::lock_guard lock(map.mutex());
    a = std::make_shared<KeyFrame>(map.next_keyframe_id(), fa);
    a->keep = true;
    map.add_keyframe(a);
    b = std::make_shared<KeyFrame>(map.next_keyframe_id(), fb);
    map.add_keyframe(b);
    for (std::size_t t = 0; t < truth.size(); ++t) {
      if (!truth[t].anchor || key_a[t] < 0 || key_b[t] < 0) continue;
      auto p = std::make_shared<MapPoint>(map.next_point_id(), truth[t].p, a.get(), a->id);
      a->add_point(key_a[t], p);
      p->add_observation(a.get(), key_a[t]);
      b->add_point(key_b[t], p);
      p->add_observation(b.get(), key_b[t]);
      p->update_descriptor();
      p->update_normal_and_depth();
      map.add_point(p);
    }
    a->update_connections();
  }
  LocalMappingOptions opt;
  opt.planes.enabled = false;
  opt.bundle_adjustment = false;
  opt.min_parallax_sigmas = min_parallax_sigmas;
  LocalMapping mapping(map, opt);
  mapping.insert_keyframe(b);
  mapping.run_pending();

  TriangulatedWall out;
  std::lock_guard lock(map.mutex());
  for (std::size_t t = 0; t < truth.size(); ++t) {
    if (truth[t].anchor || key_a[t] < 0) continue;
    const auto& p = a->points[static_cast<std::size_t>(key_a[t])];
    if (!p || p->bad) continue;
    ++out.created;
    out.mean_range_error += (p->position.norm() - truth[t].p.norm()) / truth[t].p.norm();
  }
  if (out.created > 0) out.mean_range_error /= out.created;
  return out;
}

// Near ORB-SLAM's fixed 1.15-degree threshold the parallax of two 1 px rays is uncertain by
// ~13 %, and the range, going as 1 / parallax, comes out biased (here short: the points
// accepted because noise raised their parallax outweigh the 1 / parallax convexity).
// Requiring the parallax to be many times its own error keeps the well-conditioned points.
TEST(Triangulation, WellConditionedParallaxKeepsRangesNearlyUnbiased) {
  const double k = 12.0;  // off by default (local_mapping.hpp); the value docs/slam.md measured
  for (unsigned seed : {5u, 6u, 7u}) {
    const auto fixed_only = triangulate_a_grazing_wall(0.0, 3000, seed);
    const auto sigma_rule = triangulate_a_grazing_wall(k, 3000, seed);
    std::printf("grazing wall, 1 px noise, seed %u: fixed 1.15 deg: %d points, mean range error %+.2f %%; "
                "parallax >= %.0f sigmas: %d points, %+.2f %%\n",
                seed, fixed_only.created, 100 * fixed_only.mean_range_error, k, sigma_rule.created,
                100 * sigma_rule.mean_range_error);
    ASSERT_GT(fixed_only.created, 1000);
    ASSERT_GT(sigma_rule.created, 500);
    EXPECT_GT(std::abs(fixed_only.mean_range_error), 0.008);
    EXPECT_LT(std::abs(sigma_rule.mean_range_error), 0.6 * std::abs(fixed_only.mean_range_error));
    EXPECT_LT(std::abs(sigma_rule.mean_range_error), 0.007);
  }
}

}  // namespace
}  // namespace builtscene::slam
