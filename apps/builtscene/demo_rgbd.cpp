// Demo part: a short generated RGB-D sequence with its ground truth, as thumbnails.
#include <opencv2/imgcodecs.hpp>

#include "demo_registry.hpp"
#include "synth/rgbd_preview.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace builtscene::app {
namespace {

DemoSection run_rgbd_demo(const std::filesystem::path& dir) {
  synth::RgbdSequenceOptions o;
  o.scene = "demo";
  o.out = dir / "sequence";
  o.frames = 90;
  o.seed = 1;
  o.render_threads = 1;
  nlohmann::json summary = synth::generate_rgbd_sequence(o);
  cv::imwrite((dir / "frames.png").string(), synth::rgbd_contact_sheet(o.out, {0, 30, 60, 89}, 0.35));
  cv::imwrite((dir / "truth_map.png").string(), synth::truth_map_picture(o.out, 5));
  char line[512];
  std::snprintf(line, sizeof line,
                "<p>Scene <code>demo</code>, handheld motion, Kinect depth noise: %d frames of 640 x 480 RGB + 16-bit depth "
                "written in %.1f s (%.1f frames/s, render median %.1f ms, noise %.1f ms, PNG %.1f ms per frame); "
                "%.1f %% of the pixels carry depth. Folder: <code>rgbd/sequence</code> (TUM layout with groundtruth.txt, "
                "camera.yaml, markers.csv, truth_map.pgm/.yaml, scene.json).</p>",
                summary["frames"].get<int>(), summary["seconds"].get<double>(), summary["fps"].get<double>(),
                summary["stage_ms"]["render"]["median"].get<double>(), summary["stage_ms"]["noise"]["median"].get<double>(),
                summary["stage_ms"]["encode"]["median"].get<double>(), 100.0 * summary["valid_depth_fraction"].get<double>());
  std::string html = line;
  html += "<p><img src=\"rgbd/frames.png\" alt=\"RGB and depth of frames 0, 30, 60, 89\"></p>"
          "<p>Ground-truth occupancy of the robot's height band (5 cm cells, black occupied, white free, grey unknown) "
          "with the camera path in red:</p><p><img src=\"rgbd/truth_map.png\" alt=\"truth map\"></p>";
  return {"Generated RGB-D world with exact ground truth", html, summary};
}

const bool registered_demo_rgbd = register_demo_part({.name = "rgbd", .order = 10, .run = run_rgbd_demo});

}  // namespace
}  // namespace builtscene::app
