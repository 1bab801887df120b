// Adjustment off the merge path: while a worker adjusts a copy, scans go on merging into the live
// map, which stays whole (no keyframe moved until every keyframe moves); once nothing is pending the
// map is the one the serial OnlineMapper makes from the same calls in the same order.
#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>
#include <random>

#include "drift_drive.hpp"
#include "line_map_merging/online/concurrent_mapper.hpp"

using namespace line_map_merging;
using namespace drift_drive;

namespace
{
/// Holds every adjust() until opened: the test decides when the worker may finish.
struct Latch
{
  std::mutex mutex;
  std::condition_variable cv;
  bool open = false;
  int waiting = 0;

  void pass()
  {
    std::unique_lock<std::mutex> lock(mutex);
    ++waiting;
    cv.notify_all();
    cv.wait(lock, [this] { return open; });
  }
  void waitForWorker()
  {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait(lock, [this] { return waiting > 0; });
  }
  void release()
  {
    std::lock_guard<std::mutex> lock(mutex);
    open = true;
    cv.notify_all();
  }
};

/// CAE-RLSM whose adjustments wait for the latch (clones share it).
class LatchedMerger : public Merger
{
 public:
  LatchedMerger(std::unique_ptr<Merger> inner, std::shared_ptr<Latch> latch)
      : inner_(std::move(inner)), latch_(std::move(latch))
  {
  }
  const char* name() const override { return inner_->name(); }
  AddResult addKeyframe(const Keyframe& k) override { return inner_->addKeyframe(k); }
  AddResult addOriginals(std::uint64_t k, const std::vector<linemap::Segment2>& s) override
  {
    return inner_->addOriginals(k, s);
  }
  AdjustResult adjust(const std::vector<std::pair<std::uint64_t, Pose2>>& poses) override
  {
    latch_->pass();
    return inner_->adjust(poses);
  }
  bool supportsAdjustment() const override { return true; }
  std::vector<MapSegment> map() const override { return inner_->map(); }
  std::vector<KeyframeInfo> keyframes() const override { return inner_->keyframes(); }
  std::size_t keyframeCount() const override { return inner_->keyframeCount(); }
  std::size_t leafCount() const override { return inner_->leafCount(); }
  std::size_t segmentCount() const override { return inner_->segmentCount(); }
  void reset() override { inner_->reset(); }
  std::unique_ptr<Merger> clone() const override
  {
    return std::make_unique<LatchedMerger>(inner_->clone(), latch_);
  }

 private:
  std::unique_ptr<Merger> inner_;
  std::shared_ptr<Latch> latch_;
};

OnlineMapperParams params(KeyframeSource source)
{
  OnlineMapperParams p;
  p.gate.distance = 0.19;
  p.gate.angle = 1.0;
  p.keyframe_source = source;
  return p;
}

std::unique_ptr<OnlineMapper> cae(KeyframeSource source)
{
  return std::make_unique<OnlineMapper>(makeMerger("cae", linemap::ParamSet()), params(source));
}

}  // namespace

TEST(ConcurrentMapper, ScansMergeWhileTheCopyIsAdjustedAndTheMapNeverIsHalfAdjusted)
{
  Drive run;
  auto latch = std::make_shared<Latch>();
  ConcurrentMapper live(std::make_unique<OnlineMapper>(
                            std::make_unique<LatchedMerger>(makeMerger("cae", linemap::ParamSet()), latch),
                            params(KeyframeSource::kTf)),
                        true);
  auto serial = cae(KeyframeSource::kTf);
  for (int i = 0; i < 60; ++i)
  {
    live.addScan(run.scan(i));
    serial->addScan(run.scan(i));
  }
  const auto before = live.mapper().merger().keyframes();
  ASSERT_EQ(before.size(), 15u);  // scans 0, 4, ..., 56

  EXPECT_FALSE(live.addTrajectory(nodesUpTo(run, 59)));  // to the worker
  serial->addTrajectory(nodesUpTo(run, 59));
  latch->waitForWorker();  // the copy is in adjust(), held there
  EXPECT_TRUE(live.adjusting());

  // The second half of the drive merges meanwhile; a second trajectory queues behind the first.
  for (int i = 60; i < kScans; ++i)
  {
    EXPECT_FALSE(live.poll());
    live.addScan(run.scan(i));
    serial->addScan(run.scan(i));
    if (i == 90)
    {
      EXPECT_FALSE(live.addTrajectory(nodesUpTo(run, 90)));
      serial->addTrajectory(nodesUpTo(run, 90));
    }
    // The live map is the unadjusted one, whole: the first 15 keyframes where odometry put them.
    const auto now = live.mapper().merger().keyframes();
    for (std::size_t k = 0; k < before.size(); ++k)
    {
      EXPECT_EQ(now[k].pose.x, before[k].pose.x);
      EXPECT_EQ(now[k].pose.theta, before[k].pose.theta);
    }
  }
  EXPECT_GT(live.mapper().merger().keyframeCount(), before.size());
  EXPECT_EQ(live.mapper().counters().adjustments, 0u);

  latch->release();
  EXPECT_TRUE(live.finish());
  EXPECT_FALSE(live.adjusting());
  // Both trajectories applied, each at its place among the scans: the serial mapper's map.
  EXPECT_EQ(live.mapper().counters().adjustments, 2u);
  expectSameMap(live.mapper(), *serial);
  // The first keyframes moved to the nodes: by up to 0.3 m at scan 56 from odometry alone.
  const auto after = live.mapper().merger().keyframes();
  const Pose2& truth56 = run.truth[56];
  EXPECT_LT(std::hypot(after[14].pose.x - truth56.x, after[14].pose.y - truth56.y), 0.002);
  EXPECT_GT(std::hypot(before[14].pose.x - truth56.x, before[14].pose.y - truth56.y), 0.05);
}

