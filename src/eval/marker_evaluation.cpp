#include "eval/marker_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "eval/umeyama.hpp"

namespace builtscene {

MarkerAlignment parse_marker_alignment(const std::string& name) {
  if (name == "3d") return MarkerAlignment::k3D;
  if (name == "2d") return MarkerAlignment::k2D;
  if (name == "none") return MarkerAlignment::kNone;
  throw InputError("--align: unknown alignment '" + name + "' (expected 3d, 2d or none)");
}

static double horizontal(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).head<2>().norm(); }

namespace {
struct FloorUp {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  bool from_markers = false;
};
}  // namespace

// The map frame's up axis: the normal of the plane through the measured floor markers,
// pointing the way the truth's z points under the best 3D rigid fit (a plane's normal has no
// sign of its own). Fewer than 3 markers, or markers on a line: the map's own z.
static FloorUp floor_up(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst) {
  FloorUp up;
  if (src.size() < 3) return up;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : src) c += p;
  c /= static_cast<double>(src.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : src) cov += (p - c) * (p - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d ev = es.eigenvalues();  // ascending
  // On a line the second-largest spread vanishes and the plane is undetermined.
  if (!(ev(1) > 1e-6 * ev(2)) || ev(2) <= 0) return up;
  Eigen::Vector3d n = es.eigenvectors().col(0);
  const Sim3 fit = umeyama_alignment(src, dst, false);
  if (n.dot(fit.rotation().inverse() * Eigen::Vector3d::UnitZ()) < 0) n = -n;
  up.axis = n.normalized();
  up.from_markers = true;
  return up;
}

