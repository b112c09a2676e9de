#include "slam/plane_landmark.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "slam/camera_groups.hpp"
#include "slam/key_frame.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "slam/map.hpp"

namespace builtscene::slam {

PlaneMeasurement plane_in_world(const PlaneMeasurement& m_c, const SE3& T_cw) {
  // n_c.X_c + d_c = 0 with X_c = R X_w + t: (R^T n_c).X_w + (d_c + n_c.t) = 0.
  PlaneMeasurement w = m_c;
  w.n_c = T_cw.rotation_matrix().transpose() * m_c.n_c;
  w.d_c = m_c.d_c + m_c.n_c.dot(T_cw.translation());
  return w;
}

namespace {

// The inlier-weighted mean of camera-frame plane measurements moved into the world: where bundle
// adjustment starts a map plane (add_plane_terms) and where a loop correction re-fits it.
class PlaneMean {
 public:
  void add(const PlaneMeasurement& m_c, const SE3& T_cw) {
    const PlaneMeasurement w = plane_in_world(m_c, T_cw);
    const double wt = static_cast<double>(std::max<std::size_t>(m_c.inliers, 1));
    n_ += wt * w.n_c;
    d_ += wt * w.d_c;
    w_ += wt;
  }
  bool empty() const { return w_ <= 0 || n_.norm() <= 0; }
  Eigen::Vector3d normal_or(const Eigen::Vector3d& fallback) const {
    return n_.norm() > 0 ? Eigen::Vector3d(n_.normalized()) : fallback;
  }
  double offset_or(double fallback) const { return w_ > 0 ? d_ / w_ : fallback; }

