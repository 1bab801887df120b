// A small progress bar on stderr for long-running tools (log conversion,
// simulation, batch runs). On a terminal it redraws one line in place; when
// stderr is redirected it stays silent until finish() prints one summary line,
// so log files do not fill with carriage returns.
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <string>

namespace line_map_eval
{
class ProgressBar
{
 public:
  /// `total` = 0 means unknown (shows a count instead of a bar). `enabled` = false prints nothing.
  ProgressBar(std::string label, std::size_t total, bool enabled = true);
  /// Same, writing to `out` (tests); `out` is treated as a terminal when `interactive`.
  ProgressBar(std::string label, std::size_t total, bool enabled, std::ostream& out, bool interactive);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// Reports `done` items; redraws at most every 100 ms.
  void update(std::size_t done);
  /// Draws the final state with the elapsed time and ends the line (idempotent).
  void finish();

 private:
  void draw(bool final_line);

  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool enabled_;
  bool interactive_;
  bool finished_ = false;
  std::ostream* out_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace line_map_eval
