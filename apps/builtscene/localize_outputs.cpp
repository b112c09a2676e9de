#include "localize_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>

#include <CLI/CLI.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene::app {
namespace {

std::ofstream open_output(const std::filesystem::path& path, const std::string& what) {
  std::ofstream f(path);
  if (!f) throw InputError(located(path, 0, "cannot write " + what));
  return f;
}

}  // namespace

void LocalizeOutputOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--ogm", ogm, "Occupancy grid YAML (slam --ogm-out): report the 2D pose and scan on it per frame");
  cmd.add_option("--poses2d", poses2d, "Output with --ogm: CSV frame,time,x,y,theta,beams,beams_on_map per tracked frame");
  cmd.add_option("--ogm-png", ogm_png, "Output with --ogm: the grid with the 2D track, last scan and robot");
  cmd.add_option("--poi", poi, "Points of interest CSV name,x,y,radius on the grid's ground frame (needs --ogm)");
  cmd.add_option("--poi-events", poi_events, "Output: one JSON line per POI event");
  cmd.add_option("--markers-out", markers_out, "Output: AprilTag measurements in the map frame (CSV)");
  cmd.add_option("--tag-size", tag_size, "With --markers-out: edge of the tags' black square, m");
  cmd.add_option("--sizes-from", sizes_from, "With --markers-out: survey CSV (id,x,y,z,yaw,size) giving each tag's size");
  cmd.add_option("--marker-stride", marker_stride, "With --markers-out: look for tags in every n-th frame")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd.add_option("--lcm", lcm_url, "Publish POI events on POI_EVENTS over this LCM URL");
}

LocalizeOutputs::LocalizeOutputs(const LocalizeOutputOptions& o, const PinholeCamera& camera)
    : options_(o), camera_(camera) {
  if (o.ogm.empty() && (!o.poses2d.empty() || !o.ogm_png.empty() || !o.poi.empty()))
    throw InputError("--poses2d, --ogm-png and --poi need --ogm (the grid whose ground frame they use)");
  if (!o.ogm.empty()) {
    grid_ = load_map_server(o.ogm);
    const auto T_gw = read_ground_frame(o.ogm);
    if (!T_gw)
      spdlog::warn("{}: no ground_frame_T_gw key; taking the map's world as the z-up ground frame", o.ogm.string());
    ground_ = GroundFrame(T_gw.value_or(SE3()));
    scanner_.emplace(camera, VirtualLaserScanOptions{});
    if (!o.poses2d.empty()) {
      poses2d_ = open_output(o.poses2d, "2D poses");
      poses2d_ << "frame,time,x,y,theta,beams,beams_on_map\n" << std::fixed;
    }
  }
  if (!o.poi.empty()) {
    poi_.emplace(read_points_of_interest(o.poi));
    if (!o.poi_events.empty()) poi_events_ = open_output(o.poi_events, "POI events");
  }
  if (!o.lcm_url.empty()) lcm_ = std::make_unique<LcmPublisher>(o.lcm_url);
  if (!o.markers_out.empty()) {
    std::map<int, double> sizes;
    if (!o.sizes_from.empty())
      for (const auto& t : read_marker_truth(o.sizes_from))
        if (t.size > 0) sizes[t.id] = t.size;
    if (!(o.tag_size > 0) && sizes.empty())
      throw InputError("--markers-out needs --tag-size or --sizes-from (the tags' size sets their range)");
    markers_.emplace(camera, o.tag_size, sizes);
    marker_writer_.emplace(o.markers_out);
  }
}

void LocalizeOutputs::observe(const LocalizedFrame& f) {
  if (!f.tracked || !f.T_wc) return;
  if (grid_) {
    const Pose2D p = ground_.to_2d(*f.T_wc);
    track_.push_back(p);
    ++posed_frames_;
    long beams = 0, on_map = 0;
    if (!f.depth.empty()) {
      last_scan_ = scanner_->scan(f.depth, ground_.camera_in_ground(*f.T_wc), f.timestamp);
      for (std::size_t i = 0; i < last_scan_.ranges.size(); ++i) {
        if (!last_scan_.valid(i)) continue;
        const double a = p.theta + last_scan_.beam_angle(i), r = last_scan_.ranges[i];
        ++beams;
        on_map += occupied_within(*grid_, {p.x + r * std::cos(a), p.y + r * std::sin(a)}, 1);
      }
    }
    beams_ += beams;
    beams_on_map_ += on_map;
    if (poses2d_.is_open()) {
      poses2d_ << f.index << ',' << std::setprecision(6) << f.timestamp << ',' << std::setprecision(4) << p.x << ','
               << p.y << ',' << p.theta << ',' << beams << ',' << on_map << '\n';
      poses2d_.flush();
    }
    if (poi_) {
      for (const auto& e : poi_->update(f.timestamp, f.index, p)) {
        const auto j = e.to_json();
        spdlog::info("POI '{}' entered at frame {} ({:.2f}, {:.2f})", e.poi, e.frame, p.x, p.y);
        if (poi_events_.is_open()) {
          poi_events_ << j.dump() << '\n';
          poi_events_.flush();
        }
        if (lcm_) lcm_->publish(LcmPoiEvent{e.time, static_cast<long>(e.frame), e.pose, e.poi, e.distance});
        events_.push_back(j);
      }
    }
  }
  if (markers_ && f.index % static_cast<std::size_t>(options_.marker_stride) == 0)
    for (const auto& m : markers_->observe(f.index, f.timestamp, f.image, f.depth, *f.T_wc)) {
      marker_writer_->write(m);
      if (std::find(marker_ids_seen_.begin(), marker_ids_seen_.end(), static_cast<std::size_t>(m.id)) ==
          marker_ids_seen_.end())
        marker_ids_seen_.push_back(static_cast<std::size_t>(m.id));
    }
}

nlohmann::json LocalizeOutputs::finish() {
  nlohmann::json j = nlohmann::json::object();
  if (grid_) {
    j["ogm"] = {{"map", options_.ogm.string()},
                {"posed_frames", posed_frames_},
                {"beams", beams_},
                // Valid beam endpoints within one cell of an occupied cell: how well the live
                // scans agree with the map (1 in a static world with a perfect pose).
                {"beams_on_map", beams_ > 0 ? static_cast<double>(beams_on_map_) / static_cast<double>(beams_) : 0.0}};
    if (!options_.poses2d.empty()) j["ogm"]["poses2d"] = options_.poses2d.string();
    if (!options_.ogm_png.empty()) {
      write_track_picture(options_.ogm_png, *grid_, track_, &last_scan_);
      j["ogm"]["png"] = options_.ogm_png.string();
    }
  }
  if (poi_) j["poi_events"] = events_;
  if (marker_writer_) {
    std::sort(marker_ids_seen_.begin(), marker_ids_seen_.end());
    j["markers"] = {{"measurements", marker_writer_->rows()}, {"ids", marker_ids_seen_}, {"out", options_.markers_out.string()}};
  }
  return j;
}

}  // namespace builtscene::app
