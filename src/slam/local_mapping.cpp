#include "slam/local_mapping.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "slam/key_frame.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"
#include "slam/matcher.hpp"
#include "slam/pose_optimizer.hpp"

namespace builtscene::slam {

bool is_redundant_keyframe(const KeyFrame& kf, float ratio, int min_observers) {
  if (kf.id == 0 || kf.keep || kf.bad) return false;
  int points = 0, redundant = 0;
  for (std::size_t i = 0; i < kf.points.size(); ++i) {
    const auto& p = kf.points[i];
    if (!p || p->bad) continue;
    if (!kf.f->is_close(i)) continue;
    ++points;
    if (p->observation_count() <= min_observers) continue;
    const int level = kf.f->keys_un[i].octave;
    int observers = 0;
    for (const auto& [other, idx] : p->observations) {
      if (other == &kf) continue;
      if (other->f->keys_un[static_cast<std::size_t>(idx)].octave <= level + 1) ++observers;
      if (observers >= min_observers) break;
    }
    if (observers >= min_observers) ++redundant;
  }
  return points > 0 && static_cast<float>(redundant) > ratio * static_cast<float>(points);
}

LocalMapping::LocalMapping(Map& map, LocalMappingOptions options, StageTimer* timer)
    : map_(map), opt_(options), timer_(timer) {}

LocalMapping::~LocalMapping() { finish(); }

void LocalMapping::start() {
  if (thread_.joinable()) return;
  {
    std::lock_guard lock(queue_mutex_);
    stop_ = false;
    running_ = true;
  }
  thread_ = std::thread([this] { run(); });
}

void LocalMapping::finish() {
  {
    std::lock_guard lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LocalMapping::run_pending() {
  if (thread_.joinable()) return;
  for (;;) {
    std::shared_ptr<KeyFrame> kf;
    {
      std::lock_guard lock(queue_mutex_);
      if (queue_.empty()) break;
      kf = queue_.front();
      queue_.pop_front();
    }
    process(kf);
    if (output_ && !kf->bad) output_(kf);
  }
  idle_ = true;
}

void LocalMapping::request_pause() {
  {
    std::lock_guard lock(queue_mutex_);
    pause_requested_ = true;
  }
  abort_ba_ = true;
  queue_cv_.notify_all();
}

void LocalMapping::wait_until_paused() {
  std::unique_lock lock(queue_mutex_);
  pause_cv_.wait(lock, [this] { return paused_ || !running_; });
}

void LocalMapping::resume() {
  {
    std::lock_guard lock(queue_mutex_);
    pause_requested_ = false;
  }
  queue_cv_.notify_all();
}

void LocalMapping::insert_keyframe(std::shared_ptr<KeyFrame> kf) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(kf));
    idle_ = false;
    // A new keyframe does not abort a running BA by itself; tracking asks for that when it
    // is weak (Tracker::need_new_keyframe). Aborting on every keyframe let almost no BA
    // finish when the machine is loaded (79 of 124 aborted on lab-room, load 9).
    std::lock_guard s(stats_mutex_);
    stats_.max_queue = std::max(stats_.max_queue, queue_.size());
  }
  queue_cv_.notify_one();
}

std::size_t LocalMapping::queue_size() const {
  std::lock_guard lock(queue_mutex_);
  return queue_.size();
}

bool LocalMapping::queue_empty() const { return queue_size() == 0; }

LocalMapping::Stats LocalMapping::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

void LocalMapping::run() {
  for (;;) {
    std::shared_ptr<KeyFrame> kf;
    {
      std::unique_lock lock(queue_mutex_);
      idle_ = queue_.empty();
      queue_cv_.wait(lock, [this] { return stop_ || pause_requested_ || !queue_.empty(); });
      if (pause_requested_) {
        // Parked between keyframes with no lock held: loop closing corrects the map now.
        paused_ = true;
        pause_cv_.notify_all();
        queue_cv_.wait(lock, [this] { return !pause_requested_; });
        paused_ = false;
        continue;
      }
      if (queue_.empty()) {  // stop requested and nothing left
        running_ = false;
        pause_cv_.notify_all();
        return;
      }
      kf = queue_.front();
      queue_.pop_front();
      idle_ = false;
    }
    process(kf);
    if (output_ && !kf->bad) output_(kf);
  }
}

