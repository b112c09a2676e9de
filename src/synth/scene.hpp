#pragma once
// Geometry of a generated RGB-D world: textured boxes and quads, flat AprilTags, point lights.
//
// Conventions (also written into scene.json):
//   world: metres, z up, floor at z = 0;
//   camera: x right, y down, z forward; poses are camera-to-world T_wc;
//   a box is axis-aligned in its own frame, rotated by `yaw` (radians, about +z) around its
//   centre; a quad is origin + s*u + t*v for s, t in [0, 1]; texture rows run along v;
//   a tag lies flat on the floor facing +z; its x axis (the tag image's columns) points at
//   `yaw`, its image "up" at yaw + 90 degrees; `size` is the edge of the black square (the
//   AprilTag convention), the white border around it is size / 8 wide.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace builtscene::synth {

// How a texture covers a face: `Repeat` tiles it every tile_m metres (walls, floors, wood);
// `Stretch` maps the image once onto the whole face (posters, doors, tags).
enum class TextureMapping { Repeat, Stretch };

struct Material {
  std::string texture;                    // key into Scene::textures
  TextureMapping mapping = TextureMapping::Repeat;
  double tile_m = 1.0;                    // metres per texture repeat (Repeat only)
  Eigen::Vector3f tint{1.f, 1.f, 1.f};    // multiplies the texture (B, G, R)
};

struct Box {
  std::string name;
  Eigen::Vector3d center;
  Eigen::Vector3d size;                   // extent along the box's own x, y, z
  double yaw = 0;
  int material = 0;                       // every face unless overridden
  std::array<int, 6> face_material{-1, -1, -1, -1, -1, -1};  // +x -x +y -y +z -z; -1 = material
  bool solid = true;                      // counts in the truth map
};

// A flat textured rectangle; the front (lit, textured upright) is the side v x u points to.
struct Quad {
  std::string name;
  Eigen::Vector3d origin, u, v;
  int material = 0;
};

struct Tag {
  int id = 0;
  Eigen::Vector3d center;
  double yaw = 0;
  double size = 0.2;                      // black square edge, metres
  int material = -1;                      // the tag's image (set by add_tag)
  // Corners of the black square in the world: the tag image's top-left, top-right,
  // bottom-right, bottom-left.
  std::array<Eigen::Vector3d, 4> corners() const;
};

struct Light {
  Eigen::Vector3d position;
  double intensity = 1.0;                 // irradiance at 1 m on a facing surface
};

// A flat rectangle of walkable floor (x0, y0, x1, y1).
struct FloorRegion {
  double x0, y0, x1, y1;
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

struct Scene {
  std::string name;
  std::string description;
  std::vector<Material> materials;
  std::vector<Box> boxes;
  std::vector<Quad> quads;                // floors, ceilings, posters and other flat things
  std::vector<Tag> tags;
  std::vector<Light> lights;
  double ambient = 0.25;
  std::vector<FloorRegion> floor;         // where the floor is (free unless something stands there)
  std::vector<Eigen::Vector2d> robot_loop;   // closed polyline the robot drives (corners)
  std::vector<Eigen::Vector3d> look_targets; // things worth looking at for handheld motion
  double ceiling_height = 2.8;
  double robot_band_min = 0.05, robot_band_max = 1.30;  // truth map height band (m)
  // Texture images (8-bit BGR), generated deterministically by the scene library.
  std::vector<std::pair<std::string, cv::Mat>> textures;

  int add_material(Material m);
  int texture_index(const std::string& name) const;  // -1 when missing
  // Axis-aligned bounds of every box and quad in the xy plane: (xmin, ymin, xmax, ymax).
  Eigen::Vector4d bounds_xy() const;
};

// One renderable textured rectangle (box faces, quads and tags flattened). Seen from its
// front (the side v x u points to), u runs to the right and v downwards: the texture's
// columns follow u and its rows follow v.
struct Surface {
  Eigen::Vector3d origin, u, v;
  int material = 0;
};

// The six faces of a box, normals pointing out.
std::vector<Surface> box_faces(const Box& box);

// First intersection of the ray origin + t * dir (t > min_t) with any surface; returns t.
// Used by tests and by the trajectory generator, never by the rasterizer.
std::optional<double> raycast(const std::vector<Surface>& surfaces, const Eigen::Vector3d& origin,
                              const Eigen::Vector3d& dir, double min_t = 1e-6, int* hit_index = nullptr);

// All surfaces of the scene (box faces, quads, tags with their paper border) in a fixed order.
std::vector<Surface> scene_surfaces(const Scene& scene);

nlohmann::json scene_to_json(const Scene& scene);

}  // namespace builtscene::synth
