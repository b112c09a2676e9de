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

ChannelSteps read_log_channels(const std::filesystem::path& log, const TypeRegistry& types,
                               std::map<std::string, int64_t>* skipped) {
  std::map<uint64_t, std::string> by_fp;
  for (const auto& n : types.names()) by_fp[types.fingerprint(n)] = n;
  LcmLogReader reader(log);
  ChannelSteps out;
  std::map<std::string, int64_t> unnumbered;
  while (auto e = reader.next()) {
    if (is_status_channel(e->channel)) continue;
    auto it = by_fp.find(peek_fingerprint(e->data.data(), e->data.size()));
    if (it == by_fp.end()) {
      if (skipped) ++(*skipped)[e->channel];
      continue;
    }
    json v = LcmCodec(types, it->second).decode(e->data);
    // Messages without a step are kept in arrival order.
    const int64_t step = v.contains(kStepField) ? v[kStepField].get<int64_t>() : unnumbered[e->channel]++;
    out[e->channel].emplace(step, std::move(v));
  }
  return out;
}

std::vector<double> member_series(const std::map<int64_t, json>& steps, const std::string& member) {
  std::vector<double> out;
  for (const auto& [n, v] : steps)
    if (n >= 0 && v.contains(member) && v[member].is_number()) out.push_back(v[member].get<double>());
  return out;
}

ExportSummary export_log_csv(const std::filesystem::path& log, const TypeRegistry& types,
                             const std::filesystem::path& out_dir) {
  ExportSummary summary;
  const ChannelSteps channels = read_log_channels(log, types, &summary.skipped);
  std::filesystem::create_directories(out_dir);
  for (const auto& [ch, steps] : channels) {
    std::vector<json> rows;
    for (const auto& [n, v] : steps) rows.push_back(v);
    write_csv(out_dir / (ch + ".csv"), rows);
    summary.rows[ch] = static_cast<int64_t>(rows.size());
  }
  return summary;
}

}  // namespace builtscene::couple
