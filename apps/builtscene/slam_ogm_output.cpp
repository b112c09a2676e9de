#include "slam_ogm_output.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>


#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/stage_timer.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene::app {

SlamOgmOutput::SlamOgmOutput(SlamOgmOptions options, const PinholeCamera& camera)
    : options_(std::move(options)), camera_(camera) {
  if (options_.world != "auto" && options_.world != "camera")
    throw InputError("--ogm-world: unknown value '" + options_.world + "' (expected auto or camera)");
  if (!options_.lcm_url.empty()) lcm_ = std::make_unique<LcmPublisher>(options_.lcm_url);
  if (!options_.out.empty()) {
    // Fail on an unwritable map before spending minutes on the sequence.
    const auto probe = std::filesystem::path(options_.out.string() + ".yaml");
    std::ofstream f(probe, std::ios::app);
    if (!f) throw InputError(located(probe, 0, "cannot write the occupancy grid"));
  }
  for (const auto& dir : {options_.frames, options_.loop_snapshots}) {
    if (dir.empty()) continue;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw InputError(located(dir, 0, "cannot create the folder: " + ec.message()));
  }
}

void SlamOgmOutput::consume(const PosesAndLaserScans& batch) {
  if (batch.pairs.empty()) return;
  mapper_.integrate_batch(batch.pairs);
  if (lcm_) lcm_->publish(batch);
  ++batches_;
  if (batch.full) {
    ++full_batches_;
    keyframe_poses_.clear();
    grid_poses_.clear();
    for (const auto& p : batch.pairs) keyframe_poses_.push_back(p.pose);
  } else {
    keyframe_poses_.push_back(batch.pairs.front().pose);
    last_scan_ = batch.pairs.front().scan;
  }
  for (std::size_t i = 0; i < batch.stamps.size() && i < batch.T_wc.size(); ++i) grid_poses_[batch.stamps[i]] = batch.T_wc[i];
}

void SlamOgmOutput::write_snapshot(const std::string& name) const {
  const std::filesystem::path yaml = options_.loop_snapshots / (name + ".yaml");
  save_map_server(mapper_.grid(), yaml);
  append_ground_frame(yaml, emitter_->ground().T_gw());
  Trajectory poses;
  for (const auto& [stamp, T] : grid_poses_) poses.push_back({stamp, T});
  write_tum_trajectory(options_.loop_snapshots / (name + "_keyframes.txt"), poses);
}

void SlamOgmOutput::subscribe(slam::System& system) {
  system.subscribe_loop_events([this](const slam::LoopEvent& e) {
    std::lock_guard lock(loop_mutex_);
    ++loop_events_pending_;
    if (!lcm_) return;
    LcmLoopEvent m;
    m.stage = slam::stage_name(e.stage);
    m.loop = e.loop;
    m.frame = e.frame;
    m.time = e.timestamp;
    m.keyframe = e.keyframe;
    m.matched_keyframe = e.matched_keyframe;
    m.inliers = e.inliers;
    m.correction = e.correction;
    for (const auto& k : e.keyframes) {
      m.keyframe_ids.push_back(k.id);
      m.stamps.push_back(k.timestamp);
      m.T_wc.push_back(k.T_wc);
    }
    lcm_events_pending_.push_back(std::move(m));
  });
}

void SlamOgmOutput::publish_loop_events() {
  std::vector<LcmLoopEvent> events;
  {
    std::lock_guard lock(loop_mutex_);
    events.swap(lcm_events_pending_);
  }
  for (const auto& e : events) lcm_->publish(e);
}

void SlamOgmOutput::rebuild_after_loops(slam::System& system) {
  {
    std::lock_guard lock(loop_mutex_);
    if (loop_events_pending_ == 0) return;
    loop_events_pending_ = 0;
  }
  if (!emitter_) return;  // no scan yet: the first keyframes will build from corrected poses
  const auto start = std::chrono::steady_clock::now();
  // Poses read now are the optimized ones (the event is sent after they were written).
  const std::string name = "loop_" + std::to_string(loop_rebuilds_ + 1);
  if (!options_.loop_snapshots.empty()) write_snapshot(name + "_before");
  consume(emitter_->full_batch(system.keyframe_trajectory()));
  ++loop_rebuilds_;
  if (!options_.loop_snapshots.empty()) write_snapshot(name + "_after");
  system.timer().add("ogm", ms_since(start));
}

void SlamOgmOutput::after_frame(slam::System& system, const slam::TrackingOutcome& outcome, double timestamp,
                                const cv::Mat& depth) {
  if (lcm_) publish_loop_events();
  rebuild_after_loops(system);
  if (!outcome.new_keyframe) return;
  const auto start = std::chrono::steady_clock::now();
  const Trajectory keyframes = system.keyframe_trajectory();
  const StampedPose* kf = nullptr;
  for (const auto& k : keyframes)
    if (k.timestamp == timestamp) kf = &k;
  if (!kf || depth.empty()) return;  // culled at once, or a frame without depth: no scan
  if (!emitter_) {
    GroundFrame ground = GroundFrame::first_camera(options_.camera_height);
    if (options_.world == "auto") {
      try {
        ground = GroundFrame::estimate({kf->pose}, {depth}, camera_);
      } catch (const InputError& e) {
        spdlog::warn("occupancy grid: {}; using the first camera {} m above a level floor", e.what(),
                     options_.camera_height);
      }
    }
    emitter_.emplace(camera_, ground, options_.batches);
  }
  for (const auto& batch : emitter_->add_keyframe(timestamp, kf->pose, depth, keyframes)) consume(batch);
  if (!options_.frames.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "keyframe_%05ld.png", keyframes_drawn_++);
    write_track_picture(options_.frames / name, mapper_.grid(), keyframe_poses_, &last_scan_);
  }
  system.timer().add("ogm", ms_since(start));
}

nlohmann::json SlamOgmOutput::finish(slam::System& system) {
  if (lcm_) publish_loop_events();
  nlohmann::json j = {{"batches", batches_}, {"full_batches", full_batches_}, {"loop_rebuilds", loop_rebuilds_}};
  if (!emitter_) {
    spdlog::warn("occupancy grid: no keyframe with depth; no map written");
    j["map"] = nullptr;
    return j;
  }
  // The keyframes' final poses (after the last local BA / loop closure) rebuild the map.
  consume(emitter_->full_batch(system.keyframe_trajectory()));
  j["batches"] = batches_;
  j["full_batches"] = full_batches_;
  j["scans"] = mapper_.scans_integrated();
  if (options_.out.empty()) return j;
  const OccupancyGrid grid = mapper_.grid();
  const std::filesystem::path yaml = options_.out.string() + ".yaml";
  const std::filesystem::path state = options_.out.string() + ".state";
  const std::filesystem::path png = options_.out.string() + ".png";
  save_map_server(grid, yaml);
  append_ground_frame(yaml, emitter_->ground().T_gw());  // so `localize --ogm` can put poses on it
  mapper_.save_state(state);
  write_track_picture(png, grid, keyframe_poses_);
  const auto& T = emitter_->ground().T_gw();
  j["map"] = yaml.string();
  j["state"] = state.string();
  j["png"] = png.string();
  j["width"] = grid.width();
  j["height"] = grid.height();
  j["T_gw"] = {T.translation().x(), T.translation().y(), T.translation().z(), T.rotation().x(), T.rotation().y(),
               T.rotation().z(), T.rotation().w()};
  return j;
}

}  // namespace builtscene::app