void LocalMapping::process(const std::shared_ptr<KeyFrame>& kf) {
  const auto start = std::chrono::steady_clock::now();
  abort_ba_ = false;
  {
    std::lock_guard lock(map_.mutex());
    if (kf->bad) return;
    insert_into_map(*kf);
    if (opt_.planes.enabled) associate_planes(*kf, map_, opt_.planes);
    cull_recent_points(*kf);
    if (opt_.triangulation) triangulate_with_neighbours(*kf);
  }
  if (queue_empty()) {
    std::lock_guard lock(map_.mutex());
    fuse_with_neighbours(*kf);
  }
  if (queue_empty() && !abort_ba_) {
    if (opt_.bundle_adjustment) {
      const auto ba_start = std::chrono::steady_clock::now();
      local_bundle_adjustment(*kf);
      if (timer_) timer_->add("local_ba", ms_since(ba_start));
    }
    std::lock_guard lock(map_.mutex());
    cull_keyframes(*kf);
  }
  {
    std::lock_guard s(stats_mutex_);
    ++stats_.keyframes_processed;
  }
  if (timer_) timer_->add("local_mapping", ms_since(start));
}

void LocalMapping::insert_into_map(KeyFrame& kf) {
  for (std::size_t i = 0; i < kf.points.size(); ++i) {
    const auto& p = kf.points[i];
    if (!p || p->bad) continue;
    if (!p->observed_by(&kf)) {
      p->add_observation(&kf, static_cast<int>(i));
      p->update_normal_and_depth();
      p->update_descriptor();
    } else {
      recent_points_.push_back(p);  // created by tracking for this keyframe
    }
  }
  kf.update_connections();
  // Sharing no point, it joins the spanning tree under the keyframe the bridge started from
  // (or the nearest unculled ancestor), so loop corrections and global BA carry it along.
  if (!kf.has_parent_link && kf.odometry_parent) {
    KeyFrame* p = kf.odometry_parent.get();
    while (p->bad && p->parent) p = p->parent.get();
    if (!p->bad) {
      kf.link_to_parent(*p);
      kf.parent_by_odometry = true;
    }
  }
  kf.odometry_parent.reset();
}

void LocalMapping::cull_recent_points(const KeyFrame& kf) {
  long culled = 0;
  for (auto it = recent_points_.begin(); it != recent_points_.end();) {
    auto& p = *it;
    const long age = kf.id - p->created_by_kf;
    if (p->bad) {
      it = recent_points_.erase(it);
    } else if (p->found_ratio() < opt_.min_found_ratio) {
      p->set_bad(map_);
      ++culled;
      it = recent_points_.erase(it);
    } else if (age >= 2 && p->observation_count() < opt_.min_observations) {
      p->set_bad(map_);
      ++culled;
      it = recent_points_.erase(it);
    } else if (age >= 3) {
      it = recent_points_.erase(it);
    } else {
      ++it;
    }
  }
  std::lock_guard s(stats_mutex_);
  stats_.points_culled += culled;
}

namespace {

// Linear (DLT) triangulation of normalized image rays x1, x2 seen from T1, T2 (world -> camera).
bool triangulate(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, const SE3& T1, const SE3& T2,
                 Eigen::Vector3d& out) {
  const Eigen::Matrix<double, 3, 4> P1 = T1.matrix().topRows<3>(), P2 = T2.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h[3]) < 1e-12) return false;
  out = h.head<3>() / h[3];
  return out.allFinite();
}

}  // namespace

