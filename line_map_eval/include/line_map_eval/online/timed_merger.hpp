// A merger that times another: every call forwarded, the time of each addKeyframe() and adjust()
// kept. linemap_batch puts it between the OnlineMapper and the merger to report the merging times
// of the one online path without a clock inside the mapper.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"
#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
class TimedMerger : public line_map_merging::Merger
{
 public:
  explicit TimedMerger(std::unique_ptr<line_map_merging::Merger> inner) : inner_(std::move(inner)) {}

  /// [ms] of each addKeyframe(), in call order.
  const std::vector<double>& addTimes() const { return add_ms_; }
  /// [ms] of every adjust() together, and their number.
  double adjustTime() const { return adjust_ms_; }
  std::size_t adjustments() const { return adjustments_; }
  /// [ms] of every addOriginals() together (the map-level lines).
  double originalsTime() const { return originals_ms_; }
  const line_map_merging::Merger& inner() const { return *inner_; }

  const char* name() const override { return inner_->name(); }
  bool isOnline() const override { return inner_->isOnline(); }
  line_map_merging::AddResult addKeyframe(const line_map_merging::Keyframe& keyframe) override
  {
    const auto start = std::chrono::steady_clock::now();
    auto result = inner_->addKeyframe(keyframe);
    add_ms_.push_back(linemap::millisecondsSince(start));
    return result;
  }
  line_map_merging::AddResult addOriginals(std::uint64_t keyframe,
                                           const std::vector<linemap::Segment2>& segments) override
  {
    const auto start = std::chrono::steady_clock::now();
    auto result = inner_->addOriginals(keyframe, segments);
    originals_ms_ += linemap::millisecondsSince(start);
    return result;
  }
  line_map_merging::AdjustResult adjust(
      const std::vector<std::pair<std::uint64_t, linemap::Pose2>>& poses) override
  {
    const auto start = std::chrono::steady_clock::now();
    auto result = inner_->adjust(poses);
    adjust_ms_ += linemap::millisecondsSince(start);
    ++adjustments_;
    return result;
  }
  bool supportsAdjustment() const override { return inner_->supportsAdjustment(); }
  std::vector<line_map_merging::MapSegment> map() const override { return inner_->map(); }
  std::vector<line_map_merging::KeyframeInfo> keyframes() const override { return inner_->keyframes(); }
  std::vector<line_map_merging::Leaf> leaves(std::uint64_t id) const override { return inner_->leaves(id); }
  bool hasProvenance() const override { return inner_->hasProvenance(); }
  std::size_t keyframeCount() const override { return inner_->keyframeCount(); }
  std::size_t leafCount() const override { return inner_->leafCount(); }
  std::size_t segmentCount() const override { return inner_->segmentCount(); }
  void reset() override { inner_->reset(); }
  /// The copy is the inner merger's (a snapshot is not timed).
  std::unique_ptr<line_map_merging::Merger> clone() const override { return inner_->clone(); }
  void save(const std::string& path) const override { inner_->save(path); }
  void load(const std::string& path) override { inner_->load(path); }
  void loadText(const std::string& text, const std::string& origin) override
  {
    inner_->loadText(text, origin);
  }
  void timeSteps(bool on) override { inner_->timeSteps(on); }
  std::vector<line_map_merging::StepTime> stepTimes() const override { return inner_->stepTimes(); }

 private:
  std::unique_ptr<line_map_merging::Merger> inner_;
  std::vector<double> add_ms_;
  double adjust_ms_ = 0.0;
  double originals_ms_ = 0.0;
  std::size_t adjustments_ = 0;
};

}  // namespace line_map_eval
