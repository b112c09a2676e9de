// `builtscene barcodes scan|eval`: 1D barcodes from warehouse video scans.
#include <iostream>
#include <memory>

#include "barcode/evaluation.hpp"
#include "barcode/scan_pipeline.hpp"
#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"

namespace builtscene::app {
namespace {

struct ScanCli {
  std::filesystem::path video;
  barcode::ScanOptions options;
  std::string decoder = "zxing";
};

nlohmann::json run_scan(ScanCli cli) {
  cli.options.decoder = barcode::parse_decoder_kind(cli.decoder);
  const auto r = barcode::scan(cli.video, cli.options);
  spdlog::info("barcodes scan: {} frames, {} processed, {} distinct codes, {} reads, {:.1f} fps -> {}", r.frames,
               r.keyframes, r.inventory.size(), r.inventory.total_reads(),
               r.seconds > 0 ? r.frames / r.seconds : 0.0, (cli.options.out / "inventory.csv").string());
  auto j = r.summary();
  j["inventory"] = (cli.options.out / "inventory.csv").string();
  j["threads"] = cli.options.threads;
  j["decoder"] = cli.decoder;
  j["decoder_only"] = cli.options.decoder_only;
  return j;
}

struct EvalCli {
  std::filesystem::path truth, inventory, video;
  bool sweep = false;
  barcode::ScanOptions options;
  std::string decoder = "zxing";
};

nlohmann::json run_eval(EvalCli cli) {
  const auto truth = barcode::read_truth(cli.truth);
  if (cli.sweep) {
    if (cli.video.empty()) throw InputError("--sweep needs --video (the scan to run every configuration on)");
    cli.options.decoder = barcode::parse_decoder_kind(cli.decoder);
    const auto r = barcode::run_sweep(cli.video, truth, cli.options);
    std::cerr << r.table(truth) << std::flush;
    return r.to_json();
  }
  if (cli.inventory.empty()) throw InputError("barcodes eval: give --inventory FILE (or --sweep --video FILE)");
  const auto inv = barcode::Inventory::read_csv(cli.inventory);
  const auto e = barcode::evaluate(truth, inv);
  spdlog::info("barcodes eval: recognition rate {:.1f}% ({} of {} legible labels), location labels {}/{}, {} reads, "
               "{} false codes",
               100 * e.recognition_rate, e.recognized, e.legible_labels, e.location_recognized, e.location_labels,
               e.reads, e.false_codes);
  for (const auto& m : e.missed) spdlog::info("  missed {}", m);
  for (const auto& f : e.false_code_texts) spdlog::warn("  false code {}", f);
  return e.to_json();
}

void add_stage_options(CLI::App& cmd, barcode::ScanOptions& o, std::string& decoder) {
  cmd.add_option("--keyframes", o.keyframes, "Key-frame factor k (x shot mean), auto or off")->capture_default_str();
  cmd.add_option("--region", o.region, "Region binarization threshold T in (0,1], auto, edges or off")
      ->capture_default_str();
  cmd.add_flag("--rotate,!--no-rotate", o.rotate, "Direction estimation and rotation for regions that fail")
      ->capture_default_str();
  cmd.add_flag("--whole-frame,!--no-whole-frame", o.whole_frame,
               "Decode the whole key frame too; regions only for what it misses")
      ->capture_default_str();
  cmd.add_option("--decoder", decoder, "zxing, zbar or both")->capture_default_str();
  cmd.add_option("--threads", o.threads, "Worker threads (output does not depend on it)")->capture_default_str();
}

const bool group_barcodes = register_group("barcodes", "1D barcodes from warehouse video scans");

const bool registered_scan = register_command({
    .path = {"barcodes", "scan"},
    .description = "Read every 1D barcode in a video (or image folder) into an inventory",
    .setup = [](CLI::App& cmd) -> Action {
      auto cli = std::make_shared<ScanCli>();
      cmd.add_option("--video", cli->video, "Video file (MJPG .avi, ...) or folder of numbered images")->required();
      cmd.add_option("--out", cli->options.out, "Output folder (inventory.csv, inventory.json, crops/, keyframes/)")
          ->required();
      add_stage_options(cmd, cli->options, cli->decoder);
      cmd.add_flag("--decoder-only", cli->options.decoder_only, "Baseline: the decoder alone on every whole frame");
      cmd.add_flag("--annotate,!--no-annotate", cli->options.annotate, "Write annotated key frames")
          ->capture_default_str();
      return [cli] { return run_scan(*cli); };
    },
    .order = 1});

const bool registered_eval = register_command({
    .path = {"barcodes", "eval"},
    .description = "Recognition rate, reads and false codes of an inventory against truth.csv (or a --sweep)",
    .setup = [](CLI::App& cmd) -> Action {
      auto cli = std::make_shared<EvalCli>();
      cmd.add_option("--truth", cli->truth, "truth.csv of a generated scan")->required();
      cmd.add_option("--inventory", cli->inventory, "inventory.csv from barcodes scan");
      cmd.add_flag("--sweep", cli->sweep, "Run the configurations of the source's Figures 4.12-4.14 on --video");
      cmd.add_option("--video", cli->video, "Video for --sweep");
      add_stage_options(cmd, cli->options, cli->decoder);
      return [cli] { return run_eval(*cli); };
    },
    .order = 2});

}  // namespace
}  // namespace builtscene::app
