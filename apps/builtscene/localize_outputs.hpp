#pragma once
// What `localize` reports per frame besides the trajectory (the source's section 2.6):
//   --ogm MAP.yaml [--poses2d poses.csv] [--ogm-png P]: the 2D pose on the occupancy grid and
//     the frame's virtual scan checked against it (no update of the grid);
//   --poi pois.csv [--poi-events events.jsonl]: geo-tagged data collection events, once per visit;
//   --markers-out measured.csv --tag-size S: AprilTag positions in the map frame (T_wg = T_wc T_cg);
//   --lcm URL: POI events also as LCM messages (POI_EVENTS, builtscene.poi_event_t).
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/camera.hpp"
#include "localized_frame.hpp"
#include "markers/marker_measurements.hpp"
#include "nav/points_of_interest.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/lcm_publisher.hpp"
#include "ogm/occupancy_grid.hpp"
#include "ogm/virtual_laser_scanner.hpp"

namespace CLI {
class App;
}

namespace builtscene::app {

struct LocalizeOutputOptions {
  std::filesystem::path ogm, poses2d, ogm_png, poi, poi_events, markers_out, sizes_from;
  double tag_size = 0;
  int marker_stride = 1;
  std::string lcm_url;
  void add_to(CLI::App& cmd);
};

class LocalizeOutputs {
 public:
  // Opens every output now, so a bad path fails before the run. InputError names the file.
  LocalizeOutputs(const LocalizeOutputOptions& options, const PinholeCamera& camera);
  void observe(const LocalizedFrame& frame);
  nlohmann::json finish();

 private:
  LocalizeOutputOptions options_;
  PinholeCamera camera_;
  std::optional<OccupancyGrid> grid_;
  GroundFrame ground_;
  std::optional<VirtualLaserScanner> scanner_;
  std::ofstream poses2d_;
  std::vector<Pose2D> track_;
  LaserScan last_scan_;
  long posed_frames_ = 0, beams_ = 0, beams_on_map_ = 0;

  std::optional<PoiTrigger> poi_;
  std::ofstream poi_events_;
  std::unique_ptr<LcmPublisher> lcm_;
  nlohmann::json events_ = nlohmann::json::array();

  std::optional<MarkerObserver> markers_;
  std::optional<MarkerMeasurementWriter> marker_writer_;
  std::vector<std::size_t> marker_ids_seen_;
};

}  // namespace builtscene::app
