// `builtscene synth warehouse`: a generated warehouse scan video with ground truth.
#include <cstdio>
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "synth/warehouse_scene.hpp"

namespace builtscene::app {
namespace {

struct Options {
  std::filesystem::path out;
  synth::WarehouseOptions scene;
  std::string size = "1920x1080";
};

cv::Size parse_size(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
    throw InputError("--size: expected WIDTHxHEIGHT such as 1920x1080, got '" + s + "'");
  return {w, h};
}

nlohmann::json run(Options opt) {
  opt.scene.size = parse_size(opt.size);
  const auto r = synth::write_warehouse_scan(opt.out, opt.scene);
  spdlog::info("synth warehouse: {} frames, {} labels ({} location, {} legible somewhere) -> {} in {:.1f} s", r.frames,
               r.labels, r.location_labels, r.legible_labels, r.video.string(), r.seconds);
  return {{"video", r.video.string()},     {"truth", r.truth.string()},
          {"frames", r.frames},            {"labels", r.labels},
          {"location_labels", r.location_labels}, {"legible_labels", r.legible_labels},
          {"seed", opt.scene.seed},        {"size", opt.size},
          {"seconds", r.seconds}};
}

const bool registered_synth_warehouse = register_command({
    .path = {"synth", "warehouse"},
    .description = "Generated warehouse scan video (racks, location and product labels) with truth.csv",
    .setup = [](CLI::App& cmd) -> Action {
      auto opt = std::make_shared<Options>();
      cmd.add_option("--out", opt->out, "Output folder")->required();
      cmd.add_option("--seed", opt->scene.seed, "Random seed (same seed, same video)")->capture_default_str();
      cmd.add_option("--frames", opt->scene.frames, "Number of frames")->capture_default_str();
      cmd.add_option("--size", opt->size, "Frame size WIDTHxHEIGHT")->capture_default_str();
      cmd.add_option("--labels", opt->scene.location_labels, "Location labels (multiple of 6)")->capture_default_str();
      cmd.add_flag("--products,!--no-products", opt->scene.product_labels, "Product labels on boxes")
          ->capture_default_str();
      cmd.add_option("--format", opt->scene.format, "avi (MJPG) or png (numbered frames)")->capture_default_str();
      cmd.add_option("--threads", opt->scene.threads, "Rendering threads")->capture_default_str();
      return [opt] { return run(*opt); };
    }});

}  // namespace
}  // namespace builtscene::app
