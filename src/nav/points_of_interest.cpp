#include "nav/points_of_interest.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {

std::vector<PointOfInterest> read_points_of_interest(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw_input_error(csv, 0, "cannot open points of interest");
  std::vector<PointOfInterest> out;
  std::set<std::string> names;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (line_no == 1 && line.rfind("name", 0) == 0) continue;  // header
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (cells.size() != 4) throw_input_error(csv, line_no, "expected 4 columns: name,x,y,radius");
    PointOfInterest p;
    p.name = cells[0];
    try {
      std::size_t used = 0;
      auto num = [&](const std::string& s, const char* field) {
        const double v = std::stod(s, &used);
        if (used != s.size() || !std::isfinite(v)) throw InputError(field);
        return v;
      };
      p.x = num(cells[1], "x");
      p.y = num(cells[2], "y");
      p.radius = num(cells[3], "radius");
    } catch (const std::exception&) {
      throw_input_error(csv, line_no, "x, y and radius must be numbers");
    }
    if (p.name.empty()) throw_input_error(csv, line_no, "empty name");
    if (!(p.radius > 0)) throw_input_error(csv, line_no, "radius must be positive");
    if (!names.insert(p.name).second) throw_input_error(csv, line_no, "duplicate name '" + p.name + "'");
    out.push_back(p);
  }
  if (out.empty()) throw_input_error(csv, 0, "no points of interest");
  return out;
}

nlohmann::json PoiEvent::to_json() const {
  return {{"event", "poi"}, {"time", time}, {"frame", frame}, {"poi", poi},
          {"x", pose.x},    {"y", pose.y},  {"theta", pose.theta}, {"distance", distance}};
}

PoiTrigger::PoiTrigger(std::vector<PointOfInterest> pois, double hysteresis)
    : pois_(std::move(pois)), inside_(pois_.size(), false), hysteresis_(hysteresis) {}

std::vector<PoiEvent> PoiTrigger::update(double time, std::size_t frame, const Pose2D& pose) {
  std::vector<PoiEvent> events;
  for (std::size_t i = 0; i < pois_.size(); ++i) {
    const auto& p = pois_[i];
    const double d = std::hypot(pose.x - p.x, pose.y - p.y);
    if (!inside_[i] && d <= p.radius) {
      inside_[i] = true;
      events.push_back({time, frame, pose, p.name, d});
    } else if (inside_[i] && d > p.radius + hysteresis_) {
      inside_[i] = false;
    }
  }
  return events;
}

}  // namespace builtscene
