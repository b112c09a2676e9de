#include "barcode/scan_pipeline.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include <sys/resource.h>
#include <time.h>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "barcode/frame_source.hpp"
#include "barcode/ordered_pool.hpp"
#include "core/errors.hpp"
#include "core/progress.hpp"
#include "core/stage_timer.hpp"

namespace builtscene::barcode {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

StageSettings parse_stage_settings(const ScanOptions& o) {
  StageSettings s;
  auto number = [](const std::string& v, const std::string& flag, double lo, double hi) {
    double x = 0;
    std::size_t used = 0;
    try {
      x = std::stod(v, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != v.size() || !(x > lo && x <= hi))
      throw InputError(flag + ": expected off, auto or a number in (" + std::to_string(lo).substr(0, 3) + ", " +
                       std::to_string(hi).substr(0, 3) + "], got '" + v + "'");
    return x;
  };
  if (o.keyframes == "off") {
    s.keyframes = false;
  } else if (o.keyframes != "auto") {
    s.k = number(o.keyframes, "--keyframes", 0.0, 10.0);
  }
  if (o.region == "off") {
    s.regions = false;
  } else if (o.region == "auto") {
    s.region_auto = true;
  } else if (o.region == "edges") {
    s.region_auto = false;
    s.region.mode = Binarization::edges;
  } else {
    s.region_auto = false;
    s.region.threshold = number(o.region, "--region", 0.0, 1.0);
  }
  if (o.threads < 1 || o.threads > 256) throw InputError("--threads: expected 1..256, got " + std::to_string(o.threads));
  return s;
}

namespace {

cv::Rect symbol_box(const DecodedSymbol& s, const cv::Size& size) {
  std::vector<cv::Point2f> pts(s.corners.begin(), s.corners.end());
  cv::Rect r = cv::boundingRect(pts);
  const int grow_x = std::max(8, r.width / 6);
  const int grow_y = std::max(std::max(8, r.height / 2), r.width / 4);
  r = cv::Rect(r.x - grow_x, r.y - grow_y, r.width + 2 * grow_x, r.height + 2 * grow_y);
  return r & cv::Rect(0, 0, size.width, size.height);
}

bool same(const DecodedSymbol& a, const DecodedSymbol& b) { return a.text == b.text && a.symbology == b.symbology; }

// CPU time of the calling thread in ms: per-frame stage times that do not grow with the load of a
// shared machine (a preempted worker's wall time does).
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// User + system CPU time of the whole process: on a shared machine, wall-clock frames per second
// depend on the other jobs; CPU time per frame does not (much).
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

}  // namespace

cv::Mat upright_region(const cv::Mat& gray, const Region& region, double scan_angle_deg) {
  const double a = scan_angle_deg * CV_PI / 180.0;
  const cv::Point2f u(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)));  // scan direction
  const cv::Point2f n(-u.y, u.x);                                                         // along the bars
  cv::Point2f pts[4];
  region.box.points(pts);
  float half_w = 0, half_h = 0;
  for (const auto& p : pts) {
    const cv::Point2f d = p - region.box.center;
    half_w = std::max(half_w, std::abs(d.dot(u)));
    half_h = std::max(half_h, std::abs(d.dot(n)));
  }
  // The region box is the bright label's outline; quiet zones and bar ends may reach past it.
  half_w = half_w * 1.15f + 8.0f;
  half_h = half_h * 1.3f + 8.0f;
  const cv::Point2f c = region.box.center;
  // Maps output pixels to frame pixels: x runs along the scan direction, y along the bars.
  const cv::Mat to_frame = (cv::Mat_<double>(2, 3) << u.x, n.x, c.x - u.x * half_w - n.x * half_h,  //
                            u.y, n.y, c.y - u.y * half_w - n.y * half_h);
  cv::Mat out;
  cv::warpAffine(gray, out, to_frame, cv::Size(cvCeil(2 * half_w), cvCeil(2 * half_h)),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, cv::Scalar::all(255));
  return out;
}