MarkerEvaluation evaluate_markers(const std::vector<MarkerMeasurement>& measured, const std::vector<MarkerTruth>& truth,
                                  MarkerAlignment alignment) {
  MarkerEvaluation e;
  e.alignment = alignment;
  std::map<int, const MarkerTruth*> by_id;
  for (const auto& t : truth) by_id[t.id] = &t;
  std::map<int, std::vector<Eigen::Vector3d>> raw;
  std::set<int> unknown;
  for (const auto& m : measured) {
    if (!by_id.count(m.id)) {
      unknown.insert(m.id);
      continue;
    }
    raw[m.id].push_back(m.position);
    ++e.measurements_used;
  }
  e.unknown_ids.assign(unknown.begin(), unknown.end());
  // Alignment over the measured markers' mean positions.
  std::vector<Eigen::Vector3d> src, dst;
  for (const auto& [id, ps] : raw) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : ps) mean += p;
    src.push_back(mean / static_cast<double>(ps.size()));
    dst.push_back(by_id[id]->position);
  }
  if (alignment == MarkerAlignment::k3D) {
    if (src.size() < 3)
      throw InputError("marker alignment (3d) needs at least 3 measured markers that the truth lists, got " +
                       std::to_string(src.size()));
    e.map_to_truth = umeyama_alignment(src, dst, false);
  } else if (alignment == MarkerAlignment::k2D) {
    if (src.size() < 2)
      throw InputError("marker alignment (2d) needs at least 2 measured markers that the truth lists, got " +
                       std::to_string(src.size()));
    // The map frame need not be z-up (a SLAM world is its first camera: y down, the floor in
    // x-z). The floor markers lie on the floor, so the plane through their mean positions
    // gives the map's up axis; it is turned onto the truth's z, then a rotation about z and a
    // planar translation align the floor projections.
    const FloorUp up = floor_up(src, dst);
    e.up_from_markers = up.from_markers;
    const Eigen::Quaterniond level = Eigen::Quaterniond::FromTwoVectors(up.axis, Eigen::Vector3d::UnitZ());
    std::vector<Eigen::Vector3d> s2, d2;
    double dz = 0;
    for (std::size_t i = 0; i < src.size(); ++i) {
      const Eigen::Vector3d l = level * src[i];
      dz += (dst[i].z() - l.z()) / static_cast<double>(src.size());
      // Each point lifted by a unit z copy so that the 3D solver cannot tilt the plane.
      s2.emplace_back(l.x(), l.y(), 0);
      d2.emplace_back(dst[i].x(), dst[i].y(), 0);
      s2.emplace_back(l.x(), l.y(), 1);
      d2.emplace_back(dst[i].x(), dst[i].y(), 1);
    }
    const Sim3 a = umeyama_alignment(s2, d2, false);
    e.map_to_truth = Sim3(a.rotation(), Eigen::Vector3d(a.translation().x(), a.translation().y(), dz), 1.0) *
                     Sim3(level, Eigen::Vector3d::Zero(), 1.0);
  }
  std::map<int, std::vector<Eigen::Vector3d>> aligned;
  for (const auto& [id, ps] : raw)
    for (const auto& p : ps) aligned[id].push_back(e.map_to_truth * p);

  for (const auto& t : truth) {
    MarkerResult r;
    r.id = t.id;
    r.truth = t.position;
    auto it = aligned.find(t.id);
    if (it == aligned.end()) {
      e.unseen_ids.push_back(t.id);
      e.markers.push_back(r);
      continue;
    }
    const auto& ps = it->second;
    r.times = ps.size();
    for (const auto& p : ps) r.mean_estimate += p;
    r.mean_estimate /= static_cast<double>(ps.size());
    double sq = 0, sq3 = 0;
    Eigen::Vector3d var = Eigen::Vector3d::Zero();
    for (const auto& p : ps) {
      sq += std::pow(horizontal(p, t.position), 2);
      sq3 += (p - t.position).squaredNorm();
      var += (p - r.mean_estimate).cwiseAbs2();
    }
    const double n = static_cast<double>(ps.size());
    r.rmse = std::sqrt(sq / n);
    r.rmse_3d = std::sqrt(sq3 / n);
    r.stddev = (var / n).cwiseSqrt();
    e.max_rmse = std::max(e.max_rmse, r.rmse);
    e.markers.push_back(r);
  }
  // Consecutive markers in the truth's order, and the closing pair.
  for (std::size_t i = 0; i + 1 < truth.size() + (truth.size() > 2 ? 1 : 0); ++i) {
    const auto& a = truth[i];
    const auto& b = truth[(i + 1) % truth.size()];
    MarkerDistanceResult d;
    d.from = a.id;
    d.to = b.id;
    d.truth = horizontal(a.position, b.position);
    auto ia = aligned.find(a.id), ib = aligned.find(b.id);
    if (ia != aligned.end() && ib != aligned.end()) {
      double sum = 0, sq = 0;
      for (const auto& p : ia->second)
        for (const auto& q : ib->second) {
          const double dist = horizontal(p, q);
          sum += dist;
          sq += (dist - d.truth) * (dist - d.truth);
          ++d.pairs;
        }
      d.estimated = sum / static_cast<double>(d.pairs);
      d.rmse = std::sqrt(sq / static_cast<double>(d.pairs));
      e.max_distance_rmse = std::max(e.max_distance_rmse, d.rmse);
    }
    e.distances.push_back(d);
  }
  return e;
}

std::string markers_markdown(const MarkerEvaluation& e) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3);
  o << "| Marker | Times | Est. X (m) | Est. Y (m) | True X (m) | True Y (m) | RMSE (m) | Std X (m) | Std Y (m) | Std Z (m) |\n"
       "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& m : e.markers) {
    o << "| " << m.id << " | " << m.times << " | ";
    if (m.times) o << m.mean_estimate.x() << " | " << m.mean_estimate.y() << " | ";
    else o << "- | - | ";
    o << m.truth.x() << " | " << m.truth.y() << " | ";
    if (m.times) o << m.rmse << " | " << m.stddev.x() << " | " << m.stddev.y() << " | " << m.stddev.z() << " |\n";
    else o << "not seen | - | - | - |\n";
  }
  o << "\n| Markers | Est. distance (m) | True distance (m) | RMSE (m) | Pairs |\n| --- | ---: | ---: | ---: | ---: |\n";
  for (const auto& d : e.distances) {
    o << "| " << d.from << "-" << d.to << " | ";
    if (d.pairs) o << d.estimated << " | " << d.truth << " | " << d.rmse << " | " << d.pairs << " |\n";
    else o << "- | " << d.truth << " | not seen | 0 |\n";
  }
  return o.str();
}

