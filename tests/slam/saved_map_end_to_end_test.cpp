// Saved maps and modes end to end on generated lab-room sequences (ground truth from the
// generator): build a map in SLAM mode, check culled keyframes and points are freed, save,
// reload (byte-identical re-save), localize on another sequence of the same room, extend the
// map into an unmapped part and localize in both parts, and drive `builtscene localize`.
// Relocalization after loading is the product's (bag-of-words candidates with the shipped
// vocabulary, EPnP, pose optimization).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "eval/trajectory_error.hpp"
#include "io/tum_dataset.hpp"
#include "slam/key_frame.hpp"
#include "slam/map_point.hpp"
#include "slam/system.hpp"

namespace builtscene::slam {
namespace {

namespace fs = std::filesystem;

using testing::run_cli;
using testing::shell_quote;

// BUILTSCENE_SAVED_MAP_DIR names a folder to keep (and reuse) the generated worlds in; without
// it they go to a scratch folder that the process removes when it exits.
const fs::path& work_dir() {
  if (const char* keep = std::getenv("BUILTSCENE_SAVED_MAP_DIR")) {
    static const fs::path d = [&] {
      fs::create_directories(keep);
      return fs::path(keep);
    }();
    return d;
  }
  static const fs::path d = testing::scratch_dir("saved_map");
  return d;
}

// Generated once per process: A builds the map; C starts in A's part of the loop and drives
// on into a part A never saw; D (another seed) covers the same stretch as C.
fs::path world(const std::string& name, int seed, int frames) {
  const fs::path d = work_dir() / name;
  if (!fs::exists(d / "rgb.txt")) {
    const auto r = run_cli("synth rgbd --scene lab-room --motion robot --noise kinect --seed " + std::to_string(seed) +
                           " --frames " + std::to_string(frames) + " --out " + shell_quote(d));
    EXPECT_EQ(r.exit_code, 0) << "synth failed for " << name;
  }
  return d;
}
// Short stretches: on these robot sequences tracking itself (also without any saved map)
// loses the camera near frame 146, where the robot turns towards a plain wall; see
// docs/slam.md. The map covers the first 70 frames, the extension drives 65 frames further.
constexpr int kMapFrames = 70, kLongFrames = 135;

struct RunResult {
  long frames = 0, tracked = 0, first_tracked = -1;
  std::vector<bool> tracked_at;
  Trajectory trajectory;
};

// "12-15 40" style list of the untracked frames, for the log.
std::string lost_ranges(const std::vector<bool>& tracked_at) {
  std::string out;
  for (std::size_t i = 0; i < tracked_at.size(); ++i) {
    if (tracked_at[i] || (i > 0 && !tracked_at[i - 1])) continue;
    std::size_t j = i;
    while (j + 1 < tracked_at.size() && !tracked_at[j + 1]) ++j;
    out += (out.empty() ? "" : " ") + std::to_string(i) + (j > i ? "-" + std::to_string(j) : "");
  }
  return out.empty() ? "none" : out;
}

RunResult run(System& system, const TumDataset& data, std::size_t first = 0, std::size_t end = 0) {
  RunResult r;
  if (end == 0) end = data.size();
  for (std::size_t i = first; i < end; ++i) {
    const auto out = system.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
    const bool ok = out.state == TrackingState::kOk;
    r.tracked += ok;
    if (ok && r.first_tracked < 0) r.first_tracked = static_cast<long>(i - first);
    r.tracked_at.push_back(ok);
    ++r.frames;
  }
  system.shutdown();
  r.trajectory = system.trajectory();
  return r;
}

// The map of A, its alignment to A's ground truth, and the objects it has held.
struct MapOfA {
  fs::path path;
  Sim3 est_to_gt;
  double ate_rmse = 0;
  std::size_t keyframes = 0, points = 0;
  long keyframes_culled = 0, points_retired = 0, culled_alive = 0, retired_points_alive = 0;
};

const MapOfA& map_of_a() {
  static const MapOfA m = [] {
    MapOfA out;
    const auto data = TumDataset::open(world("a", 1, kMapFrames));
    // Mapping inline (as `slam --sync-mapping`): what is still alive at the end, and so the
    // freed-memory check below, must not depend on how far the mapping thread had got.
    SystemOptions options;
    options.mapping_thread = false;
    System system(data.settings(), options);
    // Every keyframe and point the map ever held, weakly: after the run, those no longer in
    // the map must be gone from memory too.
    std::vector<std::weak_ptr<KeyFrame>> seen_kfs;
    std::vector<std::weak_ptr<MapPoint>> seen_points;
    std::unordered_set<long> kf_ids, point_ids;
    for (std::size_t i = 0; i < static_cast<std::size_t>(kMapFrames); ++i) {
      system.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
      std::lock_guard lock(system.map().mutex());
      for (const auto& kf : system.map().keyframes())
        if (kf_ids.insert(kf->id).second) seen_kfs.push_back(kf);
      for (const auto& p : system.map().points())
        if (point_ids.insert(p->id).second) seen_points.push_back(p);
    }
    system.shutdown();
    const auto traj = system.trajectory();
    out.ate_rmse = absolute_trajectory_error(data.groundtruth(), traj, Alignment::kSE3).stats.rmse;
    out.est_to_gt = absolute_trajectory_error(data.groundtruth(), traj, Alignment::kSE3).est_to_gt;
    // One more frame (localization mode, so the map stays as it is) lets tracking replace its
    // local map, which may still name keyframes the final mapping pass culled.
    system.set_mode(Mode::kLocalization);
    const std::size_t last = kMapFrames - 1;
    system.track_rgbd(data.load_rgb(last), data.load_depth(last), data.entry(last).timestamp + 0.001);
    {
      std::lock_guard lock(system.map().mutex());
      std::unordered_set<const KeyFrame*> in_map;
      for (const auto& kf : system.map().keyframes()) in_map.insert(kf.get());
      std::unordered_set<const MapPoint*> points_in_map;
      for (const auto& p : system.map().points()) points_in_map.insert(p.get());
      for (const auto& w : seen_kfs) {
        const auto kf = w.lock();
        if (kf && in_map.count(kf.get())) continue;
        ++out.keyframes_culled;
        out.culled_alive += kf != nullptr;
      }
      for (const auto& w : seen_points) {
        const auto p = w.lock();
        if (p && points_in_map.count(p.get())) continue;
        ++out.points_retired;
        out.retired_points_alive += p != nullptr;
      }
      out.keyframes = system.map().keyframe_count();
      out.points = system.map().point_count();
    }
    out.path = work_dir() / "a.map";
    system.save_map(out.path);
    std::printf("map A: %zu keyframes, %zu points, ATE %.2f cm; culled keyframes %ld (alive %ld), retired points %ld "
                "(alive %ld)\n",
                out.keyframes, out.points, 100 * out.ate_rmse, out.keyframes_culled, out.culled_alive,
                out.points_retired, out.retired_points_alive);
    return out;
  }();
  return m;
}

std::vector<std::uint8_t> bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ATE of a run placed in A's aligned frame: A's SLAM-to-truth transform applied, no new fit.
ErrorStats ate_in_first_frame(const Trajectory& gt, const Trajectory& est, const Sim3& est_to_gt) {
  return absolute_trajectory_error(gt, transformed(est, est_to_gt), Alignment::kNone).stats;
}

TEST(SavedMapEndToEnd, MappingFreesCulledKeyframesAndPoints) {
  const auto& m = map_of_a();
  EXPECT_LT(m.ate_rmse, 0.05);
  // The run must have retired something for the check to mean anything.
  ASSERT_GT(m.points_retired, 100);
  EXPECT_EQ(m.culled_alive, 0) << "of " << m.keyframes_culled << " culled keyframes";
  // Retired points may still sit in the last frame's matches and local mapping's list of the
  // last three keyframes' new points; nothing older.
  EXPECT_LE(m.retired_points_alive, std::max(100L, m.points_retired / 20)) << "of " << m.points_retired;
}

// Keyframe culling is rare with the published rule (none in A's 70 frames, none in 500 kitchen
// frames), so this run loosens it until keyframes are culled, then checks they are freed.
TEST(SavedMapEndToEnd, CulledKeyframesAreFreed) {
  const auto data = TumDataset::open(world("c", 3, kLongFrames));
  SystemOptions options;
  options.mapping.redundant_ratio = 0.3f;
  options.mapping.redundant_min_observers = 1;
  System system(data.settings(), options);
  std::vector<std::weak_ptr<KeyFrame>> seen;
  std::unordered_set<long> ids;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kLongFrames); ++i) {
    system.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
    std::lock_guard lock(system.map().mutex());
    for (const auto& kf : system.map().keyframes())
      if (ids.insert(kf->id).second) seen.push_back(kf);
  }
  system.shutdown();
  const std::size_t trajectory_before = system.trajectory().size();
  system.set_mode(Mode::kLocalization);
  const std::size_t last = kLongFrames - 1;
  system.track_rgbd(data.load_rgb(last), data.load_depth(last), data.entry(last).timestamp + 0.001);
  long culled = 0, alive = 0;
  {
    std::lock_guard lock(system.map().mutex());
    std::unordered_set<const KeyFrame*> in_map;
    for (const auto& kf : system.map().keyframes()) in_map.insert(kf.get());
    for (const auto& w : seen) {
      const auto kf = w.lock();
      if (kf && in_map.count(kf.get())) continue;
      ++culled;
      alive += kf != nullptr;
    }
  }
  std::printf("loose culling: %zu keyframes seen, %ld culled, %ld of them still alive\n", seen.size(), culled, alive);
  ASSERT_GT(culled, 0);
  EXPECT_EQ(alive, 0);
  // Frames tracked against culled keyframes are still placed (through the compacted records).
  // The loosened rule culls nearly every keyframe and costs accuracy (measured 5.9 cm); a
  // broken re-expression of the records would put frames metres off.
  const auto traj = system.trajectory();
  EXPECT_GE(traj.size(), trajectory_before);
  const auto ate = absolute_trajectory_error(data.groundtruth(), traj, Alignment::kSE3).stats;
  EXPECT_LT(ate.rmse, 0.10);
}

