#include "line_map_eval/datasets/carmen_log.hpp"

#include <algorithm>
#include <boost/iostreams/copy.hpp>
#include <boost/iostreams/device/array.hpp>
#include <boost/iostreams/device/back_inserter.hpp>
#include <boost/iostreams/filter/bzip2.hpp>
#include <boost/iostreams/filter/gzip.hpp>
#include <boost/iostreams/filtering_stream.hpp>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
namespace
{
/// Problem with one line; becomes "<file>:<line>: <message>".
struct LineError
{
  std::string message;
};

/// Splits a line on blanks into views of the line (no allocation once `out` has grown).
void tokenize(std::string_view line, std::vector<std::string_view>& out)
{
  out.clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (i < n)
  {
    while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < n && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
}

/// Parsing state for one line: the tokens after the message type and a cursor.
class Fields
{
 public:
  Fields(const char* type, const std::vector<std::string_view>& tokens) : type_(type), tokens_(tokens) {}

  std::size_t remaining() const { return tokens_.size() - pos_; }
  /// Field number (1-based, the message type being field 1) of the last field read.
  std::size_t field() const { return pos_; }

  double number(const char* what)
  {
    if (pos_ >= tokens_.size()) fail(std::string("missing ") + what);
    std::string_view t = tokens_[pos_++];
    if (!t.empty() && t.front() == '+') t.remove_prefix(1);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
      fail(std::string(what) + " (field " + std::to_string(pos_) + ") is not a number: '" +
           std::string(tokens_[pos_ - 1]) + "'");
    return v;
  }

  std::size_t count(const char* what, std::size_t limit)
  {
    const double v = number(what);
    if (v < 0.0 || v != std::floor(v) || v > static_cast<double>(limit))
      fail(std::string(what) + " is not a count: '" + std::string(tokens_[pos_ - 1]) + "'");
    return static_cast<std::size_t>(v);
  }

  /// An integer code (laser type, remission mode); a larger value would overflow the int.
  int integer(const char* what)
  {
    const double v = number(what);
    if (v != std::floor(v) || std::abs(v) > 1e9)
      fail(std::string(what) + " is not an integer: '" + std::string(tokens_[pos_ - 1]) + "'");
    return static_cast<int>(v);
  }

  std::string_view word(const char* what)
  {
    if (pos_ >= tokens_.size()) fail(std::string("missing ") + what);
    return tokens_[pos_++];
  }

  void end()
  {
    if (pos_ != tokens_.size())
      fail(std::to_string(tokens_.size() - pos_) + " unexpected trailing field(s) starting with '" +
           std::string(tokens_[pos_]) + "'");
  }

  [[noreturn]] void fail(const std::string& message) const
  {
    throw LineError{std::string(type_) + ": " + message};
  }

 private:
  const char* type_;
  const std::vector<std::string_view>& tokens_;
  std::size_t pos_ = 1;  // token 0 is the message type; field numbers in messages are 1-based
};

constexpr std::size_t kMaxBeams = 100000;

/// Reads `n` readings; when fewer fields than the n readings and the `trailer` fields after them
/// remain, reports the counts rather than a confusing parse error.
void readValues(Fields& f, std::size_t n, std::size_t trailer, const char* what, std::vector<float>& out)
{
  if (f.remaining() < n + trailer)
  {
    const std::size_t available = f.remaining() >= trailer ? f.remaining() - trailer : 0;
    f.fail("expected " + std::to_string(n) + " " + what + ", got " + std::to_string(available) + " (" +
           std::to_string(f.remaining()) + " fields left for the " + what + " and the " +
           std::to_string(trailer) + " fields after them)");
  }
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(f.number(what));
}

void parseTrailer(Fields& f, double& timestamp, double& logger_timestamp)
{
  timestamp = f.number("timestamp");
  f.word("hostname");
  logger_timestamp = f.number("logger_timestamp");
  f.end();
}

Pose2 readPose(Fields& f, const char* x, const char* y, const char* theta)
{
  Pose2 p;
  p.x = f.number(x);
  p.y = f.number(y);
  p.theta = f.number(theta);
  return p;
}

void parseFlaser(Fields& f, CarmenScan& s)
{
  s.type = CarmenScanType::FLaser;
  const std::size_t n = f.count("num_readings", kMaxBeams);
  // n ranges, 6 pose fields, timestamp, hostname, logger_timestamp
  if (f.remaining() != n + 9)
  {
    const std::size_t available = f.remaining() >= 9 ? f.remaining() - 9 : 0;
    f.fail("expected " + std::to_string(n) + " ranges, got " + std::to_string(available));
  }
  readValues(f, n, 9, "ranges", s.ranges);
  s.laser_pose = readPose(f, "x", "y", "theta");
  s.robot_pose = readPose(f, "odom_x", "odom_y", "odom_theta");
  parseTrailer(f, s.timestamp, s.logger_timestamp);
}

/// The laser fields shared by ROBOTLASER1 and RAWLASERx, up to the remissions. `trailer`: the
/// number of fields after the remissions.
void parseLaserFields(Fields& f, CarmenScan& s, std::size_t trailer)
{
  s.laser_type = f.integer("laser_type");
  s.start_angle = f.number("start_angle");
  s.field_of_view = f.number("field_of_view");
  const std::string fov_field = std::to_string(f.field());
  s.angular_resolution = f.number("angular_resolution");
  const std::string res_field = std::to_string(f.field());
  s.max_range = f.number("maximum_range");
  s.accuracy = f.number("accuracy");
  s.remission_mode = f.integer("remission_mode");
  if (!(s.angular_resolution > 0.0))
    f.fail("angular_resolution (field " + res_field + ") must be positive, got " +
           std::to_string(s.angular_resolution));
  if (s.field_of_view < 0.0)
    f.fail("field_of_view (field " + fov_field + ") must not be negative, got " +
           std::to_string(s.field_of_view));
  const std::size_t n = f.count("num_readings", kMaxBeams);
  // The beams span the field of view to within half a beam: n = fov/res (interlaced scans) or
  // fov/res + 1 (a beam at both ends).
  const double beams = s.field_of_view / s.angular_resolution;
  if (static_cast<double>(n) < beams - 0.5 || static_cast<double>(n) > beams + 1.5)
  {
    std::string expected;
    if (beams <= static_cast<double>(kMaxBeams))
    {
      const long lo = static_cast<long>(std::ceil(beams - 0.5)),
                 hi = static_cast<long>(std::floor(beams + 1.5));
      expected = std::to_string(lo);
      for (long k = lo + 1; k <= hi; ++k) expected += (k == hi ? " or " : ", ") + std::to_string(k);
    }
    else  // no count of beams a log can hold (and none a long can)
      expected = "about " + std::to_string(beams);
    f.fail("num_readings (field " + std::to_string(f.field()) + ") is " + std::to_string(n) +
           ", but field_of_view " + std::to_string(s.field_of_view) + " at angular_resolution " +
           std::to_string(s.angular_resolution) + " (fields " + fov_field + ", " + res_field + ") holds " +
           expected + " beams");
  }
  readValues(f, n, 1 + trailer, "ranges", s.ranges);
  const std::size_t m = f.count("num_remissions", kMaxBeams);
  readValues(f, m, trailer, "remissions", s.remissions);
}

void parseRobotLaser1(Fields& f, CarmenScan& s)
{
  s.type = CarmenScanType::RobotLaser1;
  // After the remissions: 6 pose fields, tv, rv, 3 safety fields, timestamp, hostname, logger_timestamp.
  parseLaserFields(f, s, 14);
  s.laser_pose = readPose(f, "laser_pose_x", "laser_pose_y", "laser_pose_theta");
  s.robot_pose = readPose(f, "robot_pose_x", "robot_pose_y", "robot_pose_theta");
  s.tv = f.number("tv");
  s.rv = f.number("rv");
  s.forward_safety_dist = f.number("forward_safety_dist");
  s.side_safety_dist = f.number("side_safety_dist");
  s.turn_axis = f.number("turn_axis");
  parseTrailer(f, s.timestamp, s.logger_timestamp);
}

void parseRawLaser(Fields& f, CarmenScan& s, int index)
{
  s.type = CarmenScanType::RawLaser;
  s.raw_laser = index;
  parseLaserFields(f, s, 3);  // timestamp, hostname, logger_timestamp
  parseTrailer(f, s.timestamp, s.logger_timestamp);
}

/// x of "RAWLASERx" (1..4), else 0.
int rawLaserIndex(std::string_view type)
{
  constexpr std::string_view prefix = "RAWLASER";
  if (type.size() != prefix.size() + 1 || type.substr(0, prefix.size()) != prefix) return 0;
  const char c = type.back();
  return c >= '1' && c <= '4' ? c - '0' : 0;
}

void parseOdom(Fields& f, CarmenOdom& o)
{
  o.pose = readPose(f, "x", "y", "theta");
  o.tv = f.number("tv");
  o.rv = f.number("rv");
  o.accel = f.number("accel");
  parseTrailer(f, o.timestamp, o.logger_timestamp);
}

bool startsWith(const std::string& s, const char* magic, std::size_t n)
{
  return s.size() >= n && std::memcmp(s.data(), magic, n) == 0;
}

}  // namespace

std::string readMaybeCompressedFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path + ": read error");

  const bool gz = startsWith(raw, "\x1f\x8b", 2);
  const bool bz = startsWith(raw, "BZh", 3);
  if (!gz && !bz) return raw;
  namespace io = boost::iostreams;
  std::string text;
  try
  {
    io::filtering_istream stream;
    if (gz)
      stream.push(io::gzip_decompressor());
    else
      stream.push(io::bzip2_decompressor());
    stream.push(io::array_source(raw.data(), raw.size()));
    text.reserve(raw.size() * 8);
    io::copy(stream, io::back_inserter(text));
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(path + ": corrupt " + (gz ? "gzip" : "bzip2") + " data: " + e.what());
  }
  return text;
}

