#include "synth/scene_library.hpp"

#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "synth/apriltag_texture.hpp"
#include "synth/texture_generator.hpp"

namespace builtscene::synth {
namespace {

using V3 = Eigen::Vector3d;

// Small helper that keeps scene descriptions short.
class Builder {
 public:
  explicit Builder(Scene& s) : s_(s) {}

  // A texture generated once per (kind, variant); returns its key.
  std::string texture(const std::string& kind, int variant = 0, cv::Scalar base = cv::Scalar(200, 205, 210), int size = 512) {
    const std::string key = kind + "_" + std::to_string(variant);
    if (s_.texture_index(key) < 0) {
      std::uint64_t h = 1469598103934665603ull;
      for (char ch : key) h = (h ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
      s_.textures.emplace_back(key, generate_texture(kind, h, size, base));
    }
    return key;
  }
  int repeat(const std::string& tex, double tile_m, Eigen::Vector3f tint = {1, 1, 1}) {
    return s_.add_material({tex, TextureMapping::Repeat, tile_m, tint});
  }
  int stretch(const std::string& tex, Eigen::Vector3f tint = {1, 1, 1}) {
    return s_.add_material({tex, TextureMapping::Stretch, 1.0, tint});
  }

  // Box standing on z0 (bottom), centred at (x, y) in the plane.
  Box& box(const std::string& name, double x, double y, double z0, double sx, double sy, double sz, double yaw, int mat) {
    s_.boxes.push_back(Box{name, V3(x, y, z0 + sz / 2), V3(sx, sy, sz), yaw, mat, {-1, -1, -1, -1, -1, -1}, true});
    return s_.boxes.back();
  }
  // Wall from (x0, y0) to (x1, y1) (its centre line), from z0 to z1.
  void wall(double x0, double y0, double x1, double y1, double thick, double z0, double z1, int mat) {
    const double len = std::hypot(x1 - x0, y1 - y0);
    box("wall", (x0 + x1) / 2, (y0 + y1) / 2, z0, len, thick, z1 - z0, std::atan2(y1 - y0, x1 - x0), mat);
  }
  void floor_quad(double x0, double y0, double x1, double y1, int mat) {
    s_.quads.push_back({"floor", V3(x0, y1, 0), V3(x1 - x0, 0, 0), V3(0, -(y1 - y0), 0), mat});
  }
  void ceiling_quad(double x0, double y0, double x1, double y1, double h, int mat) {
    s_.quads.push_back({"ceiling", V3(x0, y0, h), V3(x1 - x0, 0, 0), V3(0, y1 - y0, 0), mat});
  }
  // A flat picture on a wall: `c` is the centre on the wall's surface, `n` the horizontal
  // normal pointing into the room; it floats 3 mm in front of the wall.
  void decal(const std::string& name, V3 c, V3 n, double w, double h, int mat, bool look_target = true) {
    n.normalize();
    const V3 up(0, 0, 1);
    const V3 right = (-n).cross(up);
    c += n * 0.003;
    s_.quads.push_back({name, c - right * w / 2 + up * h / 2, right * w, -up * h, mat});
    if (look_target) s_.look_targets.push_back(c);
  }
  // Light at (x, y, z) with a visible fixture just under the ceiling.
  void light(double x, double y, double z, double intensity, int fixture_mat, double fw = 1.2, double fh = 0.3) {
    s_.lights.push_back({V3(x, y, z - 0.15), intensity});
    s_.quads.push_back({"light", V3(x - fw / 2, y - fh / 2, z - 0.005), V3(fw, 0, 0), V3(0, fh, 0), fixture_mat});
  }
  void tag(int id, double x, double y, double yaw, double size) {
    const std::string key = "tag36h11_" + std::to_string(id);
    if (s_.texture_index(key) < 0) s_.textures.emplace_back(key, tag36h11_image(id, 24));
    Tag t;
    t.id = id;
    t.center = V3(x, y, 0.0015);  // paper on the floor
    t.yaw = yaw;
    t.size = size;
    t.material = stretch(key);
    s_.tags.push_back(t);
  }
  V3 local(double x, double y, double yaw, double lx, double ly, double z = 0) {
    return V3(x + std::cos(yaw) * lx - std::sin(yaw) * ly, y + std::sin(yaw) * lx + std::cos(yaw) * ly, z);
  }
  // Desk: top at 0.75 m on four thin legs (a scan at one height misses all but the legs),
  // optionally a monitor and keyboard facing the local -y side.
  void desk(double x, double y, double yaw, double w, double d, int top_mat, int leg_mat, int screen_mat, int dark_mat, bool monitor) {
    box("desk_top", x, y, 0.72, w, d, 0.03, yaw, top_mat);
    for (int sx : {-1, 1})
      for (int sy : {-1, 1}) {
        const V3 p = local(x, y, yaw, sx * (w / 2 - 0.05), sy * (d / 2 - 0.05));
        box("desk_leg", p.x(), p.y(), 0.0, 0.05, 0.05, 0.72, yaw, leg_mat);
      }
    if (monitor) {
      const V3 m = local(x, y, yaw, 0.0, d / 2 - 0.18);
      auto& mb = box("monitor", m.x(), m.y(), 0.90, 0.56, 0.04, 0.34, yaw, dark_mat);
      mb.face_material[3] = screen_mat;
      const V3 st = local(x, y, yaw, 0.0, d / 2 - 0.15);
      box("monitor_stand", st.x(), st.y(), 0.75, 0.06, 0.06, 0.15, yaw, dark_mat);
      const V3 k = local(x, y, yaw, 0.0, -d / 2 + 0.2);
      box("keyboard", k.x(), k.y(), 0.75, 0.45, 0.15, 0.025, yaw, dark_mat);
      s_.look_targets.push_back(m + V3(0, 0, 1.07));
    }
    s_.look_targets.push_back(V3(x, y, 0.76));
  }
  void chair(double x, double y, double yaw, int seat_mat, int metal_mat) {
    box("chair_seat", x, y, 0.42, 0.46, 0.46, 0.06, yaw, seat_mat);
    const V3 b = local(x, y, yaw, 0.0, 0.21);
    box("chair_back", b.x(), b.y(), 0.55, 0.44, 0.05, 0.42, yaw, seat_mat);
    box("chair_post", x, y, 0.06, 0.06, 0.06, 0.36, yaw, metal_mat);
    box("chair_base_a", x, y, 0.0, 0.56, 0.06, 0.06, yaw + std::numbers::pi / 4, metal_mat);
    box("chair_base_b", x, y, 0.0, 0.56, 0.06, 0.06, yaw - std::numbers::pi / 4, metal_mat);
  }
  // Shelf with its front (+x local face) showing books.
  void shelf(double x, double y, double yaw, double w, double d, double h, int body_mat, int front_mat) {
    auto& b = box("shelf", x, y, 0.0, d, w, h, yaw, body_mat);
    b.face_material[0] = front_mat;
    s_.look_targets.push_back(local(x, y, yaw, d / 2, 0.0, h * 0.6));
  }

  Scene& s_;
};

void lab_room(Scene& s) {
  s.description = "University lab room, 6 x 8 m, 2.8 m high: two desk islands with legs, chairs, book shelves, "
                  "a cabinet, a door, a whiteboard, posters; two floor tags";
  Builder b(s);
  const double W = 6, D = 8, H = 2.8;
  s.ceiling_height = H;
  const int wall = b.repeat(b.texture("paint", 0, cv::Scalar(205, 215, 222)), 2.0);
  const int floor = b.repeat(b.texture("floor_tiles", 0, cv::Scalar(150, 160, 165)), 1.2);
  const int ceil = b.repeat(b.texture("ceiling_tiles", 0, cv::Scalar(225, 228, 228)), 1.2);
  const int woodm = b.repeat(b.texture("wood", 0, cv::Scalar(90, 140, 185)), 1.0);
  const int metal = b.repeat(b.texture("metal", 0, cv::Scalar(120, 120, 125)), 0.5);
  const int dark = b.repeat(b.texture("metal", 1, cv::Scalar(40, 40, 42)), 0.5);
  const int fabric = b.repeat(b.texture("carpet", 0, cv::Scalar(110, 60, 40)), 0.4);
  const int books = b.stretch(b.texture("books", 0));
  const int books2 = b.stretch(b.texture("books", 1));
  const int screen = b.stretch(b.texture("screen", 0));
  const int screen2 = b.stretch(b.texture("screen", 1));
  const int lamp = b.repeat(b.texture("paint", 1, cv::Scalar(245, 248, 250)), 1.0, {1.5f, 1.5f, 1.5f});
  const int cabinet = b.repeat(b.texture("metal", 2, cv::Scalar(175, 180, 185)), 0.9);

  b.floor_quad(0, 0, W, D, floor);
  b.ceiling_quad(0, 0, W, D, H, ceil);
  const double t = 0.15;
  b.wall(-t, -t / 2, W + t, -t / 2, t, 0, H, wall);
  b.wall(-t, D + t / 2, W + t, D + t / 2, t, 0, H, wall);
  b.wall(-t / 2, 0, -t / 2, D, t, 0, H, wall);
  b.wall(W + t / 2, 0, W + t / 2, D, t, 0, H, wall);

  // Desk island: two rows facing each other.
  b.desk(2.3, 3.65, std::numbers::pi, 1.4, 0.7, woodm, metal, screen, dark, true);
  b.desk(3.7, 3.65, std::numbers::pi, 1.4, 0.7, woodm, metal, screen2, dark, true);
  b.desk(2.3, 4.35, 0.0, 1.4, 0.7, woodm, metal, screen2, dark, true);
  b.desk(3.7, 4.35, 0.0, 1.4, 0.7, woodm, metal, screen, dark, false);
  b.box("books_on_desk", 3.9, 4.3, 0.75, 0.25, 0.3, 0.12, 0.2, books2);
  b.chair(2.3, 2.9, std::numbers::pi, fabric, dark);
  b.chair(3.75, 2.95, std::numbers::pi + 0.3, fabric, dark);
  b.chair(2.25, 5.1, 0.1, fabric, dark);
  b.chair(3.7, 5.15, -0.2, fabric, dark);
  // Desk along the north wall (no chair: the robot passes in front of it).
  b.desk(3.0, 7.6, std::numbers::pi, 1.6, 0.7, woodm, metal, screen2, dark, true);

  // Shelves and cabinets along the walls.
  b.shelf(0.2, 2.0, 0.0, 1.0, 0.4, 2.0, woodm, books);
  b.shelf(0.2, 5.6, 0.0, 1.2, 0.4, 1.9, woodm, books2);
  b.shelf(W - 0.2, 6.0, std::numbers::pi, 1.0, 0.4, 2.0, woodm, books2);
  b.shelf(W - 0.25, 2.6, std::numbers::pi, 0.9, 0.5, 1.1, cabinet, cabinet);

  // Wall pictures: door, whiteboard, posters, corkboard.
  b.decal("door", V3(5.0, 0, 1.025), V3(0, 1, 0), 0.9, 2.05, b.stretch(b.texture("door", 0)));
  b.decal("whiteboard", V3(2.4, 0, 1.4), V3(0, 1, 0), 2.0, 1.0, b.stretch(b.texture("whiteboard", 0)));
  b.decal("poster", V3(1.0, D, 1.5), V3(0, -1, 0), 0.6, 0.8, b.stretch(b.texture("poster", 0)));
  b.decal("poster", V3(4.8, D, 1.55), V3(0, -1, 0), 0.7, 0.93, b.stretch(b.texture("poster", 1)));
  b.decal("corkboard", V3(3.0, D, 1.55), V3(0, -1, 0), 1.2, 0.8, b.stretch(b.texture("corkboard", 0)));
  b.decal("poster", V3(W, 4.2, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 2)));
  b.decal("poster", V3(W, 1.0, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 3)));
  b.decal("poster", V3(0, 3.8, 1.45), V3(1, 0, 0), 0.7, 0.93, b.stretch(b.texture("poster", 4)));
  b.decal("sign", V3(0, 7.3, 1.8), V3(1, 0, 0), 0.4, 0.2, b.stretch(b.texture("sign", 0)));