void LocalMapping::triangulate_with_neighbours(KeyFrame& kf) {
  const auto& f1 = *kf.f;
  const auto& ctx = *f1.ctx;
  const auto& metric = ctx.metric;
  const auto& pyr = ctx.pyramid;
  const Intrinsics K = intrinsics_of(ctx);
  const double baseline = K.bf / K.fx;
  const Eigen::Vector3d O1 = kf.camera_center();
  const SE3 T1 = kf.pose();
  const Eigen::Matrix3d Kinv = (Eigen::Matrix3d() << 1 / K.fx, 0, -K.cx / K.fx, 0, 1 / K.fy, -K.cy / K.fy, 0, 0, 1).finished();
  long created = 0;
  for (KeyFrame* n : kf.best_covisibles(static_cast<std::size_t>(opt_.covisible_for_triangulation))) {
    if (n->bad) continue;
    const Eigen::Vector3d O2 = n->camera_center();
    if ((O2 - O1).norm() < baseline) continue;  // too short a baseline to beat the depth sensor
    const auto& f2 = *n->f;
    const SE3 T2 = n->pose();
    // Fundamental matrix 1 -> 2: F = K^-T [t21]x R21 K^-1.
    const SE3 T21 = T2 * T1.inverse();
    const Eigen::Vector3d t = T21.translation();
    Eigen::Matrix3d tx;
    tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
    const Eigen::Matrix3d F = Kinv.transpose() * tx * T21.rotation_matrix() * Kinv;
    std::vector<int> free2;
    for (std::size_t j = 0; j < f2.size(); ++j)
      if (!n->points[j]) free2.push_back(static_cast<int>(j));
    std::vector<float> best_for_j(f2.size(), metric.infinity());
    std::vector<int> match_of_j(f2.size(), -1);
    for (std::size_t i = 0; i < f1.size(); ++i) {
      if (kf.points[i]) continue;
      const auto& k1 = f1.keys_un[i];
      const Eigen::Vector3d l = F * Eigen::Vector3d(k1.pt.x, k1.pt.y, 1.0);  // epipolar line in image 2
      const double ln = l.head<2>().squaredNorm();
      if (ln < 1e-12) continue;
      float best = metric.strict + 1;
      int best_j = -1;
      for (int j : free2) {
        const auto& k2 = f2.keys_un[static_cast<std::size_t>(j)];
        const double d = l.dot(Eigen::Vector3d(k2.pt.x, k2.pt.y, 1.0));
        if (d * d / ln > 3.84 * pyr.sigma2[static_cast<std::size_t>(k2.octave)]) continue;
        const float dist = metric.distance(f1.descriptors, static_cast<int>(i), f2.descriptors, j);
        if (dist < best) {
          best = dist;
          best_j = j;
        }
      }
      if (best_j < 0 || best > metric.strict) continue;
      if (best < best_for_j[static_cast<std::size_t>(best_j)]) {
        best_for_j[static_cast<std::size_t>(best_j)] = best;
        match_of_j[static_cast<std::size_t>(best_j)] = static_cast<int>(i);
      }
    }
    for (std::size_t j = 0; j < f2.size(); ++j) {
      const int i = match_of_j[j];
      if (i < 0 || kf.points[static_cast<std::size_t>(i)] || n->points[j]) continue;
      const auto is = static_cast<std::size_t>(i);
      const auto& k1 = f1.keys_un[is];
      const auto& k2 = f2.keys_un[j];
      const Eigen::Vector2d x1((k1.pt.x - K.cx) / K.fx, (k1.pt.y - K.cy) / K.fy);
      const Eigen::Vector2d x2((k2.pt.x - K.cx) / K.fx, (k2.pt.y - K.cy) / K.fy);
      const Eigen::Vector3d r1 = T1.rotation().inverse() * Eigen::Vector3d(x1.x(), x1.y(), 1.0);
      const Eigen::Vector3d r2 = T2.rotation().inverse() * Eigen::Vector3d(x2.x(), x2.y(), 1.0);
      const double cos_parallax = r1.dot(r2) / (r1.norm() * r2.norm());
      Eigen::Vector3d pw;
      const double parallax_sigma = std::sqrt(pyr.sigma2[static_cast<std::size_t>(k1.octave)] +
                                              pyr.sigma2[static_cast<std::size_t>(k2.octave)]) / K.fx;
      const bool enough_parallax = cos_parallax < 0.9998 && cos_parallax > 0 &&
                                   std::acos(std::min(1.0, cos_parallax)) >= opt_.min_parallax_sigmas * parallax_sigma;
      if (enough_parallax) {
        if (!triangulate(x1, x2, T1, T2, pw)) continue;
      } else if (f1.has_depth(is)) {
        pw = T1.inverse() * f1.unproject(is);
      } else if (f2.has_depth(j)) {
        pw = T2.inverse() * f2.unproject(j);
      } else {
        continue;
      }
      // In front of both cameras, reprojecting within the chi-square bound in both.
      const Observation o1 = f1.observation(is), o2 = f2.observation(j);
      if (reprojection_chi2(K, o1, T1 * pw) > (o1.stereo() ? kChi2Stereo : kChi2Mono)) continue;
      if (reprojection_chi2(K, o2, T2 * pw) > (o2.stereo() ? kChi2Stereo : kChi2Mono)) continue;
      // Scale consistency: the distance ratio must agree with the pyramid levels.
      const double d1 = (pw - O1).norm(), d2 = (pw - O2).norm();
      if (d1 <= 0 || d2 <= 0) continue;
      const double ratio_dist = d2 / d1;
      const double ratio_octave = pyr.scale[static_cast<std::size_t>(k1.octave)] / pyr.scale[static_cast<std::size_t>(k2.octave)];
      const double factor = 1.5 * pyr.scale_factor;
      if (ratio_dist * factor < ratio_octave || ratio_dist > ratio_octave * factor) continue;
      auto p = std::make_shared<MapPoint>(map_.next_point_id(), pw, &kf, kf.id);
      p->add_observation(&kf, i);
      p->add_observation(n, static_cast<int>(j));
      kf.add_point(i, p);
      n->add_point(static_cast<int>(j), p);
      p->update_descriptor();
      p->update_normal_and_depth();
      map_.add_point(p);
      recent_points_.push_back(p);
      ++created;
    }
  }
  std::lock_guard s(stats_mutex_);
  stats_.points_triangulated += created;
}