TEST(SavedMapEndToEnd, LoadedMapSavesToTheSameBytes) {
  const auto& m = map_of_a();
  const auto data = TumDataset::open(world("a", 1, kMapFrames));
  System system(data.settings());
  const auto info = system.load_map(m.path);
  EXPECT_EQ(info.keyframes, m.keyframes);
  EXPECT_EQ(info.points, m.points);
  const auto again = work_dir() / "a_again.map";
  system.save_map(again);
  EXPECT_EQ(bytes_of(again), bytes_of(m.path));
}

TEST(SavedMapEndToEnd, LocalizesAnotherSequenceOfTheRoomWithoutChangingTheMap) {
  const auto& m = map_of_a();
  const auto data = TumDataset::open(world("c", 3, kLongFrames));
  System system(data.settings());
  system.load_map(m.path);
  system.set_mode(Mode::kLocalization);
  // The part of C inside A's map (C drives the same loop from the same start).
  const auto r = run(system, data, 0, kMapFrames - 5);
  const auto ate = ate_in_first_frame(data.groundtruth(), r.trajectory, m.est_to_gt);
  std::printf("localize C[0, %ld): first tracked frame %ld, tracked %ld, ATE in A's frame %.2f cm (max %.2f); lost: %s\n",
              r.frames, r.first_tracked, r.tracked, 100 * ate.rmse, 100 * ate.max, lost_ranges(r.tracked_at).c_str());
  EXPECT_GE(r.first_tracked, 0);
  EXPECT_LE(r.first_tracked, 10);
  EXPECT_GE(r.tracked, static_cast<long>(0.95 * static_cast<double>(r.frames)));
  EXPECT_LE(ate.rmse, 0.03);
  EXPECT_EQ(system.keyframe_count(), m.keyframes);
  EXPECT_EQ(system.map_point_count(), m.points);
}

