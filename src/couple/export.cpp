#include "couple/export.hpp"

#include <fstream>
#include <set>

#include "core/errors.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/model_config.hpp"
#include "couple/status.hpp"

namespace builtscene::couple {

using nlohmann::json;

void flatten(const json& v, const std::string& prefix, std::vector<std::pair<std::string, json>>& out) {
  if (v.is_object()) {
    // nlohmann sorts object keys; "step" first keeps rows readable, then the rest.
    if (v.contains(kStepField) && prefix.empty()) out.emplace_back(kStepField, v[kStepField]);
    for (const auto& [k, x] : v.items()) {
      if (prefix.empty() && k == kStepField) continue;
      flatten(x, prefix.empty() ? k : prefix + "." + k, out);
    }
  } else if (v.is_array()) {
    for (std::size_t i = 0; i < v.size(); ++i) flatten(v[i], prefix + "[" + std::to_string(i) + "]", out);
  } else {
    out.emplace_back(prefix, v);
  }
}

namespace {
std::string cell(const json& v) {
  if (v.is_string()) {
    std::string s = "\"";
    for (char c : v.get<std::string>()) s += c == '"' ? std::string("\"\"") : std::string(1, c);
    return s + "\"";
  }
  if (v.is_number_float()) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v.get<double>());
    return buf;
  }
  if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
  return v.dump();
}
}  // namespace

void write_csv(const std::filesystem::path& file, const std::vector<json>& rows) {
  std::ofstream out(file);
  if (!out) throw Failure(located(file, 0, "cannot write"));
  std::vector<std::string> header;
  for (const auto& r : rows) {
    std::vector<std::pair<std::string, json>> cells;
    flatten(r, "", cells);
    if (header.empty()) {
      for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i].first;
      out << "\n";
      for (const auto& c : cells) header.push_back(c.first);
    }
    // Variable-length arrays can change the column set; such rows keep the first header's width.
    for (std::size_t i = 0; i < header.size(); ++i) out << (i ? "," : "") << (i < cells.size() ? cell(cells[i].second) : "");
    out << "\n";
  }
  if (!out) throw Failure(located(file, 0, "write failed"));
}

ExportSummary export_log_csv(const std::filesystem::path& log, const TypeRegistry& types,
                             const std::filesystem::path& out_dir) {
  std::map<uint64_t, std::string> by_fp;
  for (const auto& n : types.names()) by_fp[types.fingerprint(n)] = n;
  LcmLogReader reader(log);
  std::map<std::string, std::vector<json>> rows;
  std::map<std::string, std::set<int64_t>> seen;
  ExportSummary summary;
  while (auto e = reader.next()) {
    if (e->channel == kStatusChannel) continue;
    auto it = by_fp.find(peek_fingerprint(e->data.data(), e->data.size()));
    if (it == by_fp.end()) {
      ++summary.skipped[e->channel];
      continue;
    }
    json v = LcmCodec(types, it->second).decode(e->data);
    if (v.contains(kStepField) && !seen[e->channel].insert(v[kStepField].get<int64_t>()).second) continue;
    rows[e->channel].push_back(std::move(v));
  }
  std::filesystem::create_directories(out_dir);
  for (auto& [ch, r] : rows) {
    std::stable_sort(r.begin(), r.end(), [](const json& a, const json& b) {
      return a.value(kStepField, int64_t{0}) < b.value(kStepField, int64_t{0});
    });
    write_csv(out_dir / (ch + ".csv"), r);
    summary.rows[ch] = static_cast<int64_t>(r.size());
  }
  return summary;
}

}  // namespace builtscene::couple
