#pragma once
// Helpers for the coupling tests: temporary folders with files, running commands.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "../common/scratch_dir.hpp"
#include "../common/shell_quote.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/model_config.hpp"

namespace couple_test {

// Removed when the test process exits.
inline std::filesystem::path temp_dir(const std::string& name) { return builtscene::testing::scratch_dir("couple_" + name); }

inline void write(const std::filesystem::path& p, const std::string& text) {
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

struct RunResult {
  int code = -1;
  std::string out;  // stdout and stderr
};

inline RunResult run(const std::string& cmd) {
  RunResult r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

inline const std::string kExample = std::string(BUILTSCENE_SOURCE_DIR) + "/examples/coupling/wind-structure-control";

// Every data message of a recorded log, decoded: channel -> step -> members.
inline std::map<std::string, std::map<int64_t, nlohmann::json>> read_log(const std::filesystem::path& log,
                                                                        const builtscene::couple::ScenarioConfig& sc) {
  using namespace builtscene::couple;
  std::map<std::string, std::string> type;
  for (const auto& m : sc.models)
    for (const auto& p : m.publish) type[p.channel] = p.type;
  std::map<std::string, std::map<int64_t, nlohmann::json>> out;
  LcmLogReader r(log);
  while (auto e = r.next()) {
    auto it = type.find(e->channel);
    if (it == type.end()) continue;
    nlohmann::json v = LcmCodec(sc.types, it->second).decode(e->data);
    out[e->channel].emplace(v["step"].get<int64_t>(), v);
  }
  return out;
}

// Runs `script` (sh) in a private network namespace whose loopback carries the multicast
// route LCM udpm needs; nullopt (and the reason in `why`) where namespaces are not permitted.
inline std::optional<RunResult> in_udpm_namespace(const std::string& script, std::string* why) {
  static const RunResult probe =
      run("unshare -n sh -c 'ip link set lo up && ip route add 224.0.0.0/4 dev lo && echo ok'");
  if (probe.code != 0 || probe.out.find("ok") == std::string::npos) {
    *why = "udpm tests run in a private network namespace with a loopback multicast route; "
           "creating one failed (needs root and unshare/ip from util-linux/iproute2): " + probe.out;
    return std::nullopt;
  }
  const auto dir = temp_dir("script");
  write(dir / "run.sh", "set -e\nip link set lo up\nip route add 224.0.0.0/4 dev lo\n" + script);
  return run("unshare -n sh " + builtscene::testing::shell_quote(dir / "run.sh"));
}

#define UDPM_OR_SKIP(result, script)                           \
  std::string why;                                             \
  auto result = couple_test::in_udpm_namespace(script, &why);  \
  if (!result) GTEST_SKIP() << why;

// Processes whose command line mentions `dir` (the pattern does not match pgrep's own shell).
inline std::string left_over(const std::filesystem::path& dir) {
  const std::string s = dir.string();
  return run("pgrep -af " + builtscene::testing::shell_quote("[" + s.substr(0, 1) + "]" + s.substr(1))).out;
}

}  // namespace couple_test
