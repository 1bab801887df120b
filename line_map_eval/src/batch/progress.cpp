#include "line_map_eval/batch/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace line_map_eval
{
ProgressBar::ProgressBar(std::string label, std::size_t total, bool enabled)
    : ProgressBar(std::move(label), total, enabled, std::cerr, isatty(STDERR_FILENO) == 1)
{
}

ProgressBar::ProgressBar(std::string label, std::size_t total, bool enabled, std::ostream& out,
                         bool interactive)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      interactive_(interactive),
      out_(&out),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_)
{
}

ProgressBar::~ProgressBar()
{
  // A bar destroyed by an exception still ends its line so the error message starts cleanly.
  if (enabled_ && interactive_ && !finished_ && done_ > 0) *out_ << '\n' << std::flush;
}

void ProgressBar::update(std::size_t done)
{
  done_ = done;
  if (!enabled_ || !interactive_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  draw(false);
}

void ProgressBar::finish()
{
  if (finished_) return;
  finished_ = true;
  if (enabled_) draw(true);
}

void ProgressBar::draw(bool final_line)
{
  constexpr int kWidth = 30;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::ostringstream line;
  line << label_ << ' ';
  if (total_ > 0)
  {
    const double fraction = std::min(1.0, static_cast<double>(done_) / static_cast<double>(total_));
    const int filled = static_cast<int>(fraction * kWidth);
    line << '[' << std::string(filled, '#') << std::string(kWidth - filled, '.') << "] " << done_ << '/'
         << total_;
    char pct[16];
    std::snprintf(pct, sizeof pct, " %3.0f%%", 100.0 * fraction);
    line << pct;
  }
  else
  {
    line << done_;
  }
  char secs[32];
  std::snprintf(secs, sizeof secs, " %.1f s", elapsed);
  line << secs;
  if (interactive_)
    *out_ << '\r' << line.str() << "\x1b[K" << (final_line ? "\n" : "") << std::flush;
  else if (final_line)
    *out_ << line.str() << '\n' << std::flush;
}

}  // namespace line_map_eval
