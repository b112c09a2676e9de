#pragma once
// A progress bar on stderr, drawn only when stderr is a terminal (never in pipes, logs or CI).
#include <chrono>
#include <cstddef>
#include <string>

namespace builtscene {

class Progress {
 public:
  Progress(std::string label, std::size_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(std::size_t done);  // redraws at most ~10 times a second
  void finish();

 private:
  std::string label_;
  std::size_t total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_draw_{};
  void draw(std::size_t done);
};

}  // namespace builtscene
