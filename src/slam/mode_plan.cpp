#include "slam/mode_plan.hpp"

#include <algorithm>
#include <charconv>
#include <limits>

#include <fmt/format.h>

#include "core/errors.hpp"

namespace builtscene::slam {

const char* to_string(Mode m) { return m == Mode::kSlam ? "slam" : "localize"; }

std::optional<Mode> parse_mode(const std::string& text) {
  if (text == "slam") return Mode::kSlam;
  if (text == "localize" || text == "localization") return Mode::kLocalization;
  return std::nullopt;
}

namespace {

bool parse_long(const std::string& s, long& out) {
  if (s.empty()) return false;
  const auto* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && out >= 0;
}

}  // namespace

ModeSchedule ModeSchedule::parse(const std::string& text, const std::string& option) {
  ModeSchedule out;
  auto bad = [&](const std::string& item, const std::string& why) {
    throw InputError(fmt::format("{}: '{}': {} (expected FIRST-LAST:slam|localize, comma separated)", option, item, why));
  };
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    start = comma + 1;
    const auto colon = item.find(':');
    const auto dash = item.find('-');
    if (colon == std::string::npos || dash == std::string::npos || dash > colon) bad(item, "malformed range");
    Range r;
    if (!parse_long(item.substr(0, dash), r.first)) bad(item, "first frame is not a non-negative integer");
    const std::string last = item.substr(dash + 1, colon - dash - 1);
    if (last.empty()) r.last = std::numeric_limits<long>::max();
    else if (!parse_long(last, r.last)) bad(item, "last frame is not a non-negative integer");
    if (r.last < r.first) bad(item, "last frame before first");
    const auto mode = parse_mode(item.substr(colon + 1));
    if (!mode) bad(item, "mode must be slam or localize");
    r.mode = *mode;
    for (const auto& o : out.ranges_)
      if (r.first <= o.last && o.first <= r.last) bad(item, "overlaps another range");
    out.ranges_.push_back(r);
    if (comma == text.size()) break;
  }
  return out;
}

std::optional<Mode> ModeSchedule::mode_at(long frame) const {
  for (const auto& r : ranges_)
    if (frame >= r.first && frame <= r.last) return r.mode;
  return std::nullopt;
}

std::optional<ModePlan::Decision> ModePlan::decide(long frame, const std::optional<SE3>& last_T_wc) const {
  if (const auto m = schedule_.mode_at(frame)) return Decision{*m, "schedule"};
  if (inside_ && last_T_wc) return Decision{inside_(*last_T_wc) ? Mode::kSlam : Mode::kLocalization, "region"};
  return std::nullopt;
}

}  // namespace builtscene::slam
