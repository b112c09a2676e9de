#include "eval/marker_detection_error.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {
namespace {

// The pose whose timestamp is nearest `t`, if within max_difference. `order` sorts `traj` by time.
std::optional<SE3> pose_at(const Trajectory& traj, const std::vector<std::size_t>& order, double t, double max_difference) {
  const auto it = std::lower_bound(order.begin(), order.end(), t,
                                   [&](std::size_t i, double v) { return traj[i].timestamp < v; });
  std::optional<std::size_t> best;
  if (it != order.end()) best = *it;
  if (it != order.begin() && (!best || t - traj[*std::prev(it)].timestamp < traj[*best].timestamp - t)) best = *std::prev(it);
  if (!best || std::abs(traj[*best].timestamp - t) > max_difference) return std::nullopt;
  return traj[*best].pose;
}

std::vector<std::size_t> time_order(const Trajectory& traj) {
  std::vector<std::size_t> order(traj.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return traj[a].timestamp < traj[b].timestamp; });
  return order;
}

}  // namespace

MarkerDetectionErrors marker_detection_errors(const std::vector<MarkerMeasurement>& measured,
                                              const std::vector<MarkerTruth>& survey, const Trajectory& localized,
                                              const Trajectory& truth, double max_difference) {
  std::map<int, Eigen::Vector3d> surveyed;
  for (const auto& s : survey) surveyed[s.id] = s.position;
  const auto loc_order = time_order(localized), truth_order = time_order(truth);
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
    const auto T_loc = pose_at(localized, loc_order, m.time, max_difference);
    const auto T_true = T_loc ? pose_at(truth, truth_order, m.time, max_difference) : std::nullopt;
    if (!T_loc || !T_true) {
      ++d.without_pose;
      continue;
    }
    const Eigen::Vector3d e = *T_true * (T_loc->inverse() * m.position) - s->second;
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
