// `builtscene demo --out DIR`: every registered pillar part on generated data, one report.
#include <chrono>
#include <fstream>
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/stage_timer.hpp"
#include "demo_registry.hpp"

namespace builtscene::app {
namespace {

struct DemoOptions {
  std::filesystem::path out = "demo-out";
  std::vector<std::string> only;
};

std::string html_escape(const std::string& s) {
  std::string r;
  for (char c : s) {
    switch (c) {
      case '<': r += "&lt;"; break;
      case '>': r += "&gt;"; break;
      case '&': r += "&amp;"; break;
      case '"': r += "&quot;"; break;
      default: r += c;
    }
  }
  return r;
}

nlohmann::json run_demo(const DemoOptions& opt) {
  std::error_code ec;
  std::filesystem::create_directories(opt.out, ec);
  if (ec) throw InputError(located(opt.out, 0, "cannot create output folder: " + ec.message()));

  nlohmann::json summary = {{"parts", nlohmann::json::object()}};
  std::string body;
  bool all_ok = true;
  StageTimer timer;
  for (const auto& part : demo_parts()) {
    if (!opt.only.empty() && std::find(opt.only.begin(), opt.only.end(), part.name) == opt.only.end()) continue;
    spdlog::info("demo: {}", part.name);
    const auto start = std::chrono::steady_clock::now();
    const auto dir = opt.out / part.name;
    std::filesystem::create_directories(dir);
    try {
      DemoSection s = part.run(dir);
      s.summary["seconds"] = ms_since(start) / 1000.0;
      summary["parts"][part.name] = s.summary;
      body += "<section id=\"" + part.name + "\"><h2>" + html_escape(s.title) + "</h2>\n" + s.html + "\n</section>\n";
    } catch (const std::exception& e) {
      all_ok = false;
      spdlog::error("demo part {} failed: {}", part.name, e.what());
      summary["parts"][part.name] = {{"error", e.what()}};
      body += "<section id=\"" + part.name + "\"><h2>" + html_escape(part.name) + "</h2><p class=\"error\">Failed: " +
              html_escape(e.what()) + "</p></section>\n";
    }
    timer.add(part.name, ms_since(start));
  }
  summary["stage_ms"] = timer.summary();
  summary["ok"] = all_ok;

  std::ofstream(opt.out / "summary.json") << summary.dump(2) << "\n";
  std::ofstream html(opt.out / "index.html");
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>builtscene demo</title>"
          "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;line-height:1.4}"
          "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}"
          "img{max-width:100%;border:1px solid #ddd}.error{color:#b00}code{background:#f4f4f4}</style>"
          "</head><body><h1>builtscene demo</h1>"
          "<p>Every number below was measured in this run on generated data with known ground truth. "
          "Machine-readable: <a href=\"summary.json\">summary.json</a>.</p>\n"
       << body << "</body></html>\n";
  if (!html) throw Failure(located(opt.out / "index.html", 0, "cannot write report"));
  spdlog::info("demo: report written to {}", (opt.out / "index.html").string());
  if (!all_ok) throw Failure("demo: some parts failed, see " + (opt.out / "index.html").string());
  return summary;
}

const bool registered_demo = register_command({
    .path = {"demo"},
    .description = "Run every pillar on generated data and write a report (DIR/index.html)",
    .setup = [](CLI::App& cmd) -> Action {
      auto opt = std::make_shared<DemoOptions>();
      cmd.add_option("--out", opt->out, "Output folder")->capture_default_str();
      cmd.add_option("--only", opt->only, "Run only these parts (by name)");
      return [opt] { return run_demo(*opt); };
    },
    .order = 1});

}  // namespace
}  // namespace builtscene::app
