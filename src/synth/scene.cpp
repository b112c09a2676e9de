#include "synth/scene.hpp"

#include <cmath>
#include <limits>

namespace builtscene::synth {

int Scene::add_material(Material m) {
  materials.push_back(std::move(m));
  return static_cast<int>(materials.size()) - 1;
}

int Scene::texture_index(const std::string& tex) const {
  for (std::size_t i = 0; i < textures.size(); ++i)
    if (textures[i].first == tex) return static_cast<int>(i);
  return -1;
}

Eigen::Vector4d Scene::bounds_xy() const {
  Eigen::Vector4d b(1e9, 1e9, -1e9, -1e9);
  auto add = [&](const Eigen::Vector3d& p) {
    b[0] = std::min(b[0], p.x());
    b[1] = std::min(b[1], p.y());
    b[2] = std::max(b[2], p.x());
    b[3] = std::max(b[3], p.y());
  };
  for (const auto& box : boxes)
    for (const auto& f : box_faces(box)) {
      add(f.origin);
      add(f.origin + f.u + f.v);
    }
  for (const auto& q : quads) {
    add(q.origin);
    add(q.origin + q.u);
    add(q.origin + q.v);
    add(q.origin + q.u + q.v);
  }
  return b;
}

std::array<Eigen::Vector3d, 4> Tag::corners() const {
  const Eigen::Vector3d x(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d up(-std::sin(yaw), std::cos(yaw), 0.0);
  const double h = size / 2;
  return {center - x * h + up * h, center + x * h + up * h, center + x * h - up * h, center - x * h - up * h};
}

std::vector<Surface> box_faces(const Box& box) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  const Eigen::Vector3d ex(c, s, 0), ey(-s, c, 0), ez(0, 0, 1);
  const Eigen::Vector3d h = box.size / 2;
  const Eigen::Vector3d& o = box.center;
  auto mat = [&](int face) { return box.face_material[face] >= 0 ? box.face_material[face] : box.material; };
  std::vector<Surface> f;
  f.reserve(6);
  // Side faces: origin at the top-left seen from outside, u to the right, v down, so that
  // texture rows run downwards and posters/books appear upright. The visible side of every
  // surface is the one v x u points to.
  auto top = ez * h.z();
  // +x face: seen from +x, right is +y.
  f.push_back({o + ex * h.x() - ey * h.y() + top, ey * box.size.y(), -ez * box.size.z(), mat(0)});
  // -x face: seen from -x, right is -y.
  f.push_back({o - ex * h.x() + ey * h.y() + top, -ey * box.size.y(), -ez * box.size.z(), mat(1)});
  // +y face: seen from +y, right is -x.
  f.push_back({o + ey * h.y() + ex * h.x() + top, -ex * box.size.x(), -ez * box.size.z(), mat(2)});
  // -y face: seen from -y, right is +x.
  f.push_back({o - ey * h.y() - ex * h.x() + top, ex * box.size.x(), -ez * box.size.z(), mat(3)});
  // top (seen from above: right +x, down -y) and bottom
  f.push_back({o - ex * h.x() + ey * h.y() + top, ex * box.size.x(), -ey * box.size.y(), mat(4)});
  f.push_back({o - ex * h.x() - ey * h.y() - top, ex * box.size.x(), ey * box.size.y(), mat(5)});
  return f;
}

std::optional<double> raycast(const std::vector<Surface>& surfaces, const Eigen::Vector3d& origin,
                              const Eigen::Vector3d& dir, double min_t, int* hit_index) {
  double best = std::numeric_limits<double>::infinity();
  int best_i = -1;
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const Surface& sf = surfaces[i];
    const Eigen::Vector3d n = sf.u.cross(sf.v);
    const double denom = n.dot(dir);
    if (std::abs(denom) < 1e-15) continue;
    const double t = n.dot(sf.origin - origin) / denom;
    if (t <= min_t || t >= best) continue;
    const Eigen::Vector3d d = origin + dir * t - sf.origin;
    const double a = d.dot(sf.u) / sf.u.squaredNorm();
    const double b = d.dot(sf.v) / sf.v.squaredNorm();
    if (a < 0 || a > 1 || b < 0 || b > 1) continue;
    best = t;
    best_i = static_cast<int>(i);
  }
  if (hit_index) *hit_index = best_i;
  if (best_i < 0) return std::nullopt;
  return best;
}

