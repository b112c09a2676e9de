#pragma once
// Tables from coupling runs: one CSV per channel (a header row of flattened member names,
// `a.b`, `v[2]`; one row per producer step, re-published duplicates dropped).
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "couple/lcm_types.hpp"

namespace builtscene::couple {

struct ExportSummary {
  std::map<std::string, int64_t> rows;  // per channel
  std::map<std::string, int64_t> skipped;  // channel -> messages of an unknown type
};

// Decodes every message of an LCM log by its fingerprint against `types`.
ExportSummary export_log_csv(const std::filesystem::path& log, const TypeRegistry& types,
                             const std::filesystem::path& out_dir);

// channel -> producer step -> decoded message (the first of re-published duplicates);
// messages of types not in `types` (and the status channel) are counted in `skipped`.
using ChannelSteps = std::map<std::string, std::map<int64_t, nlohmann::json>>;
ChannelSteps read_log_channels(const std::filesystem::path& log, const TypeRegistry& types,
                               std::map<std::string, int64_t>* skipped = nullptr);

// One numeric member of a channel, in step order (steps >= 0).
std::vector<double> member_series(const std::map<int64_t, nlohmann::json>& steps, const std::string& member);

// Flattens a decoded message into (column, value) pairs in member order.
void flatten(const nlohmann::json& v, const std::string& prefix, std::vector<std::pair<std::string, nlohmann::json>>& out);

// Writes rows (decoded messages, already ordered) of one channel.
void write_csv(const std::filesystem::path& file, const std::vector<nlohmann::json>& rows);

}  // namespace builtscene::couple
