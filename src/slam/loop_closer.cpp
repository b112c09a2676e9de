#include "slam/loop_closer.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "core/disjoint_sets.hpp"
#include "core/logging.hpp"
#include "features/bow_vector.hpp"
#include "slam/bow_matcher.hpp"
#include "slam/disparity_noise.hpp"
#include "slam/key_frame.hpp"
#include "slam/keyframe_database.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "slam/local_mapping.hpp"
#include "slam/loop_fusion.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"
#include "slam/matcher.hpp"
#include "slam/pose_graph_optimizer.hpp"
#include "slam/pose_optimizer.hpp"
#include "slam/rigid_transform_ransac.hpp"

namespace builtscene::slam {

struct LoopCloser::LoopMatch {
  std::shared_ptr<KeyFrame> candidate;
  SE3 T_cw;  // the current keyframe's pose that agrees with the candidate's map
  std::vector<std::shared_ptr<MapPoint>> points;  // per keypoint of the current keyframe: loop-side point
  int inliers = 0;
};

namespace {

std::vector<LoopEvent::KeyFramePose> keyframe_poses(const Map& map) {
  std::vector<LoopEvent::KeyFramePose> out;
  for (const auto& k : map.keyframes())
    if (!k->bad) out.push_back({k->id, k->timestamp, k->pose_inverse()});
  return out;
}

}  // namespace

LoopCloser::LoopCloser(Map& map, const KeyFrameDatabase& database, LocalMapping* mapping, LoopClosingOptions options,
                       bool threaded, StageTimer* timer)
    : map_(map), db_(database), mapping_(mapping), opt_(options), threaded_(threaded), timer_(timer),
      consistency_(options.consistency) {}

LoopCloser::~LoopCloser() { finish(); }

void LoopCloser::add_time(const char* stage, std::chrono::steady_clock::time_point start) const {
  if (timer_) timer_->add(stage, ms_since(start));
}

void LoopCloser::emit(const LoopEvent& e) const {
  if (sink_) sink_(e);
}

LoopCloser::Stats LoopCloser::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

void LoopCloser::start() {
  if (thread_.joinable()) return;
  {
    std::lock_guard lock(queue_mutex_);
    stop_ = false;
  }
  thread_ = std::thread([this] { run(); });
}

void LoopCloser::insert_keyframe(std::shared_ptr<KeyFrame> kf) {
  {
    std::lock_guard lock(queue_mutex_);
    queue_.push_back(std::move(kf));
  }
  queue_cv_.notify_one();
}

void LoopCloser::run_pending() {
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
  }
}

void LoopCloser::finish() {
  {
    std::lock_guard lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  run_pending();
  // The global BA of the last loop is worth waiting for: it is the best map there will be.
  if (gba_thread_.joinable()) gba_thread_.join();
  if (opt_.close_at_end) close_at_end();
}

void LoopCloser::close_at_end() {
  const auto kf = end_query_.lock();
  const auto candidates = std::move(end_candidates_);
  end_candidates_.clear();
  // Only a place recognised at the very end: older chains had later keyframes to confirm them.
  if (!kf || candidates.empty() || consistency_checks_ - end_check_ >= opt_.close_at_end_window) return;
  std::unique_ptr<LoopMatch> match;
  {
    std::lock_guard lock(map_.mutex());
    if (kf->bad) return;
    std::vector<std::shared_ptr<KeyFrame>> alive;  // held while verified
    std::vector<KeyFrame*> good;
    for (const auto& c : candidates)
      if (auto k = c.lock(); k && !k->bad) {
        good.push_back(k.get());
        alive.push_back(std::move(k));
      }
    match = verify_first(*kf, good, /*at_end=*/true);
  }
  if (!match) return;
  {
    std::lock_guard s(stats_mutex_);
    ++stats_.loops_closed_at_end;
  }
  correct(kf, *match);
  if (gba_thread_.joinable()) gba_thread_.join();
}

void LoopCloser::refine_map() {
  if (refined_ || !opt_.final_bundle_adjustment || !opt_.global_bundle_adjustment) return;
  refined_ = true;
  const long loops = stats().loops;
  if (loops == 0) return;  // nothing has tied the map together; local BA already did its part
  long newest = -1;
  {
    std::lock_guard lock(map_.mutex());
    for (const auto& k : map_.keyframes())
      if (!k->bad) newest = std::max(newest, k->id);
  }
  run_global_ba(loops, newest, -1, /*final_pass=*/true);
}

void LoopCloser::run() {
  for (;;) {
    std::shared_ptr<KeyFrame> kf;
    {
      std::unique_lock lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;
      kf = queue_.front();
      queue_.pop_front();
    }
    process(kf);
  }
}

void LoopCloser::process(const std::shared_ptr<KeyFrame>& kf) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<LoopMatch> match;
  {
    std::lock_guard lock(map_.mutex());
    match = detect(*kf);
  }
  add_time("loop_detection", start);
  if (match) correct(kf, *match);
}

