#include "slam/matcher.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"
#include "slam/observation.hpp"
#include "slam/pose_optimizer.hpp"

namespace builtscene::slam {

void RotationConsistency::add(float a, float b, int match) {
  float d = a - b;
  if (d < 0) d += 360.0f;
  int bin = static_cast<int>(std::lround(d * kBins / 360.0f));
  if (bin == kBins) bin = 0;
  bins_[std::clamp(bin, 0, kBins - 1)].push_back(match);
}

std::vector<int> RotationConsistency::inconsistent() const {
  int top[3] = {-1, -1, -1};
  std::size_t size[3] = {0, 0, 0};
  for (int b = 0; b < kBins; ++b) {
    const std::size_t s = bins_[b].size();
    if (s > size[0]) {
      size[2] = size[1], top[2] = top[1];
      size[1] = size[0], top[1] = top[0];
      size[0] = s, top[0] = b;
    } else if (s > size[1]) {
      size[2] = size[1], top[2] = top[1];
      size[1] = s, top[1] = b;
    } else if (s > size[2]) {
      size[2] = s, top[2] = b;
    }
  }
  // Weak secondary peaks (under a tenth of the main one) are not trusted either.
  if (size[1] < 0.1 * static_cast<double>(size[0])) top[1] = top[2] = -1;
  else if (size[2] < 0.1 * static_cast<double>(size[0])) top[2] = -1;
  std::vector<int> out;
  for (int b = 0; b < kBins; ++b) {
    if (b == top[0] || b == top[1] || b == top[2]) continue;
    out.insert(out.end(), bins_[b].begin(), bins_[b].end());
  }
  return out;
}

int search_by_projection(Frame& current, const Frame& last, float th) {
  const auto& f = *current.f;
  const auto& ctx = *f.ctx;
  const auto& metric = ctx.metric;
  const Intrinsics K = intrinsics_of(ctx);
  RotationConsistency rot;
  int matches = 0;
  for (std::size_t i = 0; i < last.points.size(); ++i) {
    const auto& p = last.points[i];
    if (!p || last.outlier[i] || p->bad || p->descriptor.empty()) continue;
    const Eigen::Vector3d pc = current.T_cw * p->position;
    if (pc.z() <= 0) continue;
    const double inv_z = 1.0 / pc.z();
    const float u = static_cast<float>(K.fx * pc.x() * inv_z + K.cx), v = static_cast<float>(K.fy * pc.y() * inv_z + K.cy);
    if (!ctx.in_image(u, v)) continue;
    const int level = last.f->keys_un[i].octave;
    const float r = th * ctx.pyramid.scale[static_cast<std::size_t>(level)];
    const auto cand = f.in_area(u, v, r, std::max(0, level - 1), level + 1);
    if (cand.empty()) continue;
    const float ur = static_cast<float>(u - K.bf * inv_z);
    float best = metric.infinity();
    int best_i = -1;
    for (int c : cand) {
      const auto& existing = current.points[static_cast<std::size_t>(c)];
      if (existing && existing->observation_count() > 0) continue;
      if (const float fu = f.measured_u_right(static_cast<std::size_t>(c)); fu >= 0 && std::abs(ur - fu) > r) continue;
      const float d = metric.distance(p->descriptor, 0, f.descriptors, c);
      if (d < best) {
        best = d;
        best_i = c;
      }
    }
    if (best_i < 0 || best > metric.loose) continue;
    current.points[static_cast<std::size_t>(best_i)] = p;
    current.outlier[static_cast<std::size_t>(best_i)] = 0;
    rot.add(last.f->keys_un[i].angle, f.keys_un[static_cast<std::size_t>(best_i)].angle, best_i);
    ++matches;
  }
  for (int idx : rot.inconsistent()) {
    current.points[static_cast<std::size_t>(idx)] = nullptr;
    --matches;
  }
  return matches;
}

int search_local_points(Frame& frame, const std::vector<ProjectedPoint>& candidates, float th) {
  const auto& f = *frame.f;
  const auto& ctx = *f.ctx;
  const auto& metric = ctx.metric;
  int matches = 0;
  for (const auto& c : candidates) {
    const auto& p = c.point;
    if (p->bad || p->descriptor.empty()) continue;
    const float r = th * (c.view_cos > 0.998f ? 2.5f : 4.0f) * ctx.pyramid.scale[static_cast<std::size_t>(c.level)];
    const auto cand = f.in_area(c.u, c.v, r, c.level - 1, c.level);
    float best = metric.infinity(), second = metric.infinity();
    int best_i = -1, best_level = -1, second_level = -1;
    for (int k : cand) {
      const auto ks = static_cast<std::size_t>(k);
      if (frame.points[ks] && frame.points[ks]->observation_count() > 0) continue;
      if (const float fu = f.measured_u_right(ks); c.u_right >= 0 && fu >= 0 && std::abs(c.u_right - fu) > r) continue;
      const float d = metric.distance(p->descriptor, 0, f.descriptors, k);
      if (d < best) {
        second = best;
        second_level = best_level;
        best = d;
        best_level = f.keys_un[ks].octave;
        best_i = k;
      } else if (d < second) {
        second = d;
        second_level = f.keys_un[ks].octave;
      }
    }
    if (best_i < 0 || best > metric.loose) continue;
    if (best_level == second_level && best > 0.8f * second) continue;
    frame.points[static_cast<std::size_t>(best_i)] = p;
    frame.outlier[static_cast<std::size_t>(best_i)] = 0;
    ++matches;
  }
  return matches;
}

int search_by_descriptor(const KeyFrame& kf, Frame& frame) {
  const auto& f = *frame.f;
  const auto& metric = f.ctx->metric;
  std::vector<float> best_for_kp(f.size(), metric.infinity());
  std::vector<int> owner(f.size(), -1);  // kf keypoint index matched to each frame keypoint
  for (std::size_t i = 0; i < kf.points.size(); ++i) {
    const auto& p = kf.points[i];
    if (!p || p->bad) continue;
    float best = metric.infinity(), second = metric.infinity();
    int best_j = -1;
    for (int j = 0; j < static_cast<int>(f.size()); ++j) {
      const float d = metric.distance(kf.f->descriptors, static_cast<int>(i), f.descriptors, j);
      if (d < best) {
        second = best;
        best = d;
        best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j < 0 || best > metric.strict || best > 0.7f * second) continue;
    const auto js = static_cast<std::size_t>(best_j);
    if (best < best_for_kp[js]) {
      best_for_kp[js] = best;
      owner[js] = static_cast<int>(i);
    }
  }
  RotationConsistency rot;
  int matches = 0;
  for (std::size_t j = 0; j < f.size(); ++j) {
    if (owner[j] < 0) continue;
    frame.points[j] = kf.points[static_cast<std::size_t>(owner[j])];
    frame.outlier[j] = 0;
    rot.add(kf.f->keys_un[static_cast<std::size_t>(owner[j])].angle, f.keys_un[j].angle, static_cast<int>(j));
    ++matches;
  }
  for (int idx : rot.inconsistent()) {
    frame.points[static_cast<std::size_t>(idx)] = nullptr;
    --matches;
  }
  return matches;
}

int fuse(KeyFrame& kf, const std::vector<std::shared_ptr<MapPoint>>& points, Map& map, float th) {
  const auto& f = *kf.f;
  const auto& ctx = *f.ctx;
  const auto& metric = ctx.metric;
  const Intrinsics K = intrinsics_of(ctx);
  const SE3& T = kf.pose();
  const Eigen::Vector3d O = kf.camera_center();
  int fused = 0;
  for (const auto& p : points) {
    if (!p || p->bad || p->observed_by(&kf) || p->descriptor.empty()) continue;
    const Eigen::Vector3d pc = T * p->position;
    if (pc.z() <= 0) continue;
    const double inv_z = 1.0 / pc.z();
    const double u = K.fx * pc.x() * inv_z + K.cx, v = K.fy * pc.y() * inv_z + K.cy;
    if (!ctx.in_image(u, v)) continue;
    const Eigen::Vector3d po = p->position - O;
    const double dist = po.norm();
    if (dist < 0.8 * p->min_distance || dist > 1.2 * p->max_distance) continue;
    if (po.dot(p->normal) < 0.5 * dist) continue;
    const int level = p->predict_level(dist, ctx.pyramid);
    const float r = th * ctx.pyramid.scale[static_cast<std::size_t>(level)];
    const auto cand = f.in_area(static_cast<float>(u), static_cast<float>(v), r, level - 1, level);
    const double ur = u - K.bf * inv_z;
    float best = metric.infinity();
    int best_i = -1;
    for (int k : cand) {
      const auto ks = static_cast<std::size_t>(k);
      const auto& kp = f.keys_un[ks];
      const double inv_s2 = ctx.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)];
      double e2 = (u - kp.pt.x) * (u - kp.pt.x) + (v - kp.pt.y) * (v - kp.pt.y);
      if (const float fu = f.measured_u_right(ks); fu >= 0) {
        e2 += (ur - fu) * (ur - fu);
        if (e2 * inv_s2 > kChi2Stereo) continue;
      } else if (e2 * inv_s2 > kChi2Mono) {
        continue;
      }
      const float d = metric.distance(p->descriptor, 0, f.descriptors, k);
      if (d < best) {
        best = d;
        best_i = k;
      }
    }
    if (best_i < 0 || best > metric.strict) continue;
    auto existing = kf.points[static_cast<std::size_t>(best_i)];
    if (existing && !existing->bad) {
      if (existing->observation_count() >= p->observation_count()) p->replace_with(existing, map);
      else existing->replace_with(p, map);
    } else {
      p->add_observation(&kf, best_i);
      kf.add_point(best_i, p);
    }
    ++fused;
  }
  return fused;
}

