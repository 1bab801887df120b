// Ground truth: visible face pieces per scan and the linemap_truth/2 YAML file.
#include "line_map_eval/simulation/ground_truth.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

namespace line_map_eval
{
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

std::vector<VisibleWall> visibleWallPieces(const std::vector<Segment2>& walls, const Pose2& laser_pose,
                                           double angle_min, double angle_increment,
                                           const std::vector<int>& hit_wall,
                                           const std::vector<double>& hit_range, std::size_t min_beams,
                                           const std::vector<std::vector<std::size_t>>& curves)
{
  if (hit_wall.size() != hit_range.size())
    throw std::invalid_argument("visibleWallPieces: hit_wall and hit_range differ in size");
  struct Span
  {
    double t_min = std::numeric_limits<double>::infinity();
    double t_max = -std::numeric_limits<double>::infinity();
    std::size_t beams = 0;
    std::size_t last_beam = 0;
    std::vector<std::pair<double, double>> runs;  ///< [t_from, t_to] per run of consecutive beams
  };
  std::map<std::size_t, Span> spans;  // ordered by wall index
  const Vec2 origin = laser_pose.translation();
  for (std::size_t i = 0; i < hit_wall.size(); ++i)
  {
    if (hit_wall[i] < 0) continue;
    const auto w = static_cast<std::size_t>(hit_wall[i]);
    if (w >= walls.size()) throw std::invalid_argument("visibleWallPieces: wall index out of range");
    const double a = laser_pose.theta + angle_min + static_cast<double>(i) * angle_increment;
    const Vec2 p = origin + hit_range[i] * Vec2(std::cos(a), std::sin(a));
    // Position of the hit along the wall, 0 at its start and 1 at its end.
    const Vec2 d = walls[w].end - walls[w].start;
    const double t = std::clamp((p - walls[w].start).dot(d) / d.squaredNorm(), 0.0, 1.0);
    Span& s = spans[w];
    s.t_min = std::min(s.t_min, t);
    s.t_max = std::max(s.t_max, t);
    if (s.beams == 0 || s.last_beam + 1 != i)
      s.runs.emplace_back(t, t);
    else
      s.runs.back() = {std::min(s.runs.back().first, t), std::max(s.runs.back().second, t)};
    s.last_beam = i;
    ++s.beams;
  }
  std::vector<VisibleWall> all;
  for (const auto& [w, s] : spans)
  {
    const Vec2 a = walls[w].start, d = walls[w].end - a;
    VisibleWall v{w, Segment2(a + s.t_min * d, a + s.t_max * d), s.beams, {}};
    if (s.runs.size() > 1)
    {
      auto runs = s.runs;
      std::sort(runs.begin(), runs.end());
      for (const auto& [from, to] : runs) v.runs.emplace_back(a + from * d, a + to * d);
    }
    all.push_back(std::move(v));
  }
  std::vector<bool> keep(all.size(), false);
  for (const auto& sight : sights(walls, all, curves))
  {
    std::size_t beams = 0;
    for (const std::size_t i : sight) beams += all[i].beams;
    if (beams >= min_beams)
      for (const std::size_t i : sight) keep[i] = true;
  }
  std::vector<VisibleWall> out;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (keep[i]) out.push_back(all[i]);
  return out;
}

namespace
{
/// Whether two faces share an end (consecutive chords of a curve do, exactly).
bool meet(const Segment2& a, const Segment2& b)
{
  constexpr double kMeet = 1e-6;  // [m]
  for (const Vec2& p : {a.start, a.end})
    for (const Vec2& q : {b.start, b.end})
      if ((p - q).norm() <= kMeet) return true;
  return false;
}
}  // namespace

std::vector<std::vector<std::size_t>> sights(const std::vector<Segment2>& walls,
                                             const std::vector<VisibleWall>& visible,
                                             const std::vector<std::vector<std::size_t>>& curves)
{
  // Where each visible face sits in a curve.
  std::map<std::size_t, std::pair<std::size_t, std::size_t>> place;  // face -> (curve, position)
  for (std::size_t c = 0; c < curves.size(); ++c)
    for (std::size_t k = 0; k < curves[c].size(); ++k)
    {
      if (curves[c][k] >= walls.size())
        throw std::invalid_argument("ground truth: curves[" + std::to_string(c) + "] lists face " +
                                    std::to_string(curves[c][k]) + " of " + std::to_string(walls.size()));
      place[curves[c][k]] = {c, k};
    }
  std::vector<std::vector<std::size_t>> groups;
  // Per curve, the visible index at each position (npos: not visible in this scan).
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::map<std::size_t, std::vector<std::size_t>> on_curve;
  for (std::size_t i = 0; i < visible.size(); ++i)
  {
    const auto it = place.find(visible[i].wall);
    if (it == place.end())
    {
      groups.push_back({i});
      continue;
    }
    auto& at = on_curve[it->second.first];
    if (at.empty()) at.assign(curves[it->second.first].size(), kNone);
    at[it->second.second] = i;
  }
  for (const auto& [c, at] : on_curve)
  {
    const auto& faces = curves[c];
    const std::size_t n = faces.size();
    const auto linked = [&](std::size_t k)  // position k and the next one form one run
    {
      return at[k] != kNone && at[(k + 1) % n] != kNone && meet(walls[faces[k]], walls[faces[(k + 1) % n]]);
    };
    // Start the runs after a break, so a run across the seam of a closed curve stays whole.
    std::size_t first = 0;
    while (first < n && (at[first] == kNone || (n > 1 && linked((first + n - 1) % n)))) ++first;
    if (first == n)  // closed curve visible all around, or nothing to start from
    {
      std::vector<std::size_t> all;
      for (const std::size_t i : at)
        if (i != kNone) all.push_back(i);
      if (!all.empty()) groups.push_back(all);
      continue;
    }
    for (std::size_t step = 0; step < n; ++step)
    {
      const std::size_t k = (first + step) % n;
      if (at[k] == kNone) continue;
      const bool continues = step > 0 && linked((k + n - 1) % n);
      if (!continues) groups.emplace_back();
      groups.back().push_back(at[k]);
    }
  }
  std::sort(groups.begin(), groups.end(),
            [](const auto& a, const auto& b)
            { return *std::min_element(a.begin(), a.end()) < *std::min_element(b.begin(), b.end()); });
  return groups;
}

std::string truthPathForBag(const std::string& bag_path)
{
  const std::string ext = ".bag";
  if (bag_path.size() > ext.size() && bag_path.compare(bag_path.size() - ext.size(), ext.size(), ext) == 0)
    return bag_path.substr(0, bag_path.size() - ext.size()) + ".truth.yaml";
  return bag_path + ".truth.yaml";
}

namespace
{
/// Shortest decimal text that reads back as exactly `v`.
std::string num(double v)
{
  std::array<char, 32> buf;
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  return std::string(buf.data(), res.ptr);
}

std::string quoted(const std::string& s)
{
  std::string out = "\"";
  for (const char c : s)
  {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string list(std::initializer_list<double> values)
{
  std::string out = "[";
  for (const double v : values) out += (out.size() > 1 ? ", " : "") + num(v);
  return out + "]";
}

class TruthParser
{
 public:
  explicit TruthParser(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) const
  {
    std::string msg = file_ + ": " + key + ": " + problem;
    if (at.IsDefined() && at.Mark().line >= 0) msg += " (line " + std::to_string(at.Mark().line + 1) + ")";
    throw std::runtime_error(msg);
  }

  YAML::Node require(const YAML::Node& map, const char* name, const std::string& key) const
  {
    const YAML::Node n = map[name];
    if (!n) fail(key, "missing key", map);
    return n;
  }

  double number(const YAML::Node& n, const std::string& key) const
  {
    try
    {
      if (n.IsScalar()) return n.as<double>();
    }
    catch (const YAML::Exception&)
    {
    }
    fail(key, "expected a number", n);
  }

  std::size_t count(const YAML::Node& n, const std::string& key) const
  {
    const double v = number(n, key);
    if (v < 0 || v != std::floor(v)) fail(key, "expected a non-negative integer", n);
    return static_cast<std::size_t>(v);
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& key, std::size_t size) const
  {
    if (!n.IsSequence() || n.size() != size)
      fail(key, "expected a list of " + std::to_string(size) + " numbers", n);
    std::vector<double> v;
    for (std::size_t i = 0; i < size; ++i) v.push_back(number(n[i], key + "[" + std::to_string(i) + "]"));
    return v;
  }

  Segment2 segment(const YAML::Node& n, const std::string& key) const
  {
    const auto v = numbers(n, key, 4);
    return {Vec2(v[0], v[1]), Vec2(v[2], v[3])};
  }

  Pose2 pose(const YAML::Node& n, const std::string& key) const
  {
    const auto v = numbers(n, key, 3);
    return {v[0], v[1], v[2]};
  }

  GroundTruth parse(const YAML::Node& root) const
  {
    if (!root.IsMap()) fail("(top level)", "expected a mapping", root);
    checkFormat(require(root, "format", "format"));
    GroundTruth t;
    t.world = require(root, "world", "world").as<std::string>();
    t.laser = parseLaser(require(root, "laser", "laser"));
    t.base_to_laser = pose(require(root, "base_to_laser", "base_to_laser"), "base_to_laser");
    if (root["min_beams"]) t.min_beams = count(root["min_beams"], "min_beams");
    if (const YAML::Node reg = root["registration"])
    {
      t.registration_position =
          number(require(reg, "position", "registration/position"), "registration/position");
      t.registration_heading =
          number(require(reg, "heading", "registration/heading"), "registration/heading");
      if (!(t.registration_position >= 0.0) || !(t.registration_heading >= 0.0))
        fail("registration", "position and heading must be >= 0", reg);
    }
    parseSolids(require(root, "solids", "solids"), t);
    const YAML::Node walls = require(root, "walls", "walls");
    if (!walls.IsSequence()) fail("walls", "expected a list", walls);
    for (std::size_t i = 0; i < walls.size(); ++i)
      t.walls.push_back(segment(walls[i], "walls[" + std::to_string(i) + "]"));
    if (const YAML::Node curves = root["curves"]) parseCurves(curves, t);
    const YAML::Node scans = require(root, "scans", "scans");
    if (!scans.IsSequence()) fail("scans", "expected a list", scans);
    for (std::size_t i = 0; i < scans.size(); ++i)
      t.scans.push_back(parseScan(scans[i], "scans[" + std::to_string(i) + "]", t.walls.size()));
    return t;
  }

 private:
  void checkFormat(const YAML::Node& format) const
  {
    if (format.IsScalar() && format.Scalar() == "linemap_truth/1")
      fail("format",
           "linemap_truth/1 (thin, undirected walls) is no longer read: simulate the world again to write " +
               std::string(kTruthFormat),
           format);
    if (!format.IsScalar() || format.Scalar() != kTruthFormat)
      fail("format",
           std::string("expected ") + kTruthFormat + ", got '" + (format.IsScalar() ? format.Scalar() : "") +
               "'",
           format);
  }

  TruthLaser parseLaser(const YAML::Node& laser) const
  {
    TruthLaser l;
    l.beams = count(require(laser, "beams", "laser/beams"), "laser/beams");
    l.angle_min = number(require(laser, "angle_min", "laser/angle_min"), "laser/angle_min");
    l.angle_increment =
        number(require(laser, "angle_increment", "laser/angle_increment"), "laser/angle_increment");
    if (laser["range_min"]) l.range_min = number(laser["range_min"], "laser/range_min");
    l.range_max = number(require(laser, "range_max", "laser/range_max"), "laser/range_max");
    l.sigma = number(require(laser, "sigma", "laser/sigma"), "laser/sigma");
    l.spurious = number(require(laser, "spurious", "laser/spurious"), "laser/spurious");
    if (laser["sigma_slope"]) l.sigma_slope = number(laser["sigma_slope"], "laser/sigma_slope");
    return l;
  }

  void parseSolids(const YAML::Node& solids, GroundTruth& t) const
  {
    if (!solids.IsSequence()) fail("solids", "expected a list", solids);
    for (std::size_t i = 0; i < solids.size(); ++i)
    {
      const std::string key = "solids[" + std::to_string(i) + "]";
      if (!solids[i].IsMap()) fail(key, "expected a mapping with segment, thickness", solids[i]);
      Wall w;
      w.segment = segment(require(solids[i], "segment", key + "/segment"), key + "/segment");
      w.thickness = number(require(solids[i], "thickness", key + "/thickness"), key + "/thickness");
      if (!(w.thickness >= 0.0)) fail(key + "/thickness", "must be >= 0", solids[i]["thickness"]);
      if (solids[i]["arc"]) w.arc = static_cast<int>(count(solids[i]["arc"], key + "/arc"));
      t.solids.push_back(w);
    }
  }

  /// A face index below `walls`.
  std::size_t faceIndex(const YAML::Node& n, const std::string& key, std::size_t walls) const
  {
    const std::size_t f = count(n, key);
    if (f >= walls)
      fail(key, "index " + std::to_string(f) + " is beyond the " + std::to_string(walls) + " walls", n);
    return f;
  }

  void parseCurves(const YAML::Node& curves, GroundTruth& t) const
  {
    if (!curves.IsSequence()) fail("curves", "expected a list of lists of face indices", curves);
    for (std::size_t i = 0; i < curves.size(); ++i)
    {
      const std::string key = "curves[" + std::to_string(i) + "]";
      if (!curves[i].IsSequence()) fail(key, "expected a list of face indices", curves[i]);
      t.curves.emplace_back();
      for (std::size_t j = 0; j < curves[i].size(); ++j)
        t.curves.back().push_back(
            faceIndex(curves[i][j], key + "[" + std::to_string(j) + "]", t.walls.size()));
    }
  }

  TruthScan parseScan(const YAML::Node& s, const std::string& key, std::size_t walls) const
  {
    if (!s.IsMap()) fail(key, "expected a mapping with stamp, pose, visible", s);
    TruthScan ts;
    ts.stamp = number(require(s, "stamp", key + "/stamp"), key + "/stamp");
    ts.pose = pose(require(s, "pose", key + "/pose"), key + "/pose");
    const YAML::Node vis = require(s, "visible", key + "/visible");
    if (!vis.IsSequence()) fail(key + "/visible", "expected a list", vis);
    for (std::size_t j = 0; j < vis.size(); ++j)
    {
      const std::string vkey = key + "/visible[" + std::to_string(j) + "]";
      VisibleWall v;
      v.wall = count(require(vis[j], "wall", vkey + "/wall"), vkey + "/wall");
      if (v.wall >= walls)
        fail(vkey + "/wall",
             "index " + std::to_string(v.wall) + " is beyond the " + std::to_string(walls) + " walls",
             vis[j]);
      v.segment = segment(require(vis[j], "segment", vkey + "/segment"), vkey + "/segment");
      v.beams = count(require(vis[j], "beams", vkey + "/beams"), vkey + "/beams");
      if (const YAML::Node runs = vis[j]["runs"])
      {
        if (!runs.IsSequence()) fail(vkey + "/runs", "expected a list of segments", runs);
        for (std::size_t r = 0; r < runs.size(); ++r)
          v.runs.push_back(segment(runs[r], vkey + "/runs[" + std::to_string(r) + "]"));
      }
      ts.visible.push_back(v);
    }
    return ts;
  }

  std::string file_;
};

}  // namespace

void writeGroundTruth(const GroundTruth& t, const std::string& path)
{
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open the ground truth file for writing");
  out << "format: " << kTruthFormat << "\n";
  out << "world: " << quoted(t.world) << "\n";
  out << "laser: {beams: " << t.laser.beams << ", angle_min: " << num(t.laser.angle_min)
      << ", angle_increment: " << num(t.laser.angle_increment) << ", range_min: " << num(t.laser.range_min)
      << ", range_max: " << num(t.laser.range_max) << ", sigma: " << num(t.laser.sigma)
      << ", spurious: " << num(t.laser.spurious);
  if (t.laser.sigma_slope != 0.0) out << ", sigma_slope: " << num(t.laser.sigma_slope);
  out << "}\n";
  out << "base_to_laser: " << list({t.base_to_laser.x, t.base_to_laser.y, t.base_to_laser.theta}) << "\n";
  out << "min_beams: " << t.min_beams << "\n";
  if (t.registration_position != 0.0 || t.registration_heading != 0.0)
    out << "registration: {position: " << num(t.registration_position)
        << ", heading: " << num(t.registration_heading) << "}\n";
  out << "# the world's walls: centre line and thickness (0: thin, seen from both sides)\n";
  out << "solids:" << (t.solids.empty() ? " []" : "") << "\n";
  for (const auto& w : t.solids)
    out << "  - {segment: "
        << list({w.segment.start.x(), w.segment.start.y(), w.segment.end.x(), w.segment.end.y()})
        << ", thickness: " << num(w.thickness) << (w.arc >= 0 ? ", arc: " + std::to_string(w.arc) : "")
        << "}\n";
  out << "# the true lines: faces of the solids, directed with free space on the left\n";
  out << "walls:" << (t.walls.empty() ? " []" : "") << "\n";
  for (const auto& w : t.walls)
    out << "  - " << list({w.start.x(), w.start.y(), w.end.x(), w.end.y()}) << "\n";
  if (!t.curves.empty())
  {
    out << "# the faces of each curved surface (an arc's side), in order along it\n";
    out << "curves:\n";
    for (const auto& c : t.curves)
    {
      out << "  - [";
      for (std::size_t i = 0; i < c.size(); ++i) out << (i ? ", " : "") << c[i];
      out << "]\n";
    }
  }
  out << "scans:" << (t.scans.empty() ? " []" : "") << "\n";
  for (const auto& s : t.scans)
  {
    out << "  - stamp: " << num(s.stamp) << "\n";
    out << "    pose: " << list({s.pose.x, s.pose.y, s.pose.theta}) << "\n";
    out << "    visible:" << (s.visible.empty() ? " []" : "") << "\n";
    for (const auto& v : s.visible)
    {
      const auto coordinates = [](const Segment2& g) {
        return list({g.start.x(), g.start.y(), g.end.x(), g.end.y()});
      };
      out << "      - {wall: " << v.wall << ", segment: " << coordinates(v.segment) << ", beams: " << v.beams;
      if (!v.runs.empty())
      {
        out << ", runs: [";
        for (std::size_t r = 0; r < v.runs.size(); ++r) out << (r ? ", " : "") << coordinates(v.runs[r]);
        out << "]";
      }
      out << "}\n";
    }
  }
  out.flush();
  if (!out) throw std::runtime_error(path + ": writing the ground truth file failed");
}

GroundTruth readGroundTruth(const std::string& path)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the ground truth file");
  YAML::Node root;
  try
  {
    root = YAML::Load(in);
  }
  catch (const YAML::ParserException& e)
  {
    throw std::runtime_error(path + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " +
                             e.msg);
  }
  return TruthParser(path).parse(root);
}

}  // namespace line_map_eval