std::vector<FrameRead> read_frame(const cv::Mat& frame, const StageSettings& settings, const DecoderSet& decoders,
                                  bool rotate, bool decoder_only, bool whole_frame, int max_symbols,
                                  std::size_t* region_count, StageTimer* timer) {
  std::vector<FrameRead> reads;
  if (frame.empty()) return reads;
  auto time = [&](const char* stage, double since) {
    if (timer) timer->add(stage, thread_cpu_ms() - since);
  };
  cv::Mat gray;
  if (frame.channels() == 3) {
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
  } else {
    gray = frame;
  }
  const bool baseline = decoder_only || !settings.regions;
  if (baseline || whole_frame) {
    const double ts = thread_cpu_ms();
    const Decoder& d = baseline ? decoders.whole : decoders.frame;
    for (auto& s : d.decode(gray, max_symbols)) reads.push_back({s, symbol_box(s, gray.size()), false});
    time("whole_frame", ts);
    if (baseline) return reads;
  }
  const std::size_t whole_reads = reads.size();
  double ts = thread_cpu_ms();
  const RegionDetector detector(settings.region);
  const auto regions = detector.detect(gray);
  time("regions", ts);
  if (region_count) *region_count += regions.size();
  const DirectionEstimator estimator;
  for (const auto& region : regions) {
    const cv::Rect box = region.bounds(gray.size());
    if (box.width < 8 || box.height < 8) continue;
    bool done = false;
    for (std::size_t i = 0; i < whole_reads; ++i) {
      const auto& c = reads[i].symbol.corners;
      done = done || box.contains((c[0] + c[1] + c[2] + c[3]) * 0.25f);
    }
    if (done) continue;
    const cv::Mat crop = gray(box);
    std::vector<DecodedSymbol> symbols;
    if (!whole_frame) {
      ts = thread_cpu_ms();
      symbols = decoders.crop.decode(crop, 1);
      time("crop_decode", ts);
    }
    bool rotated = false;
    if (symbols.empty() && rotate) {
      ts = thread_cpu_ms();
      const auto angle = estimator.scan_angle(crop);
      time("direction", ts);
      if (angle && std::min(*angle, 180.0 - *angle) > 3.0) {
        ts = thread_cpu_ms();
        symbols = decoders.upright.decode(upright_region(gray, region, *angle), 1);
        time("upright_decode", ts);
        rotated = true;
      }
    }
    for (auto& s : symbols) {
      if (std::any_of(reads.begin(), reads.end(), [&](const FrameRead& r) { return same(r.symbol, s); })) continue;
      if (rotated) {
        // Positions in the uprighted patch do not map back simply; the region stands for them.
        cv::Point2f pts[4];
        region.box.points(pts);
        for (int i = 0; i < 4; ++i) s.corners[static_cast<std::size_t>(i)] = pts[i];
      } else {
        for (auto& c : s.corners) c += cv::Point2f(static_cast<float>(box.x), static_cast<float>(box.y));
      }
      reads.push_back({s, box, rotated});
    }
  }
  return reads;
}

double calibrate_region_threshold(const std::vector<cv::Mat>& samples, const RegionOptions& base,
                                  const DecoderSet& decoders, bool rotate, int threads) {
  const std::vector<double> candidates = {0.30, 0.40, 0.45, 0.50, 0.60, 0.70};
  std::vector<std::pair<std::size_t, std::size_t>> score(candidates.size());  // distinct, reads
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t c; (c = next++) < candidates.size();) {
      StageSettings s;
      s.region = base;
      s.region.mode = Binarization::threshold;
      s.region.threshold = candidates[c];
      std::set<std::pair<std::string, std::string>> distinct;
      std::size_t reads = 0;
      for (const auto& f : samples)
        for (const auto& r : read_frame(f, s, decoders, rotate, false, false, 1)) {
          distinct.insert({r.symbol.text, r.symbol.symbology});
          ++reads;
        }
      score[c] = {distinct.size(), reads};
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  std::size_t best = 2;  // 0.45
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const bool better = score[c] > score[best] ||
                        (score[c] == score[best] && std::abs(candidates[c] - 0.45) < std::abs(candidates[best] - 0.45));
    if (better) best = c;
  }
  return candidates[best];
}

