#include "couple/lcm_log.hpp"

#include "core/errors.hpp"
#include "core/logging.hpp"

namespace builtscene::couple {
namespace {
constexpr uint32_t kSync = 0xEDA1DA01u;

template <typename T>
void put(std::ofstream& out, T v) {
  auto u = static_cast<std::make_unsigned_t<T>>(v);
  char b[sizeof(T)];
  for (std::size_t i = 0; i < sizeof(T); ++i) b[i] = static_cast<char>(u >> (8 * (sizeof(T) - 1 - i)));
  out.write(b, sizeof(T));
}

template <typename T>
bool get(std::ifstream& in, T& v) {
  unsigned char b[sizeof(T)];
  if (!in.read(reinterpret_cast<char*>(b), sizeof(T))) return false;
  std::make_unsigned_t<T> u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) u = static_cast<std::make_unsigned_t<T>>((u << 8) | b[i]);
  v = static_cast<T>(u);
  return true;
}
}  // namespace

LcmLogWriter::LcmLogWriter(const std::filesystem::path& file) : file_(file), out_(file, std::ios::binary) {
  if (!out_) throw Failure(located(file, 0, "cannot write the log"));
}

void LcmLogWriter::write(int64_t utime, const std::string& channel, const uint8_t* data, std::size_t size) {
  put<uint32_t>(out_, kSync);
  put<int64_t>(out_, next_++);
  put<int64_t>(out_, utime);
  put<int32_t>(out_, static_cast<int32_t>(channel.size()));
  put<int32_t>(out_, static_cast<int32_t>(size));
  out_.write(channel.data(), static_cast<std::streamsize>(channel.size()));
  out_.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out_) throw Failure(located(file_, 0, "write failed (disk full?)"));
}

LcmLogReader::LcmLogReader(const std::filesystem::path& file) : file_(file), in_(file, std::ios::binary) {
  if (!in_) throw InputError(located(file, 0, "cannot read the log"));
}

std::optional<LogEvent> LcmLogReader::next() {
  uint32_t sync = 0;
  if (!get(in_, sync)) return std::nullopt;
  if (sync != kSync) throw InputError(located(file_, 0, "not an LCM log (bad sync word at byte " +
                                                            std::to_string(static_cast<long>(in_.tellg()) - 4) + ")"));
  LogEvent e;
  int32_t clen = 0, dlen = 0;
  if (!get(in_, e.number) || !get(in_, e.utime) || !get(in_, clen) || !get(in_, dlen) || clen < 0 || dlen < 0 ||
      clen > 4096) {
    spdlog::warn("{}: truncated last event ignored", file_.string());
    return std::nullopt;
  }
  e.channel.resize(static_cast<std::size_t>(clen));
  e.data.resize(static_cast<std::size_t>(dlen));
  if (!in_.read(e.channel.data(), clen) || !in_.read(reinterpret_cast<char*>(e.data.data()), dlen)) {
    spdlog::warn("{}: truncated last event ignored", file_.string());
    return std::nullopt;
  }
  return e;
}

}  // namespace builtscene::couple