std::vector<Surface> scene_surfaces(const Scene& scene) {
  std::vector<Surface> out;
  for (const auto& b : scene.boxes)
    for (const auto& f : box_faces(b)) out.push_back(f);
  for (const auto& q : scene.quads) out.push_back({q.origin, q.u, q.v, q.material});
  for (const auto& t : scene.tags) {
    const Eigen::Vector3d x(std::cos(t.yaw), std::sin(t.yaw), 0.0);
    const Eigen::Vector3d up(-std::sin(t.yaw), std::cos(t.yaw), 0.0);
    const double paper = t.size * 10.0 / 8.0;  // tag36h11: 8 cells of black square + 1 white each side
    out.push_back({t.center - x * paper / 2 + up * paper / 2, x * paper, -up * paper, t.material});
  }
  return out;
}

namespace {
nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

nlohmann::json scene_to_json(const Scene& scene) {
  using nlohmann::json;
  json j;
  j["name"] = scene.name;
  j["description"] = scene.description;
  j["conventions"] = {
      {"units", "metres, radians"},
      {"world", "z up, floor at z = 0"},
      {"camera", "x right, y down, z forward; groundtruth.txt is camera-to-world T_wc"},
      {"box", "axis-aligned in its own frame, rotated by yaw about +z around center; size = full extent"},
      {"quad", "points origin + s*u + t*v, s and t in [0,1]"},
      {"tag", "tag36h11, flat on the floor facing +z; x axis (image columns) at yaw; size = black square edge; "
              "corners = image top-left, top-right, bottom-right, bottom-left"},
      {"truth_map", "occupied where a solid box overlaps the robot band [robot_band_min, robot_band_max] "
                    "in height; free on the floor regions elsewhere; unknown outside"}};
  json mats = json::array();
  for (const auto& m : scene.materials)
    mats.push_back({{"texture", m.texture},
                    {"mapping", m.mapping == TextureMapping::Repeat ? "repeat" : "stretch"},
                    {"tile_m", m.tile_m},
                    {"tint_bgr", {m.tint.x(), m.tint.y(), m.tint.z()}}});
  j["materials"] = mats;
  json boxes = json::array();
  for (const auto& b : scene.boxes)
    boxes.push_back({{"name", b.name},
                     {"center", vec(b.center)},
                     {"size", vec(b.size)},
                     {"yaw", b.yaw},
                     {"material", b.material},
                     {"face_material", b.face_material},
                     {"solid", b.solid}});
  j["boxes"] = boxes;
  json quads = json::array();
  for (const auto& q : scene.quads)
    quads.push_back({{"name", q.name}, {"origin", vec(q.origin)}, {"u", vec(q.u)}, {"v", vec(q.v)}, {"material", q.material}});
  j["quads"] = quads;
  json tags = json::array();
  for (const auto& t : scene.tags) {
    json corners = json::array();
    for (const auto& c : t.corners()) corners.push_back(vec(c));
    tags.push_back({{"family", "tag36h11"}, {"id", t.id}, {"center", vec(t.center)}, {"yaw", t.yaw}, {"size", t.size},
                    {"corners", corners}});
  }
  j["tags"] = tags;
  json lights = json::array();
  for (const auto& l : scene.lights) lights.push_back({{"position", vec(l.position)}, {"intensity", l.intensity}});
  j["lights"] = lights;
  j["ambient"] = scene.ambient;
  json floor = json::array();
  for (const auto& f : scene.floor) floor.push_back({f.x0, f.y0, f.x1, f.y1});
  j["floor_regions"] = floor;
  json loop = json::array();
  for (const auto& p : scene.robot_loop) loop.push_back({p.x(), p.y()});
  j["robot_loop"] = loop;
  j["ceiling_height"] = scene.ceiling_height;
  j["robot_band_min"] = scene.robot_band_min;
  j["robot_band_max"] = scene.robot_band_max;
  return j;
}

}  // namespace builtscene::synth
