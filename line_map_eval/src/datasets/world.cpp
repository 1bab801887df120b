// World files: parsing with errors that name the file, the key and the line.
#include "line_map_eval/datasets/world.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "linemap/small_helpers.hpp"

namespace line_map_eval
{
namespace
{
using linemap::Vec2;

YAML::Node loadYaml(const std::string& text, const std::string& source)
{
  try
  {
    return YAML::Load(text);
  }
  catch (const YAML::ParserException& e)
  {
    throw std::runtime_error(source + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                             ": " + e.msg);
  }
}

std::string readFile(const std::string& path, const char* what)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the " + what);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class WorldParser
{
 public:
  explicit WorldParser(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) const
  {
    std::ostringstream msg;
    msg << source_ << ": " << key << ": " << problem;
    if (at.IsDefined() && at.Mark().line >= 0) msg << " (line " << at.Mark().line + 1 << ")";
    throw std::runtime_error(msg.str());
  }

  void checkKeys(const YAML::Node& map, const std::string& key, const std::set<std::string>& known) const
  {
    if (!map.IsMap()) fail(key.empty() ? "(top level)" : key, "expected a mapping", map);
    for (const auto& kv : map)
    {
      const std::string name = kv.first.as<std::string>();
      if (!known.count(name))
      {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        fail(key.empty() ? name : key + "/" + name, "unknown key (expected one of: " + list + ")", kv.first);
      }
    }
  }

  double number(const YAML::Node& n, const std::string& key) const
  {
    if (!n.IsScalar()) fail(key, "expected a number", n);
    double v = 0.0;
    try
    {
      v = n.as<double>();
    }
    catch (const YAML::Exception&)
    {
      fail(key, "expected a number, got '" + n.Scalar() + "'", n);
    }
    if (!std::isfinite(v)) fail(key, "expected a finite number, got '" + n.Scalar() + "'", n);
    return v;
  }

  /// Optional number with a lower bound (inclusive unless `strict`).
  void optionalNumber(const YAML::Node& map, const std::string& block, const char* name, double& out,
                      double lo, bool strict, double hi = HUGE_VAL) const
  {
    const YAML::Node n = map[name];
    if (!n) return;
    const std::string key = block + "/" + name;
    const double v = number(n, key);
    if (strict ? !(v > lo) : !(v >= lo))
      fail(key, "must be " + std::string(strict ? "> " : ">= ") + toString(lo) + ", got " + toString(v), n);
    if (v > hi) fail(key, "must be <= " + toString(hi) + ", got " + toString(v), n);
    out = v;
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& key, std::size_t count,
                              const char* shape) const
  {
    if (!n.IsSequence() || n.size() != count)
    {
      const std::string got = n.IsSequence() ? std::to_string(n.size()) + " numbers" : "no list";
      fail(key, "expected " + std::to_string(count) + " numbers " + shape + ", got " + got, n);
    }
    std::vector<double> v;
    for (std::size_t i = 0; i < count; ++i) v.push_back(number(n[i], key + "[" + std::to_string(i) + "]"));
    return v;
  }

  static std::string toString(double v)
  {
    std::ostringstream s;
    s << v;
    return s.str();
  }

  /// The `laser` block (of a world or a sensor profile): the keys it gives replace those of `out`.
  void laser(const YAML::Node& laser, LaserModel& out) const
  {
    checkKeys(laser, "laser",
              {"beams", "fov_deg", "range_min", "range_max", "sigma", "sigma_slope", "spurious", "mounting"});
    if (laser["beams"])
    {
      const double b = number(laser["beams"], "laser/beams");
      if (b < 2 || b != std::floor(b))
        fail("laser/beams", "must be an integer >= 2, got " + toString(b), laser["beams"]);
      out.beams = static_cast<std::size_t>(b);
    }
    double fov_deg = out.fov * 180.0 / linemap::kPi;
    optionalNumber(laser, "laser", "fov_deg", fov_deg, 0.0, true, 360.0);
    out.fov = fov_deg * linemap::kPi / 180.0;
    optionalNumber(laser, "laser", "range_min", out.range_min, 0.0, false);
    optionalNumber(laser, "laser", "range_max", out.range_max, 0.0, true);
    if (out.range_max <= out.range_min)
      fail("laser/range_max", "must exceed laser/range_min (" + toString(out.range_min) + ")", laser);
    optionalNumber(laser, "laser", "sigma", out.sigma, 0.0, false);
    optionalNumber(laser, "laser", "sigma_slope", out.sigma_slope, 0.0, false);
    optionalNumber(laser, "laser", "spurious", out.spurious, 0.0, false, 1.0);
    if (laser["mounting"])
    {
      const auto v = numbers(laser["mounting"], "laser/mounting", 3, "[x, y, theta]");
      out.mounting = linemap::Pose2(v[0], v[1], linemap::normalizeAngle(v[2]));
    }
  }

  /// An arc entry [cx, cy, radius, start_deg, end_deg] as its chain of pieces.
  std::vector<Wall> arc(const YAML::Node& n, const std::string& key, double thickness, double sagitta,
                        int index) const
  {
    const auto v = numbers(n, key, 5, "[cx, cy, radius, start_deg, end_deg]");
    if (!(v[2] > 0.0)) fail(key, "the radius must be > 0, got " + toString(v[2]), n);
    if (v[3] == v[4]) fail(key, "the arc has zero sweep (start_deg = end_deg = " + toString(v[3]) + ")", n);
    if (std::abs(v[4] - v[3]) > 360.0)
      fail(key, "the sweep end_deg - start_deg must be at most 360, got " + toString(v[4] - v[3]), n);
    constexpr double deg = linemap::kPi / 180.0;
    return arcPieces({Vec2(v[0], v[1]), v[2], v[3] * deg, v[4] * deg}, thickness, sagitta, index);
  }

  SensorProfile profile(const YAML::Node& root, const LaserModel& base) const
  {
    if (!root.IsDefined() || root.IsNull()) fail("(top level)", "the file is empty", root);
    checkKeys(root, "", {"name", "laser"});
    SensorProfile p;
    p.name = root["name"] ? root["name"].as<std::string>() : linemap::fileStem(source_);
    p.laser = base;
    if (!root["laser"]) fail("laser", "missing key (the sensor's laser block, as in a world file)", root);
    laser(root["laser"], p.laser);
    return p;
  }

  World parse(const YAML::Node& root) const
  {
    World w;
    w.source = source_;
    if (!root.IsDefined() || root.IsNull()) fail("(top level)", "the file is empty", root);
    checkKeys(root, "",
              {"name", "seed", "walls", "wall_thickness", "arc_sagitta", "path", "laser", "odometry",
               "registration", "min_visible_beams"});
    parseSettings(root, w);
    parseWalls(root, w);
    parsePath(root, w.path);
    if (const YAML::Node l = root["laser"]) laser(l, w.laser);
    if (const YAML::Node odo = root["odometry"])
    {
      checkKeys(odo, "odometry", {"translation_noise", "rotation_noise", "heading_noise", "heading_bias"});
      optionalNumber(odo, "odometry", "translation_noise", w.odometry.translation_noise, 0.0, false);
      optionalNumber(odo, "odometry", "rotation_noise", w.odometry.rotation_noise, 0.0, false);
      optionalNumber(odo, "odometry", "heading_noise", w.odometry.heading_noise, 0.0, false);
      optionalNumber(odo, "odometry", "heading_bias", w.odometry.heading_bias, -HUGE_VAL, false);
    }
    if (const YAML::Node reg = root["registration"])
    {
      checkKeys(reg, "registration", {"position", "heading_deg", "correlation_length"});
      optionalNumber(reg, "registration", "position", w.registration.position, 0.0, false);
      double heading_deg = w.registration.heading * 180.0 / linemap::kPi;
      optionalNumber(reg, "registration", "heading_deg", heading_deg, 0.0, false);
      w.registration.heading = heading_deg * linemap::kPi / 180.0;
      optionalNumber(reg, "registration", "correlation_length", w.registration.correlation_length, 0.0, true);
    }
    return w;
  }

 private:
  /// name, seed, min_visible_beams and the defaults of the walls.
  void parseSettings(const YAML::Node& root, World& w) const
  {
    if (root["name"]) w.name = root["name"].as<std::string>();
    if (w.name.empty()) w.name = linemap::fileStem(source_);
    if (root["seed"])
    {
      const double s = number(root["seed"], "seed");
      if (s < 0 || s > 4294967295.0 || s != std::floor(s))
        fail("seed", "must be an integer in [0, 2^32), got " + toString(s), root["seed"]);
      w.seed = static_cast<std::uint32_t>(s);
    }
    if (root["min_visible_beams"])
    {
      const double m = number(root["min_visible_beams"], "min_visible_beams");
      if (m < 1 || m != std::floor(m))
        fail("min_visible_beams", "must be an integer >= 1, got " + toString(m), root["min_visible_beams"]);
      w.min_visible_beams = static_cast<std::size_t>(m);
    }

    if (root["wall_thickness"])
    {
      w.wall_thickness = number(root["wall_thickness"], "wall_thickness");
      if (w.wall_thickness < 0.0)
        fail("wall_thickness", "must be >= 0, got " + toString(w.wall_thickness), root["wall_thickness"]);
    }
    if (root["arc_sagitta"])
    {
      w.arc_sagitta = number(root["arc_sagitta"], "arc_sagitta");
      if (!(w.arc_sagitta > 0.0))
        fail("arc_sagitta", "must be > 0, got " + toString(w.arc_sagitta), root["arc_sagitta"]);
    }
  }

  void parseWalls(const YAML::Node& root, World& w) const
  {
    const YAML::Node walls = root["walls"];
    const char* kWallForms =
        "[x1, y1, x2, y2], {segment: [x1, y1, x2, y2], thickness: t} or {arc: [cx, cy, radius, start_deg, "
        "end_deg], thickness: t}";
    if (!walls) fail("walls", std::string("missing key (a list of ") + kWallForms + ")", root);
    if (!walls.IsSequence() || walls.size() == 0)
      fail("walls", std::string("expected a non-empty list of ") + kWallForms, walls);
    int arcs = 0;
    for (std::size_t i = 0; i < walls.size(); ++i)
      parseWall(walls[i], "walls[" + std::to_string(i) + "]", w, arcs);
  }

  /// One entry of `walls`: a segment, or an arc's chain of pieces (`arcs` counts the arcs so far).
  void parseWall(const YAML::Node& entry, const std::string& key, World& w, int& arcs) const
  {
    Wall wall;
    wall.thickness = w.wall_thickness;
    const bool with_thickness = entry.IsMap();
    if (with_thickness)
    {
      checkKeys(entry, key, {"segment", "arc", "thickness"});
      if (entry["segment"] && entry["arc"]) fail(key, "give either segment or arc, not both", entry);
      if (!entry["segment"] && !entry["arc"])
        fail(key + "/segment", "missing key ([x1, y1, x2, y2], or arc: [cx, cy, radius, start_deg, end_deg])",
             entry);
      optionalNumber(entry, key, "thickness", wall.thickness, 0.0, false);
      if (const YAML::Node a = entry["arc"])
      {
        const auto pieces = arc(a, key + "/arc", wall.thickness, w.arc_sagitta, arcs++);
        w.walls.insert(w.walls.end(), pieces.begin(), pieces.end());
        return;
      }
    }
    // (A new Node, not an assignment: assigning a yaml-cpp Node overwrites the node it refers to.)
    const YAML::Node at = with_thickness ? entry["segment"] : entry;
    const auto v = numbers(at, with_thickness ? key + "/segment" : key, 4, "[x1, y1, x2, y2]");
    wall.segment = linemap::Segment2(Vec2(v[0], v[1]), Vec2(v[2], v[3]));
    if (wall.segment.length() <= 1e-9) fail(key, "the wall has zero length", entry);
    w.walls.push_back(wall);
  }

  void parsePath(const YAML::Node& root, PathModel& out) const
  {
    const YAML::Node path = root["path"];
    if (!path) fail("path", "missing key (waypoints, speed, turn_rate, scan_period)", root);
    checkKeys(path, "path", {"waypoints", "speed", "turn_rate", "scan_period", "scans", "clearance"});
    const YAML::Node wps = path["waypoints"];
    if (!wps) fail("path/waypoints", "missing key (a list of [x, y])", path);
    if (!wps.IsSequence() || wps.size() < 2)
      fail("path/waypoints", "expected a list of at least 2 [x, y]", wps);
    for (std::size_t i = 0; i < wps.size(); ++i)
    {
      const std::string key = "path/waypoints[" + std::to_string(i) + "]";
      const auto v = numbers(wps[i], key, 2, "[x, y]");
      const Vec2 p(v[0], v[1]);
      if (!out.waypoints.empty() && (p - out.waypoints.back()).norm() < 1e-6)
        fail(key, "repeats the previous waypoint", wps[i]);
      out.waypoints.push_back(p);
    }
    if ((out.waypoints.back() - out.waypoints.front()).norm() < 1e-6)
      fail("path/waypoints", "the last waypoint repeats the first (the loop closes by itself)", wps);
    optionalNumber(path, "path", "speed", out.speed, 0.0, true);
    optionalNumber(path, "path", "turn_rate", out.turn_rate, 0.0, true);
    optionalNumber(path, "path", "scan_period", out.scan_period, 0.0, true);
    optionalNumber(path, "path", "clearance", out.clearance, 0.0, false);
    if (path["scans"])
    {
      const double n = number(path["scans"], "path/scans");
      if (n < 0 || n != std::floor(n))
        fail("path/scans", "must be an integer >= 0, got " + toString(n), path["scans"]);
      out.scans = static_cast<std::size_t>(n);
    }
  }

  std::string source_;
};

double cross(const Vec2& a, const Vec2& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// Shortest distance between the closed segments [p1, p2] and [q1, q2] (0 when they cross).
double segmentDistance(const Vec2& p1, const Vec2& p2, const Vec2& q1, const Vec2& q2)
{
  const Vec2 r = p2 - p1, s = q2 - q1;
  const double denom = cross(r, s);
  if (std::abs(denom) > 1e-15)
  {
    const double t = cross(q1 - p1, s) / denom;
    const double u = cross(q1 - p1, r) / denom;
    if (t >= 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0) return 0.0;
  }
  return std::min({linemap::distanceToSegment(p1, q1, q2), linemap::distanceToSegment(p2, q1, q2),
                   linemap::distanceToSegment(q1, p1, p2), linemap::distanceToSegment(q2, p1, p2)});
}

}  // namespace

World parseWorld(const std::string& yaml_text, const std::string& source)
{
  World w = WorldParser(source).parse(loadYaml(yaml_text, source));
  validateWorld(w);
  return w;
}

World loadWorld(const std::string& path)
{
  return parseWorld(readFile(path, "world file"), path);
}

SensorProfile parseSensorProfile(const std::string& yaml_text, const std::string& source,
                                 const LaserModel& base)
{
  return WorldParser(source).profile(loadYaml(yaml_text, source), base);
}

SensorProfile loadSensorProfile(const std::string& path, const LaserModel& base)
{
  return parseSensorProfile(readFile(path, "sensor profile"), path, base);
}

World withSensorProfile(const World& world, const std::string& profile_path)
{
  World w = world;
  const SensorProfile p = loadSensorProfile(profile_path, world.laser);
  w.laser = p.laser;
  w.name = world.name + " / " + p.name;
  validateWorld(w);
  return w;
}

void validateWorld(const World& w)
{
  const auto fail = [&](const std::string& key, const std::string& problem)
  { throw std::runtime_error(w.source + ": " + key + ": " + problem); };
  if (w.walls.empty()) fail("walls", "no walls");
  if (!(w.wall_thickness >= 0.0)) fail("wall_thickness", "must be >= 0");
  for (std::size_t k = 0; k < w.walls.size(); ++k)
    if (!(w.walls[k].thickness >= 0.0) || !std::isfinite(w.walls[k].thickness))
      fail("walls[" + std::to_string(k) + "]/thickness", "must be finite and >= 0");
  if (w.path.waypoints.size() < 2) fail("path/waypoints", "at least 2 waypoints are needed");
  if (!(w.path.speed > 0.0) || !(w.path.turn_rate > 0.0) || !(w.path.scan_period > 0.0))
    fail("path", "speed, turn_rate and scan_period must be > 0");
  if (w.laser.beams < 2) fail("laser/beams", "at least 2 beams are needed");
  if (!(w.laser.range_max > w.laser.range_min) || w.laser.range_min < 0.0)
    fail("laser/range_max", "0 <= range_min < range_max is required");
  if (!(w.laser.sigma >= 0.0)) fail("laser/sigma", "must be >= 0");
  if (!(w.laser.sigma_slope >= 0.0)) fail("laser/sigma_slope", "must be >= 0");
  if (!(w.arc_sagitta > 0.0)) fail("arc_sagitta", "must be > 0");
  if (!(w.laser.spurious >= 0.0 && w.laser.spurious <= 1.0)) fail("laser/spurious", "must be in [0, 1]");

  const auto& wp = w.path.waypoints;
  for (std::size_t i = 0; i < wp.size(); ++i)
  {
    const std::size_t j = (i + 1) % wp.size();
    for (std::size_t k = 0; k < w.walls.size(); ++k)
    {
      const Wall& wall = w.walls[k];
      const double d =
          segmentDistance(wp[i], wp[j], wall.segment.start, wall.segment.end) - 0.5 * wall.thickness;
      if (d < w.path.clearance)
      {
        std::ostringstream msg;
        msg << "the leg from waypoint " << i << " to waypoint " << j << " passes " << d
            << " m from the surface of walls[" << k << "] (path/clearance is " << w.path.clearance << " m)";
        fail("path/waypoints[" + std::to_string(i) + "]", msg.str());
      }
    }
  }
}

RegistrationModel parseRegistrationOption(const std::string& option, const std::string& value)
{
  std::vector<double> numbers;
  std::stringstream in(value);
  for (std::string item; std::getline(in, item, ',');)
  {
    std::size_t used = 0;
    double v = 0.0;
    try
    {
      v = std::stod(item, &used);
    }
    catch (const std::exception&)
    {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v) || v < 0.0)
      throw std::invalid_argument(option + ": '" + item +
                                  "' is not a number >= 0 (expected POSITION,HEADING_DEG[,LENGTH])");
    numbers.push_back(v);
  }
  if (numbers.size() < 2 || numbers.size() > 3)
    throw std::invalid_argument(
        option + " takes POSITION,HEADING_DEG[,LENGTH] (metres, degrees, metres), got '" + value + "'");
  RegistrationModel m;
  m.position = numbers[0];
  m.heading = numbers[1] * linemap::kPi / 180.0;
  if (numbers.size() == 3)
  {
    if (!(numbers[2] > 0.0)) throw std::invalid_argument(option + ": the correlation length must be > 0");
    m.correlation_length = numbers[2];
  }
  return m;
}

double pathLength(const PathModel& path)
{
  double length = 0.0;
  for (std::size_t i = 0; i < path.waypoints.size(); ++i)
    length += (path.waypoints[(i + 1) % path.waypoints.size()] - path.waypoints[i]).norm();
  return length;
}

}  // namespace line_map_eval
