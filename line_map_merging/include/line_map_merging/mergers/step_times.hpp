// Opt-in timers for the named steps of a merger, to see where its time goes (benchmarks, linemap_batch
// --time-steps). Off by default: a disabled scope costs one branch, so the timed path stays the same.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace line_map_merging
{
/// One named step and the time spent in it [ms].
using StepTime = std::pair<std::string, double>;

template <std::size_t N>
class StepTimes
{
 public:
  using Clock = std::chrono::steady_clock;

  explicit StepTimes(const std::array<const char*, N>& names) : names_(names) {}

  void enable(bool on) { enabled_ = on; }
  bool enabled() const { return enabled_; }
  void clear() { ns_.fill(0); }

  /// Adds the time from its construction to its destruction to `step`, when enabled.
  class Scope
  {
   public:
    Scope(StepTimes& times, std::size_t step) : times_(times.enabled_ ? &times : nullptr), step_(step)
    {
      if (times_) start_ = Clock::now();
    }
    ~Scope()
    {
      if (times_)
        times_->ns_[step_] +=
            std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start_).count();
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    StepTimes* times_;
    std::size_t step_;
    Clock::time_point start_;
  };

  /// Every step with its total [ms], in the order of the names.
  std::vector<StepTime> totals() const
  {
    std::vector<StepTime> out;
    for (std::size_t i = 0; i < N; ++i) out.emplace_back(names_[i], 1e-6 * static_cast<double>(ns_[i]));
    return out;
  }

 private:
  std::array<const char*, N> names_;
  std::array<long long, N> ns_{};
  bool enabled_ = false;
};

}  // namespace line_map_merging