TEST(ConcurrentMapper, FreeRunningWorkerEndsWithTheSerialMap)
{
  // Node keyframes (auto): held scans, rebuilds at the first trajectory, node keyframes merged when
  // their scan comes; trajectories at random places, some while the worker runs, some duplicates.
  for (const KeyframeSource source :
       {KeyframeSource::kAuto, KeyframeSource::kTf, KeyframeSource::kTrajectory})
  {
    Drive run;
    std::mt19937 rng(7);
    ConcurrentMapper live(cae(source), true);
    auto serial = cae(source);
    for (int i = 0; i < kScans; ++i)
    {
      live.poll();
      live.addScan(run.scan(i));
      serial->addScan(run.scan(i));
      if (i % 3 == 0) live.countDropped(), serial->countDropped();
      if (rng() % 7 == 0)
      {
        const auto nodes = nodesUpTo(run, i);
        live.addTrajectory(nodes);
        serial->addTrajectory(nodes);
        if (rng() % 2 == 0)  // the same again at once: queued while the first runs
        {
          live.addTrajectory(nodes);
          serial->addTrajectory(nodes);
        }
      }
    }
    live.finish();
    SCOPED_TRACE(static_cast<int>(source));
    EXPECT_GT(live.mapper().counters().trajectories, 5u);
    expectSameMap(live.mapper(), *serial);
    EXPECT_EQ(live.mapper().counters().node_keyframes, serial->counters().node_keyframes);
    EXPECT_EQ(live.mapper().counters().rebuilds, serial->counters().rebuilds);
  }
}

TEST(ConcurrentMapper, WithoutBackgroundEveryTrajectoryIsAppliedAtOnce)
{
  Drive run;
  ConcurrentMapper live(cae(KeyframeSource::kTf), false);
  for (int i = 0; i < kScans; ++i) live.addScan(run.scan(i));
  EXPECT_TRUE(live.addTrajectory(run.nodes()));
  EXPECT_FALSE(live.adjusting());
  EXPECT_EQ(live.mapper().counters().adjustments, 1u);
}

TEST(ConcurrentMapper, ResetWaitsForTheAdjustmentAndAutosaveStaysDue)
{
  Drive run;
  OnlineMapperParams p = params(KeyframeSource::kTf);
  p.autosave_period = 1.0;
  ConcurrentMapper live(std::make_unique<OnlineMapper>(makeMerger("cae", linemap::ParamSet()), p), true);
  for (int i = 0; i < kScans; ++i) live.addScan(run.scan(i));
  live.addTrajectory(run.nodes());
  live.finish();
  // Replaced by the adjusted copy: the new map is due for saving.
  EXPECT_TRUE(live.mapper().autosaveDue(100.0));
  live.addTrajectory(run.nodes());
  live.reset();  // after the adjustment, not under it
  EXPECT_FALSE(live.adjusting());
  EXPECT_EQ(live.mapper().merger().keyframeCount(), 0u);
  EXPECT_EQ(live.mapper().counters().adjustments, 2u);
}

// The map services: a save answers with the count of the newest (adjusted) map, a failed load
// names the file and keeps the map, a good load brings the saved map back.
TEST(ConcurrentMapper, SaveAndLoadAnswerAndAFailedLoadKeepsTheMap)
{
  Drive run;
  ConcurrentMapper live(cae(KeyframeSource::kTf), true);
  for (int i = 0; i < kScans; ++i) live.addScan(run.scan(i));
  live.addTrajectory(run.nodes());
  const std::string path = ::testing::TempDir() + "concurrent_mapper_map.yaml";
  const MapCommandAnswer saved = live.saveMap(path);
  ASSERT_TRUE(saved.success) << saved.message;
  EXPECT_FALSE(live.adjusting());  // saved after the adjustment, not under it
  const std::size_t segments = live.mapper().merger().segmentCount();
  ASSERT_GT(segments, 0u);
  EXPECT_EQ(saved.message, "saved " + std::to_string(segments) + " segments to " + path);

  const std::string missing = ::testing::TempDir() + "no_such_map.yaml";
  const MapCommandAnswer failed = live.loadMap(missing);
  EXPECT_FALSE(failed.success);
  EXPECT_NE(failed.message.find("no_such_map.yaml"), std::string::npos) << failed.message;
  EXPECT_EQ(live.mapper().merger().segmentCount(), segments);

  live.reset();
  ASSERT_EQ(live.mapper().merger().segmentCount(), 0u);
  const MapCommandAnswer loaded = live.loadMap(path);
  ASSERT_TRUE(loaded.success) << loaded.message;
  EXPECT_EQ(live.mapper().merger().segmentCount(), segments);
  EXPECT_EQ(loaded.message.rfind("loaded " + std::to_string(segments) + " segments, ", 0), 0u)
      << loaded.message;
}