std::unique_ptr<LoopCloser::LoopMatch> LoopCloser::detect(KeyFrame& kf) {
  if (kf.bad || kf.bow.empty()) return nullptr;
  {
    std::lock_guard s(stats_mutex_);
    ++stats_.keyframes_checked;
  }
  if (static_cast<int>(map_.keyframe_count()) < opt_.min_keyframes || kf.id < last_loop_kf_id_ + opt_.min_keyframes)
    return nullptr;
  // The place must look more like the candidate than the keyframe's least similar
  // covisible neighbour does (ORB-SLAM2's relative minimum score).
  double min_score = 1.0;
  for (const KeyFrame* n : kf.ordered_connections)
    if (!n->bad && !n->bow.empty()) min_score = std::min(min_score, bow_l1_score(kf.bow, n->bow));
  std::vector<LoopConsistency::Candidate> candidates;
  std::unordered_map<long, KeyFrame*> by_id;
  for (KeyFrame* c : db_.loop_candidates(kf, min_score)) {
    if (c->bad || c->id > kf.id - opt_.min_keyframe_gap) continue;
    LoopConsistency::Candidate cand{c->id, {}};
    for (const auto& [n, w] : c->connections) cand.group.push_back(n->id);
    candidates.push_back(std::move(cand));
    by_id[c->id] = c;
  }
  const auto accepted = consistency_.update(candidates);
  ++consistency_checks_;
  // The newest keyframe whose place fell one short, kept for the end of the run: the last
  // keyframes may no longer see it (seed 1 of the generated corridor: one short at frame 7140,
  // the run's last keyframe at 7148 matched other candidates that failed verification).
  if (!consistency_.one_short().empty()) {
    end_query_ = kf.shared_from_this();
    end_candidates_.clear();
    for (long id : consistency_.one_short()) end_candidates_.push_back(by_id.at(id)->shared_from_this());
    end_check_ = consistency_checks_;
  }
  std::vector<KeyFrame*> consistent;
  for (long id : accepted) consistent.push_back(by_id.at(id));
  auto m = verify_first(kf, consistent, /*at_end=*/false);
  if (m) end_candidates_.clear();  // a loop closed after it: nothing is left open
  return m;
}

std::unique_ptr<LoopCloser::LoopMatch> LoopCloser::verify_first(KeyFrame& kf, const std::vector<KeyFrame*>& candidates,
                                                                bool at_end) {
  for (KeyFrame* c : candidates) {
    {
      std::lock_guard s(stats_mutex_);
      ++stats_.consistent_candidates;
      stats_.end_candidates += at_end;
    }
    if (auto m = verify(kf, *c)) return m;
    std::lock_guard s(stats_mutex_);
    ++stats_.rejected;
  }
  return nullptr;
}