  for (double x : {1.5, 4.5})
    for (double y : {1.5, 4.0, 6.5}) b.light(x, y, H, 2.2, lamp);
  s.ambient = 0.35;

  b.tag(0, 1.45, 2.3, 0.3, 0.16);
  b.tag(1, 4.65, 5.9, -1.0, 0.16);

  s.floor = {{0, 0, W, D}};
  s.robot_loop = {{0.95, 1.3}, {5.1, 1.3}, {5.1, 6.6}, {0.95, 6.6}};
}

void corridor_loop(Scene& s) {
  s.description = "Basement corridor loop: 2 m wide corridors around a 23 x 13 m block (80 m centre line), 2.6 m high, "
                  "long plain walls, doors, notice boards, pipes, 15 tag36h11 markers on the floor";
  Builder b(s);
  const double X = 27, Y = 17, H = 2.6, t = 0.2;
  s.ceiling_height = H;
  const int wall = b.repeat(b.texture("paint", 2, cv::Scalar(185, 210, 220)), 2.5);
  const int wall2 = b.repeat(b.texture("paint", 3, cv::Scalar(200, 200, 195)), 2.5);
  const int floor = b.repeat(b.texture("concrete", 0, cv::Scalar(135, 140, 142)), 2.0);
  const int ceil = b.repeat(b.texture("ceiling_tiles", 1, cv::Scalar(215, 218, 218)), 1.2);
  const int skirting = b.repeat(b.texture("metal", 3, cv::Scalar(50, 55, 60)), 1.0);
  const int pipe = b.repeat(b.texture("metal", 4, cv::Scalar(150, 150, 150)), 1.0);
  const int red = b.repeat(b.texture("metal", 5, cv::Scalar(40, 40, 190)), 0.5);
  const int radiator = b.repeat(b.texture("metal", 6, cv::Scalar(210, 210, 210)), 0.3);
  const int brick = b.repeat(b.texture("brick", 0, cv::Scalar(80, 100, 150)), 1.2);
  const int lamp = b.repeat(b.texture("paint", 1, cv::Scalar(245, 248, 250)), 1.0, {1.5f, 1.5f, 1.5f});

  b.floor_quad(0, 0, X, Y, floor);
  b.ceiling_quad(0, 0, X, Y, H, ceil);
  b.wall(-t, -t / 2, X + t, -t / 2, t, 0, H, wall);
  b.wall(-t, Y + t / 2, X + t, Y + t / 2, t, 0, H, wall);
  b.wall(-t / 2, 0, -t / 2, Y, t, 0, H, wall2);
  b.wall(X + t / 2, 0, X + t / 2, Y, t, 0, H, wall2);
  // The inner block; its west face is brick, the others painted.
  auto& block = b.box("inner_block", X / 2, Y / 2, 0, 23, 13, H, 0, wall);
  block.face_material[1] = brick;
  // Skirting boards on the outer walls and around the block.
  b.box("skirting", X / 2, 0.01, 0, X, 0.02, 0.1, 0, skirting);
  b.box("skirting", X / 2, Y - 0.01, 0, X, 0.02, 0.1, 0, skirting);
  b.box("skirting", 0.01, Y / 2, 0, 0.02, Y, 0.1, 0, skirting);
  b.box("skirting", X - 0.01, Y / 2, 0, 0.02, Y, 0.1, 0, skirting);
  // Pipes under the ceiling along the outer walls.
  b.box("pipe", X / 2, 0.12, 2.3, X, 0.1, 0.1, 0, pipe);
  b.box("pipe", X - 0.12, Y / 2, 2.3, 0.1, Y, 0.1, 0, pipe);
  b.box("pipe", X / 2, Y - 0.12, 2.15, X, 0.14, 0.14, 0, pipe);

  // Wall furniture. South corridor: outer wall y = 0 (normal +y), block wall y = 2 (normal -y).
  const int door = b.stretch(b.texture("door", 1));
  const int door2 = b.stretch(b.texture("door", 2));
  b.decal("door", V3(3.5, 2, 1.025), V3(0, -1, 0), 0.9, 2.05, door);
  b.decal("door", V3(21.0, 0, 1.025), V3(0, 1, 0), 0.9, 2.05, door2);
  b.decal("notice", V3(17.5, 0, 1.5), V3(0, 1, 0), 1.0, 0.7, b.stretch(b.texture("corkboard", 1)));
  b.decal("sign", V3(12.0, 2, 2.0), V3(0, -1, 0), 0.4, 0.2, b.stretch(b.texture("sign", 1)));
  b.box("radiator", 5.5, 0.06, 0.15, 1.0, 0.1, 0.6, 0, radiator);
  // East corridor: outer wall x = 27 (normal -x), block wall x = 25 (normal +x).
  b.decal("poster", V3(X, 4.0, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 5)));
  b.decal("door", V3(25, 9.0, 1.025), V3(1, 0, 0), 0.9, 2.05, door);
  b.box("extinguisher", X - 0.1, 12.5, 0.3, 0.16, 0.16, 0.5, 0, red);
  b.decal("sign", V3(X, 12.5, 1.1), V3(-1, 0, 0), 0.3, 0.15, b.stretch(b.texture("sign", 2)));
  // North corridor: outer wall y = 17 (normal -y), block wall y = 15 (normal +y).
  b.decal("door", V3(22.0, Y, 1.025), V3(0, -1, 0), 0.9, 2.05, door2);
  b.decal("door", V3(15.5, 15, 1.025), V3(0, 1, 0), 0.9, 2.05, door);
  b.decal("poster", V3(11.0, Y, 1.5), V3(0, -1, 0), 0.7, 0.93, b.stretch(b.texture("poster", 6)));
  b.decal("notice", V3(5.0, 15, 1.5), V3(0, 1, 0), 1.2, 0.8, b.stretch(b.texture("corkboard", 2)));
  b.box("radiator", 8.0, Y - 0.06, 0.15, 1.0, 0.1, 0.6, 0, radiator);
  // West corridor: outer wall x = 0 (normal +x), block wall x = 2 (normal -x, brick).
  b.decal("door", V3(0, 8.0, 1.025), V3(1, 0, 0), 0.9, 2.05, door2);
  b.decal("sign", V3(0, 3.0, 2.0), V3(1, 0, 0), 0.4, 0.2, b.stretch(b.texture("sign", 3)));
  b.box("extinguisher", 0.1, 13.0, 0.3, 0.16, 0.16, 0.5, 0, red);
  b.decal("poster", V3(0, 11.0, 1.5), V3(1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 7)));
  // Corners: something to look at while turning.
  b.decal("poster", V3(X, 0.9, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 8)));
  b.decal("poster", V3(26.0, Y, 1.5), V3(0, -1, 0), 0.6, 0.8, b.stretch(b.texture("poster", 9)));
  b.decal("notice", V3(0, 16.0, 1.5), V3(1, 0, 0), 0.8, 0.6, b.stretch(b.texture("corkboard", 3)));
  b.decal("poster", V3(1.0, 0, 1.5), V3(0, 1, 0), 0.6, 0.8, b.stretch(b.texture("poster", 10)));

  // Lights along the centre line.
  for (double x = 2.0; x < X; x += 4.5) {
    b.light(x, 1.0, H, 1.6, lamp, 1.2, 0.25);
    b.light(x, 16.0, H, 1.6, lamp, 1.2, 0.25);
  }
  for (double y = 4.5; y < 14; y += 4.5) {
    b.light(1.0, y, H, 1.6, lamp, 0.25, 1.2);
    b.light(26.0, y, H, 1.6, lamp, 0.25, 1.2);
  }
  s.ambient = 0.3;

  // 15 markers on the floor along the loop, at irregular spacing and small offsets from the
  // centre line, as in the source's basement experiment; none closer than 3 m after a corner,
  // where the robot's camera, just round it, would not see it (rgbd_motion_test).
  const std::vector<Eigen::Vector2d> loop = {{1, 1}, {26, 1}, {26, 16}, {1, 16}};
  const double at[15] = {3.0, 8.5, 14.0, 19.5, 24.0, 28.0, 33.0, 37.5, 43.0, 49.0, 55.5, 61.0, 68.0, 71.0, 76.5};
  const double off[15] = {0.3, -0.35, 0.1, 0.4, -0.2, 0.35, -0.3, 0.0, 0.25, -0.4, 0.3, -0.1, 0.4, -0.3, 0.2};
  for (int i = 0; i < 15; ++i) {
    double sarc = at[i];
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d a = loop[k], c = loop[(k + 1) % 4];
      const double len = (c - a).norm();
      if (sarc <= len) {
        const Eigen::Vector2d dir = (c - a) / len;
        const Eigen::Vector2d p = a + dir * sarc + Eigen::Vector2d(-dir.y(), dir.x()) * off[i];
        b.tag(i + 1, p.x(), p.y(), std::atan2(dir.y(), dir.x()) + 0.4 * std::sin(i * 1.7), 0.2);
        s.look_targets.push_back(V3(p.x(), p.y(), 0.0));
        break;
      }
      sarc -= len;
    }
  }
  s.floor = {{0, 0, X, 2}, {0, Y - 2, X, Y}, {0, 0, 2, Y}, {X - 2, 0, X, Y}};
  s.robot_loop = loop;
}

