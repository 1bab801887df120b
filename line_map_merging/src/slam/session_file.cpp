#include "line_map_merging/slam/session_file.hpp"

#include <zlib.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "linemap/atomic_file.hpp"

namespace line_map_merging
{
namespace
{
using linemap::Pose2;
using linemap::Vec2;

constexpr char kMagic[] = "LINEMAP SESSION\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;
constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();

class Encoder
{
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v)
  {
    for (int i = 0; i < 4; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
  }
  void u64(std::uint64_t v)
  {
    for (int i = 0; i < 8; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
  }
  void f64(double v)
  {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void pose(const Pose2& p)
  {
    f64(p.x);
    f64(p.y);
    f64(p.theta);
  }
  void point(const Vec2& p)
  {
    f64(p.x());
    f64(p.y());
  }
  void bytes(const std::string& s) { out_ += s; }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

std::uint32_t checksum(const std::string& payload)
{
  return static_cast<std::uint32_t>(
      ::crc32(0L, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size())));
}

void appendRecord(Encoder& file, const char (&tag)[5], const std::string& payload)
{
  file.bytes(std::string(tag, 4));
  file.u64(payload.size());
  file.u32(checksum(payload));
  file.bytes(payload);
}

std::string keyframesPayload(const std::vector<SlamKeyframe>& keyframes)
{
  Encoder e;
  e.u64(keyframes.size());
  for (const SlamKeyframe& k : keyframes)
  {
    e.f64(k.stamp);
    e.u64(k.scan);
    e.pose(k.local);
    e.f64(k.path);
    e.u64(k.points.size());
    for (const Vec2& p : k.points) e.point(p);
    e.u64(k.joins.size());
    for (const auto& s : k.joins)
    {
      e.point(s.start);
      e.point(s.end);
    }
  }
  return std::move(e.str());
}

std::string edgesPayload(const std::vector<PoseGraphEdge>& edges)
{
  Encoder e;
  e.u64(edges.size());
  for (const PoseGraphEdge& g : edges)
  {
    e.u64(g.from);
    e.u64(g.to);
    e.pose(g.measurement);
    e.f64(g.sigma_xy);
    e.f64(g.sigma_theta);
    e.f64(g.translation_weights(0, 0));
    e.f64(g.translation_weights(0, 1));
    e.f64(g.translation_weights(1, 0));
    e.f64(g.translation_weights(1, 1));
    e.u8(g.loop ? 1 : 0);
    e.f64(g.loss_scale);
  }
  return std::move(e.str());
}

/// Reads one record's payload; every failure names the record and the item being read.
class Decoder
{
 public:
  Decoder(const std::string& bytes, std::size_t begin, std::size_t end, std::string where)
      : bytes_(bytes), at_(begin), end_(end), where_(std::move(where))
  {
  }
  std::uint8_t u8(const char* what) { return static_cast<std::uint8_t>(take(1, what)[0]); }
  std::uint64_t u64(const char* what)
  {
    const char* p = take(8, what);
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
    return v;
  }
  double f64(const char* what)
  {
    const std::uint64_t bits = u64(what);
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  double finite(const char* what)
  {
    const double v = f64(what);
    if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
    return v;
  }
  Pose2 pose(const char* what)
  {
    const double x = finite(what), y = finite(what), theta = finite(what);
    return {x, y, theta};
  }
  /// A count of items of at least `item_bytes` each: no more than the payload can hold.
  std::size_t count(const char* what, std::size_t item_bytes)
  {
    const std::uint64_t n = u64(what);
    if (n > (end_ - at_) / item_bytes)
      fail(std::string(what) + " " + std::to_string(n) + " exceeds what the record holds");
    return static_cast<std::size_t>(n);
  }
  void item(const std::string& what) { item_ = what; }
  [[noreturn]] void fail(const std::string& why) const
  {
    throw SessionFileError(where_ + (item_.empty() ? "" : ", " + item_) + ": " + why);
  }
  bool done() const { return at_ == end_; }

 private:
  const char* take(std::size_t n, const char* what)
  {
    if (end_ - at_ < n) fail(std::string("truncated reading ") + what);
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }
  const std::string& bytes_;
  std::size_t at_, end_;
  std::string where_, item_;
};

std::vector<SlamKeyframe> decodeKeyframes(Decoder& d)
{
  std::vector<SlamKeyframe> out(d.count("keyframe count", 64));
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    d.item("keyframe " + std::to_string(i));
    SlamKeyframe& k = out[i];
    k.stamp = d.finite("stamp");
    k.scan = static_cast<std::size_t>(d.u64("scan index"));
    k.local = d.pose("front-end pose");
    k.path = d.finite("path");
    k.points.resize(d.count("point count", 16));
    for (Vec2& p : k.points)
    {
      const double x = d.finite("point"), y = d.finite("point");
      p = Vec2(x, y);
    }
    k.joins.resize(d.count("surface count", 32));
    for (auto& s : k.joins)
    {
      const double x0 = d.finite("surface"), y0 = d.finite("surface"), x1 = d.finite("surface"),
                   y1 = d.finite("surface");
      s = linemap::Segment2(Vec2(x0, y0), Vec2(x1, y1));
    }
  }
  return out;
}

std::vector<PoseGraphEdge> decodeEdges(Decoder& d, std::size_t nodes)
{
  std::vector<PoseGraphEdge> out(d.count("edge count", 97));
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    d.item("edge " + std::to_string(i));
    PoseGraphEdge& e = out[i];
    const std::uint64_t from = d.u64("from"), to = d.u64("to");
    if (from >= nodes || to >= nodes || from == to)
      d.fail("joins nodes " + std::to_string(from) + " and " + std::to_string(to) + " of " +
             std::to_string(nodes));
    e.from = static_cast<std::size_t>(from);
    e.to = static_cast<std::size_t>(to);
    e.measurement = d.pose("measurement");
    e.sigma_xy = d.finite("sigma_xy");
    e.sigma_theta = d.finite("sigma_theta");
    if (!(e.sigma_xy > 0.0) || !(e.sigma_theta > 0.0)) d.fail("sigma_xy and sigma_theta must be positive");
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) e.translation_weights(r, c) = d.finite("translation weights");
    const std::uint8_t loop = d.u8("loop flag");
    if (loop > 1) d.fail("loop flag " + std::to_string(loop) + " is neither 0 nor 1");
    e.loop = loop == 1;
    e.loss_scale = d.finite("loss_scale");
  }
  return out;
}

std::vector<SlamSession::Scan> decodeScans(Decoder& d, std::size_t keyframes)
{
  std::vector<SlamSession::Scan> out(d.count("scan count", 40));
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    d.item("scan " + std::to_string(i));
    out[i].stamp = d.finite("stamp");
    const std::uint64_t k = d.u64("keyframe");
    if (k != kNone && k >= keyframes)
      d.fail("keyframe " + std::to_string(k) + " of " + std::to_string(keyframes));
    out[i].keyframe = k == kNone ? static_cast<std::size_t>(-1) : static_cast<std::size_t>(k);
    out[i].relative = d.pose("relative pose");
  }
  return out;
}

/// A record's bytes within the file, as the header announced them.
struct RecordSpan
{
  std::string tag;
  std::size_t begin = 0, end = 0;
  std::string where;  ///< "<origin>: record 'TAG' (n-th, at byte b)"
};

}  // namespace

