// truth_map.pgm/.yaml agree with the geometry in scene.json, and with the depth images.
#include <gtest/gtest.h>

#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "io/tum_dataset.hpp"
#include "rgbd_test_util.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace bs = builtscene;
namespace synth = builtscene::synth;
using namespace synth_test;

namespace {

struct MapFile {
  cv::Mat pgm;
  double res = 0, ox = 0, oy = 0;
  // PGM value at world (x, y): row 0 of the image is the top (max y).
  int at(double x, double y) const {
    const int c = static_cast<int>(std::floor((x - ox) / res));
    const int r = pgm.rows - 1 - static_cast<int>(std::floor((y - oy) / res));
    if (c < 0 || r < 0 || c >= pgm.cols || r >= pgm.rows) return -1;
    return pgm.at<uint8_t>(r, c);
  }
};

MapFile read_map(const std::filesystem::path& dir) {
  MapFile m;
  std::ifstream y(dir / "truth_map.yaml");
  std::string line, image;
  while (std::getline(y, line)) {
    if (line.rfind("resolution:", 0) == 0) m.res = std::stod(line.substr(11));
    if (line.rfind("origin:", 0) == 0) {
      EXPECT_EQ(std::sscanf(line.c_str(), "origin: [%lf, %lf", &m.ox, &m.oy), 2);
    }
    if (line.rfind("image:", 0) == 0) image = line.substr(7);
    if (line.rfind("negate:", 0) == 0) {
      EXPECT_EQ(line, "negate: 0");
    }
  }
  EXPECT_EQ(image, "truth_map.pgm");
  m.pgm = cv::imread((dir / image).string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(m.pgm.type(), CV_8U);
  return m;
}

// Inside box b's footprint, by at least `margin`?
bool inside_footprint(const JsonBox& b, double x, double y, double margin) {
  const Eigen::Vector3d l = box_local(b, {x, y, b.c.z()});
  return std::abs(l.x()) <= b.h.x() - margin && std::abs(l.y()) <= b.h.y() - margin;
}
double footprint_distance(const JsonBox& b, double x, double y) {
  const Eigen::Vector3d l = box_local(b, {x, y, b.c.z()});
  return std::hypot(std::max(0.0, std::abs(l.x()) - b.h.x()), std::max(0.0, std::abs(l.y()) - b.h.y()));
}

}  // namespace

TEST(RgbdTruthMap, AgreesWithSceneGeometry) {
  for (const std::string scene : {"lab-room", "corridor-loop", "office"}) {
    synth::RgbdSequenceOptions o;
    o.scene = scene;
    o.out = temp_dir("map_" + scene);
    o.frames = 1;
    o.width = 160;
    o.height = 120;
    synth::generate_rgbd_sequence(o);
    const JsonScene js = load_scene_json(o.out / "scene.json");
    const MapFile m = read_map(o.out);
    EXPECT_DOUBLE_EQ(m.res, 0.05);
    std::size_t checked_occ = 0, checked_free = 0, checked_unknown = 0;
    for (int r = 0; r < m.pgm.rows; ++r)
      for (int c = 0; c < m.pgm.cols; ++c) {
        const double x = m.ox + (c + 0.5) * m.res, y = m.oy + (m.pgm.rows - 1 - r + 0.5) * m.res;
        bool in_band_box = false, near_box = false;
        for (const auto& b : js.boxes) {
          if (!b.solid) continue;
          const bool in_band = b.c.z() + b.h.z() >= js.band_min && b.c.z() - b.h.z() <= js.band_max;
          if (!in_band) continue;
          if (inside_footprint(b, x, y, 0.0)) in_band_box = true;
          if (footprint_distance(b, x, y) < 0.05) near_box = true;
        }
        bool on_floor = false;
        for (const auto& f : js.floor) on_floor = on_floor || (x >= f[0] && x <= f[2] && y >= f[1] && y <= f[3]);
        const int v = m.pgm.at<uint8_t>(r, c);
        if (in_band_box) {
          EXPECT_EQ(v, 0) << scene << " cell centre (" << x << ", " << y << ") is inside a box in the band";
          ++checked_occ;
        } else if (!near_box && on_floor) {
          EXPECT_EQ(v, 254) << scene << " (" << x << ", " << y << ") is open floor";
          ++checked_free;
        } else if (!near_box && !on_floor) {
          EXPECT_EQ(v, 205) << scene << " (" << x << ", " << y << ") is off the floor";
          ++checked_unknown;
        }
      }
    EXPECT_GT(checked_occ, 100u);
    EXPECT_GT(checked_free, 1000u);
    EXPECT_GT(checked_unknown, 100u);
    std::filesystem::remove_all(o.out);
  }
}

TEST(RgbdTruthMap, DeskTopOccupiedBetweenItsLegs) {
  synth::RgbdSequenceOptions o;
  o.scene = "lab-room";
  o.out = temp_dir("desk");
  o.frames = 1;
  o.width = 160;
  o.height = 120;
  synth::generate_rgbd_sequence(o);
  const JsonScene js = load_scene_json(o.out / "scene.json");
  const MapFile m = read_map(o.out);
  int desks = 0;
  for (const auto& b : js.boxes) {
    if (b.name != "desk_top") continue;
    ++desks;
    // Nothing stands at the camera's height (1 m) here: a one-height scan sees free space.
    bool anything_at_1m = false;
    for (const auto& other : js.boxes)
      if (other.c.z() - other.h.z() <= 1.0 && other.c.z() + other.h.z() >= 1.0 && inside_footprint(other, b.c.x(), b.c.y(), 0))
        anything_at_1m = true;
    EXPECT_FALSE(anything_at_1m);
    EXPECT_EQ(m.at(b.c.x(), b.c.y()), 0) << "desk top at (" << b.c.x() << ", " << b.c.y() << ") must be occupied";
  }
  EXPECT_GE(desks, 4);
  std::filesystem::remove_all(o.out);
}

TEST(RgbdTruthMap, DepthPointsInTheBandFallOnOccupiedCells) {
  synth::RgbdSequenceOptions o;
  o.scene = "lab-room";
  o.out = temp_dir("depth_band");
  o.frames = 3;
  o.motion = synth::MotionKind::Robot;
  o.kinect_noise = false;
  o.width = 320;
  o.height = 240;
  synth::generate_rgbd_sequence(o);
  const MapFile m = read_map(o.out);
  const JsonScene js = load_scene_json(o.out / "scene.json");
  const auto ds = bs::TumDataset::open(o.out);
  const auto gt = ds.groundtruth();
  std::size_t n = 0, hit = 0;
  for (std::size_t i = 0; i < ds.size(); ++i) {
    const cv::Mat d = ds.load_depth(i);
    for (int y = 0; y < d.rows; y += 2)
      for (int x = 0; x < d.cols; x += 2) {
        const float z = d.at<float>(y, x);
        if (z <= 0) continue;
        const Eigen::Vector3d p = gt[i].pose * ds.settings().camera.unproject({x, y}, z);
        // Points of the band, excluding the paper-thin floor decals and the ceiling.
        if (p.z() < js.band_min + 0.02 || p.z() > js.band_max - 0.02) continue;
        ++n;
        bool occ = false;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) occ = occ || m.at(p.x() + dx * m.res, p.y() + dy * m.res) == 0;
        if (occ) ++hit;
      }
  }
  ASSERT_GT(n, 1000u);
  EXPECT_GE(static_cast<double>(hit) / n, 0.99);
  std::filesystem::remove_all(o.out);
}
