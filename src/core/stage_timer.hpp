#pragma once
// Per-stage wall-clock timings that feed the `stage_ms` block of every --json summary.
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace builtscene {

// Collects durations per named stage; thread-safe (one mutex, held only to append).
class StageTimer {
 public:
  StageTimer() = default;
  StageTimer(const StageTimer& other);  // copies the samples under the other's lock
  StageTimer& operator=(const StageTimer& other);

  void add(const std::string& stage, double ms);

  // {"stage": {"median": ms, "p95": ms, "mean": ms, "total": ms, "count": n}, ...}
  nlohmann::json summary() const;
  double median_ms(const std::string& stage) const;
  std::size_t count(const std::string& stage) const;

  // Times one scope: `{ auto t = timer.scope("tracking"); ... }`.
  class Scope {
   public:
    Scope(StageTimer& owner, std::string stage);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    StageTimer& owner_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
  };
  Scope scope(std::string stage) { return Scope(*this, std::move(stage)); }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<double>> samples_;
};

// Milliseconds since `start` on the steady clock.
double ms_since(std::chrono::steady_clock::time_point start);

// Quantile q in [0,1] by linear interpolation; 0 for an empty vector. Takes a copy to sort.
double quantile(std::vector<double> values, double q);

}  // namespace builtscene