std::string encodeSession(const Session& session)
{
  const SlamSession& slam = session.slam;
  Encoder file;
  file.bytes(std::string(kMagic, kMagicSize));
  file.u32(kSessionFormatVersion);
  appendRecord(file, "KEYF", keyframesPayload(slam.keyframes));
  Encoder nodes;
  nodes.u64(slam.nodes.size());
  for (const Pose2& n : slam.nodes) nodes.pose(n);
  appendRecord(file, "NODE", nodes.str());
  appendRecord(file, "EDGE", edgesPayload(slam.edges));
  Encoder scans;
  scans.u64(slam.scans.size());
  for (const auto& s : slam.scans)
  {
    scans.f64(s.stamp);
    scans.u64(s.keyframe == static_cast<std::size_t>(-1) ? kNone : s.keyframe);
    scans.pose(s.relative);
  }
  appendRecord(file, "SCAN", scans.str());
  if (!session.line_map.empty()) appendRecord(file, "LMAP", session.line_map);
  appendRecord(file, "END ", "");
  return std::move(file.str());
}

namespace
{
std::vector<RecordSpan> splitRecords(const std::string& bytes, const std::string& origin)
{
  const std::string file = "session file '" + origin + "'";
  if (bytes.size() < kMagicSize + 4 || bytes.compare(0, kMagicSize, kMagic) != 0)
    throw SessionFileError(file +
                           ": not a linemap session file (it does not start with \"LINEMAP SESSION\")");
  Decoder header(bytes, kMagicSize, kMagicSize + 4, file);
  std::uint32_t version = 0;
  for (int i = 0; i < 4; ++i) version |= static_cast<std::uint32_t>(header.u8("version")) << (8 * i);
  if (version != kSessionFormatVersion)
    throw SessionFileError(file + ": format version " + std::to_string(version) +
                           " is not supported (this build reads version " +
                           std::to_string(kSessionFormatVersion) + ")");
  std::vector<RecordSpan> records;
  std::size_t at = kMagicSize + 4;
  while (at < bytes.size())
  {
    RecordSpan r;
    r.tag = bytes.substr(at, 4);
    r.where = file + ": record '" + r.tag + "' (record " + std::to_string(records.size() + 1) + ", at byte " +
              std::to_string(at) + ")";
    if (bytes.size() - at < 16) throw SessionFileError(r.where + ": truncated in its header");
    Decoder head(bytes, at + 4, at + 16, r.where);
    const std::uint64_t size = head.u64("size");
    std::uint32_t crc = 0;
    for (int i = 0; i < 4; ++i) crc |= static_cast<std::uint32_t>(head.u8("checksum")) << (8 * i);
    r.begin = at + 16;
    if (size > bytes.size() - r.begin)
      throw SessionFileError(r.where + ": truncated: " + std::to_string(size) + " bytes announced, " +
                             std::to_string(bytes.size() - r.begin) + " left");
    r.end = r.begin + static_cast<std::size_t>(size);
    if (checksum(bytes.substr(r.begin, r.end - r.begin)) != crc)
      throw SessionFileError(r.where + ": corrupt (its checksum does not match)");
    records.push_back(r);
    at = r.end;
    if (r.tag == "END ") break;
  }
  if (records.empty() || records.back().tag != "END ")
    throw SessionFileError(file + ": truncated: no END record after " + std::to_string(records.size()) +
                           " records");
  if (at != bytes.size())
    throw SessionFileError(file + ": " + std::to_string(bytes.size() - at) + " bytes after the END record");
  return records;
}
}  // namespace

