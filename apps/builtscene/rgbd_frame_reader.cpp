#include "rgbd_frame_reader.hpp"

#include "core/errors.hpp"
#include "core/logging.hpp"

namespace builtscene::app {

std::optional<RgbdInputFrame> RgbdFrameReader::next() {
  while (next_ < count_) {
    const std::size_t i = next_++;
    const auto& e = data_.entry(i);
    if (!(e.timestamp > last_timestamp_)) {
      ++out_of_order_;
      spdlog::warn("frame {}: timestamp {:.6f} not after {:.6f}; skipped", i, e.timestamp, last_timestamp_);
      continue;
    }
    RgbdInputFrame f{i, e.timestamp, {}, {}};
    try {
      f.rgb = data_.load_rgb(i);
    } catch (const InputError& err) {
      ++unreadable_rgb_;
      spdlog::warn("frame {}: {}; skipped", i, err.what());
      continue;
    }
    try {
      f.depth = data_.load_depth(i);
    } catch (const InputError& err) {
      ++bad_depth_;
      spdlog::warn("frame {}: {}; tracked without depth", i, err.what());
    }
    last_timestamp_ = e.timestamp;
    ++delivered_;
    return f;
  }
  return std::nullopt;
}

nlohmann::json RgbdFrameReader::bad_input() const {
  return {{"unreadable_rgb", unreadable_rgb_}, {"bad_depth", bad_depth_}, {"timestamp_out_of_order", out_of_order_}};
}

}  // namespace builtscene::app
