// Map-level lines: walls no single scan sees well enough for its extractor (far away with coarse
// beams, glimpsed in pieces, smeared by the registration) still gather a band of points once the
// keyframes' scans are registered by the map's poses. The returns a keyframe's own segments do not
// explain, and the map does not either, are searched for lines (ResidualLineFinder) with each point's
// noise from the sensor model and the registration's error at its range. Every keyframe that gave a
// line points gets the part of the line it saw as an original of its own, so the map segment has
// provenance to each of them and moves with them when the trajectory is corrected. ROS-free.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "line_extraction/residual_lines.hpp"
#include "line_extraction/sensor_model.hpp"
#include "line_map_merging/mergers/merger.hpp"
#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
/// Keys of the "map_level" block of config/line_map_merging.yaml.
struct MapLevelParams
{
  bool enabled = true;
  /// Keyframes merged between two passes that no trajectory triggered (0: only after trajectories).
  int every_keyframes = 50;
  /// The laser's noise model ("map_level/range_sigma", "map_level/range_sigma_per_m",
  /// "map_level/gap_incidence": the keys of line_extraction.yaml without the prefix).
  line_extraction::SensorModel sensor;
  /// Registration error of a keyframe's pose: a point at range r is displaced across a line by up to
  /// sqrt(pose_sigma^2 + (r heading_sigma)^2) besides its range noise.
  double pose_sigma = 0.02;      ///< [m]
  double heading_sigma = 0.003;  ///< [rad]
  /// A keyframe's points seed lines when it is new, and again after it moved this much since (a loop
  /// closed): lines through them were sought before.
  double reseed_distance = 0.25;  ///< [m]
  double reseed_angle = 0.05;     ///< [rad]
  /// Lines through the seeding points are sought among the points within this of them [m]: a longer
  /// wall is found in parts, which the merger fuses.
  double search_margin = 20.0;
  /// A return lies on a segment (its keyframe's own, or the map's) within this many of its sigmas.
  double explained_sigmas = 3.0;
  /// ... and on a map segment within this distance at least [m]: a line closer to it than the
  /// fusion's d_max would only be the same wall drawn again.
  double map_distance = 0.10;
  /// The tests of a line; min_sources counts keyframes. A line must run through its points over
  /// min_fill of its length at fill_bin (the map's resolution): a wall is seen all along, a few far
  /// returns or a row of posts are not.
  line_extraction::ResidualLineParams lines = []
  {
    line_extraction::ResidualLineParams p;
    p.min_fill = 0.85;
    p.fill_bin = 0.05;
    return p;
  }();

  /// Reads the "map_level/..." keys; throws linemap::ParameterError naming a bad one.
  static MapLevelParams fromParams(const linemap::ParamSet& params);
};

/// One scan as the laser returned it (the beams of sensor_msgs/LaserScan).
struct KeyframeScan
{
  double angle_min = 0.0, angle_increment = 0.0;  ///< [rad]
  double range_min = 0.0, range_max = 0.0;        ///< [m]: returns outside (range_min, range_max) are none
  std::vector<float> ranges;                      ///< [m]
};

/// Originals found for one keyframe: in its laser frame, observers on the left.
struct KeyframeOriginals
{
  std::uint64_t keyframe = 0;
  std::vector<linemap::Segment2> segments;
};

class MapLevelLines
{
 public:
  explicit MapLevelLines(const MapLevelParams& params);

  /// Keeps what a keyframe's scan returned, and which returns its own segments (laser frame) explain.
  void addKeyframe(std::uint64_t index, const KeyframeScan& scan,
                   const std::vector<linemap::Segment2>& segments);
  /// Forgets every keyframe (a new map).
  void clear()
  {
    scans_.clear();
    searched_.clear();
  }
  std::size_t keyframes() const { return scans_.size(); }

  /// The lines in the returns neither their keyframe's segments nor a segment of `map` explain, the
  /// keyframes registered at their poses in `keyframes` (those unknown here are left out): per
  /// keyframe that saw a line, the part it saw. `lines` (optional) receives the lines, map frame.
  /// A line is grown from the points of keyframes new since the last call or moved by more than
  /// reseed_distance / reseed_angle since they last seeded: from the others it was sought before. Only
  /// points within search_margin of those take part, and the keyframes whose range reaches them.
  std::vector<KeyframeOriginals> extract(const std::vector<KeyframeInfo>& keyframes,
                                         const std::vector<MapSegment>& map,
                                         std::vector<linemap::Segment2>* lines = nullptr);

  const MapLevelParams& params() const { return params_; }

 private:
  /// What one keyframe's scan keeps: every valid return (for the test that a line is not seen
  /// through) and the unexplained ones (the candidates).
  struct Stored
  {
    std::shared_ptr<const line_extraction::ResidualReturns> returns;  ///< every valid return
    std::vector<linemap::Vec2> residual_at;   ///< the unexplained returns, laser frame
    std::vector<float> residual_range;        ///< their ranges [m]
    std::vector<float> residual_gap;          ///< largest gap to a neighbour on one surface [m]
    std::vector<std::int32_t> residual_beam;  ///< their beams' indices
    double beam_spacing = 0.0;                ///< |angle_increment| [rad]
  };

  /// A keyframe known here at its current pose; `seeds` when lines are grown from its points.
  struct Known
  {
    const KeyframeInfo* keyframe;
    const Stored* stored;
    bool seeds;
  };
  /// The keyframes known here, and the box around the seeding keyframes' points within which lines
  /// are sought (empty when none seeds).
  struct SeedArea
  {
    std::vector<Known> known;
    linemap::Vec2 lo, hi;
  };
  /// The keyframes that reach the box as sources (ids by position), and the unexplained returns in it
  /// registered by their poses.
  struct Registered
  {
    std::vector<line_extraction::ResidualSource> sources;
    std::vector<const Stored*> stored_of;
    std::vector<std::uint64_t> keyframe_of;
    std::vector<char> seeds;
    std::vector<line_extraction::ResidualPoint> points;
    std::vector<double> point_range;  ///< [m], per point
  };
  class FacesNear;

  /// Marks the keyframes that seed (new, or moved since they last did) and records their pose.
  SeedArea seedArea(const std::vector<KeyframeInfo>& keyframes);
  Registered registerResiduals(const SeedArea& area, const FacesNear& faces) const;
  /// Appends to `out` each keyframe's part of `line` (out_slot: keyframe -> its entry in out).
  static void addParts(const line_extraction::ResidualLine& line, const Registered& reg,
                       std::vector<KeyframeOriginals>& out, std::map<std::uint64_t, std::size_t>& out_slot);

  MapLevelParams params_;
  // Shared between copies of a mapper (ConcurrentMapper adjusts a copy): a keyframe's scan never changes.
  std::map<std::uint64_t, std::shared_ptr<const Stored>> scans_;
  std::map<std::uint64_t, linemap::Pose2> searched_;  ///< keyframes searched from, at that pose
};

}  // namespace line_map_merging
