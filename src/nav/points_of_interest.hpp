#pragma once
// Geo-tagged data collection: points of interest on the map (CSV `name,x,y,radius`) and a
// trigger that fires one event when the robot's 2D pose enters a point's radius, once per
// visit. A visit ends when the pose leaves the radius by a hysteresis margin, so noise at
// the boundary does not fire the event twice.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ogm/ground_frame.hpp"

namespace builtscene {

struct PointOfInterest {
  std::string name;
  double x = 0, y = 0, radius = 0;
};

// InputError naming file and line on a malformed row, a non-positive radius or a duplicate name.
std::vector<PointOfInterest> read_points_of_interest(const std::filesystem::path& csv);

struct PoiEvent {
  double time = 0;
  std::size_t frame = 0;
  Pose2D pose;
  std::string poi;
  double distance = 0;
  nlohmann::json to_json() const;
};

class PoiTrigger {
 public:
  explicit PoiTrigger(std::vector<PointOfInterest> pois, double hysteresis = 0.1);
  // Events for the POIs entered at this pose (possibly several).
  std::vector<PoiEvent> update(double time, std::size_t frame, const Pose2D& pose);
  const std::vector<PointOfInterest>& pois() const { return pois_; }

 private:
  std::vector<PointOfInterest> pois_;
  std::vector<bool> inside_;
  double hysteresis_;
};

}  // namespace builtscene