void office(Scene& s) {
  s.description = "Office floor 14 x 10 m: a corridor (y 4..6) joining four rooms through two doors each; desks, "
                  "shelves, whiteboards, posters";
  Builder b(s);
  const double X = 14, Y = 10, H = 2.7, t = 0.15;
  s.ceiling_height = H;
  const int wall = b.repeat(b.texture("paint", 4, cv::Scalar(190, 215, 225)), 2.0);
  const int wall2 = b.repeat(b.texture("paint", 5, cv::Scalar(215, 205, 200)), 2.0);
  const int carpet = b.repeat(b.texture("carpet", 1, cv::Scalar(95, 90, 85)), 1.0);
  const int lino = b.repeat(b.texture("lino", 0, cv::Scalar(170, 175, 180)), 1.2);
  const int ceil = b.repeat(b.texture("ceiling_tiles", 2, cv::Scalar(225, 228, 228)), 1.2);
  const int woodm = b.repeat(b.texture("wood", 1, cv::Scalar(110, 150, 190)), 1.0);
  const int metal = b.repeat(b.texture("metal", 0, cv::Scalar(120, 120, 125)), 0.5);
  const int dark = b.repeat(b.texture("metal", 1, cv::Scalar(40, 40, 42)), 0.5);
  const int fabric = b.repeat(b.texture("carpet", 2, cv::Scalar(60, 110, 60)), 0.4);
  const int screen = b.stretch(b.texture("screen", 2));
  const int lamp = b.repeat(b.texture("paint", 1, cv::Scalar(245, 248, 250)), 1.0, {1.5f, 1.5f, 1.5f});

  b.floor_quad(0, 4, X, 6, lino);
  b.floor_quad(0, 6, X, Y, carpet);
  b.floor_quad(0, 0, X, 4, carpet);
  b.ceiling_quad(0, 0, X, Y, H, ceil);
  // Outer walls.
  b.wall(-t, -t / 2, X + t, -t / 2, t, 0, H, wall);
  b.wall(-t, Y + t / 2, X + t, Y + t / 2, t, 0, H, wall);
  b.wall(-t / 2, 0, -t / 2, Y, t, 0, H, wall2);
  b.wall(X + t / 2, 0, X + t / 2, Y, t, 0, H, wall2);
  // Corridor walls with door openings 1.2 m wide at x = 2, 5, 9, 12 and lintels above.
  const double doors[4] = {2.0, 5.0, 9.0, 12.0};
  for (double yw : {3.925, 6.075}) {
    double x = 0;
    for (double dx : doors) {
      b.wall(x, yw, dx - 0.6, yw, t, 0, H, wall);
      b.wall(dx - 0.6, yw, dx + 0.6, yw, t, 2.1, H, wall);
      x = dx + 0.6;
    }
    b.wall(x, yw, X, yw, t, 0, H, wall);
  }
  // Room dividers.
  b.wall(7.0, 6.15, 7.0, Y, t, 0, H, wall2);
  b.wall(7.0, 0, 7.0, 3.85, t, 0, H, wall2);

  // Room A (north-west): desks along the north wall, a shelf on the west wall.
  b.desk(3.5, 9.6, std::numbers::pi, 1.6, 0.7, woodm, metal, screen, dark, true);
  b.chair(3.4, 9.0, std::numbers::pi, fabric, dark);
  b.shelf(0.2, 8.3, 0.0, 1.2, 0.4, 2.0, woodm, b.stretch(b.texture("books", 2)));
  b.desk(6.45, 8.0, std::numbers::pi / 2, 1.4, 0.7, woodm, metal, screen, dark, false);
  b.decal("whiteboard", V3(3.5, Y, 1.4), V3(0, -1, 0), 1.8, 0.9, b.stretch(b.texture("whiteboard", 1)));
  b.decal("poster", V3(6.925, 9.0, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 11)));
  // Room B (north-east).
  b.desk(10.5, 9.6, std::numbers::pi, 1.6, 0.7, woodm, metal, screen, dark, true);
  b.shelf(X - 0.2, 8.0, std::numbers::pi, 1.0, 0.4, 1.8, woodm, b.stretch(b.texture("books", 3)));
  b.decal("poster", V3(7.075, 8.5, 1.5), V3(1, 0, 0), 0.7, 0.93, b.stretch(b.texture("poster", 12)));
  b.decal("corkboard", V3(10.5, Y, 1.6), V3(0, -1, 0), 1.2, 0.7, b.stretch(b.texture("corkboard", 4)));
  // Room C (south-west).
  b.desk(3.5, 0.4, 0.0, 1.6, 0.7, woodm, metal, screen, dark, true);
  b.shelf(0.2, 1.7, 0.0, 1.0, 0.4, 2.0, woodm, b.stretch(b.texture("books", 4)));
  b.decal("poster", V3(6.925, 1.5, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 13)));
  b.decal("whiteboard", V3(3.5, 0, 1.45), V3(0, 1, 0), 1.6, 0.8, b.stretch(b.texture("whiteboard", 2)));
  // Room D (south-east).
  b.desk(10.5, 0.4, 0.0, 1.6, 0.7, woodm, metal, screen, dark, true);
  b.chair(10.4, 1.0, 0.0, fabric, dark);
  b.shelf(X - 0.25, 2.0, std::numbers::pi, 0.9, 0.5, 1.1, metal, metal);
  b.decal("poster", V3(X, 1.0, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 14)));
  // Corridor ends.
  b.decal("door", V3(0, 5.0, 1.025), V3(1, 0, 0), 0.9, 2.05, b.stretch(b.texture("door", 3)));
  b.decal("poster", V3(X, 5.0, 1.5), V3(-1, 0, 0), 0.6, 0.8, b.stretch(b.texture("poster", 15)));
  b.decal("sign", V3(7.0, 6.0, 2.0), V3(0, -1, 0), 0.4, 0.2, b.stretch(b.texture("sign", 4)));

  for (double x : {3.5, 10.5}) {
    b.light(x, 8.0, H, 2.0, lamp);
    b.light(x, 2.0, H, 2.0, lamp);
  }
  for (double x : {2.0, 7.0, 12.0}) b.light(x, 5.0, H, 1.5, lamp, 0.3, 1.0);
  s.ambient = 0.35;
  b.tag(20, 3.5, 4.7, 0.2, 0.16);
  b.tag(21, 10.5, 5.3, -0.5, 0.16);

  s.floor = {{0, 4, X, 6}, {0, 6.15, 6.925, Y}, {7.075, 6.15, X, Y}, {0, 0, 6.925, 3.85}, {7.075, 0, X, 3.85}};
  for (double dx : doors) {
    s.floor.push_back({dx - 0.6, 3.85, dx + 0.6, 4.0});
    s.floor.push_back({dx - 0.6, 6.0, dx + 0.6, 6.15});
  }
  s.robot_loop = {{2, 5}, {2, 8}, {5, 8}, {5, 5}, {9, 5}, {9, 8}, {12, 8}, {12, 5}, {12, 2}, {9, 2}, {9, 5}, {5, 5}, {5, 2}, {2, 2}};
}

