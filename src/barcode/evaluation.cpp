#include "barcode/evaluation.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "core/errors.hpp"

namespace builtscene::barcode {

std::vector<TruthLabel> read_truth(const std::filesystem::path& file) {
  std::ifstream f(file);
  if (!f) throw InputError(located(file, 0, "cannot open truth file"));
  std::string line;
  if (!std::getline(f, line)) throw InputError(located(file, 0, "empty file, expected a header row"));
  const auto header = split_csv_line(line);
  auto find = [&](const std::string& name) -> int {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  const int c_text = find("text"), c_sym = find("symbology"), c_kind = find("kind"), c_leg = find("legible_count");
  if (c_text < 0) throw InputError(located(file, 1, "missing column 'text'"));
  if (c_sym < 0) throw InputError(located(file, 1, "missing column 'symbology'"));
  std::vector<TruthLabel> truth;
  std::size_t lineno = 1;
  while (std::getline(f, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    const auto v = split_csv_line(line);
    if (v.size() < header.size()) throw InputError(located(file, lineno, "too few fields"));
    TruthLabel t;
    t.text = v[static_cast<std::size_t>(c_text)];
    t.symbology = v[static_cast<std::size_t>(c_sym)];
    if (c_kind >= 0) t.kind = v[static_cast<std::size_t>(c_kind)];
    t.legible_count = 1;
    if (c_leg >= 0) {
      try {
        t.legible_count = std::stoul(v[static_cast<std::size_t>(c_leg)]);
      } catch (const std::exception&) {
        throw InputError(located(file, lineno, "field 'legible_count' is not a number"));
      }
    }
    truth.push_back(t);
  }
  if (truth.empty()) throw InputError(located(file, 0, "no labels in the truth file"));
  return truth;
}

Evaluation evaluate(const std::vector<TruthLabel>& truth, const Inventory& inventory) {
  Evaluation e;
  std::set<std::pair<std::string, std::string>> known;
  for (const auto& t : truth) known.insert({t.text, t.symbology});
  for (const auto& t : truth) {
    ++e.labels;
    const bool read = inventory.contains(t.text, t.symbology);
    if (t.kind == "location") {
      ++e.location_labels;
      if (read) ++e.location_recognized;
    }
    if (t.legible_count == 0) continue;
    ++e.legible_labels;
    if (read) {
      ++e.recognized;
    } else {
      e.missed.push_back(t.text);
    }
  }
  for (const auto* entry : inventory.entries()) {
    if (known.count({entry->code, entry->symbology})) {
      e.reads += entry->reads;
    } else {
      ++e.false_codes;
      e.false_code_texts.push_back(entry->symbology + ":" + entry->code);
    }
  }
  e.recognition_rate = e.legible_labels ? static_cast<double>(e.recognized) / static_cast<double>(e.legible_labels) : 0.0;
  e.location_recognition_rate =
      e.location_labels ? static_cast<double>(e.location_recognized) / static_cast<double>(e.location_labels) : 0.0;
  return e;
}

nlohmann::json Evaluation::to_json() const {
  return {{"labels", labels},
          {"legible_labels", legible_labels},
          {"recognized", recognized},
          {"recognition_rate", recognition_rate},
          {"location_labels", location_labels},
          {"location_recognized", location_recognized},
          {"location_recognition_rate", location_recognition_rate},
          {"reads", reads},
          {"false_codes", false_codes},
          {"false_code_texts", false_code_texts},
          {"missed", missed}};
}

std::vector<SweepColumn> sweep_columns(const ScanOptions& base) {
  std::vector<SweepColumn> cols;
  ScanOptions o = base;
  o.out.clear();
  o.annotate = false;
  o.decoder_only = true;
  cols.push_back({"decoder_only", o});
  o.decoder_only = false;
  o.keyframes = "off";
  o.rotate = false;
  o.whole_frame = false;  // regions alone, as in the source's reg_dec columns
  for (const char* t : {"0.3", "0.4", "0.45", "0.5", "0.6", "0.7"}) {
    o.region = t;
    cols.push_back({std::string("reg(") + t + ")", o});
  }
  o.region = "auto";
  cols.push_back({"reg(auto)", o});
  o.rotate = true;
  cols.push_back({"reg(auto)+rot", o});
  o.whole_frame = true;
  cols.push_back({"whole+reg+rot", o});
  for (const char* k : {"0.5", "0.6", "0.7", "0.8", "0.9", "1.0"}) {
    o.keyframes = k;
    cols.push_back({std::string("key(") + k + ")", o});
  }
  return cols;
}

SweepResult run_sweep(const std::filesystem::path& video, const std::vector<TruthLabel>& truth, const ScanOptions& base) {
  SweepResult r;
  r.columns = sweep_columns(base);
  for (const auto& c : r.columns) {
    r.scans.push_back(scan(video, c.options));
    r.evaluations.push_back(evaluate(truth, r.scans.back().inventory));
  }
  return r;
}

std::string SweepResult::table(const std::vector<TruthLabel>& truth) const {
  std::ostringstream out;
  // Three tables as in the source: regions (4.12), rotation (4.13), key frames (4.14).
  const std::vector<std::vector<std::size_t>> groups = {{0, 1, 2, 3, 4, 5, 6, 7}, {0, 7, 8, 9}, {9, 10, 11, 12, 13, 14, 15}};
  const char* titles[] = {"Regions (cf. Figure 4.12)", "Rotation (cf. Figure 4.13)", "Key frames with whole frame + regions + rotation (cf. Figure 4.14)"};
  for (std::size_t g = 0; g < groups.size(); ++g) {
    out << "\n" << titles[g] << "\n";
    out << fmt::format("{:<18}", "");
    for (auto c : groups[g])
      if (c < columns.size()) out << fmt::format("{:>18}", columns[c].name);
    out << "\n";
    auto row = [&](const std::string& name, auto value) {
      out << fmt::format("{:<18}", name);
      for (auto c : groups[g])
        if (c < columns.size()) out << fmt::format("{:>18}", value(c));
      out << "\n";
    };
    row("frames processed", [&](std::size_t c) { return std::to_string(scans[c].keyframes); });
    for (const auto& t : truth) {
      if (t.kind != "location") continue;
      row(t.text, [&](std::size_t c) {
        for (const auto* e : scans[c].inventory.entries())
          if (e->code == t.text && e->symbology == t.symbology) return std::to_string(e->reads);
        return std::string("0");
      });
    }
    row("successful reads", [&](std::size_t c) { return std::to_string(evaluations[c].reads); });
    row("location rate", [&](std::size_t c) { return fmt::format("{:.1f}%", 100 * evaluations[c].location_recognition_rate); });
    row("recognition rate", [&](std::size_t c) { return fmt::format("{:.1f}%", 100 * evaluations[c].recognition_rate); });
    row("false codes", [&](std::size_t c) { return std::to_string(evaluations[c].false_codes); });
    row("time (s)", [&](std::size_t c) { return fmt::format("{:.2f}", scans[c].seconds); });
  }
  return out.str();
}

nlohmann::json SweepResult::to_json() const {
  nlohmann::json cols = nlohmann::json::array();
  for (std::size_t c = 0; c < columns.size(); ++c) {
    nlohmann::json j = evaluations[c].to_json();
    j["name"] = columns[c].name;
    j["frames"] = scans[c].frames;
    j["keyframes"] = scans[c].keyframes;
    j["seconds"] = scans[c].seconds;
    j["region_threshold"] = scans[c].region_threshold;
    cols.push_back(j);
  }
  return {{"columns", cols}};
}

}  // namespace builtscene::barcode