namespace
{
/// Adds one tokenized line (a laser scan, odometry or a parameter) to the log; throws LineError.
/// Returns true when the log holds options.max_scans scans.
bool parseRecord(const std::vector<std::string_view>& tokens, std::size_t line_no,
                 const CarmenReadOptions& options, CarmenLog& log)
{
  const std::string_view type = tokens[0];
  if (type.front() == '#')
  {
    ++log.skipped_unknown;
    return false;
  }
  const int raw_laser = rawLaserIndex(type);
  if (type == "FLASER" || type == "ROBOTLASER1" || raw_laser > 0)
  {
    static const char* const kRawNames[] = {"", "RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4"};
    Fields f(raw_laser > 0 ? kRawNames[raw_laser] : type == "FLASER" ? "FLASER" : "ROBOTLASER1", tokens);
    CarmenScan scan;
    if (raw_laser > 0)
      parseRawLaser(f, scan, raw_laser);
    else if (type == "FLASER")
      parseFlaser(f, scan);
    else
      parseRobotLaser1(f, scan);
    scan.line = line_no;
    log.scans.push_back(std::move(scan));
    return options.max_scans > 0 && log.scans.size() >= options.max_scans;
  }
  if (type == "ODOM")
  {
    Fields f("ODOM", tokens);
    CarmenOdom odom;
    parseOdom(f, odom);
    odom.line = line_no;
    log.odometry.push_back(odom);
  }
  else if (type == "PARAM")
  {
    Fields f("PARAM", tokens);
    const std::string_view key = f.word("name");
    const std::string_view value = f.word("value");
    log.params[std::string(key)] = std::string(value);
  }
  else
  {
    ++log.skipped_unknown;
  }
  return false;
}
}  // namespace