Session decodeSession(const std::string& bytes, const std::string& origin)
{
  Session out;
  bool keyframes = false, nodes = false, edges = false, scans = false;
  for (const RecordSpan& r : splitRecords(bytes, origin))
  {
    Decoder d(bytes, r.begin, r.end, r.where);
    if (r.tag == "KEYF")
    {
      out.slam.keyframes = decodeKeyframes(d);
      keyframes = true;
    }
    else if (r.tag == "NODE")
    {
      if (!keyframes) d.fail("comes before the keyframes (KEYF)");
      out.slam.nodes.resize(d.count("node count", 24));
      for (std::size_t i = 0; i < out.slam.nodes.size(); ++i)
      {
        d.item("node " + std::to_string(i));
        out.slam.nodes[i] = d.pose("pose");
      }
      if (out.slam.nodes.size() != out.slam.keyframes.size())
        d.fail(std::to_string(out.slam.nodes.size()) + " nodes for " +
               std::to_string(out.slam.keyframes.size()) + " keyframes");
      nodes = true;
    }
    else if (r.tag == "EDGE")
    {
      if (!nodes) d.fail("comes before the nodes (NODE)");
      out.slam.edges = decodeEdges(d, out.slam.nodes.size());
      edges = true;
    }
    else if (r.tag == "SCAN")
    {
      if (!keyframes) d.fail("comes before the keyframes (KEYF)");
      out.slam.scans = decodeScans(d, out.slam.keyframes.size());
      scans = true;
    }
    else if (r.tag == "LMAP")
      out.line_map = bytes.substr(r.begin, r.end - r.begin);
    else if (r.tag != "END ")
      d.fail("unknown record");
    d.item("");
    if (r.tag != "LMAP" && !d.done()) d.fail("bytes left over after its last item");
  }
  if (!(keyframes && nodes && edges && scans))
    throw SessionFileError("session file '" + origin +
                           "': a record is missing (KEYF, NODE, EDGE and SCAN are required)");
  return out;
}

void writeSessionFile(const std::string& path, const Session& session)
{
  try
  {
    linemap::writeFileAtomically(path, encodeSession(session), "session file");
  }
  catch (const SessionFileError&)
  {
    throw;
  }
  catch (const std::runtime_error& e)
  {
    throw SessionFileError(e.what());
  }
}

Session readSessionFile(const std::string& path)
{
  std::string bytes;
  try
  {
    bytes = linemap::readWholeFile(path, "session file");
  }
  catch (const std::runtime_error& e)
  {
    throw SessionFileError(e.what());
  }
  return decodeSession(bytes, path);
}

}  // namespace line_map_merging
