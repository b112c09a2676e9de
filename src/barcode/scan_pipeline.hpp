#pragma once
// The complete reader of the source's Figure 4.10: key frames -> regions -> decode as is ->
// direction estimation and rotation for regions that failed -> inventory. Every stage can be
// switched off; `decoder_only` is the baseline (the decoder alone on every whole frame).
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "barcode/decoder.hpp"
#include "barcode/direction_estimator.hpp"
#include "barcode/inventory.hpp"
#include "barcode/key_frame_selector.hpp"
#include "barcode/region_detector.hpp"

namespace builtscene::barcode {

struct ScanOptions {
  std::string keyframes = "auto";  // "off", "auto" (k = 0.7, automatic shots) or a factor k
  std::string region = "auto";     // "off", "auto" (threshold from sample frames), "edges" or T in (0,1)
  bool rotate = true;
  // Decode the whole key frame first and examine only the regions holding no symbol read there
  // (the source let its decoder search whole frames too; zxing-cpp is fast enough to afford it).
  bool whole_frame = true;
  DecoderKind decoder = DecoderKind::zxing;
  bool decoder_only = false;
  int threads = 2;
  int max_symbols_per_frame = 32;  // whole-frame decoding
  std::filesystem::path out;       // empty: nothing written
  bool annotate = true;            // annotated key frames (the frames where a code was first read)
  std::size_t checkpoint_every = 200;  // inventory rewritten every this many processed frames
};

// Parsed form of the stage settings.
struct StageSettings {
  bool keyframes = true;
  double k = 0.7;
  bool regions = true;
  bool region_auto = true;
  RegionOptions region;
};
StageSettings parse_stage_settings(const ScanOptions& options);  // throws InputError

struct ScanResult {
  Inventory inventory;
  std::size_t frames = 0;       // frames in the video
  std::size_t keyframes = 0;    // frames processed (all of them without key-frame selection)
  std::size_t region_count = 0; // candidate regions examined
  std::size_t rotated_reads = 0;  // reads that needed direction estimation
  double region_threshold = 0;  // the threshold used (chosen when auto)
  double seconds = 0;
  nlohmann::json stage_ms;
  nlohmann::json summary() const;  // frames, keyframes, codes, reads, fps, stage_ms, ...
};

// Result of one frame, in the frame's own pixel coordinates.
struct FrameRead {
  DecodedSymbol symbol;
  cv::Rect crop_box;   // where it was read (region bounds, or the symbol's bounds)
  bool rotated = false;
};

// The decoders of a scan: `whole` searches whole frames thoroughly, `crop` reads region crops.
struct DecoderSet {
  const Decoder& whole;
  const Decoder& crop;
};

// Reads one frame (no key-frame logic): the decoder alone on the whole frame (decoder_only or
// regions off); otherwise optionally the whole frame first, then every region holding no symbol
// yet as is, then turned upright by the estimated direction when that fails. Thread-safe.
std::vector<FrameRead> read_frame(const cv::Mat& frame, const StageSettings& settings, const DecoderSet& decoders,
                                  bool rotate, bool decoder_only, bool whole_frame, int max_symbols,
                                  std::size_t* regions = nullptr);

// Picks the region threshold that reads the most distinct codes (then the most reads) on the
// sample frames; ties go to the threshold nearest 0.45.
double calibrate_region_threshold(const std::vector<cv::Mat>& samples, const RegionOptions& base,
                                  const DecoderSet& decoders, bool rotate, int threads);

// Scans a video file or image folder. On an InputError while reading frames, the inventory
// found so far is written (when options.out is set) before the error propagates.
ScanResult scan(const std::filesystem::path& video, const ScanOptions& options);

}  // namespace builtscene::barcode
