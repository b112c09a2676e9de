#include "ogm/map_server_io.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>

#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include "core/errors.hpp"

namespace builtscene {

int occupancy_class(std::int8_t v, MapServerThresholds t) {
  if (v < 0) return -1;
  if (v >= t.occupied * 100.0) return 1;
  if (v <= t.free * 100.0) return 0;
  return -1;
}

void save_map_server(const OccupancyGrid& grid, const std::filesystem::path& yaml_path, MapServerThresholds t) {
  if (yaml_path.has_parent_path()) std::filesystem::create_directories(yaml_path.parent_path());
  auto pgm_path = yaml_path;
  pgm_path.replace_extension(".pgm");
  cv::Mat img(std::max(1, grid.height()), std::max(1, grid.width()), CV_8UC1, cv::Scalar(205));
  for (int r = 0; r < grid.height(); ++r)
    for (int c = 0; c < grid.width(); ++c) {
      const int cls = occupancy_class(grid.at({c, r}), t);
      img.at<std::uint8_t>(grid.height() - 1 - r, c) = cls == 1 ? 0 : cls == 0 ? 254 : 205;
    }
  if (!cv::imwrite(pgm_path.string(), img)) throw Failure(located(pgm_path, 0, "cannot write map image"));
  std::ofstream y(yaml_path);
  y << std::setprecision(10) << "image: " << pgm_path.filename().string() << "\nmode: trinary\nresolution: "
    << grid.resolution() << "\norigin: [" << grid.origin().x() << ", " << grid.origin().y() << ", 0.0]\n"
    << "negate: 0\noccupied_thresh: " << t.occupied << "\nfree_thresh: " << t.free << "\n";
  if (!y) throw Failure(located(yaml_path, 0, "cannot write map YAML"));
}

OccupancyGrid load_map_server(const std::filesystem::path& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path.string());
  } catch (const YAML::BadFile&) {
    throw_input_error(yaml_path, 0, "cannot open map YAML");
  } catch (const YAML::Exception& e) {
    throw_input_error(yaml_path, static_cast<std::size_t>(e.mark.line + 1), "invalid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw_input_error(yaml_path, 0, "expected a map_server YAML map");
  auto field = [&](const char* key) {
    YAML::Node n = root[key];
    if (!n.IsDefined()) throw_input_error(yaml_path, 0, std::string("missing field '") + key + "'");
    return n;
  };
  auto number = [&](const YAML::Node& n, const char* key) {
    try {
      const double v = n.as<double>();
      if (!std::isfinite(v)) throw YAML::Exception(n.Mark(), "not finite");
      return v;
    } catch (const YAML::Exception&) {
      throw_input_error(yaml_path, static_cast<std::size_t>(n.Mark().line + 1), std::string("field '") + key + "' must be a number");
    }
  };
  const std::string image = field("image").as<std::string>();
  const double res = number(field("resolution"), "resolution");
  if (res <= 0) throw_input_error(yaml_path, 0, "field 'resolution' must be positive");
  const YAML::Node origin = field("origin");
  if (!origin.IsSequence() || origin.size() != 3) throw_input_error(yaml_path, 0, "field 'origin' must be [x, y, yaw]");
  const double ox = number(origin[0], "origin"), oy = number(origin[1], "origin"), yaw = number(origin[2], "origin");
  if (std::abs(yaw) > 1e-9) throw_input_error(yaml_path, 0, "field 'origin': a rotated map (yaw != 0) is not supported");
  const bool negate = root["negate"].IsDefined() && number(root["negate"], "negate") != 0;
  MapServerThresholds t;
  t.occupied = number(field("occupied_thresh"), "occupied_thresh");
  t.free = number(field("free_thresh"), "free_thresh");
  if (!(t.free < t.occupied)) throw_input_error(yaml_path, 0, "free_thresh must be below occupied_thresh");
  const std::string mode = root["mode"].IsDefined() ? root["mode"].as<std::string>() : "trinary";
  if (mode != "trinary" && mode != "scale" && mode != "raw") throw_input_error(yaml_path, 0, "field 'mode' must be trinary, scale or raw");

  std::filesystem::path img_path = image;
  if (img_path.is_relative()) img_path = yaml_path.parent_path() / img_path;
  const cv::Mat img = cv::imread(img_path.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw_input_error(img_path, 0, "cannot read map image (named by 'image' in " + yaml_path.string() + ")");
  OccupancyGrid g(img.cols, img.rows, res, {ox, oy});
  for (int r = 0; r < g.height(); ++r)
    for (int c = 0; c < g.width(); ++c) {
      const int px = img.at<std::uint8_t>(g.height() - 1 - r, c);
      const double occ = negate ? px / 255.0 : (255 - px) / 255.0;
      std::int8_t v = -1;
      if (occ > t.occupied) v = 100;
      else if (occ < t.free) v = 0;
      else if (mode != "trinary") v = static_cast<std::int8_t>(std::lround(99.0 * (occ - t.free) / (t.occupied - t.free)));
      g.at({c, r}) = v;
    }
  return g;
}

}  // namespace builtscene

namespace builtscene {

void append_ground_frame(const std::filesystem::path& yaml_path, const SE3& T_gw) {
  std::ofstream y(yaml_path, std::ios::app);
  const auto& t = T_gw.translation();
  const auto& q = T_gw.rotation();
  y << std::setprecision(17) << "ground_frame_T_gw: [" << t.x() << ", " << t.y() << ", " << t.z() << ", " << q.x()
    << ", " << q.y() << ", " << q.z() << ", " << q.w() << "]\n";
  if (!y) throw Failure(located(yaml_path, 0, "cannot write map YAML"));
}

std::optional<SE3> read_ground_frame(const std::filesystem::path& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path.string());
  } catch (const YAML::BadFile&) {
    throw_input_error(yaml_path, 0, "cannot open map YAML");
  } catch (const YAML::Exception& e) {
    throw_input_error(yaml_path, static_cast<std::size_t>(e.mark.line + 1), "invalid YAML: " + e.msg);
  }
  const YAML::Node n = root["ground_frame_T_gw"];
  if (!n.IsDefined()) return std::nullopt;
  std::vector<double> v;
  try {
    v = n.as<std::vector<double>>();
  } catch (const YAML::Exception&) {
    throw_input_error(yaml_path, static_cast<std::size_t>(n.Mark().line + 1), "field 'ground_frame_T_gw' must be 7 numbers");
  }
  Eigen::Quaterniond q(v.size() == 7 ? v[6] : 0, v.size() == 7 ? v[3] : 0, v.size() == 7 ? v[4] : 0, v.size() == 7 ? v[5] : 0);
  if (v.size() != 7 || !std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > 1e-6 ||
      !std::isfinite(v[0] + v[1] + v[2]))
    throw_input_error(yaml_path, static_cast<std::size_t>(n.Mark().line + 1),
                      "field 'ground_frame_T_gw' must be tx ty tz qx qy qz qw with a unit quaternion");
  return SE3(q, Eigen::Vector3d(v[0], v[1], v[2]));
}

}  // namespace builtscene