void LocalMapping::fuse_with_neighbours(KeyFrame& kf) {
  // Neighbours and their neighbours (ORB-SLAM's SearchInNeighbors).
  std::vector<KeyFrame*> targets;
  for (KeyFrame* n : kf.best_covisibles(static_cast<std::size_t>(opt_.covisible_for_fusion))) {
    if (n->bad || n->fuse_mark == kf.id) continue;
    n->fuse_mark = kf.id;
    targets.push_back(n);
  }
  const std::size_t first = targets.size();
  for (std::size_t i = 0; i < first; ++i)
    for (KeyFrame* n2 : targets[i]->best_covisibles(5))
      if (!n2->bad && n2 != &kf && n2->fuse_mark != kf.id) {
        n2->fuse_mark = kf.id;
        targets.push_back(n2);
      }
  long fused = 0;
  const auto own = kf.good_points();
  for (KeyFrame* t : targets) fused += fuse(*t, own, map_);
  // And the neighbours' points into this keyframe.
  std::vector<std::shared_ptr<MapPoint>> theirs;
  for (KeyFrame* t : targets)
    for (const auto& p : t->points)
      if (p && !p->bad && p->fuse_mark != kf.id) {
        p->fuse_mark = kf.id;
        theirs.push_back(p);
      }
  fused += fuse(kf, theirs, map_);
  for (const auto& p : kf.points)
    if (p && !p->bad) {
      p->update_descriptor();
      p->update_normal_and_depth();
    }
  kf.update_connections();
  std::lock_guard s(stats_mutex_);
  stats_.points_fused += fused;
}

