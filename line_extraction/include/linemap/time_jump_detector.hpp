// Detects time jumping back: a clock or a message stamp earlier than before by more than a
// tolerance, as when `rosbag play` loops or restarts. One policy for every node of the suite.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace linemap
{
class TimeJumpDetector
{
 public:
  /// `streams` name the message streams whose stamps are watched, each on its own (a stamp is
  /// compared with the last of its stream only); their names appear in cause().
  explicit TimeJumpDetector(double tolerance = 1.0, std::vector<std::string> streams = {"message"});

  /// A clock reading and/or a stamp of stream `stream` (0, negative or NaN: not known). True when
  /// either went back by more than the tolerance; then every stream starts afresh.
  bool observe(double clock, double stamp, std::size_t stream = 0);

  /// The newest stamp seen on `stream` since the last jump (0: none).
  double lastStamp(std::size_t stream = 0) const { return last_stamps_.at(stream); }
  /// The newest stamp seen on any stream since the last jump (0: none).
  double newestStamp() const;
  /// What the last jump was: the clock or a stamp, from and to.
  const std::string& cause() const { return cause_; }
  std::size_t jumps() const { return jumps_; }
  double tolerance() const { return tolerance_; }
  void setTolerance(double tolerance) { tolerance_ = tolerance; }
  /// Forgets the clock and every stamp (not the count of jumps).
  void reset();

 private:
  double tolerance_;
  std::vector<std::string> streams_;
  double last_clock_ = 0.0;
  std::vector<double> last_stamps_;
  std::string cause_;
  std::size_t jumps_ = 0;
};
}  // namespace linemap