CarmenLog parseCarmenLog(const std::string& text, const std::string& name, const CarmenReadOptions& options)
{
  CarmenLog log;
  log.path = name;
  const std::string shown = linemap::baseName(name);
  std::vector<std::string_view> tokens;
  tokens.reserve(512);
  const char* p = text.data();
  const char* const end = p + text.size();
  std::size_t line_no = 0;

  while (p < end)
  {
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', end - p));
    const char* line_end = nl ? nl : end;
    const std::string_view line(p, line_end - p);
    p = nl ? nl + 1 : end;
    ++line_no;
    try
    {
      if (line.size() > options.max_line_length)
        throw LineError{"line is " + std::to_string(line.size()) + " bytes long, longer than the limit of " +
                        std::to_string(options.max_line_length)};
      tokenize(line, tokens);
      if (tokens.empty()) continue;
      if (parseRecord(tokens, line_no, options, log)) break;
    }
    catch (const LineError& e)
    {
      const std::string message = shown + ":" + std::to_string(line_no) + ": " + e.message;
      if (!options.lenient) throw std::runtime_error(message);
      ++log.skipped_bad;
      if (log.problems.size() < 20) log.problems.push_back(message);
    }
  }
  log.lines = line_no;
  return log;
}

CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options)
{
  return parseCarmenLog(readMaybeCompressedFile(path), path, options);
}

