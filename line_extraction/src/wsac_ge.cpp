// WSAC-GE: window sampling consensus with global evaluation.
//
// Hypotheses come from a window of neighbouring points (a random point and a
// random partner at most `window` beams away), refined by TLS on their
// inliers. A set of lines is judged as a whole: every point supports only its
// nearest line, with the Tukey weight h_j = (1 - (d/c)^2)^2 for |d| < c; the
// supports of points that form runs of at least min_points points (a segment)
// count as h_j^2, points that only form shorter runs cost `short_penalty`
// each, and every line costs `line_cost`:
//   H = sum_{segment points} h_j^2 - short_penalty * #short-run points - line_cost * #lines.
// Moves add a hypothesis or delete a line and are kept when H grows; the search
// ends after `max_failures` consecutive moves without improvement.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "line_extraction/extractor_registry.hpp"
#include "line_extraction/param_checks.hpp"
#include "line_extraction/ransac.hpp"

namespace line_extraction
{
namespace
{
struct Line
{
  Vec2 normal = Vec2::UnitX();
  double offset = 0.0;
};

class WsacGeExtractor : public Extractor
{
 public:
  explicit WsacGeExtractor(const linemap::ParamSet& params)
      : runs_(readRunSettings(params, "wsac_ge")),
        window_(params.getInt("wsac_ge/window", 10)),
        tukey_c_(params.getDouble("wsac_ge/tukey_c", 0.1)),
        short_penalty_(params.getDouble("wsac_ge/short_penalty", 0.5)),
        line_cost_(params.getDouble("wsac_ge/line_cost", 5.0)),
        max_failures_(params.getInt("wsac_ge/max_failures", 40)),
        delete_probability_(params.getDouble("wsac_ge/delete_probability", 0.25)),
        refine_iterations_(params.getInt("wsac_ge/refine_iterations", 3)),
        seed_(static_cast<std::uint32_t>(params.getInt("wsac_ge/seed", 1)))
  {
    requireParam(window_ >= 1, "wsac_ge/window", ">= 1");
    requireParam(tukey_c_ > 0.0, "wsac_ge/tukey_c", "> 0");
    requireParam(short_penalty_ >= 0.0, "wsac_ge/short_penalty", ">= 0");
    requireParam(line_cost_ >= 0.0, "wsac_ge/line_cost", ">= 0");
    requireParam(max_failures_ >= 1, "wsac_ge/max_failures", ">= 1");
    requireParam(delete_probability_ >= 0.0 && delete_probability_ < 1.0, "wsac_ge/delete_probability",
                 "in [0, 1)");
    requireParam(refine_iterations_ >= 0, "wsac_ge/refine_iterations", ">= 0");
  }

  const char* name() const override { return "wsac_ge"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    rng_.seed(seed_);
    begin_ = range.begin;
    n_ = range.size();
    if (n_ < runs_.min_points) return;
    lines_.clear();
    double score = evaluate(scan, lines_, assignment_);
    // Every accepted move raises H by more than a fixed epsilon, so the moves are bounded anyway;
    // the cap only protects against pathological parameter choices.
    const int max_moves = 50 * max_failures_ + 10 * n_;
    int failures = 0;
    for (int move = 0; move < max_moves && failures < max_failures_; ++move)
    {
      candidate_ = lines_;
      const bool remove = !lines_.empty() && std::generate_canonical<double, 32>(rng_) < delete_probability_;
      if (remove)
      {
        candidate_.erase(candidate_.begin() + randomBelow(rng_, static_cast<int>(lines_.size())));
      }
      else
      {
        Line line;
        if (!hypothesis(scan, line))
        {
          ++failures;
          continue;
        }
        candidate_.push_back(line);
      }
      const double candidate_score = evaluate(scan, candidate_, candidate_assignment_);
      if (candidate_score > score + 1e-9)
      {
        score = candidate_score;
        lines_.swap(candidate_);
        assignment_.swap(candidate_assignment_);
        failures = 0;
      }
      else
      {
        ++failures;
      }
    }

    emitAssignedLines(scan, begin_, n_, assignment_, lines_.size(), runs_, members_, out);
  }

