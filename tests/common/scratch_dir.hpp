#pragma once
// A test's own folder under the system's temporary folder (TMPDIR): `bs_<name>_<pid>`, emptied
// and made when asked for and removed when the test process exits (normally or through a
// failed check; not after a crash). Generated worlds are hundreds of megabytes: folders left
// behind by every run filled the disk. BUILTSCENE_KEEP_TEST_FILES=1 keeps them for a look.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

namespace builtscene::testing {

namespace detail {
class ScratchRegistry {
 public:
  void add(const std::filesystem::path& p) {
    std::lock_guard lock(mutex_);
    dirs_.push_back(p);
  }
  ~ScratchRegistry() {
    if (std::getenv("BUILTSCENE_KEEP_TEST_FILES")) return;
    std::error_code ec;  // a folder already gone, or still busy, is no reason to fail
    for (const auto& d : dirs_) std::filesystem::remove_all(d, ec);
  }

 private:
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};
inline ScratchRegistry& scratch_registry() {
  static ScratchRegistry r;
  return r;
}
}  // namespace detail

inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("bs_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  detail::scratch_registry().add(d);
  return d;
}

}  // namespace builtscene::testing
