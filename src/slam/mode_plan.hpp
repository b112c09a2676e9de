#pragma once
// SLAM mode versus localization mode, and when to be in which: a schedule by frame ranges
// ("0-199:slam,200-399:localize") and a rule by region (SLAM mode while the camera is inside
// an area of the ground plane, localization outside; the source's location-aware map update,
// section 2.6.3). The region test itself is a predicate on the camera pose so this module
// does not depend on the map geometry code; the CLI builds it from nav's Region and ogm's
// GroundFrame.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/se3.hpp"

namespace builtscene::slam {

enum class Mode { kSlam, kLocalization };
const char* to_string(Mode m);
// "slam" or "localize"/"localization"; nullopt otherwise.
std::optional<Mode> parse_mode(const std::string& text);

struct ModeSwitch {
  long frame = 0;         // index of the first frame tracked in the new mode
  double timestamp = 0;   // of the last frame before the switch (0 before any frame)
  Mode from = Mode::kSlam, to = Mode::kSlam;
  std::string reason;     // "api", "schedule", "region", ...
};

// Frame ranges with a mode each; frames outside every range keep whatever mode is current.
class ModeSchedule {
 public:
  // "FIRST-LAST:MODE[,FIRST-LAST:MODE...]" (LAST may be empty for "to the end"); throws
  // InputError naming `option` on a malformed or overlapping list.
  static ModeSchedule parse(const std::string& text, const std::string& option = "--mode-schedule");
  std::optional<Mode> mode_at(long frame) const;
  bool empty() const { return ranges_.empty(); }

 private:
  struct Range {
    long first = 0, last = 0;
    Mode mode = Mode::kSlam;
  };
  std::vector<Range> ranges_;
};

// Decides the mode of the next frame: the schedule wins where it has a range; otherwise the
// region rule, judged at the last tracked camera pose (camera to world); otherwise no change.
class ModePlan {
 public:
  using InsideRegion = std::function<bool(const SE3& T_wc)>;
  void set_schedule(ModeSchedule schedule) { schedule_ = std::move(schedule); }
  void set_region(InsideRegion inside) { inside_ = std::move(inside); }
  bool empty() const { return schedule_.empty() && !inside_; }

  struct Decision {
    Mode mode;
    const char* reason;
  };
  std::optional<Decision> decide(long frame, const std::optional<SE3>& last_T_wc) const;

 private:
  ModeSchedule schedule_;
  InsideRegion inside_;
};

}  // namespace builtscene::slam
