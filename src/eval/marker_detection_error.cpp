#include "eval/marker_detection_error.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "core/errors.hpp"
#include "eval/trajectory_error.hpp"

namespace builtscene {
namespace {

// A localized frame with its true pose (the two trajectories associated as for `eval ate`).
struct PosePair {
  double time;
  SE3 localized, truth;
};

// The pair whose time is nearest `t`, if within max_difference. `pairs` is sorted by time.
const PosePair* pair_at(const std::vector<PosePair>& pairs, double t, double max_difference) {
  const auto it = std::lower_bound(pairs.begin(), pairs.end(), t, [](const PosePair& p, double v) { return p.time < v; });
  const PosePair* best = it != pairs.end() ? &*it : nullptr;
  if (it != pairs.begin() && (!best || t - std::prev(it)->time < best->time - t)) best = &*std::prev(it);
  return best && std::abs(best->time - t) <= max_difference ? best : nullptr;
}

}  // namespace

MarkerDetectionErrors marker_detection_errors(const std::vector<MarkerMeasurement>& measured,
                                              const std::vector<MarkerTruth>& survey, const Trajectory& localized,
                                              const Trajectory& truth, double max_difference) {
  std::map<int, Eigen::Vector3d> surveyed;
  for (const auto& s : survey) surveyed[s.id] = s.position;
  std::vector<PosePair> pairs;
  for (const auto& [it, il] : associate_trajectories(truth, localized, max_difference))
    pairs.push_back({localized[il].timestamp, localized[il].pose, truth[it].pose});
  std::sort(pairs.begin(), pairs.end(), [](const PosePair& a, const PosePair& b) { return a.time < b.time; });
  struct Sum {
    std::size_t n = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double sq = 0;
  };
  std::map<int, Sum> sums;
  MarkerDetectionErrors d;
  for (const auto& m : measured) {
    const auto s = surveyed.find(m.id);
    if (s == surveyed.end()) continue;
    const PosePair* poses = pair_at(pairs, m.time, max_difference);
    if (!poses) {
      ++d.without_pose;
      continue;
    }
    const Eigen::Vector3d e = poses->truth * (poses->localized.inverse() * m.position) - s->second;
    Sum& a = sums[m.id];
    ++a.n;
    a.sum += e;
    a.sq += e.squaredNorm();
    ++d.used;
  }
  if (d.used == 0)
    throw InputError("no marker measurement's time has a pose in both the localized and the true trajectory (within " +
                     std::to_string(max_difference) + " s)");
  for (const auto& [id, a] : sums) {
    MarkerDetectionError r;
    r.id = id;
    r.times = a.n;
    r.bias = a.sum / static_cast<double>(a.n);
    r.rmse = std::sqrt(a.sq / static_cast<double>(a.n));
    d.max_rmse = std::max(d.max_rmse, r.rmse);
    d.markers.push_back(r);
  }
  return d;
}

std::string detection_markdown(const MarkerDetectionErrors& d) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(4);
  o << "| Marker | Times | Detection bias X (m) | Bias Y (m) | Bias Z (m) | Detection RMSE (m) |\n"
       "| ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& m : d.markers)
    o << "| " << m.id << " | " << m.times << " | " << m.bias.x() << " | " << m.bias.y() << " | " << m.bias.z() << " | " << m.rmse
      << " |\n";
  return o.str();
}

nlohmann::json to_json(const MarkerDetectionErrors& d) {
  nlohmann::json markers = nlohmann::json::array();
  for (const auto& m : d.markers)
    markers.push_back({{"id", m.id}, {"times", m.times}, {"bias", {m.bias.x(), m.bias.y(), m.bias.z()}}, {"rmse", m.rmse}});
  return {{"markers", markers}, {"used", d.used}, {"without_pose", d.without_pose}, {"max_rmse", d.max_rmse}};
}

}  // namespace builtscene
