#include "eval/trajectory_error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "core/errors.hpp"
#include "core/stage_timer.hpp"
#include "eval/umeyama.hpp"
#include "io/tum_dataset.hpp"

namespace builtscene {

Alignment parse_alignment(const std::string& name) {
  if (name == "none") return Alignment::kNone;
  if (name == "se3") return Alignment::kSE3;
  if (name == "sim3") return Alignment::kSim3;
  throw InputError("--align: unknown alignment '" + name + "' (expected se3, sim3 or none)");
}

std::string to_string(Alignment a) {
  switch (a) {
    case Alignment::kNone: return "none";
    case Alignment::kSE3: return "se3";
    case Alignment::kSim3: return "sim3";
  }
  return "?";
}

ErrorStats error_stats(const std::vector<double>& e) {
  ErrorStats s;
  s.count = e.size();
  if (e.empty()) return s;
  const double n = static_cast<double>(e.size());
  s.mean = std::accumulate(e.begin(), e.end(), 0.0) / n;
  double sq = 0, var = 0;
  for (double v : e) {
    sq += v * v;
    var += (v - s.mean) * (v - s.mean);
  }
  s.rmse = std::sqrt(sq / n);
  s.std = std::sqrt(var / n);
  s.median = quantile(e, 0.5);
  s.min = *std::min_element(e.begin(), e.end());
  s.max = *std::max_element(e.begin(), e.end());
  return s;
}

std::vector<std::pair<std::size_t, std::size_t>> associate_trajectories(const Trajectory& gt, const Trajectory& est,
                                                                        double max_difference) {
  std::vector<double> a, b;
  for (const auto& p : gt) a.push_back(p.timestamp);
  for (const auto& p : est) b.push_back(p.timestamp);
  return associate_timestamps(a, b, max_difference);
}

Trajectory transformed(const Trajectory& est, const Sim3& transform) {
  Trajectory out;
  out.reserve(est.size());
  for (const auto& p : est) out.push_back({p.timestamp, transform.transform_pose(p.pose)});
  return out;
}

AteResult absolute_trajectory_error(const Trajectory& gt, const Trajectory& est, Alignment alignment,
                                    double max_difference) {
  AteResult r;
  r.alignment = alignment;
  r.pairs = associate_trajectories(gt, est, max_difference);
  const std::size_t needed = alignment == Alignment::kNone ? 1 : 3;
  if (r.pairs.size() < needed)
    throw InputError("no overlapping timestamps: " + std::to_string(r.pairs.size()) + " pose pairs within " +
                     std::to_string(max_difference) + " s (need at least " + std::to_string(needed) + ")");
  std::vector<Eigen::Vector3d> src, dst;
  for (const auto& [ig, ie] : r.pairs) {
    dst.push_back(gt[ig].pose.translation());
    src.push_back(est[ie].pose.translation());
  }
  if (alignment != Alignment::kNone) r.est_to_gt = umeyama_alignment(src, dst, alignment == Alignment::kSim3);
  for (std::size_t i = 0; i < src.size(); ++i) r.errors.push_back((dst[i] - r.est_to_gt * src[i]).norm());
  r.stats = error_stats(r.errors);
  return r;
}

RpeResult relative_pose_error(const Trajectory& gt, const Trajectory& est, std::size_t delta, double max_difference,
                              bool correct_scale) {
  if (delta == 0) throw InputError("--delta must be at least 1");
  const auto pairs = associate_trajectories(gt, est, max_difference);
  if (pairs.size() <= delta)
    throw InputError("no overlapping timestamps: " + std::to_string(pairs.size()) +
                     " pose pairs, need more than --delta " + std::to_string(delta));
  double scale = 1.0;
  if (correct_scale) {
    std::vector<Eigen::Vector3d> src, dst;
    for (const auto& [ig, ie] : pairs) {
      dst.push_back(gt[ig].pose.translation());
      src.push_back(est[ie].pose.translation());
    }
    scale = umeyama_alignment(src, dst, true).scale();
  }
  std::vector<double> et, er;
  for (std::size_t k = 0; k + delta < pairs.size(); ++k) {
    const auto [g0, e0] = pairs[k];
    const auto [g1, e1] = pairs[k + delta];
    const SE3 dg = gt[g0].pose.inverse() * gt[g1].pose;
    SE3 de = est[e0].pose.inverse() * est[e1].pose;
    de = SE3(de.rotation(), scale * de.translation());
    const SE3 err = dg.inverse() * de;
    et.push_back(err.translation().norm());
    er.push_back(err.log().tail<3>().norm() * 180.0 / std::numbers::pi);
  }
  return {error_stats(et), error_stats(er), delta};
}

nlohmann::json to_json(const ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"pairs", s.count}};
}

}  // namespace builtscene
