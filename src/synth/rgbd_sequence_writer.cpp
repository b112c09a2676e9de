#include "synth/rgbd_sequence_writer.hpp"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <numbers>
#include <sstream>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/stage_timer.hpp"
#include "io/trajectory.hpp"
#include "synth/png_writer.hpp"
#include "synth/renderer.hpp"
#include "synth/scene_library.hpp"
#include "synth/sensor_noise.hpp"
#include "synth/truth_map.hpp"

namespace builtscene::synth {
namespace fs = std::filesystem;

RgbdCameraSettings kinect_settings(int width, int height) {
  RgbdCameraSettings s;
  const double k = width / 640.0;
  s.camera.fx = s.camera.fy = 525.0 * k;
  s.camera.cx = (width - 1) / 2.0;
  s.camera.cy = (height - 1) / 2.0;
  s.camera.width = width;
  s.camera.height = height;
  s.fps = 30.0;
  s.bf = 40.0 * k;
  s.th_depth = 40.0;
  s.depth_map_factor = 5000.0;
  s.rgb_order = true;
  return s;
}

namespace {

// Turns renders into sensor images and PNG files on worker threads. Each frame's noise is
// seeded by its index, so the files do not depend on which worker takes which frame. The
// queue is bounded so memory stays flat.
class FrameFinisher {
 public:
  struct Job {
    int index = 0;
    RenderOutput render;
    ColorCameraModel color;
    fs::path rgb_path, depth_path;
  };

  FrameFinisher(int workers, int frames, std::uint64_t seed, bool kinect, double depth_factor, StageTimer& timer)
      : seed_(seed), kinect_(kinect), depth_factor_(depth_factor), timer_(timer), valid_(static_cast<std::size_t>(frames), 0.0) {
    for (int k = 0; k < workers; ++k) workers_.emplace_back([this] { loop(); });
  }
  ~FrameFinisher() {
    try {
      finish();
    } catch (...) {
    }
  }
  void push(Job job) {
    std::unique_lock lock(mutex_);
    space_.wait(lock, [&] { return queue_.size() < 2 * workers_.size() || !error_.empty(); });
    if (!error_.empty()) throw Failure(error_);
    queue_.push_back(std::move(job));
    ready_.notify_one();
  }
  void finish() {
    {
      std::lock_guard lock(mutex_);
      if (done_) return;
      done_ = true;
    }
    ready_.notify_all();
    for (auto& w : workers_) w.join();
    if (!error_.empty()) throw Failure(error_);
  }
  // Mean over the frames from `first` on (the ones written).
  double mean_valid(int first = 0) const {
    double s = 0;
    for (std::size_t i = static_cast<std::size_t>(std::max(0, first)); i < valid_.size(); ++i) s += valid_[i];
    const auto count = static_cast<double>(valid_.size()) - std::max(0, first);
    return count > 0 ? s / count : 0.0;
  }

 private:
  void loop() {
    while (true) {
      Job job;
      {
        std::unique_lock lock(mutex_);
        ready_.wait(lock, [&] { return !queue_.empty() || done_; });
        if (queue_.empty()) return;
        job = std::move(queue_.front());
        queue_.pop_front();
      }
      space_.notify_one();
      const auto ns = std::chrono::steady_clock::now();
      FrameRng rng_color(seed_, static_cast<std::uint64_t>(job.index), 1), rng_depth(seed_, static_cast<std::uint64_t>(job.index), 2);
      const cv::Mat rgb8 = apply_color_camera(job.render.bgr, job.color, rng_color);
      const cv::Mat depth_m = kinect_ ? apply_kinect_noise(job.render.depth, job.render.incidence, KinectNoiseModel{}, rng_depth) : job.render.depth;
      const cv::Mat depth16 = depth_to_u16(depth_m, depth_factor_);
      valid_[static_cast<std::size_t>(job.index)] = static_cast<double>(cv::countNonZero(depth16)) / static_cast<double>(depth16.total());
      timer_.add("noise", ms_since(ns));
      const auto es = std::chrono::steady_clock::now();
      const bool ok = write_png_fast(job.rgb_path, rgb8) && write_png_fast(job.depth_path, depth16);
      timer_.add("encode", ms_since(es));
      if (!ok) {
        std::lock_guard lock(mutex_);
        error_ = located(job.rgb_path, 0, "cannot write image");
        space_.notify_all();
        return;
      }
    }
  }

