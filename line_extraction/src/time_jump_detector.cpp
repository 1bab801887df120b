#include "linemap/time_jump_detector.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace linemap
{
TimeJumpDetector::TimeJumpDetector(double tolerance, std::vector<std::string> streams)
    : tolerance_(tolerance), streams_(std::move(streams)), last_stamps_(streams_.size(), 0.0)
{
  if (streams_.empty()) throw std::invalid_argument("TimeJumpDetector: no stream to watch");
}

bool TimeJumpDetector::observe(double clock, double stamp, std::size_t stream)
{
  double& last = last_stamps_.at(stream);
  // Written so that NaN readings compare false and count as unknown.
  const bool clock_known = clock > 0.0, stamp_known = stamp > 0.0;
  const bool clock_back = last_clock_ > 0.0 && clock_known && last_clock_ - clock > tolerance_;
  const bool stamp_back = last > 0.0 && stamp_known && last - stamp > tolerance_;
  if (clock_back || stamp_back)
  {
    char text[160];
    if (clock_back)
      std::snprintf(text, sizeof text, "the clock went back from %.3f to %.3f s", last_clock_, clock);
    else
      std::snprintf(text, sizeof text, "a %s stamped %.3f s after one stamped %.3f s",
                    streams_[stream].c_str(), stamp, last);
    cause_ = text;
    ++jumps_;
    std::fill(last_stamps_.begin(), last_stamps_.end(), 0.0);
  }
  if (clock_known) last_clock_ = clock;
  if (stamp_known) last = std::max(last, stamp);
  return clock_back || stamp_back;
}

double TimeJumpDetector::newestStamp() const
{
  return *std::max_element(last_stamps_.begin(), last_stamps_.end());
}

void TimeJumpDetector::reset()
{
  last_clock_ = 0.0;
  std::fill(last_stamps_.begin(), last_stamps_.end(), 0.0);
}
}  // namespace linemap
