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
#include "core/stage_timer.hpp"

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
  double cpu_seconds = 0;       // user + system time of the process during the scan (all threads)
  nlohmann::json stage_ms;
  nlohmann::json summary() const;  // frames, keyframes, codes, reads, fps, stage_ms, ...
};

// Result of one frame, in the frame's own pixel coordinates.
struct FrameRead {
  DecodedSymbol symbol;
  cv::Rect crop_box;   // where it was read (region bounds, or the symbol's bounds)
  bool rotated = false;
};

// The decoders of a scan. `whole`: zxing-cpp's thorough search (its defaults: 90-degree retry,
// downscaled pyramid), the decoder alone on whole frames. `frame`: the pipeline's whole-key-frame
// pass, rows and columns without the pyramid (on the generated 2000-frame scan the pyramid read
// nothing more, at twice the cost; the columns keep symbols turned by 90 degrees, which region
// detection often misses). `crop`: quick search of region crops. `upright`: quick search of
// uprighted region patches with 3 agreeing scan lines.
struct DecoderSet {
  const Decoder& whole;
  const Decoder& frame;
  const Decoder& crop;
  const Decoder& upright;
};

// Reads one frame (no key-frame logic): the thorough decoder alone on the whole frame
// (decoder_only or regions off); otherwise optionally the `frame` decoder on the whole frame first,
// then every region holding no symbol yet: as is (only when the whole frame was not read, since
// that read the same pixels already), then turned upright by the estimated direction. Thread-safe.
// `timer`, when given, receives per-stage times (whole_frame, regions, direction, upright_decode).
std::vector<FrameRead> read_frame(const cv::Mat& frame, const StageSettings& settings, const DecoderSet& decoders,
                                  bool rotate, bool decoder_only, bool whole_frame, int max_symbols,
                                  std::size_t* regions = nullptr, StageTimer* timer = nullptr);

// The region turned upright: the part of `gray` covered by `region`'s box (with a margin), resampled
// along the scan direction `scan_angle_deg` (bars vertical). Cheaper than turning the region's
// whole axis-aligned bounds, and the symbol fills the result, so the decoder scans fewer pixels.
cv::Mat upright_region(const cv::Mat& gray, const Region& region, double scan_angle_deg);

// Picks the region threshold that reads the most distinct codes (then the most reads) on the
// sample frames; ties go to the threshold nearest 0.45.
double calibrate_region_threshold(const std::vector<cv::Mat>& samples, const RegionOptions& base,
                                  const DecoderSet& decoders, bool rotate, int threads);

// Scans a video file or image folder. On an InputError while reading frames, the inventory
// found so far is written (when options.out is set) before the error propagates.
ScanResult scan(const std::filesystem::path& video, const ScanOptions& options);

}  // namespace builtscene::barcode
