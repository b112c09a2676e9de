#include "couple/status.hpp"

#include "couple/lcm_codec.hpp"

#include <chrono>
#include <limits>

namespace builtscene::couple {

namespace {
const char* kStatusLcm = R"(package builtscene;
struct status_t {
  int64_t step;
  int64_t steps;
  int64_t utime;
  string model;
  int8_t state;
  int32_t nwait;
  string wait_channel[nwait];
  int64_t wait_step[nwait];
  int32_t nneed;
  string need_channel[nneed];
  int64_t need_step[nneed];
  string error;
  double granted;
  int32_t nevent;
  string event_channel[nevent];
  int64_t event_count[nevent];
}
)";
}

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string status_channel(const std::string& model) {
  return model == kRecorderName ? std::string(kStatusChannel) : std::string(kStatusChannel) + "." + model;
}

bool is_status_channel(const std::string& channel) {
  const std::size_t n = std::char_traits<char>::length(kStatusChannel);
  return channel.compare(0, n, kStatusChannel) == 0 && (channel.size() == n || channel[n] == '.');
}

const char* state_name(ModelState s) {
  switch (s) {
    case ModelState::kRunning: return "running";
    case ModelState::kWaiting: return "waiting";
    case ModelState::kDone: return "done";
    case ModelState::kFailed: return "failed";
    case ModelState::kStopped: return "stopped";
  }
  return "?";
}

void add_builtin_types(TypeRegistry& types) {
  if (!types.find(kStatusType)) types.parse_text(kStatusLcm, "<builtin builtscene.status_t>");
}

std::vector<uint8_t> encode_status(const TypeRegistry& types, const ModelStatus& s) {
  nlohmann::json v = {{"step", s.step}, {"steps", s.steps}, {"utime", s.utime}, {"model", s.model},
                      {"state", static_cast<int>(s.state)}, {"error", s.error},
                      {"granted", s.granted}};
  v["wait_channel"] = nlohmann::json::array();
  v["wait_step"] = nlohmann::json::array();
  for (const auto& [c, n] : s.waiting) {
    v["wait_channel"].push_back(c);
    v["wait_step"].push_back(n);
  }
  v["event_channel"] = nlohmann::json::array();
  v["event_count"] = nlohmann::json::array();
  for (const auto& [c, n] : s.events) {
    v["event_channel"].push_back(c);
    v["event_count"].push_back(n);
  }
  v["need_channel"] = nlohmann::json::array();
  v["need_step"] = nlohmann::json::array();
  for (const auto& [c, n] : s.needs) {
    v["need_channel"].push_back(c);
    v["need_step"].push_back(n);
  }
  return LcmCodec(types, kStatusType).encode(v);
}

ModelStatus decode_status(const TypeRegistry& types, const uint8_t* data, std::size_t size) {
  const auto v = LcmCodec(types, kStatusType).decode(data, size);
  ModelStatus s;
  s.model = v["model"];
  s.step = v["step"];
  s.steps = v["steps"];
  s.utime = v["utime"];
  s.state = static_cast<ModelState>(v["state"].get<int>());
  s.error = v["error"];
  s.granted = v["granted"].is_number() ? v["granted"].get<double>() : std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < v["wait_channel"].size(); ++i) s.waiting.emplace_back(v["wait_channel"][i], v["wait_step"][i]);
  for (std::size_t i = 0; i < v["event_channel"].size(); ++i) s.events.emplace_back(v["event_channel"][i], v["event_count"][i]);
  for (std::size_t i = 0; i < v["need_channel"].size(); ++i) s.needs.emplace_back(v["need_channel"][i], v["need_step"][i]);
  return s;
}

}  // namespace builtscene::couple