std::unique_ptr<LoopCloser::LoopMatch> LoopCloser::verify(KeyFrame& kf, KeyFrame& cand) {
  if (cand.bow_features.empty() || kf.bow_features.empty()) return nullptr;
  int n = 0;
  const auto matches = search_by_bow(cand, *kf.f, kf.bow_features, &n);
  auto reject = [&](const char* stage, int count) {
    spdlog::debug("loop candidate {} for keyframe {} (frame {}): {} ({})", cand.id, kf.id, kf.frame_id, stage, count);
    return nullptr;
  };
  if (n < opt_.min_bow_matches) return reject("too few BoW matches", n);
  // 3D-3D pairs in the two cameras' frames: the candidate's points, and for the current
  // keyframe its own map point at the keypoint (or the keypoint's depth).
  const SE3 T1 = kf.pose(), T2 = cand.pose();
  std::vector<Eigen::Vector3d> src, dst;
  std::vector<std::size_t> keypoint;
  for (std::size_t j = 0; j < matches.size(); ++j) {
    if (!matches[j] || matches[j]->bad) continue;
    Eigen::Vector3d p1;
    const auto& own = kf.points[j];
    if (own && !own->bad) p1 = T1 * own->position;
    else if (kf.f->has_depth(j)) p1 = kf.f->unproject(j);
    else continue;
    src.push_back(T2 * matches[j]->position);
    dst.push_back(p1);
    keypoint.push_back(j);
  }
  if (static_cast<int>(src.size()) < opt_.ransac_min_inliers) return reject("too few 3D-3D pairs", static_cast<int>(src.size()));
  const auto fit = ransac_rigid_transform(src, dst, opt_.ransac_inlier_m, opt_.ransac_min_inliers, opt_.ransac_iterations,
                                          static_cast<std::uint32_t>(kf.id));
  if (!fit) return reject("no rigid transform by RANSAC; pairs", static_cast<int>(src.size()));
  const SE3 T12(Eigen::Matrix3d(fit->transform.linear()), Eigen::Vector3d(fit->transform.translation()));
  // The keyframe relocalized against the candidate's map: reprojection errors decide.
  Frame frame(kf.frame_id, kf.timestamp, kf.f);
  frame.set_pose(T12 * T2);
  for (std::size_t k = 0; k < keypoint.size(); ++k)
    if (fit->inliers[k]) frame.points[keypoint[k]] = matches[keypoint[k]];
  optimize_frame_pose(frame);
  int good = frame.keep_inlier_matches();
  if (good < opt_.min_refined_inliers) return reject("too few inliers after pose refinement", good);
  search_keyframe_neighbourhood(frame, cand, cand.ordered_connections.size(), opt_.guided_search_radius);
  optimize_frame_pose(frame);
  good = frame.keep_inlier_matches();
  if (good < opt_.min_inliers) return reject("too few inliers after the guided search", good);
  // How far the loop would move the keyframe; both rules below judge it.
  const SE3 correction = frame.T_cw.inverse() * T1;
  const double angle_deg = Eigen::AngleAxisd(correction.rotation()).angle() * 180.0 / M_PI;
  const double moved = (frame.camera_center() - kf.camera_center()).norm();
  // Path length along the keyframes in id order, for both rules below.
  std::unordered_map<long, double> path_at;
  {
    double path_m = 0;
    const KeyFrame* prev = nullptr;
    for (const auto& k : map_.keyframes()) {  // by id
      if (k->bad || k->id > kf.id) continue;
      if (prev) path_m += (k->camera_center() - prev->camera_center()).norm();
      path_at[k->id] = path_m;
      prev = k.get();
    }
  }
  auto path_between = [&](const KeyFrame& a, const KeyFrame& b) {
    const auto ia = path_at.find(a.id), ib = path_at.find(b.id);
    return ia == path_at.end() || ib == path_at.end() ? 0.0 : std::abs(ib->second - ia->second);
  };
  // Anchored: the keyframe shares points with an older keyframe it came back to, i.e. one
  // much further away along the path than in space. Keyframes that merely see far along
  // a straight corridor share points with keyframes 20-60 ids back too, but their path and
  // distance agree; counting those made every loop in a corridor "anchored" (a true
  // 3.3 m correction at the end of the 79 m corridor loop was refused).
  bool anchored = false;
  for (const auto& [n, w] : kf.connections) {
    if (n->bad || n->id >= kf.id - opt_.min_keyframe_gap) continue;
    const double apart = (n->camera_center() - kf.camera_center()).norm();
    anchored |= path_between(*n, kf) > opt_.revisit_path_ratio * apart + opt_.revisit_margin_m;
  }
  if (anchored) {
    if (moved > opt_.max_anchored_correction_m || angle_deg > opt_.max_anchored_correction_deg) {
      spdlog::info("loop candidate {} for keyframe {} (frame {}) rejected: {} inliers, but it would move a keyframe "
                   "tied to older ones by {:.2f} m / {:.1f} deg",
                   cand.id, kf.id, kf.frame_id, good, moved, angle_deg);
      std::lock_guard s(stats_mutex_);
      ++stats_.rejected_anchored;
      return nullptr;
    }
  }
  {
    const double path_m = path_between(cand, kf);
    const double max_m = opt_.max_correction_base_m + opt_.max_correction_per_metre * path_m;
    const double max_deg = opt_.max_correction_base_deg + opt_.max_correction_deg_per_metre * path_m;
    if (moved > max_m || angle_deg > max_deg) {
      spdlog::info("loop candidate {} for keyframe {} (frame {}) rejected: {} inliers, but a correction of {:.2f} m / "
                   "{:.1f} deg is more than {:.1f} m of path could drift ({:.2f} m / {:.1f} deg)",
                   cand.id, kf.id, kf.frame_id, good, moved, angle_deg, path_m, max_m, max_deg);
      std::lock_guard s(stats_mutex_);
      ++stats_.rejected_implausible;
      return nullptr;
    }
  }
  auto m = std::make_unique<LoopMatch>();
  m->candidate = cand.shared_from_this();
  m->T_cw = frame.T_cw;
  m->points = frame.points;
  m->inliers = good;
  return m;
}