int search_keyframe_neighbourhood(Frame& frame, const KeyFrame& candidate, std::size_t neighbours, float th) {
  const auto& ctx = *frame.f->ctx;
  const Intrinsics K = intrinsics_of(ctx);
  const Eigen::Vector3d O = frame.camera_center();
  std::vector<KeyFrame*> kfs = candidate.best_covisibles(neighbours);
  kfs.push_back(const_cast<KeyFrame*>(&candidate));
  std::vector<const MapPoint*> already;
  for (const auto& p : frame.points)
    if (p) already.push_back(p.get());
  std::sort(already.begin(), already.end());
  std::vector<ProjectedPoint> candidates;
  std::unordered_set<const MapPoint*> seen;
  for (KeyFrame* kf : kfs) {
    if (kf->bad) continue;
    for (const auto& p : kf->points) {
      if (!p || p->bad || std::binary_search(already.begin(), already.end(), p.get())) continue;
      if (!seen.insert(p.get()).second) continue;
      const Eigen::Vector3d pc = frame.T_cw * p->position;
      if (pc.z() <= 0) continue;
      const double inv_z = 1.0 / pc.z();
      const double u = K.fx * pc.x() * inv_z + K.cx, v = K.fy * pc.y() * inv_z + K.cy;
      if (!ctx.in_image(u, v)) continue;
      const Eigen::Vector3d po = p->position - O;
      const double dist = po.norm();
      if (dist < 0.8 * p->min_distance || dist > 1.2 * p->max_distance) continue;
      const double view_cos = po.dot(p->normal) / dist;
      if (view_cos < 0.5) continue;
      candidates.push_back({p, static_cast<float>(u), static_cast<float>(v), static_cast<float>(u - K.bf * inv_z),
                            p->predict_level(dist, ctx.pyramid), static_cast<float>(view_cos)});
    }
  }
  return search_local_points(frame, candidates, th);
}

}  // namespace builtscene::slam