TEST(SavedMapEndToEnd, ExtendedMapLocalizesInTheOldAndTheNewPart) {
  const auto& m = map_of_a();
  const auto c = TumDataset::open(world("c", 3, kLongFrames));
  const auto extended = work_dir() / "ac.map";
  {
    System system(c.settings());
    system.load_map(m.path);
    const auto r = run(system, c, 0, kLongFrames);
    const auto ate = ate_in_first_frame(c.groundtruth(), r.trajectory, m.est_to_gt);
    std::printf("extend with C: tracked %ld/%ld, keyframes %zu -> %zu, ATE in A's frame %.2f cm\n", r.tracked, r.frames,
                m.keyframes, system.keyframe_count(), 100 * ate.rmse);
    EXPECT_GT(system.keyframe_count(), m.keyframes);
    EXPECT_GE(r.tracked, static_cast<long>(0.95 * static_cast<double>(r.frames)));
    EXPECT_LE(ate.rmse, 0.05);
    system.save_map(extended);
  }
  const auto d = TumDataset::open(world("d", 4, kLongFrames));
  System system(d.settings());
  const auto info = system.load_map(extended);
  system.set_mode(Mode::kLocalization);
  const auto r = run(system, d, 0, kLongFrames);
  long old_part = 0, new_part = 0;
  for (std::size_t i = 0; i < r.tracked_at.size(); ++i)
    (i < static_cast<std::size_t>(kMapFrames) ? old_part : new_part) += r.tracked_at[i];
  const auto ate = ate_in_first_frame(d.groundtruth(), r.trajectory, m.est_to_gt);
  std::printf("localize D in the extended map: old part %ld/%d, new part %ld/%d tracked, ATE %.2f cm; lost: %s\n",
              old_part, kMapFrames, new_part, kLongFrames - kMapFrames, 100 * ate.rmse, lost_ranges(r.tracked_at).c_str());
  EXPECT_GE(old_part, static_cast<long>(0.95 * kMapFrames));
  EXPECT_GE(new_part, static_cast<long>(0.95 * (kLongFrames - kMapFrames)));
  EXPECT_LE(ate.rmse, 0.05);
  EXPECT_EQ(system.keyframe_count(), info.keyframes);
}