nlohmann::json ScanResult::summary() const {
  nlohmann::json codes = nlohmann::json::array();
  for (const auto* e : inventory.entries())
    codes.push_back({{"code", e->code}, {"symbology", e->symbology}, {"reads", e->reads},
                     {"first_frame", e->first_frame}, {"last_frame", e->last_frame}});
  return {{"frames", frames},
          {"keyframes", keyframes},
          {"codes", codes},
          {"distinct_codes", inventory.size()},
          {"reads", inventory.total_reads()},
          {"rotated_reads", rotated_reads},
          {"regions", region_count},
          {"region_threshold", region_threshold},
          {"seconds", seconds},
          {"fps", seconds > 0 ? static_cast<double>(frames) / seconds : 0.0},
          {"cpu_seconds", cpu_seconds},
          {"cpu_ms_per_frame", frames > 0 ? 1000.0 * cpu_seconds / static_cast<double>(frames) : 0.0},
          {"stage_ms", stage_ms}};
}

namespace {

void annotate(const fs::path& file, const cv::Mat& gray, const std::vector<FrameRead>& reads) {
  cv::Mat out;
  cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
  for (const auto& r : reads) {
    cv::rectangle(out, r.crop_box, cv::Scalar(255, 128, 0), 2);
    std::vector<cv::Point> poly;
    for (const auto& c : r.symbol.corners) poly.emplace_back(cvRound(c.x), cvRound(c.y));
    cv::polylines(out, poly, true, cv::Scalar(0, 200, 0), 3);
    cv::putText(out, r.symbol.text + (r.rotated ? " (rotated)" : ""), r.crop_box.tl() + cv::Point(0, -6),
                cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(0, 0, 255), 2);
  }
  cv::imwrite(file.string(), out, {cv::IMWRITE_JPEG_QUALITY, 85});
}

struct HistOut {
  std::vector<float> hist;
  std::string error;
};

struct FrameOut {
  std::size_t frame = 0;
  cv::Mat gray;  // kept only when something was read (crops, annotation)
  std::vector<FrameRead> reads;
  std::size_t regions = 0;
  std::string input_error, failure;
};

}  // namespace