void LoopCloser::stop_global_ba() {
  abort_gba_ = true;
  if (gba_thread_.joinable()) gba_thread_.join();
  abort_gba_ = false;
}

void LoopCloser::correct(const std::shared_ptr<KeyFrame>& kf, const LoopMatch& m) {
  const auto start = std::chrono::steady_clock::now();
  stop_global_ba();
  if (mapping_) {
    mapping_->request_pause();
    mapping_->wait_until_paused();
  }
  LoopEvent event;
  bool closed = false;
  int fused = 0, planes_merged = 0;
  {
    std::lock_guard lock(map_.mutex());
    KeyFrame* cand = m.candidate.get();
    if (!kf->bad && !cand->bad) {
      closed = true;
      kf->update_connections();
      const auto all = map_.keyframes();
      std::unordered_map<const KeyFrame*, SE3> before;  // T_cw before the correction
      for (const auto& k : all) before[k.get()] = k->pose();

      // The keyframe, its covisible keyframes, and keyframes tracking made after it that
      // local mapping has not linked into the graph yet (they sit right behind it).
      std::vector<KeyFrame*> connected{kf.get()};
      for (KeyFrame* n : kf->ordered_connections)
        if (!n->bad) connected.push_back(n);
      for (const auto& k : all)
        if (!k->has_parent_link && k->id > kf->id &&
            std::find(connected.begin(), connected.end(), k.get()) == connected.end())
          connected.push_back(k.get());
      const std::unordered_set<const KeyFrame*> connected_set(connected.begin(), connected.end());
      const SE3 T_wc_old = kf->pose_inverse();
      std::unordered_map<MapPoint*, KeyFrame*> corrector;
      for (KeyFrame* c : connected) {
        const SE3 T_new = c == kf.get() ? m.T_cw : before[c] * T_wc_old * m.T_cw;
        const SE3 move = T_new.inverse() * before[c];  // old world -> corrected world, seen from c
        for (const auto& p : c->points)
          if (p && !p->bad && corrector.emplace(p.get(), c).second) p->position = move * p->position;
        c->set_pose(T_new);
      }
      for (const auto& [p, c] : corrector) p->update_normal_and_depth();

      std::unordered_map<const KeyFrame*, std::set<const KeyFrame*>> previous;
      for (KeyFrame* c : connected)
        for (const auto& [n, w] : c->connections) previous[c].insert(n);
      fused += fuse_loop_matches(*kf, m.points, map_);
      const auto loop_points = neighbourhood_points(*cand);
      for (KeyFrame* c : connected) fused += fuse(*c, loop_points, map_, opt_.fuse_radius);

      // Links the fusion created between the two sides: the loop connections.
      struct Link {
        KeyFrame *a, *b;
        int weight;
      };
      std::vector<Link> loop_links;
      for (KeyFrame* c : connected) {
        if (c->bad) continue;
        c->update_connections();
        for (const auto& [n, w] : c->connections)
          if (!previous[c].count(n) && !connected_set.count(n)) loop_links.push_back({c, n, w});
      }
      kf->loop_edges.insert(cand);
      cand->loop_edges.insert(kf.get());
      kf->keep = cand->keep = true;

      // Essential graph. Odometry-like edges (tree, strong covisibility, earlier loops) keep
      // the relative poses from before the correction; the new loop's edges take the
      // corrected ones: the optimization spreads the loop's error along the graph.
      const auto live = map_.keyframes();
      PoseGraph graph;
      std::unordered_map<const KeyFrame*, int> node;
      std::vector<const KeyFrame*> node_kf;
      for (const auto& k : live) {
        if (k->bad) continue;
        node[k.get()] = static_cast<int>(graph.nodes.size());
        node_kf.push_back(k.get());
        graph.nodes.push_back({k->pose(), k.get() == cand});
      }
      std::set<std::pair<long, long>> done;
      auto add_edge = [&](const KeyFrame* a, const KeyFrame* b, const SE3& Ta, const SE3& Tb, double weight = 1.0) {
        if (!node.count(a) || !node.count(b) || a == b) return;
        if (!done.insert({std::min(a->id, b->id), std::max(a->id, b->id)}).second) return;
        graph.edges.push_back({node[a], node[b], Ta * Tb.inverse(), weight});
      };
      auto old_pose = [&](const KeyFrame* k) {
        const auto it = before.find(k);
        return it == before.end() ? k->pose() : it->second;
      };
      add_edge(kf.get(), cand, kf->pose(), cand->pose());
      for (const Link& l : loop_links)
        if (l.weight >= opt_.strong_covisibility) add_edge(l.a, l.b, l.a->pose(), l.b->pose());
      for (const auto& k : live) {
        if (k->bad) continue;
        if (k->parent && !k->parent->bad)
          add_edge(k.get(), k->parent.get(), old_pose(k.get()), old_pose(k->parent.get()),
                   k->parent_by_odometry ? opt_.odometry_edge_weight : 1.0);
        for (const KeyFrame* l : k->loop_edges) add_edge(k.get(), l, old_pose(k.get()), old_pose(l));
        for (const auto& [n, w] : k->connections)
          if (w >= opt_.strong_covisibility) add_edge(k.get(), n, old_pose(k.get()), old_pose(n));
      }
      // Parts of the graph no edge joins move rigidly: more than one is a defect. (Keyframes
      // local mapping has not linked yet, in threaded runs, are left out of the count.)
      DisjointSets joined(graph.nodes.size());
      for (const auto& ed : graph.edges) joined.join(ed.i, ed.j);
      std::set<int> part_roots;
      for (std::size_t i = 0; i < graph.nodes.size(); ++i)
        if (i == 0 || node_kf[i]->has_parent_link) part_roots.insert(joined.find(static_cast<int>(i)));
      const auto parts = static_cast<long>(part_roots.size());
      {
        std::lock_guard s(stats_mutex_);
        stats_.max_pose_graph_parts = std::max(stats_.max_pose_graph_parts, parts);
      }
      const auto t_pg = std::chrono::steady_clock::now();
      const auto result = optimize_pose_graph(graph, {opt_.pose_graph_iterations});
      add_time("pose_graph", t_pg);
      if (result.solved) {
        // The edge the optimized graph fits worst: a large residual left on an odometry-like
        // edge means the graph could not spread the loop's error (debug aid).
        double worst = 0;
        std::size_t worst_edge = 0;
        for (std::size_t e = 0; e < graph.edges.size(); ++e) {
          const auto& ed = graph.edges[e];
          const SE3 pred = result.poses[static_cast<std::size_t>(ed.i)] * result.poses[static_cast<std::size_t>(ed.j)].inverse();
          const double r = (ed.T_ij.inverse() * pred).translation().norm();
          if (r > worst) worst = r, worst_edge = e;
        }
        spdlog::debug("pose graph: {} nodes in {} connected parts, {} edges, {} iterations max, cost {:.4g} -> {:.4g}, worst edge {} - {} off by {:.3f} m",
                      graph.nodes.size(), parts, graph.edges.size(), opt_.pose_graph_iterations, result.initial_cost, result.final_cost,
                      graph.edges.empty() ? -1L : node_kf[static_cast<std::size_t>(graph.edges[worst_edge].i)]->id,
                      graph.edges.empty() ? -1L : node_kf[static_cast<std::size_t>(graph.edges[worst_edge].j)]->id, worst);
      }
      if (result.solved) {
        std::unordered_map<const KeyFrame*, SE3> pre;  // after the first correction, before the graph
        for (const auto& k : live) {
          if (k->bad || !node.count(k.get())) continue;
          pre[k.get()] = k->pose();
          k->set_pose(result.poses[static_cast<std::size_t>(node[k.get()])]);
        }
        for (const auto& p : map_.points()) {
          if (p->bad) continue;
          const auto it = corrector.find(p.get());
          const KeyFrame* r = it != corrector.end() ? it->second : p->reference;
          if (!r || r->bad || !pre.count(r)) continue;
          p->position = r->pose_inverse() * (pre[r] * p->position);
          p->update_normal_and_depth();
        }
      }
      // The planes stayed where the drifted keyframes had put them: re-estimated from their
      // observers at the corrected poses, and a wall's plane from each lap joined into one.
      if (opt_.planes.enabled) planes_merged = refit_and_merge_planes(map_, opt_.planes);
      ++loops_;
      last_loop_kf_id_ = kf->id;
      consistency_.reset();
      event.stage = LoopEvent::Stage::kPoseGraph;
      event.loop = loops_;
      event.frame = kf->frame_id;
      event.timestamp = kf->timestamp;
      event.keyframe = kf->id;
      event.matched_keyframe = cand->id;
      event.inliers = m.inliers;
      event.correction = m.T_cw.inverse() * before[kf.get()];
      event.keyframes = keyframe_poses(map_);
      spdlog::info("loop closed: keyframe {} (frame {}) with keyframe {}, {} inliers, correction {:.3f} m, {} fused, "
                   "{} graph edges, {} planes merged",
                   kf->id, kf->frame_id, cand->id, m.inliers, event.correction.translation().norm(), fused,
                   graph.edges.size(), planes_merged);
    }
  }
  if (mapping_) mapping_->resume();
  add_time("loop_correction", start);
  {
    std::lock_guard s(stats_mutex_);
    if (closed) ++stats_.loops;
    stats_.points_fused += fused;
    stats_.planes_merged += planes_merged;
  }
  if (!closed) return;
  emit(event);
  if (!opt_.global_bundle_adjustment) return;
  const long loop = event.loop, keyframe = event.keyframe, matched = event.matched_keyframe;
  if (threaded_) gba_thread_ = std::thread([this, loop, keyframe, matched] { run_global_ba(loop, keyframe, matched); });
  else run_global_ba(loop, keyframe, matched);
}