  std::uint64_t seed_;
  bool kinect_;
  double depth_factor_;
  StageTimer& timer_;
  std::vector<double> valid_;  // one slot per frame: workers never share an element
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Job> queue_;
  bool done_ = false;
  std::string error_;
  std::vector<std::thread> workers_;
};

// Slowly drifting auto-exposure with occasional steps (entering a brighter or darker place).
double exposure_gain(double t, std::uint64_t seed) {
  FrameRng rng(seed, 0, 99);
  double v = 0;
  for (int i = 0; i < 3; ++i) {
    const double f = 0.05 + 0.15 * rng.uniform(), p = 2 * std::numbers::pi * rng.uniform();
    v += 0.18 * std::sin(2 * std::numbers::pi * f * t + p);
  }
  // Steps every ~5 s, each smoothed over ~0.3 s.
  for (int k = 1; k < 200; ++k) {
    const double tk = 5.0 * k + 2.0 * rng.uniform();
    const double amp = 0.35 * (rng.uniform() - 0.5);
    if (tk > t + 2) break;
    v += amp / (1 + std::exp(-(t - tk) / 0.08));
  }
  return std::exp(v);
}

std::string stamp(double t) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(6) << t;
  return s.str();
}

void check_writable(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw InputError(located(dir, 0, "--out: cannot create output folder" + (ec ? ": " + ec.message() : std::string())));
  const fs::path probe = dir / ".write_test";
  {
    std::ofstream f(probe);
    f << "x";
    if (!f) throw InputError(located(dir, 0, "--out: output folder is not writable"));
  }
  fs::remove(probe, ec);
}

}  // namespace

