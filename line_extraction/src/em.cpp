// Expectation-maximisation line extraction: a mixture of lines (Gaussian
// perpendicular residuals) and a uniform outlier component.
//
// The number of lines is chosen greedily: lines are added one at a time while
// the log-likelihood gain of the best of `restarts` candidates exceeds
// `line_penalty` (a BIC-like price per line); the search stops after `patience`
// consecutive rounds without such a candidate. Each candidate starts from two
// nearby, poorly explained points and is fitted by a partial EM in which the
// lines already accepted stay fixed (cheap: one component); the best
// likelihood wins, and a few full EM iterations then refine every line. Points
// go to their most responsible line and its contiguous runs become segments.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
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
struct Component
{
  Vec2 normal = Vec2::UnitX();
  double offset = 0.0;
  double sigma = 0.02;
  double weight = 0.0;
};

class EmExtractor : public Extractor
{
 public:
  explicit EmExtractor(const linemap::ParamSet& params)
      : runs_(readRunSettings(params, "em")),
        initial_sigma_(params.getDouble("em/initial_sigma", 0.03)),
        min_sigma_(params.getDouble("em/min_sigma", 0.005)),
        max_sigma_(params.getDouble("em/max_sigma", 0.1)),
        outlier_density_(params.getDouble("em/outlier_density", 0.05)),
        line_penalty_(params.getDouble("em/line_penalty", 15.0)),
        restarts_(params.getInt("em/restarts", 5)),
        iterations_(params.getInt("em/iterations", 10)),
        full_iterations_(params.getInt("em/full_iterations", 3)),
        max_lines_(params.getInt("em/max_lines", 30)),
        patience_(params.getInt("em/patience", 3)),
        window_(params.getInt("em/window", 8)),
        seed_(static_cast<std::uint32_t>(params.getInt("em/seed", 1)))
  {
    requireParam(min_sigma_ > 0.0, "em/min_sigma", "> 0");
    requireParam(max_sigma_ >= min_sigma_, "em/max_sigma", ">= em/min_sigma");
    requireParam(initial_sigma_ >= min_sigma_ && initial_sigma_ <= max_sigma_, "em/initial_sigma",
                 "within [em/min_sigma, em/max_sigma]");
    requireParam(outlier_density_ > 0.0, "em/outlier_density", "> 0");
    requireParam(line_penalty_ >= 0.0, "em/line_penalty", ">= 0");
    requireParam(restarts_ >= 1, "em/restarts", ">= 1");
    requireParam(iterations_ >= 1, "em/iterations", ">= 1");
    requireParam(full_iterations_ >= 0, "em/full_iterations", ">= 0");
    requireParam(max_lines_ >= 1, "em/max_lines", ">= 1");
    requireParam(patience_ >= 1, "em/patience", ">= 1");
    requireParam(window_ >= 1, "em/window", ">= 1");
  }

  const char* name() const override { return "em"; }

