// World files: parsing with errors that name the file, the key and the line.
#include "line_map_eval/datasets/world.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

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

using linemap::cross;

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

/// The keys of a world file's top level.
const std::set<std::string> kWorldKeys{"name", "seed",  "walls",    "wall_thickness", "arc_sagitta",
                                       "path", "laser", "odometry", "registration",   "min_visible_beams"};

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
    checkKeys(root, "", kWorldKeys);
    parseSettings(root, w);
    parseWalls(root, w);
    parsePath(root, w.path);
    if (const YAML::Node l = root["laser"]) laser(l, w.laser);
    if (const YAML::Node odo = root["odometry"]) odometry(odo, w.odometry);
    if (const YAML::Node reg = root["registration"]) registration(reg, w.registration);
    return w;
  }

  /// The base world file of a world with `based_on`, relative to the directory of this one when it
  /// is a file (else to the current directory).
  std::string basePath(const YAML::Node& root) const
  {
    const YAML::Node n = root["based_on"];
    if (!n.IsScalar() || n.Scalar().empty())
      fail("based_on", "expected the path of the base world file (relative to this file's directory)", n);
    std::filesystem::path base(n.Scalar());
    std::error_code ec;
    if (base.is_relative() && std::filesystem::is_regular_file(source_, ec))
      base = std::filesystem::path(source_).parent_path() / base;
    return base.string();
  }

  /// The world of `root`, which is `based_on` the world `base` read from `base_path`: the base with
  /// this file's top-level keys in place of the base's (each key whole, as if the two top-level
  /// maps were merged) and its `changes` applied to the base's walls. Not yet validated.
  World derive(const YAML::Node& root, const World& base, const std::string& base_path) const
  {
    std::set<std::string> keys = kWorldKeys;
    keys.insert({"based_on", "changes"});
    checkKeys(root, "", keys);
    if (root["walls"])
      fail("walls",
           "cannot be given with based_on (the walls are the base's: take some out and put others in "
           "under changes: remove and add)",
           root["walls"]);
    if (root["wall_thickness"])
      fail("wall_thickness",
           "cannot be changed in a world based_on another (the base's walls keep their thickness; give an "
           "added wall its own: {segment: [x1, y1, x2, y2], thickness: t})",
           root["wall_thickness"]);
    if (root["arc_sagitta"])
      fail("arc_sagitta", "cannot be changed in a world based_on another (the base's arcs keep their pieces)",
           root["arc_sagitta"]);

    World w = base;
    w.source = source_;
    w.based_on = base_path;
    w.removed_walls.clear();
    w.added_walls.clear();
    w.name.clear();  // this file's `name`, else its own base name
    parseSettings(root, w);
    if (root["path"])
    {
      w.path = PathModel{};
      parsePath(root, w.path);
    }
    if (const YAML::Node l = root["laser"])
    {
      w.laser = LaserModel{};
      laser(l, w.laser);
    }
    if (const YAML::Node odo = root["odometry"])
    {
      w.odometry = OdometryModel{};
      odometry(odo, w.odometry);
    }
    if (const YAML::Node reg = root["registration"])
    {
      w.registration = RegistrationModel{};
      registration(reg, w.registration);
    }
    const YAML::Node changes = root["changes"];
    if (changes && !changes.IsNull()) applyChanges(changes, base_path, w);
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

  void odometry(const YAML::Node& odo, OdometryModel& out) const
  {
    checkKeys(odo, "odometry", {"translation_noise", "rotation_noise", "heading_noise", "heading_bias"});
    optionalNumber(odo, "odometry", "translation_noise", out.translation_noise, 0.0, false);
    optionalNumber(odo, "odometry", "rotation_noise", out.rotation_noise, 0.0, false);
    optionalNumber(odo, "odometry", "heading_noise", out.heading_noise, 0.0, false);
    optionalNumber(odo, "odometry", "heading_bias", out.heading_bias, -HUGE_VAL, false);
  }

  void registration(const YAML::Node& reg, RegistrationModel& out) const
  {
    checkKeys(reg, "registration", {"position", "heading_deg", "correlation_length"});
    optionalNumber(reg, "registration", "position", out.position, 0.0, false);
    double heading_deg = out.heading * 180.0 / linemap::kPi;
    optionalNumber(reg, "registration", "heading_deg", heading_deg, 0.0, false);
    out.heading = heading_deg * linemap::kPi / 180.0;
    optionalNumber(reg, "registration", "correlation_length", out.correlation_length, 0.0, true);
  }

  /// `changes: {remove, add}` of a world based_on `base_path`, applied to `w`, the base's world (its
  /// path already the final one).
  void applyChanges(const YAML::Node& changes, const std::string& base_path, World& w) const
  {
    checkKeys(changes, "changes", {"remove", "add"});
    // removed_by[k]: the entry of changes.remove that takes out the base's walls[k], -1 for none.
    std::vector<int> removed_by(w.walls.size(), -1);
    if (const YAML::Node remove = changes["remove"])
    {
      if (!remove.IsSequence())
        fail("changes/remove", "expected a list of [x1, y1, x2, y2] (centre lines of the base's walls)",
             remove);
      for (std::size_t i = 0; i < remove.size(); ++i)
      {
        const std::string key = "changes/remove[" + std::to_string(i) + "]";
        const auto v = numbers(remove[i], key, 4, "[x1, y1, x2, y2] (the centre line of a wall of the base)");
        const Vec2 a(v[0], v[1]), b(v[2], v[3]);
        const auto near = [](const Vec2& p, const Vec2& q)
        { return std::abs(p.x() - q.x()) <= 1e-6 && std::abs(p.y() - q.y()) <= 1e-6; };
        int taken_by = -1;
        bool found = false;
        for (std::size_t k = 0; k < w.walls.size() && !found; ++k)
        {
          const linemap::Segment2& s = w.walls[k].segment;
          if (!((near(s.start, a) && near(s.end, b)) || (near(s.start, b) && near(s.end, a)))) continue;
          if (removed_by[k] >= 0)
          {
            taken_by = removed_by[k];
            continue;
          }
          removed_by[k] = static_cast<int>(i);
          w.removed_walls.push_back(w.walls[k]);
          found = true;
        }
        if (found) continue;
        const std::string line = "[" + toString(v[0]) + ", " + toString(v[1]) + ", " + toString(v[2]) + ", " +
                                 toString(v[3]) + "]";
        if (taken_by >= 0)
          fail(key,
               "removes the wall " + line + " again (changes/remove[" + std::to_string(taken_by) +
                   "] takes it out)",
               remove[i]);
        fail(key,
             "matches no wall of the base world " + base_path + ": no centre line is " + line +
                 " (to 1e-06 m, in either direction)",
             remove[i]);
      }
    }
    std::vector<Wall> kept;
    for (std::size_t k = 0; k < w.walls.size(); ++k)
      if (removed_by[k] < 0) kept.push_back(w.walls[k]);
    w.walls = std::move(kept);

    if (const YAML::Node add = changes["add"])
    {
      if (!add.IsSequence()) fail("changes/add", "expected a list of walls, written as in walls", add);
      int arcs = 0;  // the added arcs are numbered after the base's
      for (const Wall& wall : w.walls) arcs = std::max(arcs, wall.arc + 1);
      for (const Wall& wall : w.removed_walls) arcs = std::max(arcs, wall.arc + 1);
      for (std::size_t i = 0; i < add.size(); ++i)
      {
        const std::string key = "changes/add[" + std::to_string(i) + "]";
        const std::size_t first = w.walls.size();
        parseWall(add[i], key, w, arcs);
        w.added_walls.insert(w.added_walls.end(), w.walls.begin() + static_cast<std::ptrdiff_t>(first),
                             w.walls.end());
        for (std::size_t k = first; k < w.walls.size(); ++k) checkClearance(w.walls[k], w.path, key, add[i]);
      }
    }
  }

  /// An added wall that the path passes closer than its clearance, named with its entry's line
  /// (validateWorld() finds it too, but only by its index in the changed world's walls).
  void checkClearance(const Wall& wall, const PathModel& path, const std::string& key,
                      const YAML::Node& at) const
  {
    const auto& wp = path.waypoints;
    for (std::size_t i = 0; i < wp.size(); ++i)
    {
      const std::size_t j = (i + 1) % wp.size();
      const double d =
          segmentDistance(wp[i], wp[j], wall.segment.start, wall.segment.end) - 0.5 * wall.thickness;
      if (d < path.clearance)
        fail(key,
             "the path's leg from waypoint " + std::to_string(i) + " to waypoint " + std::to_string(j) +
                 " passes " + toString(d) + " m from the surface of this wall (path/clearance is " +
                 toString(path.clearance) + " m)",
             at);
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

/// The world files being read, outermost first: each file's path as named and as a canonical key.
using BasedOnChain = std::vector<std::pair<std::string, std::string>>;

std::string canonicalKey(const std::string& path)
{
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::weakly_canonical(path, ec);
  return ec ? std::filesystem::path(path).lexically_normal().string() : p.string();
}

World parseWorldIn(const std::string& yaml_text, const std::string& source, BasedOnChain& chain)
{
  const YAML::Node root = loadYaml(yaml_text, source);
  const WorldParser parser(source);
  if (!root.IsMap() || !root["based_on"])
  {
    World w = parser.parse(root);
    validateWorld(w);
    return w;
  }
  const std::string base_path = parser.basePath(root);
  const std::string key = canonicalKey(base_path);
  for (const auto& link : chain)
    if (link.second == key)
    {
      std::string cycle;
      for (const auto& named : chain) cycle += named.first + " -> ";
      parser.fail("based_on", "a cycle of based_on: " + cycle + base_path, root["based_on"]);
    }
  std::ifstream in(base_path);
  if (!in) parser.fail("based_on", "cannot open the base world file " + base_path, root["based_on"]);
  std::stringstream text;
  text << in.rdbuf();
  chain.emplace_back(base_path, key);
  const World base = parseWorldIn(text.str(), base_path, chain);
  chain.pop_back();
  World w = parser.derive(root, base, base_path);
  validateWorld(w);
  return w;
}
}  // namespace

World parseWorld(const std::string& yaml_text, const std::string& source)
{
  BasedOnChain chain;
  std::error_code ec;
  if (std::filesystem::is_regular_file(source, ec)) chain.emplace_back(source, canonicalKey(source));
  return parseWorldIn(yaml_text, source, chain);
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