void LoopCloser::run_global_ba(long loop, long keyframe, long matched, bool final_pass) {
  const auto start = std::chrono::steady_clock::now();
  BundleAdjustmentProblem pb;
  pb.planar = opt_.planar;
  std::vector<std::shared_ptr<KeyFrame>> cams;
  std::vector<std::shared_ptr<MapPoint>> pts;
  std::vector<std::shared_ptr<MapPlane>> planes;
  int gba_planes_merged = 0, bridge_links = 0;
  DisparityNoise noise;
  {
    std::lock_guard lock(map_.mutex());
    const auto all = map_.keyframes();
    if (all.empty()) return;
    pb.K = global_ba_intrinsics_of(*all.front()->f->ctx);
    // Keyframes local mapping has not linked yet are left to follow their parent later, and so
    // are keyframes sharing (almost) no point with the others (made on the depth-odometry
    // bridge): with no measurement to hold them, they would stay behind while the rest moves.
    std::unordered_set<const KeyFrame*> linked;
    for (const auto& k : all)
      if (!k->bad && (k->has_parent_link || k == all.front())) linked.insert(k.get());
    std::unordered_map<const KeyFrame*, int> cam_index;
    std::vector<char> keep_far;  // per camera: KeyFrame::keeps_far_readings
    for (const auto& k : all) {
      if (!linked.count(k.get())) continue;
      int shared = 0;
      for (const auto& p : k->points) {
        if (!p || p->bad) continue;
        for (const auto& [okf, idx] : p->observations)
          if (okf != k.get() && linked.count(okf)) {
            ++shared;
            break;
          }
      }
      // A depth link to a keyframe already in the problem holds it as well.
      const auto link = k->depth_link_to.lock();
      const bool held_by_link = link && cam_index.count(link.get());
      if (shared < opt_.global_ba_min_shared_points && !held_by_link && k != all.front()) continue;
      cam_index[k.get()] = static_cast<int>(cams.size());
      cams.push_back(k);
      pb.cameras.push_back({k->pose(), k == all.front()});  // the oldest keyframe holds the gauge
      keep_far.push_back(k->keeps_far_readings());
    }
    for (const auto& p : map_.points()) {
      if (p->bad) continue;
      int seen = 0;
      for (const auto& [okf, idx] : p->observations) seen += cam_index.count(okf) > 0;
      if (seen < 2) continue;
      const int pi = static_cast<int>(pts.size());
      pts.push_back(p);
      pb.points.push_back(p->position);
      for (const auto& [okf, idx] : p->observations) {
        const auto it = cam_index.find(okf);
        if (it == cam_index.end()) continue;
        const auto is = static_cast<std::size_t>(idx);
        BundleAdjustmentProblem::Measurement meas;
        meas.camera = it->second;
        meas.point = pi;
        meas.o = okf->f->observation(is, keep_far[static_cast<std::size_t>(it->second)]);
        pb.measurements.push_back(meas);
      }
    }
    if (final_pass && pb.K.disparity_sigma > 0) {
      noise = estimate_disparity_noise(pb);
      if (noise.sigma > 0)
        pb.K.disparity_sigma = std::clamp(noise.sigma, opt_.final_ba_min_disparity_sigma,
                                          std::max(pb.K.disparity_sigma, opt_.final_ba_min_disparity_sigma));
    }
    add_depth_links(cams, pb);  // TrackingOptions::depth_links
    bridge_links = add_bridge_links(cams, opt_.bridge_links, pb);
    planes = add_plane_terms(cams, pb, opt_.planes, 0, /*hold_groups_as_a_whole=*/true);
  }
  {
    std::lock_guard s(stats_mutex_);
    if (final_pass) {
      ++stats_.final_ba_runs;
      stats_.final_ba_disparity_sigma = pb.K.disparity_sigma;
      stats_.final_ba_measured_disparity_sigma = noise.sigma;
    } else {
      ++stats_.global_ba_runs;
    }
  }
  BundleAdjustmentOptions bo;
  bo.first_iterations = final_pass ? opt_.final_ba_iterations : opt_.global_ba_iterations;
  bo.second_iterations = bo.first_iterations;
  const auto r = solve_bundle_adjustment(pb, bo, &abort_gba_);
  if (r.aborted || !r.solved) {
    std::lock_guard s(stats_mutex_);
    ++(final_pass ? stats_.final_ba_aborted : stats_.global_ba_aborted);
    return;
  }
  if (mapping_) {
    mapping_->request_pause();
    mapping_->wait_until_paused();
  }
  LoopEvent event;
  {
    std::lock_guard lock(map_.mutex());
    const auto all = map_.keyframes();  // by id: a parent (older) is placed before its children
    std::unordered_map<const KeyFrame*, SE3> before;
    for (const auto& k : all) before[k.get()] = k->pose();
    std::unordered_set<const KeyFrame*> solved;
    for (std::size_t c = 0; c < cams.size(); ++c) {
      if (cams[c]->bad) continue;
      solved.insert(cams[c].get());
      if (!pb.cameras[c].fixed) cams[c]->set_pose(r.poses[c]);
    }
    // Keyframes made since the copy follow their parent: same pose relative to it.
    for (const auto& k : all) {
      if (k->bad || solved.count(k.get()) || !k->parent || k->parent->bad || !before.count(k->parent.get())) continue;
      k->set_pose(before[k.get()] * before[k->parent.get()].inverse() * k->parent->pose());
    }
    std::unordered_set<const MapPoint*> moved;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i]->bad) continue;
      pts[i]->position = r.points[i];
      moved.insert(pts[i].get());
    }
    for (const auto& p : map_.points()) {
      if (p->bad) continue;
      if (!moved.count(p.get()) && p->reference && before.count(p->reference))
        p->position = p->reference->pose_inverse() * (before[p->reference] * p->position);
      p->update_normal_and_depth();
    }
    store_solved_planes(planes, r.planes);
    if (opt_.planes.enabled) gba_planes_merged = refit_and_merge_planes(map_, opt_.planes, /*refit=*/false);
    event.stage = final_pass ? LoopEvent::Stage::kFinalBundleAdjustment : LoopEvent::Stage::kGlobalBundleAdjustment;
    event.loop = loop;
    event.keyframe = keyframe;
    event.matched_keyframe = matched;
    for (const auto& k : all)
      if (k->id == keyframe) {
        event.frame = k->frame_id;
        event.timestamp = k->timestamp;
      }
    event.keyframes = keyframe_poses(map_);
  }
  if (mapping_) mapping_->resume();
  {
    std::lock_guard s(stats_mutex_);
    if (!final_pass) ++stats_.global_ba_merged;
    stats_.planes_merged += gba_planes_merged;
  }
  add_time(final_pass ? "final_ba" : "global_ba", start);
  if (final_pass)
    spdlog::info("final BA merged: {} keyframes, {} points, disparity sigma {:.3f} px (measured {:.3f} px over {} readings), "
                 "RMS {:.2f} -> {:.2f} px",
                 cams.size(), pts.size(), pb.K.disparity_sigma, noise.sigma, noise.readings, r.initial_rms_px, r.final_rms_px);
  else
    spdlog::info("global BA after loop {} merged: {} keyframes, {} points, {} bridge links, RMS {:.2f} -> {:.2f} px", loop,
                 cams.size(), pts.size(), bridge_links, r.initial_rms_px, r.final_rms_px);
  emit(event);
}

}  // namespace builtscene::slam