TEST(SavedMapEndToEnd, CommandLineSavesLocalizesAndRejectsBadMaps) {
  const auto& m = map_of_a();
  const fs::path a = world("a", 1, kMapFrames);
  const auto out = work_dir() / "cli.map";
  // The map's sequence has kMapFrames (70) frames: SLAM mode for 50, then localization.
  auto r = run_cli("slam --json --dataset " + shell_quote(a) + " --trajectory " +
                   shell_quote(work_dir() / "cli_traj.txt") + " --map-out " + shell_quote(out) +
                   " --mode-schedule 0-49:slam,50-:localize");
  ASSERT_EQ(r.exit_code, 0);
  auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["mode_switches"].size(), 1u) << r.out;
  EXPECT_EQ(j["mode_switches"][0]["frame"], 50);
  EXPECT_EQ(j["mode_switches"][0]["to"], "localize");
  EXPECT_GT(j["map_out"]["keyframes"].get<long>(), 0);
  EXPECT_TRUE(fs::exists(out));

  r = run_cli("localize --json --max-frames 20 --dataset " + shell_quote(a) + " --map " + shell_quote(m.path) +
              " --trajectory " + shell_quote(work_dir() / "loc.txt"));
  ASSERT_EQ(r.exit_code, 0);
  j = nlohmann::json::parse(r.out);
  for (const char* key : {"frames", "tracked_frames", "lost_frames", "relocalizations", "first_relocalized_frame", "fps",
                          "stage_ms", "mode_switches"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"], 20);
  EXPECT_EQ(j["tracked_frames"].get<long>() + j["lost_frames"].get<long>(), 20);
  EXPECT_EQ(j["keyframes_after"], m.keyframes);

  // Region rule: SLAM inside y <= 0.8 m of the first camera's ground frame (ground y = the
  // first camera's forward axis), localization beyond. The truth: the first frame whose true
  // position, relative to the first camera, is more than 0.8 m ahead; the switch happens on
  // the frame after it (the rule looks at the last tracked pose).
  r = run_cli("slam --json --max-frames 90 --dataset " + shell_quote(a) + " --trajectory " +
              shell_quote(work_dir() / "region_traj.txt") + " --slam-region -1,-1,1,0.8 --world camera");
  ASSERT_EQ(r.exit_code, 0);
  j = nlohmann::json::parse(r.out);
  const auto gt = TumDataset::open(a).groundtruth();
  long expected = -1;
  for (std::size_t i = 0; i < gt.size() && expected < 0; ++i)
    if ((gt[0].pose.inverse() * gt[i].pose).translation().z() > 0.8) expected = static_cast<long>(i) + 1;
  ASSERT_GT(expected, 0);
  ASSERT_EQ(j["mode_switches"].size(), 1u);
  EXPECT_EQ(j["mode_switches"][0]["reason"], "region");
  EXPECT_EQ(j["mode_switches"][0]["to"], "localize");
  EXPECT_NEAR(j["mode_switches"][0]["frame"].get<double>(), static_cast<double>(expected), 2.0);

  const auto bad = work_dir() / "bad.map";
  { std::ofstream(bad) << "not a map"; }
  r = run_cli("localize --dataset " + shell_quote(a) + " --map " + shell_quote(bad));
  EXPECT_EQ(r.exit_code, 2);
  r = run_cli("slam --dataset " + shell_quote(a) + " --trajectory /dev/null --map-in " + shell_quote(bad));
  EXPECT_EQ(r.exit_code, 2);
  r = run_cli("slam --dataset " + shell_quote(a) + " --trajectory /dev/null --mode-schedule 5-1:slam");
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace builtscene::slam
