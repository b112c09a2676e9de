#pragma once
// A generated RGB-D world (builtscene synth rgbd, Kinect noise unless told otherwise) in a temporary folder for
// end-to-end tests, removed on every exit (also when a check throws: 300 frames are 250 MB).

#include <filesystem>
#include <string>

#include "synth/rgbd_sequence_writer.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::slam {

struct GeneratedWorld {
  std::filesystem::path dir;
  GeneratedWorld(const std::string& scene, synth::MotionKind motion, std::uint64_t seed, int frames, bool kinect_noise = true) {
    synth::RgbdSequenceOptions o;
    o.scene = scene;
    o.motion = motion;
    o.seed = seed;
    o.frames = frames;
    o.kinect_noise = kinect_noise;
    o.out = testing::scratch_dir("slam_world_" + scene + "_" + std::to_string(seed));  // also removed at exit
    dir = o.out;
    std::filesystem::remove_all(dir);
    synth::generate_rgbd_sequence(o);
  }
  ~GeneratedWorld() { std::filesystem::remove_all(dir); }
  GeneratedWorld(const GeneratedWorld&) = delete;
  GeneratedWorld& operator=(const GeneratedWorld&) = delete;
};

}  // namespace builtscene::slam
