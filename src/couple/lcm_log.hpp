#pragma once
// LCM log files (the format lcm-logger writes and lcm-logplayer replays): per event a
// sync word 0xEDA1DA01, event number, timestamp (microseconds), channel length, data
// length, channel, data; all integers big-endian.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace builtscene::couple {

struct LogEvent {
  int64_t number = 0;
  int64_t utime = 0;
  std::string channel;
  std::vector<uint8_t> data;
};

class LcmLogWriter {
 public:
  explicit LcmLogWriter(const std::filesystem::path& file);  // throws Failure
  void write(int64_t utime, const std::string& channel, const uint8_t* data, std::size_t size);
  void flush() { out_.flush(); }
  int64_t events() const { return next_; }

 private:
  std::filesystem::path file_;
  std::ofstream out_;
  int64_t next_ = 0;
};

class LcmLogReader {
 public:
  explicit LcmLogReader(const std::filesystem::path& file);  // throws InputError
  // The next event; nullopt at the end. A truncated last event (a run killed mid-write)
  // ends the log with a warning; garbage elsewhere throws InputError.
  std::optional<LogEvent> next();

 private:
  std::filesystem::path file_;
  std::ifstream in_;
};

}  // namespace builtscene::couple