ScanResult scan(const fs::path& video, const ScanOptions& options) {
  const auto t0 = Clock::now();
  const double cpu0 = process_cpu_seconds();
  StageSettings settings = parse_stage_settings(options);
  const bool use_keys = settings.keyframes && !options.decoder_only;
  const bool use_regions = settings.regions && !options.decoder_only;
  // The decoder alone gets zxing's thorough search; the pipeline's whole-frame pass the same
  // without the downscaled pyramid; region crops the quick search (see DecoderSet).
  const auto whole_decoder = make_decoder(options.decoder, ZXingSearch::thorough);
  const auto frame_decoder = make_decoder(options.decoder, ZXingSearch::rotated);
  const auto crop_decoder = make_decoder(options.decoder, ZXingSearch::quick);
  const auto upright_decoder = make_decoder(options.decoder, ZXingSearch::quick, 3);
  const DecoderSet decoders{*whole_decoder, *frame_decoder, *crop_decoder, *upright_decoder};
  StageTimer timer;
  ScanResult result;
  const int threads = std::max(1, options.threads);
  cv::setNumThreads(1);  // our workers are the parallelism; OpenCV's own pool would oversubscribe

  auto write_inventory = [&](const nlohmann::json& extra) {
    if (!options.out.empty()) result.inventory.write(options.out, extra);
  };
  if (!options.out.empty()) {
    std::error_code ec;
    fs::create_directories(options.out, ec);
    if (ec) throw InputError(located(options.out, 0, "cannot create output folder: " + ec.message()));
  }

  auto source = FrameSource::open(video);
  const std::size_t expected = source->expected_frames();

  // Pass 1: histograms of every frame (key frames) and sample frames (automatic threshold).
  std::vector<char> is_key;
  std::vector<EncodedFrame> samples;
  const bool want_samples = use_regions && settings.region_auto;
  const std::size_t n_samples = 8;
  const std::size_t stride = std::max<std::size_t>(1, expected / n_samples);
  auto sample_here = [&](std::size_t i) { return want_samples && i % stride == stride / 2 && samples.size() < n_samples; };
  std::string input_error;
  try {
    if (use_keys) {
      const auto ts = Clock::now();
      std::vector<double> diffs;
      std::vector<float> prev;
      OrderedPool<EncodedFrame, HistOut> pool(threads, static_cast<std::size_t>(threads) * 4, [&](EncodedFrame& f) {
        HistOut h;
        try {
          // A quarter of the size: JPEG decodes it with a reduced inverse DCT. (An eighth costs
          // 0.3 ms less but its coarser histograms kept 93 % of the frames as key frames instead
          // of 85 % on the generated 2000-frame scan, which costs more than it saves.)
          const double th = thread_cpu_ms();
          h.hist = KeyFrameSelector::histogram(decode_gray(f, 4), 1);
          timer.add("histogram", thread_cpu_ms() - th);
        } catch (const InputError& e) {
          h.error = e.what();
        }
        return h;
      });
      auto take = [&](bool wait) {
        HistOut h;
        while (input_error.empty() && pool.pop(h, wait)) {
          if (!h.error.empty()) {
            input_error = h.error;
            break;
          }
          diffs.push_back(prev.empty() ? 0.0 : KeyFrameSelector::difference(prev, h.hist));
          prev = std::move(h.hist);
        }
      };
      Progress progress("key frames", expected);
      try {
        for (EncodedFrame f; input_error.empty() && source->read_encoded(f);) {
          if (sample_here(f.index)) samples.push_back(f);
          pool.push(std::move(f));
          take(false);
          progress.update(diffs.size());
        }
      } catch (const InputError& e) {
        input_error = e.what();
      }
      take(true);
      progress.finish();
      if (!input_error.empty()) throw InputError(input_error);
      result.frames = diffs.size();
      const auto keys = KeyFrameSelector::select(diffs, {settings.k, -1.0});
      is_key.assign(result.frames, 0);
      for (auto k : keys) is_key[k] = 1;
      source->rewind();
      timer.add("keyframe_pass", ms_since(ts));
    } else if (want_samples) {
      EncodedFrame f;
      for (std::size_t i = 0;; ++i) {
        const bool take = sample_here(i);
        if (!(take ? source->read_encoded(f) : source->skip())) break;
        if (take) samples.push_back(f);
      }
      source->rewind();
    }
  } catch (const InputError&) {
    write_inventory({{"error", "input"}});
    throw;
  }
  if (use_regions && settings.region_auto) {
    const auto ts = Clock::now();
    std::vector<cv::Mat> gray;
    for (const auto& f : samples) gray.push_back(decode_gray(f));
    settings.region.threshold = gray.empty() ? 0.45
                                             : calibrate_region_threshold(gray, settings.region, decoders,
                                                                          options.rotate, threads);
    timer.add("calibrate", ms_since(ts));
    spdlog::info("barcodes: region threshold {:.2f} (chosen on {} sample frames)", settings.region.threshold,
                 gray.size());
  }
  samples.clear();
  result.region_threshold = use_regions && settings.region.mode == Binarization::threshold ? settings.region.threshold : 0.0;

  // Pass 2: workers decode and read the frames; results merge into the inventory in frame order.
  if (!options.out.empty() && options.annotate) fs::create_directories(options.out / "keyframes");
  OrderedPool<EncodedFrame, FrameOut> pool(threads, static_cast<std::size_t>(threads) * 2, [&](EncodedFrame& f) {
    FrameOut out;
    out.frame = f.index;
    const double ts = thread_cpu_ms();
    try {
      cv::Mat gray = decode_gray(f);
      timer.add("decode", thread_cpu_ms() - ts);
      const double tp = thread_cpu_ms();
      out.reads = read_frame(gray, settings, decoders, options.rotate, options.decoder_only, options.whole_frame,
                             options.max_symbols_per_frame, &out.regions, &timer);
      timer.add("read_frame", thread_cpu_ms() - tp);
      if (!out.reads.empty()) out.gray = gray;
    } catch (const InputError& e) {
      out.input_error = e.what();
    } catch (const std::exception& e) {
      out.failure = "frame " + std::to_string(f.index) + ": " + e.what();
    }
    timer.add("frame_total", thread_cpu_ms() - ts);
    return out;
  });
  std::string failure;
  std::size_t merged_since_checkpoint = 0, pushed = 0;
  auto merge = [&](bool wait) {
    FrameOut d;
    while (input_error.empty() && failure.empty() && pool.pop(d, wait)) {
      if (!d.input_error.empty() || !d.failure.empty()) {
        // Frames after a bad one are dropped: the inventory holds exactly the frames before it.
        input_error = d.input_error;
        failure = d.failure;
        break;
      }
      result.region_count += d.regions;
      bool new_code = false;
      for (const auto& r : d.reads) {
        if (!result.inventory.contains(r.symbol.text, r.symbol.symbology)) new_code = true;
        if (r.rotated) ++result.rotated_reads;
        result.inventory.add(d.frame, r.symbol.text, r.symbol.symbology, d.gray(r.crop_box));
      }
      if (new_code && options.annotate && !options.out.empty()) {
        char name[64];
        std::snprintf(name, sizeof name, "frame_%06zu.jpg", d.frame);
        const double tw = thread_cpu_ms();
        annotate(options.out / "keyframes" / name, d.gray, d.reads);
        timer.add("write", thread_cpu_ms() - tw);
      }
      if (++merged_since_checkpoint >= options.checkpoint_every && !options.out.empty()) {
        merged_since_checkpoint = 0;
        const double tw = thread_cpu_ms();
        write_inventory({{"partial", true}, {"frames_done", d.frame + 1}});
        timer.add("write", thread_cpu_ms() - tw);
      }
    }
  };
  std::size_t index = 0;
  {
    Progress progress(options.decoder_only ? "decode" : "scan", expected);
    try {
      while (input_error.empty() && failure.empty()) {
        const bool process = !use_keys || (index < is_key.size() && is_key[index]);
        const double ts = thread_cpu_ms();
        if (process) {
          EncodedFrame f;
          if (!source->read_encoded(f)) break;
          pool.push(std::move(f));
          ++pushed;
        } else if (!source->skip()) {
          break;
        }
        timer.add("read", thread_cpu_ms() - ts);
        ++index;
        merge(false);
        progress.update(index);
      }
    } catch (const InputError& e) {
      input_error = e.what();
    }
    pool.close();
    merge(true);
    progress.finish();
  }
  if (!use_keys) result.frames = index;
  result.keyframes = pushed;
  result.seconds = ms_since(t0) / 1000.0;
  result.cpu_seconds = process_cpu_seconds() - cpu0;
  result.stage_ms = timer.summary();
  nlohmann::json extra = result.summary();
  extra.erase("codes");
  if (!input_error.empty() || !failure.empty()) {
    extra["error"] = input_error.empty() ? failure : input_error;
    write_inventory(extra);
    if (!input_error.empty()) throw InputError(input_error);
    throw Failure(failure);
  }
  write_inventory(extra);
  return result;
}

}  // namespace builtscene::barcode