  void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) override
  {
    rng_.seed(seed_);
    const int n = range.size();
    if (n < runs_.min_points) return;
    begin_ = range.begin;
    n_ = n;
    lines_.clear();
    outlier_weight_ = 1.0;
    mixture_.assign(n, outlier_density_);  // density of each point under the current model
    log_likelihood_ = n * std::log(outlier_density_);

    int failures = 0;
    while (static_cast<int>(lines_.size()) < max_lines_)
    {
      // Seeds: points the outlier component explains best.
      poor_.clear();
      for (int i = 0; i < n; ++i)
        if (outlier_weight_ * outlier_density_ > 0.5 * mixture_[i]) poor_.push_back(i);
      if (static_cast<int>(poor_.size()) < 2) break;

      Component best;
      double best_ll = -std::numeric_limits<double>::infinity();
      for (int r = 0; r < restarts_; ++r)
      {
        Component c;
        if (!initialise(scan, c)) continue;
        const double ll = fitNewComponent(scan, c);
        if (ll > best_ll)
        {
          best_ll = ll;
          best = c;
        }
      }
      if (!(best_ll - log_likelihood_ > line_penalty_) || best.weight * n < runs_.min_points)
      {
        // Seeds are often spurious points: give up only after `patience` fruitless rounds.
        if (++failures >= patience_) break;
        continue;
      }
      failures = 0;

      for (Component& c : lines_) c.weight *= 1.0 - best.weight;
      outlier_weight_ *= 1.0 - best.weight;
      lines_.push_back(best);
      log_likelihood_ = fullEm(scan);
    }

    // Runs of each line become segments.
    assignHard(scan);
    emitAssignedLines(scan, begin_, n, assignment_, lines_.size(), runs_, members_, out);
  }

 private:
  /// Hard assignment of each point to the most responsible component (-1: the outliers).
  void assignHard(const PreparedScan& scan)
  {
    assignment_.assign(n_, -1);
    for (int i = 0; i < n_; ++i)
    {
      double best = outlier_weight_ * outlier_density_;
      for (std::size_t k = 0; k < lines_.size(); ++k)
      {
        const double g =
            lines_[k].weight * density(lines_[k], scan.points[begin_ + i], scan.tolerance(begin_ + i, 1.0));
        if (g > best)
        {
          best = g;
          assignment_[i] = static_cast<int>(k);
        }
      }
    }
  }

  /// The line's noise is c.sigma at the base range noise and grows with the point's noise scale.
  static double density(const Component& c, const Vec2& p, double scale)
  {
    const double sigma = c.sigma * scale;
    const double z = (c.normal.dot(p) - c.offset) / sigma;
    if (std::abs(z) > 8.0) return 0.0;  // below 1e-14 of the peak: skip the exp
    return std::exp(-0.5 * z * z) / (std::sqrt(2.0 * linemap::kPi) * sigma);
  }

  /// A line through a poorly explained point and a random neighbour within `window` indices.
  bool initialise(const PreparedScan& scan, Component& c)
  {
    for (int attempt = 0; attempt < 8; ++attempt)
    {
      const int i = poor_[randomBelow(rng_, static_cast<int>(poor_.size()))];
      const int lo = std::max(0, i - window_), hi = std::min(n_ - 1, i + window_);
      if (hi - lo < 1) return false;
      int j = lo + randomBelow(rng_, hi - lo);
      if (j >= i) ++j;
      const Vec2& a = scan.points[begin_ + i];
      const Vec2 d = scan.points[begin_ + j] - a;
      if (d.norm() < 1e-6) continue;
      c.normal = Vec2(-d.y(), d.x()).normalized();
      c.offset = c.normal.dot(a);
      c.sigma = initial_sigma_;
      c.weight = 1.0 / (lines_.size() + 2.0);
      return true;
    }
    return false;
  }

  /// Weighted TLS of the points with the given weights; updates the line and its sigma.
  void weightedFit(const PreparedScan& scan, const std::vector<double>& w, Component& c) const
  {
    LineSums sums;
    for (int i = 0; i < n_; ++i)
    {
      const Vec2& p = scan.points[begin_ + i];
      const double wi = w[i];
      sums.n += wi;
      sums.sx += wi * p.x();
      sums.sy += wi * p.y();
      sums.sxx += wi * p.x() * p.x();
      sums.syy += wi * p.y() * p.y();
      sums.sxy += wi * p.x() * p.y();
    }
    if (sums.n < 2.0) return;
    const LineFit fit = fitLine(sums, runs_.range_sigma);
    if (!fit.valid) return;
    c.normal = Vec2(std::cos(fit.angle), std::sin(fit.angle));
    c.offset = fit.radius;
    double ssr = 0.0;
    for (int i = 0; i < n_; ++i)
    {
      // In units of the base noise, as density() reads c.sigma.
      const double d = (c.normal.dot(scan.points[begin_ + i]) - c.offset) / scan.tolerance(begin_ + i, 1.0);
      ssr += w[i] * d * d;
    }
    c.sigma = std::clamp(std::sqrt(ssr / sums.n), min_sigma_, max_sigma_);
  }

  /// EM on the new component alone (the current mixture scaled by 1 - weight
  /// stays fixed); returns the log-likelihood of the extended mixture.
  double fitNewComponent(const PreparedScan& scan, Component& c)
  {
    weights_.resize(n_);
    for (int it = 0;; ++it)
    {
      double support = 0.0;
      for (int i = 0; i < n_; ++i)
      {
        const double g = c.weight * density(c, scan.points[begin_ + i], scan.tolerance(begin_ + i, 1.0));
        weights_[i] = g > 0.0 ? g / ((1.0 - c.weight) * mixture_[i] + g) : 0.0;
        support += weights_[i];
      }
      if (it == iterations_) break;
      c.weight = std::clamp(support / n_, 1e-6, 1.0 - 1e-6);
      weightedFit(scan, weights_, c);
    }
    // log f_i = log((1 - w) m_i + g_i): points the new line does not reach (g_i = 0) only
    // add log(1 - w) to their current log m_i, whose sum is the current log-likelihood.
    double ll = log_likelihood_ + n_ * std::log(1.0 - c.weight);
    for (int i = 0; i < n_; ++i)
    {
      if (weights_[i] > 0.0) ll -= std::log1p(-weights_[i]);  // log f_i - log((1 - w) m_i) = -log(1 - r_i)
    }
    return ll;
  }

  /// A few EM iterations over every component; refreshes mixture_ and returns the log-likelihood.
  double fullEm(const PreparedScan& scan)
  {
    const std::size_t k_count = lines_.size();
    for (int it = 0; it < full_iterations_; ++it)
    {
      resp_.assign(k_count * n_, 0.0);
      double outlier_support = 0.0;
      for (int i = 0; i < n_; ++i)
      {
        const Vec2& p = scan.points[begin_ + i];
        const double scale = scan.tolerance(begin_ + i, 1.0);
        const double o = outlier_weight_ * outlier_density_;
        double f = o;
        for (std::size_t k = 0; k < k_count; ++k)
        {
          resp_[k * n_ + i] = lines_[k].weight * density(lines_[k], p, scale);
          f += resp_[k * n_ + i];
        }
        for (std::size_t k = 0; k < k_count; ++k) resp_[k * n_ + i] /= f;
        outlier_support += o / f;
      }
      outlier_weight_ = std::max(outlier_support / n_, 1e-6);
      for (std::size_t k = 0; k < k_count; ++k)
      {
        weights_.assign(resp_.begin() + k * n_, resp_.begin() + (k + 1) * n_);
        double support = 0.0;
        for (double w : weights_) support += w;
        lines_[k].weight = std::max(support / n_, 1e-6);
        weightedFit(scan, weights_, lines_[k]);
      }
    }
    double ll = 0.0;
    for (int i = 0; i < n_; ++i)
    {
      const Vec2& p = scan.points[begin_ + i];
      const double scale = scan.tolerance(begin_ + i, 1.0);
      double f = outlier_weight_ * outlier_density_;
      for (const Component& c : lines_) f += c.weight * density(c, p, scale);
      mixture_[i] = f;
      ll += std::log(f);
    }
    return ll;
  }

  RunSettings runs_;
  double initial_sigma_, min_sigma_, max_sigma_, outlier_density_, line_penalty_;
  int restarts_, iterations_, full_iterations_, max_lines_, patience_, window_;
  std::uint32_t seed_;
  std::mt19937 rng_;

  int begin_ = 0, n_ = 0;
  double outlier_weight_ = 1.0;
  double log_likelihood_ = 0.0;  ///< of the current mixture
  std::vector<Component> lines_;
  std::vector<double> mixture_, weights_, resp_;
  std::vector<int> poor_, assignment_, members_;
};

const ExtractorRegistration kRegistration("em", 90, &makeExtractorOf<EmExtractor>);

}  // namespace
}  // namespace line_extraction