 private:
  /// Global score H of a set of lines; fills each point's line (-1: none, or only a short run).
  double evaluate(const PreparedScan& scan, const std::vector<Line>& lines, std::vector<int>& assignment)
  {
    const std::size_t k_count = lines.size();
    assignNearest(scan, lines, assignment);
    // Runs per line in one pass: a run ends where the gap to the line's previous point is too large.
    run_start_.assign(k_count, -1);
    run_last_.assign(k_count, -1);
    run_count_.assign(k_count, 0);
    run_sum_.assign(k_count, 0.0);
    const double max_gap2 = runs_.max_gap * runs_.max_gap;
    double score = -line_cost_ * static_cast<double>(k_count);
    auto close = [&](std::size_t k)
    {
      if (run_count_[k] == 0) return;
      if (run_count_[k] >= runs_.min_points)
      {
        score += run_sum_[k];
      }
      else
      {
        score -= short_penalty_ * run_count_[k];
        // Short-run points support no segment: mark them unexplained (seeds for new hypotheses).
        for (int j = run_start_[k]; j <= run_last_[k]; ++j)
          if (assignment[j] == static_cast<int>(k)) assignment[j] = -2 - static_cast<int>(k);
      }
      run_count_[k] = 0;
      run_sum_[k] = 0.0;
    };
    for (int i = 0; i < n_; ++i)
    {
      const int k = assignment[i];
      if (k < 0) continue;
      if (run_count_[k] > 0 && (scan.points[begin_ + i] - scan.points[begin_ + run_last_[k]]).squaredNorm() >
                                   (run_last_[k] == i - 1 ? scan.maxGap2(begin_ + i, max_gap2) : max_gap2))
        close(k);
      if (run_count_[k] == 0) run_start_[k] = i;
      run_last_[k] = i;
      ++run_count_[k];
      run_sum_[k] += support_[i];
    }
    for (std::size_t k = 0; k < k_count; ++k) close(k);
    return score;
  }

  /// Each point's nearest line within tukey_c (-1: none) and its Tukey support in support_.
  void assignNearest(const PreparedScan& scan, const std::vector<Line>& lines, std::vector<int>& assignment)
  {
    const std::size_t k_count = lines.size();
    assignment.assign(n_, -1);
    support_.resize(n_);
    for (int i = 0; i < n_; ++i)
    {
      const Vec2& p = scan.points[begin_ + i];
      const double limit = scan.tolerance(begin_ + i, tukey_c_);
      double best = limit;
      for (std::size_t k = 0; k < k_count; ++k)
      {
        const double d = std::abs(lines[k].normal.dot(p) - lines[k].offset);
        if (d < best)
        {
          best = d;
          assignment[i] = static_cast<int>(k);
        }
      }
      const double u = best / limit;
      const double h = (1.0 - u * u) * (1.0 - u * u);
      support_[i] = h * h;
    }
  }

  /// A random point without a segment and a random partner within `window` beams, refined by TLS.
  bool hypothesis(const PreparedScan& scan, Line& line)
  {
    unexplained_.clear();
    for (int i = 0; i < n_; ++i)
      if (assignment_[i] < 0) unexplained_.push_back(i);
    if (unexplained_.empty()) return false;
    const int i = unexplained_[randomBelow(rng_, static_cast<int>(unexplained_.size()))];
    const int lo = std::max(0, i - window_), hi = std::min(n_ - 1, i + window_);
    if (hi - lo < 1) return false;
    int j = lo + randomBelow(rng_, hi - lo);
    if (j >= i) ++j;
    const Vec2& a = scan.points[begin_ + i];
    const Vec2 d = scan.points[begin_ + j] - a;
    if (d.norm() < 1e-6) return false;
    line.normal = Vec2(-d.y(), d.x()).normalized();
    line.offset = line.normal.dot(a);
    for (int it = 0; it < refine_iterations_; ++it)
    {
      LineSums sums;
      for (int m = 0; m < n_; ++m)
      {
        const Vec2& p = scan.points[begin_ + m];
        if (std::abs(line.normal.dot(p) - line.offset) < scan.tolerance(begin_ + m, tukey_c_)) sums.add(p);
      }
      const LineFit fit = fitLine(sums, runs_.range_sigma);
      if (!fit.valid) break;
      line.normal = Vec2(std::cos(fit.angle), std::sin(fit.angle));
      line.offset = fit.radius;
    }
    return true;
  }

  RunSettings runs_;
  int window_;
  double tukey_c_, short_penalty_, line_cost_;
  int max_failures_;
  double delete_probability_;
  int refine_iterations_;
  std::uint32_t seed_;
  std::mt19937 rng_;

  int begin_ = 0, n_ = 0;
  std::vector<Line> lines_, candidate_;
  std::vector<int> assignment_, candidate_assignment_, unexplained_, members_;
  std::vector<double> support_, run_sum_;
  std::vector<int> run_start_, run_last_, run_count_;
};

const ExtractorRegistration kRegistration("wsac_ge", 100, &makeExtractorOf<WsacGeExtractor>);

}  // namespace
}  // namespace line_extraction