nlohmann::json generate_rgbd_sequence(const RgbdSequenceOptions& opt) {
  if (!is_scene_name(opt.scene)) {
    std::string known;
    for (const auto& n : scene_names()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("--scene: unknown scene '" + opt.scene + "' (known: " + known + ")");
  }
  if (opt.frames < 0 || opt.frames > 200000) throw InputError("--frames: must be between 1 and 200000, got " + std::to_string(opt.frames));
  if (opt.loops < 1 || opt.loops > 100) throw InputError("--loops: must be between 1 and 100, got " + std::to_string(opt.loops));
  if (opt.width < 64 || opt.height < 48 || opt.width > 4096 || opt.height > 4096) throw InputError("image size out of range");
  // The sub-frames interpolate between the neighbouring poses, so a shutter cannot outlast a frame.
  if (opt.blur && !(opt.exposure_time_s >= 0.001 && opt.exposure_time_s <= 0.033))
    throw InputError("--exposure-ms: expected 1 to 33 (one frame interval), got " + std::to_string(opt.exposure_time_s * 1000.0));
  if (!(opt.light_fade_to >= 0.02 && opt.light_fade_to <= 1.0)) throw InputError("--light-fade: expected 0.02 to 1, got " + std::to_string(opt.light_fade_to));
  if (opt.out.empty()) throw InputError("--out: an output folder is required");
  check_writable(opt.out);
  check_writable(opt.out / "rgb");
  check_writable(opt.out / "depth");

  const auto t_start = std::chrono::steady_clock::now();
  StageTimer timer;
  const Scene scene = build_scene(opt.scene);
  const RgbdCameraSettings settings = kinect_settings(opt.width, opt.height);
  MotionOptions mo;
  mo.kind = opt.motion;
  mo.frames = opt.frames;
  mo.loops = opt.loops;
  mo.seed = opt.seed;
  mo.fps = settings.fps;
  const MotionResult motion = generate_motion(scene, mo);
  const Renderer renderer(scene, settings.camera);
  timer.add("setup", ms_since(t_start));

  // Ground truth files first: geometry, markers, occupancy, camera, poses.
  std::ofstream(opt.out / "scene.json") << scene_to_json(scene).dump(1) << "\n";
  {
    std::ofstream m(opt.out / "markers.csv");
    m << "id,x,y,z,yaw,size\n" << std::setprecision(9);
    for (const auto& t : scene.tags) m << t.id << "," << t.center.x() << "," << t.center.y() << "," << t.center.z() << "," << t.yaw << "," << t.size << "\n";
    if (!m) throw Failure(located(opt.out / "markers.csv", 0, "cannot write"));
  }
  const OccupancyTruth truth = compute_truth_map(scene, scene.robot_band_min, scene.robot_band_max, 0.05);
  write_truth_map(truth, opt.out / "truth_map.pgm", opt.out / "truth_map.yaml", scene.robot_band_min, scene.robot_band_max);
  save_camera_settings(opt.out / "camera.yaml", settings);

  const int n = static_cast<int>(motion.poses.size());
  const int first = opt.first_frame;
  if (first < 0 || first >= n)
    throw InputError("--first-frame: must be between 0 and " + std::to_string(n - 1) + " (the sequence has " + std::to_string(n) +
                     " frames), got " + std::to_string(first));
  const double t0 = 1.0;
  Trajectory gt;
  std::ofstream rgb_list(opt.out / "rgb.txt"), depth_list(opt.out / "depth.txt");
  rgb_list << "# color images\n# generated by builtscene synth rgbd, scene " << opt.scene << "\n# timestamp filename\n";
  depth_list << "# depth maps (16-bit PNG, 5000 per metre, 0 = no reading)\n# generated by builtscene synth rgbd, scene " << opt.scene
             << "\n# timestamp filename\n";

  ColorCameraModel color;
  color.exposure = 1.15;
  color.noise = opt.kinect_noise && opt.image_noise;
  int blur_subframes_max = 1;
  // At most 9 sub-frames per 20 ms of exposure (a 20 ms shutter keeps its old images).
  const int max_subframes = static_cast<int>(std::ceil(9.0 * opt.exposure_time_s / 0.02 - 1e-9));
  double mean_valid = 0;
  {
    FrameFinisher finisher(std::max(1, opt.finish_threads), n, opt.seed, opt.kinect_noise && opt.depth_noise,
                           settings.depth_map_factor, timer);
    Progress progress("synth rgbd", static_cast<std::size_t>(n - first));
    RenderOutput sub;
    for (int i = first; i < n; ++i) {
      const double t = t0 + i / settings.fps;
      const SE3& pose = motion.poses[static_cast<std::size_t>(i)];
      gt.push_back({t, pose});
      char name[32];
      std::snprintf(name, sizeof name, "%06d.png", i);
      rgb_list << stamp(t) << " rgb/" << name << "\n";
      depth_list << stamp(t) << " depth/" << name << "\n";

      auto rs = std::chrono::steady_clock::now();
      RenderOutput ro;
      renderer.render(pose, ro, opt.render_threads);
      if (opt.blur) {
        // Integrate over the shutter time: sub-frames on the path through neighbouring poses,
        // as many as the image motion needs (about one per 1.5 pixels of travel).
        const SE3& prev = motion.poses[static_cast<std::size_t>(std::max(0, i - 1))];
        const SE3& next = motion.poses[static_cast<std::size_t>(std::min(n - 1, i + 1))];
        const SE3 rel = prev.inverse() * next;
        const double span_frames = std::max(1, std::min(n - 1, i + 1) - std::max(0, i - 1));
        const double px_per_frame = (Eigen::AngleAxisd(rel.rotation()).angle() * settings.camera.fx + rel.translation().norm() * settings.camera.fx / 1.5) / span_frames;
        const double px = px_per_frame * opt.exposure_time_s * settings.fps;
        const int K = std::clamp(static_cast<int>(std::ceil(px / 1.5)), 1, max_subframes);
        blur_subframes_max = std::max(blur_subframes_max, K);
        if (K > 1) {
          cv::Mat acc = cv::Mat::zeros(ro.bgr.size(), CV_32FC3);
          for (int k = 0; k < K; ++k) {
            const double off = (static_cast<double>(k) / (K - 1) - 0.5) * opt.exposure_time_s * settings.fps;  // in frames
            const SE3 p = off < 0 ? SE3::interpolate(pose, prev, -off) : SE3::interpolate(pose, next, off);
            renderer.render(p, sub, opt.render_threads);
            acc += sub.bgr;
          }
          ro.bgr = acc / K;
        }
      }
      timer.add("render", ms_since(rs));

      FrameFinisher::Job job;
      job.index = i;
      job.render = std::move(ro);
      job.color = color;
      if (opt.exposure_changes) job.color.exposure *= exposure_gain(t - t0, opt.seed);
      if (opt.light_fade_to != 1.0) {
        const double light = 1.0 + (opt.light_fade_to - 1.0) * (n > 1 ? static_cast<double>(i) / (n - 1) : 0.0);
        job.color.exposure *= light;
        job.color.gain /= light;
      }
      job.rgb_path = opt.out / "rgb" / name;
      job.depth_path = opt.out / "depth" / name;
      finisher.push(std::move(job));
      progress.update(static_cast<std::size_t>(i + 1 - first));
    }
    finisher.finish();
    mean_valid = finisher.mean_valid(first);
    progress.finish();
  }
  if (!rgb_list || !depth_list) throw Failure(located(opt.out, 0, "cannot write rgb.txt/depth.txt"));
  write_tum_trajectory(opt.out / "groundtruth.txt", gt);

  const double seconds = ms_since(t_start) / 1000.0;
  nlohmann::json j;
  j["scene"] = opt.scene;
  j["out"] = opt.out.string();
  j["motion"] = opt.motion == MotionKind::Robot ? "robot" : "handheld";
  j["noise"] = !opt.kinect_noise || (!opt.depth_noise && !opt.image_noise) ? "none"
               : opt.depth_noise && opt.image_noise                        ? "kinect"
               : opt.depth_noise                                           ? "depth"
                                                                           : "image";
  j["blur"] = opt.blur;
  j["exposure_changes"] = opt.exposure_changes;
  j["light_fade_to"] = opt.light_fade_to;
  j["seed"] = opt.seed;
  j["frames"] = n - first;
  j["first_frame"] = first;
  j["seconds"] = seconds;
  j["fps"] = (n - first) / seconds;
  j["width"] = opt.width;
  j["height"] = opt.height;
  j["tags"] = scene.tags.size();
  j["surfaces"] = renderer.surfaces().size();
  j["valid_depth_fraction"] = mean_valid;
  if (opt.motion == MotionKind::Robot) {
    j["loops"] = opt.loops;
    j["loop_length_m"] = motion.loop_length_m;
  } else {
    j["fast_turns"] = motion.fast_turns;
  }
  if (opt.blur) {
    j["blur_subframes_max"] = blur_subframes_max;
    j["exposure_ms"] = opt.exposure_time_s * 1000.0;
  }
  j["stage_ms"] = timer.summary();
  spdlog::info("synth rgbd: {} frames of {} in {:.1f} s ({:.1f} fps) -> {}", n - first, opt.scene, seconds, (n - first) / seconds,
               opt.out.string());
  return j;
}

}  // namespace builtscene::synth
