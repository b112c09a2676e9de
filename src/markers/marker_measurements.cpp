#include "markers/marker_measurements.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {
namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string c;
  while (std::getline(ss, c, ',')) cells.push_back(c);
  return cells;
}

double number(const std::string& s, const std::filesystem::path& path, std::size_t line, const char* field) {
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    while (used < s.size() && std::isspace(static_cast<unsigned char>(s[used]))) ++used;
    if (used == s.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw_input_error(path, line, std::string("field '") + field + "' must be a finite number, got '" + s + "'");
}

template <typename Row>
std::vector<Row> read_rows(const std::filesystem::path& path, std::size_t columns, const char* header_start,
                           Row (*parse)(const std::vector<std::string>&, const std::filesystem::path&, std::size_t)) {
  std::ifstream in(path);
  if (!in) throw_input_error(path, 0, "cannot open file");
  std::vector<Row> out;
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#' || line.rfind(header_start, 0) == 0) continue;
    const auto cells = split_csv(line);
    if (cells.size() < columns)
      throw_input_error(path, n, "expected " + std::to_string(columns) + " columns, got " + std::to_string(cells.size()));
    out.push_back(parse(cells, path, n));
  }
  return out;
}

MarkerMeasurement parse_measurement(const std::vector<std::string>& c, const std::filesystem::path& p, std::size_t n) {
  MarkerMeasurement m;
  m.frame = static_cast<std::size_t>(number(c[0], p, n, "frame"));
  m.time = number(c[1], p, n, "time");
  m.id = static_cast<int>(number(c[2], p, n, "id"));
  m.position = {number(c[3], p, n, "x"), number(c[4], p, n, "y"), number(c[5], p, n, "z")};
  m.distance = number(c[6], p, n, "distance");
  m.angle_deg = number(c[7], p, n, "angle_deg");
  return m;
}

MarkerTruth parse_truth(const std::vector<std::string>& c, const std::filesystem::path& p, std::size_t n) {
  MarkerTruth t;
  t.id = static_cast<int>(number(c[0], p, n, "id"));
  t.position = {number(c[1], p, n, "x"), number(c[2], p, n, "y"), number(c[3], p, n, "z")};
  t.yaw = c.size() > 4 ? number(c[4], p, n, "yaw") : 0.0;
  t.size = c.size() > 5 ? number(c[5], p, n, "size") : 0.0;
  return t;
}

}  // namespace

MarkerMeasurementWriter::MarkerMeasurementWriter(const std::filesystem::path& path) : path_(path), out_(path) {
  out_ << "frame,time,id,x,y,z,distance,angle_deg\n" << std::fixed;
  out_.flush();
  if (!out_) throw InputError(located(path, 0, "cannot write marker measurements"));
}

void MarkerMeasurementWriter::write(const MarkerMeasurement& m) {
  out_ << m.frame << ',' << std::setprecision(6) << m.time << ',' << m.id << ',' << std::setprecision(5)
       << m.position.x() << ',' << m.position.y() << ',' << m.position.z() << ',' << m.distance << ','
       << std::setprecision(2) << m.angle_deg << '\n';
  out_.flush();  // a run stopped later keeps every measurement made so far
  if (!out_) throw Failure(located(path_, 0, "cannot write marker measurements"));
  ++rows_;
}

void write_marker_measurements(const std::filesystem::path& path, const std::vector<MarkerMeasurement>& ms) {
  MarkerMeasurementWriter w(path);
  for (const auto& m : ms) w.write(m);
}

std::vector<MarkerMeasurement> read_marker_measurements(const std::filesystem::path& path) {
  return read_rows<MarkerMeasurement>(path, 8, "frame", parse_measurement);
}

std::vector<MarkerTruth> read_marker_truth(const std::filesystem::path& path) {
  auto rows = read_rows<MarkerTruth>(path, 4, "id", parse_truth);
  if (rows.empty()) throw_input_error(path, 0, "no markers");
  return rows;
}

MarkerObserver::MarkerObserver(const PinholeCamera& camera, double default_size, std::map<int, double> sizes,
                               AprilTagOptions options, double max_distance, double max_reprojection_px)
    : camera_(camera),
      default_size_(default_size),
      sizes_(std::move(sizes)),
      max_distance_(max_distance),
      max_reprojection_px_(max_reprojection_px),
      detector_(std::move(options)) {
  if (!(default_size > 0) && sizes_.empty()) throw InputError("--tag-size must be positive (or give the sizes per marker)");
  for (const auto& [id, s] : sizes_)
    if (!(s > 0)) throw InputError("marker " + std::to_string(id) + ": size must be positive");
}

std::vector<MarkerMeasurement> MarkerObserver::observe(std::size_t frame, double time, const cv::Mat& image,
                                                       const cv::Mat& depth, const SE3& T_wc) const {
  std::vector<MarkerMeasurement> out;
  for (const auto& d : detector_.detect(image)) {
    const auto it = sizes_.find(d.id);
    const double size = it != sizes_.end() ? it->second : default_size_;
    if (!(size > 0)) continue;
    const auto pose = estimate_tag_pose(d, size, camera_, depth);
    if (!pose || pose->distance > max_distance_ || pose->reprojection_rms_px > max_reprojection_px_) continue;
    const SE3 T_wg = T_wc * pose->T_cg;
    out.push_back({frame, time, d.id, T_wg.translation(), pose->distance, pose->viewing_angle_deg});
  }
  return out;
}

}  // namespace builtscene
