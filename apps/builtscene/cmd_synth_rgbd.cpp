// `builtscene synth rgbd`: generated RGB-D worlds with exact ground truth (TUM layout).
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "synth/rgbd_sequence_writer.hpp"
#include "synth/scene_library.hpp"

namespace builtscene::app {
namespace {

struct SynthRgbdCli {
  synth::RgbdSequenceOptions opt;
  std::string motion = "handheld";
  std::string noise = "kinect";
  std::string out;
  double exposure_ms = 20.0;
};

const bool registered_synth_rgbd = register_command({
    .path = {"synth", "rgbd"},
    .description = "Generate an RGB-D sequence of a built world with exact ground truth (TUM layout)",
    .setup = [](CLI::App& cmd) -> Action {
      auto c = std::make_shared<SynthRgbdCli>();
      std::string names;
      for (const auto& n : synth::scene_names()) names += (names.empty() ? "" : ", ") + n;
      cmd.add_option("--scene", c->opt.scene, "Scene: " + names)->capture_default_str();
      cmd.add_option("--out", c->out, "Output folder (created)")->required();
      auto* frames = cmd.add_option("--frames", c->opt.frames, "Number of frames (default: handheld 300, robot: --loops loops)");
      cmd.add_option("--first-frame", c->opt.first_frame,
                     "Write only frames from this index on (the same files as in the whole sequence)")
          ->capture_default_str();
      cmd.add_option("--seed", c->opt.seed, "Seed of the motion and the noise")->capture_default_str();
      cmd.add_option("--motion", c->motion, "handheld | robot")->capture_default_str();
      cmd.add_option("--loops", c->opt.loops, "Robot: times around the scene's loop")->capture_default_str();
      cmd.add_flag("--blur", c->opt.blur, "Motion blur integrated over the exposure (--exposure-ms)");
      auto* exposure = cmd.add_option("--exposure-ms", c->exposure_ms, "Shutter time of --blur in ms, 1 to 33 (implies --blur)")->capture_default_str();
      cmd.add_option("--noise", c->noise, "none | kinect (depth and image noise) | depth | image (one part of kinect alone)")->capture_default_str();
      cmd.add_flag("--exposure-changes", c->opt.exposure_changes, "Auto-exposure drift and steps");
      cmd.add_option("--light-fade", c->opt.light_fade_to,
                     "The light falls linearly to this fraction by the last frame (0.02 to 1); auto-gain keeps the brightness, so noise grows")
          ->capture_default_str();
      cmd.add_option("--render-threads", c->opt.render_threads, "Rendering threads (output does not depend on it)")->capture_default_str();
      return [c, frames, exposure] {
        if (exposure->count() > 0) c->opt.blur = true;
        c->opt.exposure_time_s = c->exposure_ms / 1000.0;
        if (c->motion == "handheld") c->opt.motion = synth::MotionKind::Handheld;
        else if (c->motion == "robot") c->opt.motion = synth::MotionKind::Robot;
        else throw InputError("--motion: expected handheld or robot, got '" + c->motion + "'");
        if (c->noise == "kinect") c->opt.kinect_noise = true;
        else if (c->noise == "none") c->opt.kinect_noise = false;
        else if (c->noise == "depth") c->opt.image_noise = false;
        else if (c->noise == "image") c->opt.depth_noise = false;
        else throw InputError("--noise: expected none, kinect, depth or image, got '" + c->noise + "'");
        if (frames->count() > 0 && c->opt.frames < 1) throw InputError("--frames: must be at least 1, got " + std::to_string(c->opt.frames));
        c->opt.out = c->out;
        return synth::generate_rgbd_sequence(c->opt);
      };
    },
    .order = 10});

const bool group_synth_rgbd = register_group("synth", "Generated test worlds with exact ground truth");

}  // namespace
}  // namespace builtscene::app