 private:
  Eigen::Vector3d n_ = Eigen::Vector3d::Zero();
  double d_ = 0, w_ = 0;
};

}  // namespace

void associate_planes(KeyFrame& kf, Map& map, const PlaneLandmarkOptions& opt) {
  const double cos_match = std::cos(opt.match_deg * M_PI / 180.0);
  const Eigen::Vector3d centre = kf.camera_center();
  std::vector<const MapPlane*> taken;
  for (auto& p : kf.planes) {
    if (p.landmark) continue;
    const PlaneMeasurement w = plane_in_world(p.m, kf.pose());
    std::shared_ptr<MapPlane> best;
    double best_gap = opt.match_m;
    for (const auto& mp : map.planes()) {
      if (std::find(taken.begin(), taken.end(), mp.get()) != taken.end()) continue;
      if (mp->n_w.dot(w.n_c) < cos_match || (mp->last_seen_from - centre).norm() > opt.match_range_m) continue;
      const double gap = std::abs(mp->d_w - w.d_c);
      if (gap < best_gap) best_gap = gap, best = mp;
    }
    if (!best) {
      best = std::make_shared<MapPlane>();
      best->id = map.next_plane_id();
      best->n_w = w.n_c;
      best->d_w = w.d_c;
      map.add_plane(best);
    }
    std::erase_if(best->observers, [](const std::weak_ptr<KeyFrame>& o) {
      const auto k = o.lock();
      return !k || k->bad;
    });
    best->observers.push_back(kf.shared_from_this());
    best->last_seen_from = centre;
    taken.push_back(best.get());
    p.landmark = best;
  }
}

std::vector<std::shared_ptr<MapPlane>> add_plane_terms(std::vector<std::shared_ptr<KeyFrame>>& cams,
                                                       BundleAdjustmentProblem& pb, const PlaneLandmarkOptions& opt,
                                                       int anchors, bool hold_groups_as_a_whole) {
  std::vector<std::shared_ptr<MapPlane>> planes;
  if (!opt.enabled) return planes;
  // Planes leave the motion along them free: a group of cameras joined by shared points (or
  // depth links) none of which is fixed would slide along the walls with its points to
  // wherever the planes' small disagreements pull it. Such groups exist in local BA (keyframes
  // made on the depth-odometry bridge share no point with the map) and in global BA (the
  // keyframes just after a bridge, when the bridge's own are left out: in the office world one
  // slid 1.4-4 m). Their cameras are held near where tracking put them, loosely
  // (BundleAdjustmentProblem::held_in_place), so the planes still set their tilt, height and
  // distance to the walls. With hold_groups_as_a_whole (global BA) the hold is on each group's
  // common motion, so a group of hundreds of keyframes is still shaped by its points.
  {
    const std::size_t n = pb.cameras.size();
    DisjointSets groups = camera_groups(pb, 1, /*by_relative_poses=*/true);
    const auto held = held_by_fixed_camera(pb, groups);
    std::vector<int> size(n, 0);  // free cameras per group
    for (std::size_t c = 0; c < n; ++c)
      if (!pb.cameras[c].fixed) ++size[static_cast<std::size_t>(groups.find(static_cast<int>(c)))];
    for (std::size_t c = 0; c < n; ++c)
      if (!pb.cameras[c].fixed && !held[c])
        pb.held_in_place.push_back({static_cast<int>(c), hold_groups_as_a_whole
                                                             ? size[static_cast<std::size_t>(groups.find(static_cast<int>(c)))]
                                                             : 1});
  }
  pb.plane_sigma_rad = opt.sigma_rad;
  pb.plane_sigma_m = opt.sigma_m;
  std::unordered_map<const MapPlane*, int> index;
  std::unordered_map<const KeyFrame*, int> in_problem;
  for (std::size_t c = 0; c < cams.size(); ++c) in_problem[cams[c].get()] = static_cast<int>(c);
  auto add_measurements = [&](std::size_t c, bool new_planes) {
    for (const auto& p : cams[c]->planes) {
      if (!p.landmark) continue;
      auto it = index.find(p.landmark.get());
      if (it == index.end()) {
        if (!new_planes) continue;
        it = index.emplace(p.landmark.get(), static_cast<int>(planes.size())).first;
        planes.push_back(p.landmark);
      }
      pb.plane_measurements.push_back({static_cast<int>(c), it->second, p.m});
    }
  };
  const std::size_t given = cams.size();
  for (std::size_t c = 0; c < given; ++c) add_measurements(c, true);
  if (anchors > 0) {
    const std::size_t local_planes = planes.size();
    for (std::size_t i = 0; i < local_planes; ++i) {
      std::vector<std::shared_ptr<KeyFrame>> others;
      for (const auto& o : planes[i]->observers)
        if (auto k = o.lock(); k && !k->bad && !in_problem.count(k.get())) others.push_back(k);
      const std::size_t n = std::min(others.size(), static_cast<std::size_t>(anchors));
      for (std::size_t a = 0; a < n; ++a) {
        // Evenly over the plane's history, the oldest and the newest included.
        const std::size_t at = n == 1 ? others.size() - 1 : a * (others.size() - 1) / (n - 1);
        const auto& k = others[at];
        if (in_problem.count(k.get())) continue;
        in_problem[k.get()] = static_cast<int>(cams.size());
        cams.push_back(k);
        pb.cameras.push_back({k->pose(), true});
        add_measurements(cams.size() - 1, false);
      }
    }
  }
  // Each plane starts at the inlier-weighted mean of its measurements.
  std::vector<PlaneMean> means(planes.size());
  for (const auto& pm : pb.plane_measurements)
    means[static_cast<std::size_t>(pm.plane)].add(pm.m, pb.cameras[static_cast<std::size_t>(pm.camera)].T_cw);
  for (std::size_t j = 0; j < planes.size(); ++j)
    pb.planes.push_back({means[j].normal_or(planes[j]->n_w), means[j].offset_or(planes[j]->d_w)});
  return planes;
}

namespace {

std::vector<std::shared_ptr<KeyFrame>> live_observers(MapPlane& plane) {
  std::erase_if(plane.observers, [](const std::weak_ptr<KeyFrame>& o) {
    const auto k = o.lock();
    return !k || k->bad;
  });
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (const auto& o : plane.observers) out.push_back(o.lock());
  return out;
}

// The inlier-weighted mean of the plane's measurements by its observers at their poses; false
// when none of them measures it any more.
bool refit_plane(MapPlane& plane) {
  PlaneMean mean;
  const auto observers = live_observers(plane);
  for (const auto& k : observers)
    for (const auto& kp : k->planes)
      if (kp.landmark.get() == &plane) mean.add(kp.m, k->pose());
  if (observers.empty()) return false;
  plane.last_seen_from = observers.back()->camera_center();
  if (mean.empty()) return false;
  plane.n_w = mean.normal_or(plane.n_w);
  plane.d_w = mean.offset_or(plane.d_w);
  return true;
}

bool observed_near(const std::vector<std::shared_ptr<KeyFrame>>& a, const std::vector<std::shared_ptr<KeyFrame>>& b,
                   double range_m) {
  for (const auto& x : a) {
    const Eigen::Vector3d c = x->camera_center();
    for (const auto& y : b)
      if ((y->camera_center() - c).norm() <= range_m) return true;
  }
  return false;
}

}  // namespace

int refit_and_merge_planes(Map& map, const PlaneLandmarkOptions& opt, bool refit) {
  if (refit)
    for (const auto& p : map.planes()) refit_plane(*p);
  const double cos_match = std::cos(opt.match_deg * M_PI / 180.0);
  const auto planes = map.planes();  // oldest first
  std::vector<char> gone(planes.size(), 0);
  int merged = 0;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (gone[i]) continue;
    MapPlane& keep = *planes[i];
    for (std::size_t j = i + 1; j < planes.size(); ++j) {
      if (gone[j]) continue;
      MapPlane& other = *planes[j];
      if (keep.n_w.dot(other.n_w) < cos_match || std::abs(keep.d_w - other.d_w) > opt.match_m) continue;
      const auto keep_obs = live_observers(keep), other_obs = live_observers(other);
      if (!observed_near(keep_obs, other_obs, opt.match_range_m)) continue;
      const double wk = static_cast<double>(keep_obs.size()), wo = static_cast<double>(other_obs.size());
      const Eigen::Vector3d n_mean = wk * keep.n_w + wo * other.n_w;
      const double d_mean = wk + wo > 0 ? (wk * keep.d_w + wo * other.d_w) / (wk + wo) : keep.d_w;
      for (const auto& k : other_obs) {
        for (auto& kp : k->planes)
          if (kp.landmark.get() == &other) kp.landmark = planes[i];
        if (std::none_of(keep_obs.begin(), keep_obs.end(), [&](const auto& x) { return x == k; }))
          keep.observers.push_back(k);
      }
      // Observers in the order they joined: by keyframe id.
      std::sort(keep.observers.begin(), keep.observers.end(), [](const auto& a, const auto& b) {
        return a.lock()->id < b.lock()->id;
      });
      if (!refit || !refit_plane(keep)) {
        if (n_mean.norm() > 0) keep.n_w = n_mean.normalized();
        keep.d_w = d_mean;
        keep.last_seen_from = keep.observers.empty() ? keep.last_seen_from : keep.observers.back().lock()->camera_center();
      }
      other.observers.clear();
      gone[j] = 1;
      ++merged;
    }
  }
  for (std::size_t j = 0; j < planes.size(); ++j)
    if (gone[j]) map.erase_plane(planes[j].get());
  return merged;
}

void store_solved_planes(const std::vector<std::shared_ptr<MapPlane>>& planes,
                         const std::vector<BundleAdjustmentProblem::Plane>& solved) {
  for (std::size_t j = 0; j < planes.size() && j < solved.size(); ++j) {
    planes[j]->n_w = solved[j].n;
    planes[j]->d_w = solved[j].d;
  }
}

}  // namespace builtscene::slam
