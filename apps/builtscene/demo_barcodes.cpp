// `builtscene demo`, barcodes part: a small generated warehouse scan, read by the full pipeline
// and by the decoder alone, scored against the scan's ground truth.
#include <fmt/format.h>

#include "barcode/evaluation.hpp"
#include "barcode/scan_pipeline.hpp"
#include "core/logging.hpp"
#include "demo_registry.hpp"
#include "synth/warehouse_scene.hpp"

namespace builtscene::app {
namespace {
namespace fs = std::filesystem;

std::string row(const std::string& name, const barcode::ScanResult& r, const barcode::Evaluation& e) {
  return fmt::format(
      "<tr><th>{}</th><td>{}</td><td>{}</td><td>{}/{}</td><td>{}/{}</td><td>{}</td><td>{}</td><td>{:.1f}</td></tr>\n", name,
      r.frames, r.keyframes, e.location_recognized, e.location_labels, e.recognized, e.legible_labels, e.reads,
      e.false_codes, r.seconds > 0 ? r.frames / r.seconds : 0.0);
}

DemoSection run_barcodes_demo(const fs::path& dir) {
  synth::WarehouseOptions w;
  w.seed = 3;
  w.frames = 240;
  w.size = {1280, 720};
  w.location_labels = 6;
  const auto gen = synth::write_warehouse_scan(dir / "scan", w);
  const auto truth = barcode::read_truth(gen.truth);
  barcode::ScanOptions best;
  best.out = dir / "pipeline";
  const auto rp = barcode::scan(gen.video, best);
  barcode::ScanOptions alone;
  alone.decoder_only = true;
  alone.out = dir / "decoder_only";
  alone.annotate = false;
  const auto rd = barcode::scan(gen.video, alone);
  const auto ep = barcode::evaluate(truth, rp.inventory), ed = barcode::evaluate(truth, rd.inventory);

  std::string html =
      "<p>A generated handheld scan along one rack bay (240 frames, 1280x720, 6 location labels on the beams and "
      "product labels on boxes; camera roll up to 45 degrees, shake, motion blur, defocus, shadows). Ground truth "
      "by construction: a label counts as legible in a frame when its whole symbol is in view with modules of at "
      "least 1.5 px and little blur across the bars.</p>\n"
      "<table><tr><th></th><th>frames</th><th>processed</th><th>location labels read</th><th>legible labels "
      "read</th><th>reads</th><th>false codes</th><th>fps</th></tr>\n" +
      row("pipeline (key frames, regions, rotation)", rp, ep) + row("decoder alone, every whole frame", rd, ed) +
      "</table>\n";
  // One annotated key frame (the first with a code) and the best crops.
  std::vector<fs::path> frames;
  if (fs::is_directory(dir / "pipeline" / "keyframes"))
    for (const auto& e : fs::directory_iterator(dir / "pipeline" / "keyframes")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  if (!frames.empty())
    html += "<p>Key frame " + frames.front().stem().string() + " with the regions examined (blue) and the codes read:</p>" +
            "<img src=\"barcodes/pipeline/keyframes/" + frames.front().filename().string() + "\" width=\"640\">\n";
  html += "<p>Best crop of each code read:</p><p>";
  std::size_t k = 0;
  for (const auto* e : rp.inventory.entries()) {
    if (!e->best_crop.empty())
      html += fmt::format("<img src=\"barcodes/pipeline/crops/{}.png\" height=\"70\" title=\"{}\"> ", k, e->code);
    ++k;
  }
  html += "</p>\n";
  return {"Barcodes from a warehouse video scan", html,
          nlohmann::json{{"pipeline", ep.to_json()},
                         {"decoder_only", ed.to_json()},
                         {"frames", rp.frames},
                         {"keyframes", rp.keyframes},
                         {"pipeline_fps", rp.seconds > 0 ? rp.frames / rp.seconds : 0.0},
                         {"decoder_only_fps", rd.seconds > 0 ? rd.frames / rd.seconds : 0.0}}};
}

const bool registered_demo_barcodes = register_demo_part({.name = "barcodes", .order = 30, .run = run_barcodes_demo});

}  // namespace
}  // namespace builtscene::app
