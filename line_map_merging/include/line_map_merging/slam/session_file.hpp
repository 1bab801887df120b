// The session file (ROS-free): what a later run needs to go on from a mapping session. The SLAM's
// keyframes with their scan points and surfaces, its pose graph (optimised nodes; edges with their
// measurements and information), every scan's pose relative to its keyframe, and the line map with its
// provenance (the text of the CAE-RLSM map file).
//
// Layout (version 1; integers and IEEE-754 doubles little-endian, doubles bit for bit):
//   "LINEMAP SESSION\n" (16 bytes), u32 format version,
//   then records: 4-byte tag, u64 payload size, u32 CRC-32 (zlib) of the payload, the payload:
//   KEYF  u64 n; n x { f64 stamp, u64 scan, f64 x y theta (front-end pose), f64 path,
//                      u64 m, m x f64 px py (base frame), u64 j, j x f64 x0 y0 x1 y1 (surfaces) }
//   NODE  u64 n; n x f64 x y theta (optimised keyframe poses, map frame)
//   EDGE  u64 n; n x { u64 from, u64 to, f64 x y theta, f64 sigma_xy, f64 sigma_theta,
//                      f64 w00 w01 w10 w11 (translation weights), u8 loop, f64 loss_scale }
//   SCAN  u64 n; n x { f64 stamp, u64 keyframe (2^64-1: none), f64 x y theta (relative to it) }
//   LMAP  the line map file's text (optional)
//   END   empty: the last record (a file cut between records lacks it)
// Written to a temporary file, fsynced and renamed over the target. Reading checks every record's size and
// checksum and every index before anything is used; each error names the file, the record and the item.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_map_merging/slam/pose_graph.hpp"
#include "line_map_merging/slam/slam_types.hpp"
#include "linemap/geometry.hpp"

namespace line_map_merging
{
constexpr std::uint32_t kSessionFormatVersion = 1;

/// The SLAM's part of a session.
struct SlamSession
{
  std::vector<SlamKeyframe> keyframes;
  std::vector<linemap::Pose2> nodes;  ///< one per keyframe
  std::vector<PoseGraphEdge> edges;
  struct Scan
  {
    double stamp = 0.0;
    std::size_t keyframe = static_cast<std::size_t>(-1);  ///< none: before the first keyframe
    linemap::Pose2 relative;                              ///< keyframe local^-1 * scan local
  };
  std::vector<Scan> scans;
};

struct Session
{
  SlamSession slam;
  std::string line_map;  ///< the map file's text (CaeRlsm::mapText); empty: none saved
};

struct SessionFileError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// The file's bytes; `decodeSession` reads them back (`origin` names them in errors).
std::string encodeSession(const Session& session);
Session decodeSession(const std::string& bytes, const std::string& origin);

/// Atomic write; read and validate. Throw SessionFileError naming the file, record and item.
void writeSessionFile(const std::string& path, const Session& session);
Session readSessionFile(const std::string& path);

}  // namespace line_map_merging
