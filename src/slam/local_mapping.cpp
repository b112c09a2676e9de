#include "slam/local_mapping.hpp"

#include <chrono>

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
  stop_ = false;
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

void LocalMapping::insert_keyframe(std::shared_ptr<KeyFrame> kf) {
  if (!thread_.joinable()) {
    process(kf);
    return;
  }
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(kf));
    idle_ = false;
    abort_ba_ = true;
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
      queue_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop requested and nothing left
      kf = queue_.front();
      queue_.pop_front();
      idle_ = false;
    }
    process(kf);
  }
}

void LocalMapping::process(const std::shared_ptr<KeyFrame>& kf) {
  const auto start = std::chrono::steady_clock::now();
  abort_ba_ = false;
  {
    std::lock_guard lock(map_.mutex());
    if (kf->bad) return;
    insert_into_map(*kf);
    cull_recent_points(*kf);
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
  std::vector<std::shared_ptr<KeyFrame>> cams;
  std::vector<std::shared_ptr<MapPoint>> pts;
  struct Link {
    KeyFrame* kf;
    MapPoint* point;
    int index;
  };
  std::vector<Link> links;
  {
    std::lock_guard lock(map_.mutex());
    if (kf.bad) return;
    pb.K = intrinsics_of(*kf.f->ctx);
    std::unordered_map<KeyFrame*, int> cam_index;
    auto add_cam = [&](KeyFrame* k, bool fixed) {
      cam_index[k] = static_cast<int>(cams.size());
      cams.push_back(k->shared_from_this());
      pb.cameras.push_back({k->pose(), fixed || k->id == 0});
    };
    add_cam(&kf, false);
    kf.ba_local_mark = kf.id;
    for (KeyFrame* n : kf.ordered_connections) {
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
    const auto& pyr = kf.f->ctx->pyramid;
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
        m.o.uv = {okf->f->keys_un[is].pt.x, okf->f->keys_un[is].pt.y};
        m.o.u_right = okf->f->u_right[is];
        m.o.inv_sigma2 = pyr.inv_sigma2[static_cast<std::size_t>(okf->f->keys_un[is].octave)];
        pb.measurements.push_back(m);
        links.push_back({okf, pts[i].get(), idx});
      }
    }
  }
  if (abort_ba_) return;
  const auto r = solve_bundle_adjustment(pb, {}, &abort_ba_);
  {
    std::lock_guard s(stats_mutex_);
    ++stats_.bundle_adjustments;
    stats_.bundle_adjustments_aborted += r.aborted;
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
