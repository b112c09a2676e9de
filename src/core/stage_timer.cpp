#include "core/stage_timer.hpp"

#include <algorithm>
#include <numeric>

namespace builtscene {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return values[lo] * (1.0 - frac) + values[hi] * frac;
}

StageTimer::StageTimer(const StageTimer& other) {
  std::lock_guard lock(other.mutex_);
  samples_ = other.samples_;
}

StageTimer& StageTimer::operator=(const StageTimer& other) {
  if (this == &other) return *this;
  std::map<std::string, std::vector<double>> copy;
  {
    std::lock_guard lock(other.mutex_);
    copy = other.samples_;
  }
  std::lock_guard lock(mutex_);
  samples_ = std::move(copy);
  return *this;
}

void StageTimer::add(const std::string& stage, double ms) {
  std::lock_guard lock(mutex_);
  samples_[stage].push_back(ms);
}

nlohmann::json StageTimer::summary() const {
  std::lock_guard lock(mutex_);
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [stage, v] : samples_) {
    const double total = std::accumulate(v.begin(), v.end(), 0.0);
    out[stage] = {{"median", quantile(v, 0.5)},
                  {"p95", quantile(v, 0.95)},
                  {"mean", v.empty() ? 0.0 : total / static_cast<double>(v.size())},
                  {"total", total},
                  {"count", v.size()}};
  }
  return out;
}

double StageTimer::median_ms(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  auto it = samples_.find(stage);
  return it == samples_.end() ? 0.0 : quantile(it->second, 0.5);
}

std::size_t StageTimer::count(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  auto it = samples_.find(stage);
  return it == samples_.end() ? 0 : it->second.size();
}

StageTimer::Scope::Scope(StageTimer& owner, std::string stage)
    : owner_(owner), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}

StageTimer::Scope::~Scope() { owner_.add(stage_, ms_since(start_)); }

}  // namespace builtscene
