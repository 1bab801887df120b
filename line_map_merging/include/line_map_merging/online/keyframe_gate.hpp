// Keyframe gating shared by the merger nodelet and the batch tool: a scan is merged only when the
// robot has moved far enough since the last keyframe, which bounds the work per metre travelled and
// keeps near-duplicate scans from dominating the map.
#pragma once

#include <optional>

#include "linemap/geometry.hpp"
#include "linemap/params.hpp"

namespace line_map_merging
{
struct KeyframeGateParams
{
  double distance = 0.2;               ///< [m] translation since the last keyframe
  double angle = 0.17453292519943295;  ///< [rad] rotation since the last keyframe (10 deg)

  /// Reads "keyframe_distance" and "keyframe_angle" (radians); throws linemap::ParameterError
  /// naming the key for a negative or non-finite value.
  static KeyframeGateParams fromParams(const linemap::ParamSet& params);
};

class KeyframeGate
{
 public:
  explicit KeyframeGate(const KeyframeGateParams& params = {}) : params_(params) {}

  /// True when `pose` becomes a keyframe: the first pose always does, later ones when the
  /// translation reaches `distance` or the rotation reaches `angle` relative to the last keyframe.
  /// An accepted pose becomes the new reference.
  bool accept(const linemap::Pose2& pose);

  /// The same test without updating the reference.
  bool wouldAccept(const linemap::Pose2& pose) const;

  /// Forgets the last keyframe: the next pose is accepted.
  void reset() { last_.reset(); }

  /// Moves the reference, e.g. after a trajectory correction changed the last keyframe's pose.
  void setReference(const linemap::Pose2& pose) { last_ = pose; }

  const std::optional<linemap::Pose2>& reference() const { return last_; }
  const KeyframeGateParams& params() const { return params_; }

 private:
  KeyframeGateParams params_;
  std::optional<linemap::Pose2> last_;
};

}  // namespace line_map_merging
