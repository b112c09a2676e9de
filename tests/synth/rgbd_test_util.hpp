#pragma once
// Helpers for the synth rgbd tests: the scene's geometry read back from scene.json (not from
// the library's own structures), and generating small sequences into temporary folders.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "../common/scratch_dir.hpp"

namespace synth_test {

struct JsonBox {
  Eigen::Vector3d c, h;  // centre, half extents
  double yaw;
  bool solid;
  std::string name;
};
struct JsonQuad {
  Eigen::Vector3d o, u, v;
};
struct JsonScene {
  std::vector<JsonBox> boxes;
  std::vector<JsonQuad> quads;
  std::vector<std::array<double, 4>> floor;
  double band_min = 0, band_max = 0;
};

inline Eigen::Vector3d v3(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

inline JsonScene load_scene_json(const std::filesystem::path& file) {
  std::ifstream in(file);
  const auto j = nlohmann::json::parse(in);
  JsonScene s;
  for (const auto& b : j["boxes"]) s.boxes.push_back({v3(b["center"]), v3(b["size"]) / 2, b["yaw"].get<double>(), b["solid"].get<bool>(), b["name"].get<std::string>()});
  for (const auto& q : j["quads"]) s.quads.push_back({v3(q["origin"]), v3(q["u"]), v3(q["v"])});
  // Tags are paper quads too: 10/8 of the black square, flat at their centre height.
  for (const auto& t : j["tags"]) {
    const double paper = t["size"].get<double>() * 10 / 8, yaw = t["yaw"].get<double>();
    const Eigen::Vector3d x(std::cos(yaw), std::sin(yaw), 0), y(-std::sin(yaw), std::cos(yaw), 0);
    s.quads.push_back({v3(t["center"]) - x * paper / 2 - y * paper / 2, x * paper, y * paper});
  }
  for (const auto& f : j["floor_regions"]) s.floor.push_back({f[0].get<double>(), f[1].get<double>(), f[2].get<double>(), f[3].get<double>()});
  s.band_min = j["robot_band_min"].get<double>();
  s.band_max = j["robot_band_max"].get<double>();
  return s;
}

inline Eigen::Vector3d box_local(const JsonBox& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - b.c;
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z()};
}

// Distance from p to the nearest surface of the scene (box faces and quads).
inline double distance_to_surfaces(const JsonScene& s, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& b : s.boxes) {
    const Eigen::Vector3d l = box_local(b, p);
    const Eigen::Vector3d q = l.cwiseAbs() - b.h;  // signed distances to the slabs
    const double outside = q.cwiseMax(0.0).norm();
    const double inside = std::min(0.0, q.maxCoeff());
    best = std::min(best, outside > 0 ? outside : -inside);
  }
  for (const auto& qd : s.quads) {
    const Eigen::Vector3d d = p - qd.o;
    const double a = std::clamp(d.dot(qd.u) / qd.u.squaredNorm(), 0.0, 1.0);
    const double c = std::clamp(d.dot(qd.v) / qd.v.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (qd.o + qd.u * a + qd.v * c - p).norm());
  }
  return best;
}

// An empty folder for a generated sequence, removed when the test process exits.
inline std::filesystem::path temp_dir(const std::string& name) { return builtscene::testing::scratch_dir("synth_test_" + name); }

}  // namespace synth_test
