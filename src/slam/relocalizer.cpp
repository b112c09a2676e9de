#include "slam/relocalizer.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "core/so3.hpp"
#include "slam/bow_matcher.hpp"
#include "slam/key_frame.hpp"
#include "slam/keyframe_database.hpp"
#include "slam/map_point.hpp"
#include "slam/matcher.hpp"
#include "slam/pose_optimizer.hpp"

namespace builtscene::slam {

Relocalizer::Relocalizer(const KeyFrameDatabase& database, RelocalizerOptions options)
    : db_(database), opt_(options) {}

int Relocalizer::search_local_map(Frame& frame, const KeyFrame& candidate, float th) const {
  return search_keyframe_neighbourhood(frame, candidate, 10, th);
}

std::shared_ptr<KeyFrame> Relocalizer::relocalize(Frame& frame) const {
  ++stats_.attempts;
  frame.clear_matches();
  if (frame.size() == 0 || db_.size() == 0) return nullptr;
  BowVector bow;
  FeatureVector features;
  db_.compute_bow(frame.f->descriptors, bow, features);
  auto candidates = db_.relocalization_candidates(bow);
  if (static_cast<int>(candidates.size()) > opt_.max_candidates) candidates.resize(static_cast<std::size_t>(opt_.max_candidates));

  // The best pose short of min_inliers, kept for the two-frame rule.
  int best_good = 0;
  SE3 best_T;
  std::shared_ptr<KeyFrame> best_kf;
  std::vector<std::shared_ptr<MapPoint>> best_points;
  const auto& cam = frame.f->ctx->camera;
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  for (KeyFrame* kf : candidates) {
    if (kf->bad) continue;
    int n = 0;
    auto matches = search_by_bow(*kf, *frame.f, features, &n);
    if (n < opt_.min_bow_matches) continue;
    std::vector<cv::Point3f> object;
    std::vector<cv::Point2f> image;
    std::vector<int> keypoint;
    for (std::size_t i = 0; i < matches.size(); ++i) {
      if (!matches[i]) continue;
      const auto& X = matches[i]->position;
      object.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()));
      image.push_back(frame.f->keys_un[i].pt);
      keypoint.push_back(static_cast<int>(i));
    }
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    bool found = false;
    try {
      found = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, opt_.ransac_iterations,
                                 opt_.ransac_reprojection_px, 0.99, inliers, cv::SOLVEPNP_EPNP);
    } catch (const cv::Exception&) {
      found = false;  // degenerate configurations make EPnP throw; try the next candidate
    }
    if (!found || static_cast<int>(inliers.size()) < 10) continue;
    cv::Mat R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d Re;
    Eigen::Vector3d te;
    cv::cv2eigen(R, Re);
    cv::cv2eigen(tvec, te);
    frame.clear_matches();
    frame.set_pose(SE3(Re, te));
    for (int j : inliers) frame.points[static_cast<std::size_t>(keypoint[static_cast<std::size_t>(j)])] = matches[static_cast<std::size_t>(keypoint[static_cast<std::size_t>(j)])];
    optimize_frame_pose(frame);
    int good = frame.keep_inlier_matches();
    if (good < 10) continue;
    if (good < opt_.min_inliers) {
      // Guided search: ORB-SLAM's wide window first, then a narrow one once the pose is better.
      const int added = search_local_map(frame, *kf, 4.0f);
      if (good + added >= opt_.min_inliers) {
        optimize_frame_pose(frame);
        good = frame.keep_inlier_matches();
        if (good > 30 && good < opt_.min_inliers) {
          search_local_map(frame, *kf, 1.5f);
          optimize_frame_pose(frame);
          good = frame.keep_inlier_matches();
        }
      }
    }
    if (good >= opt_.min_inliers) {
      ++stats_.successes;
      last_tentative_ = {};
      return kf->shared_from_this();
    }
    if (good > best_good) {
      best_good = good;
      best_T = frame.T_cw;
      best_kf = kf->shared_from_this();
      best_points = frame.points;
    }
  }
  frame.clear_matches();
  // Two-frame rule: this frame's best pose short of min_inliers is accepted when the frame
  // before left one close to it; otherwise it waits for the next frame's.
  const Tentative previous = std::exchange(last_tentative_, {});
  if (opt_.min_inliers_twice <= 0 || best_good < opt_.min_inliers_twice) return nullptr;
  const SE3 moved = best_T * previous.T_cw.inverse();
  const bool agrees = previous.frame_id == frame.id - 1 && moved.translation().norm() <= opt_.twice_max_m &&
                      so3_log(moved.rotation()).norm() <= opt_.twice_max_deg * M_PI / 180.0;
  if (!agrees) {
    last_tentative_ = {frame.id, best_T};
    return nullptr;
  }
  frame.set_pose(best_T);
  frame.points = best_points;
  std::fill(frame.outlier.begin(), frame.outlier.end(), 0);
  ++stats_.successes;
  return best_kf;
}

}  // namespace builtscene::slam
