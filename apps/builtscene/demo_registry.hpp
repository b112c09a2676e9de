#pragma once
// Each pillar adds its part to `builtscene demo` from its own file (demo_<pillar>.cpp):
//
//   static const bool registered = builtscene::app::register_demo_part({
//       .name = "barcodes", .order = 30,
//       .run = [](const std::filesystem::path& dir) { ...; return DemoSection{...}; }});
//
// Parts run in `order`; each gets its own folder DIR/<name>/ for files and returns an HTML
// fragment (paths relative to DIR) and a JSON summary that lands in DIR/summary.json.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace builtscene::app {

struct DemoSection {
  std::string title;
  std::string html;          // fragment placed in index.html under the title
  nlohmann::json summary;    // this part's numbers
};

struct DemoPart {
  std::string name;
  int order = 100;
  std::function<DemoSection(const std::filesystem::path& part_dir)> run;
};

bool register_demo_part(DemoPart part);
const std::vector<DemoPart>& demo_parts();

}  // namespace builtscene::app