namespace
{
std::uint64_t hashRanges(const std::vector<float>& ranges)
{
  // FNV-1a over the bit patterns: equal vectors (as parsed from the same text) hash equally.
  std::uint64_t h = 1469598103934665603ull;
  for (const float r : ranges)
  {
    std::uint32_t bits;
    std::memcpy(&bits, &r, sizeof bits);
    for (int b = 0; b < 4; ++b)
    {
      h ^= (bits >> (8 * b)) & 0xffu;
      h *= 1099511628211ull;
    }
  }
  return h ^ ranges.size();
}
}  // namespace

std::vector<std::size_t> pairKeyframes(const CarmenLog& raw, const CarmenLog& corrected)
{
  std::unordered_multimap<std::uint64_t, std::size_t> index;
  index.reserve(raw.scans.size());
  for (std::size_t i = 0; i < raw.scans.size(); ++i) index.emplace(hashRanges(raw.scans[i].ranges), i);

  std::vector<std::size_t> pairs;
  pairs.reserve(corrected.scans.size());
  for (std::size_t k = 0; k < corrected.scans.size(); ++k)
  {
    const auto& ranges = corrected.scans[k].ranges;
    const bool has_previous = !pairs.empty();
    const std::size_t previous = has_previous ? pairs.back() : 0;
    std::size_t best = raw.scans.size();
    const auto [first, last] = index.equal_range(hashRanges(ranges));
    for (auto it = first; it != last; ++it)
    {
      const std::size_t i = it->second;
      if ((has_previous && i <= previous) || i >= best) continue;
      if (raw.scans[i].ranges == ranges) best = i;
    }
    if (best == raw.scans.size())
    {
      throw std::runtime_error(
          linemap::baseName(corrected.path) + ":" + std::to_string(corrected.scans[k].line) + ": keyframe " +
          std::to_string(k) + " has no scan with identical ranges in " + linemap::baseName(raw.path) +
          (has_previous ? " after raw scan " + std::to_string(previous) : std::string()) +
          " (is it the matching raw log, and is the raw log complete?)");
    }
    pairs.push_back(best);
  }
  return pairs;
}

double carmenNoReturnFloor(const CarmenLog& log)
{
  float largest = 0.0f;
  for (const CarmenScan& s : log.scans)
    for (const float r : s.ranges)
      if (std::isfinite(r)) largest = std::max(largest, r);
  if (!(largest > 0.0f)) return 0.0;
  const double lowest_code = static_cast<double>(largest) * (1.0 - kNoReturnSpan);
  std::set<float, std::greater<float>> near_top;  // distinct readings within the span, largest first
  for (const CarmenScan& s : log.scans)
    for (const float r : s.ranges)
      if (std::isfinite(r) && r >= lowest_code) near_top.insert(r);
  float floor = largest;
  for (const float r : near_top)
  {
    // The margin absorbs float rounding: 81.89f - 81.87f is 0.0200005 m.
    if (static_cast<double>(floor - r) > kNoReturnStep + 1e-4) break;
    floor = r;
  }
  return floor;
}

ScanGeometry carmenBeamGeometry(std::size_t beam_count, double no_return, double range_min)
{
  if (beam_count < 2) throw std::invalid_argument("carmenBeamGeometry: need at least 2 beams");
  ScanGeometry g;
  g.beam_count = beam_count;
  const double span =
      beam_count % 2 == 0 ? static_cast<double>(beam_count) : static_cast<double>(beam_count - 1);
  g.angle_increment = linemap::kPi / span;
  g.angle_min = -0.5 * static_cast<double>(beam_count - 1) * g.angle_increment;
  g.range_min = range_min;
  g.range_max = no_return - 0.005;
  return g;
}

ScanGeometry carmenScanGeometry(const CarmenScan& scan, double no_return, double range_min)
{
  if (scan.type == CarmenScanType::FLaser)
  {
    if (!(no_return > 0.0)) throw std::invalid_argument("carmenScanGeometry: FLASER needs a no-return value");
    return carmenBeamGeometry(scan.ranges.size(), no_return, range_min);
  }
  const std::size_t n = scan.ranges.size();
  ScanGeometry g;
  g.beam_count = n;
  g.angle_min = scan.start_angle;
  g.angle_increment = scan.angular_resolution > 0.0 || n < 2
                          ? scan.angular_resolution
                          : scan.field_of_view / static_cast<double>(n - 1);
  g.range_min = range_min;
  g.range_max = (no_return > 0.0 ? no_return : scan.max_range) - 0.005;
  return g;
}

}  // namespace line_map_eval