void low_texture(Scene& s) {
  s.description = "Hard case: a 5 x 6 m room with plain paint, plain lino and plain ceiling; one door, one small "
                  "sign, one white cabinet";
  Builder b(s);
  const double X = 5, Y = 6, H = 2.7, t = 0.15;
  s.ceiling_height = H;
  const int wall = b.repeat(b.texture("paint", 6, cv::Scalar(215, 222, 226)), 3.0);
  const int floor = b.repeat(b.texture("paint", 7, cv::Scalar(150, 152, 150)), 3.0);
  const int ceil = b.repeat(b.texture("paint", 8, cv::Scalar(230, 232, 232)), 3.0);
  const int white = b.repeat(b.texture("paint", 9, cv::Scalar(225, 228, 230)), 1.0);
  const int lamp = b.repeat(b.texture("paint", 1, cv::Scalar(245, 248, 250)), 1.0, {1.5f, 1.5f, 1.5f});
  b.floor_quad(0, 0, X, Y, floor);
  b.ceiling_quad(0, 0, X, Y, H, ceil);
  b.wall(-t, -t / 2, X + t, -t / 2, t, 0, H, wall);
  b.wall(-t, Y + t / 2, X + t, Y + t / 2, t, 0, H, wall);
  b.wall(-t / 2, 0, -t / 2, Y, t, 0, H, wall);
  b.wall(X + t / 2, 0, X + t / 2, Y, t, 0, H, wall);
  b.decal("door", V3(3.8, 0, 1.025), V3(0, 1, 0), 0.9, 2.05, b.stretch(b.texture("door", 4)));
  b.decal("sign", V3(0, 3.0, 1.6), V3(1, 0, 0), 0.3, 0.15, b.stretch(b.texture("sign", 5)));
  b.box("cabinet", X - 0.25, 4.5, 0, 0.5, 0.8, 1.2, 0, white);
  s.look_targets.push_back(V3(X / 2, Y, 1.4));
  s.look_targets.push_back(V3(0, 1.5, 1.4));
  s.look_targets.push_back(V3(X, 2.0, 1.2));
  b.light(2.5, 3.0, H, 2.5, lamp);
  s.ambient = 0.4;
  s.floor = {{0, 0, X, Y}};
  s.robot_loop = {{1, 1}, {3.9, 1}, {3.9, 5}, {1, 5}};
}

