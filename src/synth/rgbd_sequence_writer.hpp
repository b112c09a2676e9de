#pragma once
// `builtscene synth rgbd`: renders a generated world along a camera motion and writes a TUM
// RGB-D folder with exact ground truth (poses, tags, occupancy, geometry).
#include <cstdint>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/camera.hpp"
#include "synth/camera_motion.hpp"

namespace builtscene::synth {

struct RgbdSequenceOptions {
  std::string scene = "demo";
  std::filesystem::path out;
  int frames = 0;                 // 0: the motion's default (handheld 300, robot: --loops loops)
  // Write only frames first_frame.. of the sequence (names, times and bytes as in the whole
  // sequence; every frame's noise is seeded by its index): a slice of a long run for tests.
  int first_frame = 0;
  std::uint64_t seed = 1;
  MotionKind motion = MotionKind::Handheld;
  int loops = 1;
  bool blur = false;              // motion blur integrated over the exposure time
  bool kinect_noise = true;       // false: exact depth and noise-free colour
  // With kinect_noise, which of its parts (both by default; one alone tells which part a
  // result depends on: `synth rgbd --noise depth|image`).
  bool depth_noise = true, image_noise = true;
  bool exposure_changes = false;  // slow auto-exposure drift and steps
  double exposure_time_s = 0.02;  // shutter time for --blur; at most one frame interval (1/fps)
  // The light falls linearly over the sequence to this fraction of its start (1: constant);
  // the camera's auto-gain keeps the picture's brightness, so its noise grows as the light fades.
  double light_fade_to = 1.0;
  int render_threads = 1;         // rendering threads (bands of rows)
  int finish_threads = 2;         // sensor noise + PNG encoding threads (frames in parallel)
  int width = 640, height = 480;  // intrinsics scale with the size (tests use smaller images)
};

// Kinect-like colour camera at the given size (525 px focal length at 640 x 480).
RgbdCameraSettings kinect_settings(int width = 640, int height = 480);

// Validates options (InputError naming the option or path), generates and writes the folder.
// Returns the summary printed by --json.
nlohmann::json generate_rgbd_sequence(const RgbdSequenceOptions& options);

}  // namespace builtscene::synth
