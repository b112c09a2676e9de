#include "demo_registry.hpp"

#include <algorithm>

namespace builtscene::app {
namespace {
std::vector<DemoPart>& parts() {
  static std::vector<DemoPart> list;
  return list;
}
}  // namespace

bool register_demo_part(DemoPart part) {
  parts().push_back(std::move(part));
  std::stable_sort(parts().begin(), parts().end(),
                   [](const DemoPart& a, const DemoPart& b) { return a.order < b.order; });
  return true;
}

const std::vector<DemoPart>& demo_parts() { return parts(); }

}  // namespace builtscene::app