void LocalMapping::local_bundle_adjustment(KeyFrame& kf) {
  BundleAdjustmentProblem pb;
  pb.planar = opt_.planar;
  std::vector<std::shared_ptr<KeyFrame>> cams;
  std::vector<std::shared_ptr<MapPoint>> pts;
  struct Link {
    KeyFrame* kf;
    MapPoint* point;
    int index;
  };
  std::vector<Link> links;
  std::vector<std::shared_ptr<MapPlane>> planes;
  {
    std::lock_guard lock(map_.mutex());
    if (kf.bad) return;
    pb.K = local_ba_intrinsics_of(*kf.f->ctx);
    std::unordered_map<KeyFrame*, int> cam_index;
    std::vector<char> keep_far;  // per camera: KeyFrame::keeps_far_readings
    auto add_cam = [&](KeyFrame* k, bool fixed) {
      cam_index[k] = static_cast<int>(cams.size());
      cams.push_back(k->shared_from_this());
      pb.cameras.push_back({k->pose(), fixed || k->id == 0});
      keep_far.push_back(k->keeps_far_readings());
    };
    add_cam(&kf, false);
    kf.ba_local_mark = kf.id;
    for (KeyFrame* n : kf.best_covisibles(static_cast<std::size_t>(opt_.ba_window))) {
      if (n->bad) continue;
      n->ba_local_mark = kf.id;
      add_cam(n, false);
    }
    const std::size_t local_count = cams.size();
    for (std::size_t c = 0; c < local_count; ++c)
      for (const auto& p : cams[c]->points)
        if (p && !p->bad && p->ba_mark != kf.id) {
          p->ba_mark = kf.id;
          pts.push_back(p);
        }
    for (std::size_t i = 0; i < pts.size(); ++i) {
      pb.points.push_back(pts[i]->position);
      for (const auto& [okf, idx] : pts[i]->observations) {
        if (okf->bad) continue;
        auto it = cam_index.find(okf);
        if (it == cam_index.end()) {
          add_cam(okf, true);  // observes local points but is not local: fixed
          it = cam_index.find(okf);
        }
        const auto is = static_cast<std::size_t>(idx);
        BundleAdjustmentProblem::Measurement m;
        m.camera = it->second;
        m.point = static_cast<int>(i);
        m.o = okf->f->observation(is, keep_far[static_cast<std::size_t>(it->second)]);
        pb.measurements.push_back(m);
        links.push_back({okf, pts[i].get(), idx});
      }
    }
    add_depth_links(cams, pb);
    planes = add_plane_terms(cams, pb, opt_.planes, opt_.planes.anchors);
  }
  if (abort_ba_) return;
  LocalBADisparityChoice disparity;  // not measured, held: the stats count nothing
  if (!(kf.f->ctx->local_ba_disparity_sigma > 0)) {
    disparity = choose_local_ba_disparity_sigma(pb, opt_.ba_disparity);
    pb.K.disparity_sigma = disparity.sigma;
  }
  const auto r = solve_bundle_adjustment(pb, {}, &abort_ba_);
  {
    std::lock_guard s(stats_mutex_);
    ++stats_.bundle_adjustments;
    stats_.bundle_adjustments_aborted += r.aborted;
    stats_.bundle_adjustments_not_held += !disparity.held;
    if (disparity.measured > 0) {
      ++stats_.bundle_adjustments_measured_disparity;
      stats_.ba_disparity_sigma_sum += disparity.sigma;
    }
  }
  if (!r.solved) return;
  std::lock_guard lock(map_.mutex());
  for (std::size_t m = 0; m < links.size(); ++m) {
    if (r.measurement_inlier[m]) continue;
    const auto& l = links[m];
    if (l.kf->bad) continue;
    auto& slot = l.kf->points[static_cast<std::size_t>(l.index)];
    if (slot.get() != l.point || l.point->bad) continue;
    auto keep = slot;
    l.kf->erase_point(l.index);
    keep->erase_observation(l.kf, map_);
  }
  for (std::size_t c = 0; c < cams.size(); ++c)
    if (!pb.cameras[c].fixed && !cams[c]->bad) cams[c]->set_pose(r.poses[c]);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (pts[i]->bad) continue;
    pts[i]->position = r.points[i];
    pts[i]->update_normal_and_depth();
  }
  store_solved_planes(planes, r.planes);
}

void LocalMapping::cull_keyframes(KeyFrame& kf) {
  long culled = 0;
  const auto neighbours = kf.ordered_connections;
  for (KeyFrame* n : neighbours) {
    if (n->bad) continue;
    if (is_redundant_keyframe(*n, opt_.redundant_ratio, opt_.redundant_min_observers)) {
      n->set_bad(map_);
      ++culled;
    }
  }
  std::lock_guard s(stats_mutex_);
  stats_.keyframes_culled += culled;
}

}  // namespace builtscene::slam