nlohmann::json to_json(const MarkerEvaluation& e) {
  nlohmann::json markers = nlohmann::json::array(), distances = nlohmann::json::array();
  for (const auto& m : e.markers) {
    nlohmann::json j = {{"id", m.id}, {"times", m.times}, {"true", {m.truth.x(), m.truth.y(), m.truth.z()}}};
    if (m.times) {
      j["rmse"] = m.rmse;
      j["rmse_3d"] = m.rmse_3d;
      j["estimate"] = {m.mean_estimate.x(), m.mean_estimate.y(), m.mean_estimate.z()};
      j["std"] = {m.stddev.x(), m.stddev.y(), m.stddev.z()};
    } else {
      j["rmse"] = nullptr;
    }
    markers.push_back(j);
  }
  for (const auto& d : e.distances)
    distances.push_back({{"from", d.from}, {"to", d.to}, {"estimated", d.estimated}, {"true", d.truth},
                         {"rmse", d.pairs ? nlohmann::json(d.rmse) : nlohmann::json(nullptr)}, {"pairs", d.pairs}});
  const auto& q = e.map_to_truth.rotation();
  const auto& t = e.map_to_truth.translation();
  return {{"markers", markers},
          {"distances", distances},
          {"max_rmse", e.max_rmse},
          {"max_distance_rmse", e.max_distance_rmse},
          {"measurements", e.measurements_used},
          {"unknown_ids", e.unknown_ids},
          {"unseen_ids", e.unseen_ids},
          {"alignment", e.alignment == MarkerAlignment::k3D ? "3d" : e.alignment == MarkerAlignment::k2D ? "2d" : "none"},
          {"map_to_truth", {{"t", {t.x(), t.y(), t.z()}}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}}},
          {"map_up", e.alignment != MarkerAlignment::k2D ? nlohmann::json(nullptr)
                     : e.up_from_markers                 ? nlohmann::json("markers_plane")
                                                         : nlohmann::json("z")}};
}

void write_marker_tables(const MarkerEvaluation& e, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "markers.md") << markers_markdown(e);
  {
    std::ofstream c(dir / "markers_table.csv");
    c << "id,times,est_x,est_y,true_x,true_y,rmse,std_x,std_y,std_z\n" << std::fixed << std::setprecision(4);
    for (const auto& m : e.markers)
      c << m.id << ',' << m.times << ',' << m.mean_estimate.x() << ',' << m.mean_estimate.y() << ',' << m.truth.x() << ','
        << m.truth.y() << ',' << m.rmse << ',' << m.stddev.x() << ',' << m.stddev.y() << ',' << m.stddev.z() << '\n';
  }
  {
    std::ofstream c(dir / "distances_table.csv");
    c << "from,to,estimated,true,rmse,pairs\n" << std::fixed << std::setprecision(4);
    for (const auto& d : e.distances) c << d.from << ',' << d.to << ',' << d.estimated << ',' << d.truth << ',' << d.rmse << ',' << d.pairs << '\n';
  }
  // Plot: true positions as circles, estimates as crosses, errors magnified 10x as lines.
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& m : e.markers) {
    x0 = std::min(x0, m.truth.x());
    y0 = std::min(y0, m.truth.y());
    x1 = std::max(x1, m.truth.x());
    y1 = std::max(y1, m.truth.y());
  }
  const double span = std::max({x1 - x0, y1 - y0, 1.0});
  const int size = 900, margin = 60;
  const double scale = (size - 2 * margin) / span;
  cv::Mat img(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(margin + (p.x() - x0) * scale), static_cast<int>(size - margin - (p.y() - y0) * scale));
  };
  for (const auto& m : e.markers) {
    cv::circle(img, px(m.truth), 6, {0, 140, 0}, 2, cv::LINE_AA);
    cv::putText(img, std::to_string(m.id), px(m.truth) + cv::Point(8, -8), cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
    if (!m.times) continue;
    const Eigen::Vector3d magnified = m.truth + 10.0 * (m.mean_estimate - m.truth);
    cv::line(img, px(m.truth), px(magnified), {0, 0, 220}, 1, cv::LINE_AA);
    cv::drawMarker(img, px(magnified), {0, 0, 220}, cv::MARKER_CROSS, 10, 2);
  }
  cv::putText(img, "true (circles), estimated mean (crosses, error x10)", {margin, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 1, cv::LINE_AA);
  cv::imwrite((dir / "markers.png").string(), img);
}

}  // namespace builtscene
