#pragma once
// Marker measurements while localizing (the source's T_wg = T_wc * T_cg): every tag seen in a
// frame gives its position in the map frame, with the distance and viewing angle it was seen
// from. CSV columns: frame,time,id,x,y,z,distance,angle_deg. Surveyed markers ("truth") use
// the generated worlds' markers.csv columns: id,x,y,z,yaw,size.
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "core/se3.hpp"
#include "markers/apriltag_detector.hpp"
#include "markers/tag_pose.hpp"

namespace builtscene {

struct MarkerMeasurement {
  std::size_t frame = 0;
  double time = 0;
  int id = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // map frame
  double distance = 0, angle_deg = 0;
};

struct MarkerTruth {
  int id = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0, size = 0;
};

void write_marker_measurements(const std::filesystem::path& path, const std::vector<MarkerMeasurement>& m);

// Writes measurements as they are made (header first, a flushed row each), so a long
// localization run that stops keeps what it measured. InputError if the file cannot be opened.
class MarkerMeasurementWriter {
 public:
  explicit MarkerMeasurementWriter(const std::filesystem::path& path);
  void write(const MarkerMeasurement& m);
  std::size_t rows() const { return rows_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  std::size_t rows_ = 0;
};
std::vector<MarkerMeasurement> read_marker_measurements(const std::filesystem::path& path);
std::vector<MarkerTruth> read_marker_truth(const std::filesystem::path& path);

// Detects tags in a frame and turns them into map-frame measurements. Tag sizes: per id
// where given (e.g. from the survey's size column), else `default_size` (<= 0: such tags
// are skipped, since their range would be wrong).
class MarkerObserver {
 public:
  MarkerObserver(const PinholeCamera& camera, double default_size, std::map<int, double> sizes = {},
                 AprilTagOptions options = {}, double max_distance = 4.0, double max_reprojection_px = 2.0);
  std::vector<MarkerMeasurement> observe(std::size_t frame, double time, const cv::Mat& image, const cv::Mat& depth,
                                         const SE3& T_wc) const;

 private:
  PinholeCamera camera_;
  double default_size_;
  std::map<int, double> sizes_;
  double max_distance_, max_reprojection_px_;
  AprilTagDetector detector_;
};

}  // namespace builtscene