void demo_room(Scene& s) {
  s.description = "Small furnished room 4 x 5 m for the demo: shelves, a desk, posters and two floor tags";
  Builder b(s);
  const double X = 4, Y = 5, H = 2.6, t = 0.15;
  s.ceiling_height = H;
  const int wall = b.repeat(b.texture("paint", 10, cv::Scalar(200, 212, 220)), 2.0);
  const int floor = b.repeat(b.texture("wood", 2, cv::Scalar(80, 125, 170)), 1.5);
  const int ceil = b.repeat(b.texture("ceiling_tiles", 3, cv::Scalar(225, 228, 228)), 1.2);
  const int woodm = b.repeat(b.texture("wood", 0, cv::Scalar(90, 140, 185)), 1.0);
  const int metal = b.repeat(b.texture("metal", 0, cv::Scalar(120, 120, 125)), 0.5);
  const int dark = b.repeat(b.texture("metal", 1, cv::Scalar(40, 40, 42)), 0.5);
  const int lamp = b.repeat(b.texture("paint", 1, cv::Scalar(245, 248, 250)), 1.0, {1.5f, 1.5f, 1.5f});
  b.floor_quad(0, 0, X, Y, floor);
  b.ceiling_quad(0, 0, X, Y, H, ceil);
  b.wall(-t, -t / 2, X + t, -t / 2, t, 0, H, wall);
  b.wall(-t, Y + t / 2, X + t, Y + t / 2, t, 0, H, wall);
  b.wall(-t / 2, 0, -t / 2, Y, t, 0, H, wall);
  b.wall(X + t / 2, 0, X + t / 2, Y, t, 0, H, wall);
  b.shelf(0.2, 2.5, 0.0, 1.2, 0.4, 2.0, woodm, b.stretch(b.texture("books", 5)));
  b.desk(2.0, Y - 0.4, std::numbers::pi, 1.4, 0.7, woodm, metal, b.stretch(b.texture("screen", 3)), dark, true);
  b.decal("poster", V3(X, 2.5, 1.5), V3(-1, 0, 0), 0.7, 0.93, b.stretch(b.texture("poster", 16)));
  b.decal("whiteboard", V3(2.0, 0, 1.4), V3(0, 1, 0), 1.6, 0.8, b.stretch(b.texture("whiteboard", 3)));
  b.decal("poster", V3(0.8, Y, 1.6), V3(0, -1, 0), 0.5, 0.67, b.stretch(b.texture("poster", 17)));
  b.light(2.0, 2.5, H, 2.5, lamp);
  s.ambient = 0.4;
  b.tag(30, 1.5, 1.5, 0.0, 0.16);
  b.tag(31, 2.6, 3.0, 0.8, 0.16);
  s.floor = {{0, 0, X, Y}};
  s.robot_loop = {{1.0, 1.0}, {3.0, 1.0}, {3.0, 3.8}, {1.0, 3.8}};
}

}  // namespace

std::vector<std::string> scene_names() { return {"demo", "lab-room", "corridor-loop", "office", "low-texture"}; }

bool is_scene_name(const std::string& name) {
  for (const auto& n : scene_names())
    if (n == name) return true;
  return false;
}

Scene build_scene(const std::string& name) {
  Scene s;
  s.name = name;
  if (name == "lab-room") lab_room(s);
  else if (name == "corridor-loop") corridor_loop(s);
  else if (name == "office") office(s);
  else if (name == "low-texture") low_texture(s);
  else if (name == "demo") demo_room(s);
  else throw std::invalid_argument("unknown scene " + name);
  return s;
}

}  // namespace builtscene::synth
