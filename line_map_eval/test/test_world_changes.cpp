// Worlds that change between sessions: a world file `based_on` another with `changes` (walls taken
// out, put in), its keys over the base's, its errors, and the office some months later
// (config/worlds/office_changed.yaml), whose changes the robot on the office's path sees.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "eval_test_helpers.hpp"
#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/simulation/simulator.hpp"

namespace
{
using namespace line_map_eval;
using line_map_eval::test_helpers::expectMentions;
using line_map_eval::test_helpers::TempDir;
using linemap::Segment2;
using linemap::Vec2;

const std::string kWorlds = std::string(LINEMAP_SOURCE_DIR) + "/config/worlds/";

/// A 10 x 10 m room with a partition stub and a thin shelf, driven around in a loop.
const char* kBase = R"(name: box
seed: 7
wall_thickness: 0.1
walls:
  - [0, 0, 10, 0]
  - [10, 0, 10, 10]
  - [10, 10, 0, 10]
  - [0, 10, 0, 0]
  - [5, 0, 5, 3]                            # walls[4]: a partition stub
  - {segment: [7, 7, 8, 7], thickness: 0}   # walls[5]: a shelf
path:
  waypoints: [[2, 5], [8.5, 5], [8.5, 8.5], [2, 8.5]]
  clearance: 0.3
laser: {beams: 91, sigma: 0.02, range_max: 12}
odometry: {translation_noise: 0.01}
)";

std::string errorOf(const std::string& text, const std::string& source = "changed.yaml")
{
  try
  {
    parseWorld(text, source);
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

std::string loadError(const std::string& path)
{
  try
  {
    loadWorld(path);
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

void expectSegment(const Segment2& s, double x1, double y1, double x2, double y2)
{
  EXPECT_EQ(s.start, Vec2(x1, y1)) << s.start.transpose() << " -> " << s.end.transpose();
  EXPECT_EQ(s.end, Vec2(x2, y2)) << s.start.transpose() << " -> " << s.end.transpose();
}

/// Whether `piece` lies on a surface of `wall` (parallel, half its thickness off its centre line to
/// 1e-6 m) over more than 0.1 m of the wall's length: a side face, not an end cap or a neighbour.
bool onSurface(const Segment2& piece, const Wall& wall)
{
  const Vec2 a = wall.segment.start, d = (wall.segment.end - wall.segment.start).normalized();
  const Vec2 n(-d.y(), d.x());
  for (const Vec2& p : {piece.start, piece.end})
    if (std::abs(std::abs(n.dot(p - a)) - 0.5 * wall.thickness) > 1e-6) return false;
  const double t0 = d.dot(piece.start - a), t1 = d.dot(piece.end - a);
  const double overlap = std::min(std::max(t0, t1), wall.segment.length()) - std::max(std::min(t0, t1), 0.0);
  return overlap > 0.1;
}

/// How many scans of `sim` see a piece of a surface of `wall`.
std::size_t scansSeeing(const SimulationResult& sim, const Wall& wall)
{
  std::size_t n = 0;
  for (const TruthScan& scan : sim.truth.scans)
    n += std::any_of(scan.visible.begin(), scan.visible.end(),
                     [&](const VisibleWall& v) { return onSurface(v.segment, wall); });
  return n;
}

/// How many of the true faces of `sim` lie on a surface of `wall`.
std::size_t facesOn(const SimulationResult& sim, const Wall& wall)
{
  return std::count_if(sim.truth.walls.begin(), sim.truth.walls.end(),
                       [&](const Segment2& f) { return onSurface(f, wall); });
}
}  // namespace

TEST(WorldChanges, BaseWallsLessRemovedPlusAdded)
{
  TempDir dir("world_changes");
  const std::string base = dir.write("base.yaml", kBase);
  const World w = parseWorld("based_on: " + base + R"(
seed: 9
laser: {beams: 181}
changes:
  remove:
    - [5, 3, 5, 0]              # walls[4], written the other way round
    - [7, 7, 8, 7.0000005]      # walls[5], to 1e-6 m
  add:
    - [0, 3, 1.5, 3]
    - {segment: [6, 0, 6, 2], thickness: 0.2}
)",
                             "changed.yaml");
  EXPECT_EQ(w.name, "changed");  // its own base name, not the base's name
  EXPECT_EQ(w.source, "changed.yaml");
  EXPECT_EQ(w.based_on, base);
  // The base's 6 walls less 2 plus 2: walls[0..3] of the base in order, then the added ones.
  ASSERT_EQ(w.walls.size(), 6u);
  expectSegment(w.walls[0].segment, 0, 0, 10, 0);
  expectSegment(w.walls[1].segment, 10, 0, 10, 10);
  expectSegment(w.walls[2].segment, 10, 10, 0, 10);
  expectSegment(w.walls[3].segment, 0, 10, 0, 0);
  expectSegment(w.walls[4].segment, 0, 3, 1.5, 3);
  EXPECT_EQ(w.walls[4].thickness, 0.1);  // the base's wall_thickness
  expectSegment(w.walls[5].segment, 6, 0, 6, 2);
  EXPECT_EQ(w.walls[5].thickness, 0.2);
  // What changed, in the order of the entries; the removed walls as the base has them.
  ASSERT_EQ(w.removed_walls.size(), 2u);
  expectSegment(w.removed_walls[0].segment, 5, 0, 5, 3);
  EXPECT_EQ(w.removed_walls[0].thickness, 0.1);
  expectSegment(w.removed_walls[1].segment, 7, 7, 8, 7);
  EXPECT_EQ(w.removed_walls[1].thickness, 0.0);
  ASSERT_EQ(w.added_walls.size(), 2u);
  expectSegment(w.added_walls[0].segment, 0, 3, 1.5, 3);
  expectSegment(w.added_walls[1].segment, 6, 0, 6, 2);
  // The path, odometry and wall thickness are the base's; seed and laser this file's, the laser
  // block whole (sigma and range_max at their defaults, not the base's 0.02 and 12).
  ASSERT_EQ(w.path.waypoints.size(), 4u);
  EXPECT_EQ(w.path.waypoints[1], Vec2(8.5, 5));
  EXPECT_EQ(w.path.clearance, 0.3);
  EXPECT_EQ(w.odometry.translation_noise, 0.01);
  EXPECT_EQ(w.wall_thickness, 0.1);
  EXPECT_EQ(w.seed, 9u);
  EXPECT_EQ(w.laser.beams, 181u);
  EXPECT_EQ(w.laser.sigma, LaserModel{}.sigma);
  EXPECT_EQ(w.laser.range_max, LaserModel{}.range_max);

  // No changes: the base's walls and everything else, with this file's name.
  const World same = parseWorld("name: again\nbased_on: " + base + "\n", "inline");
  EXPECT_EQ(same.name, "again");
  EXPECT_EQ(same.walls.size(), 6u);
  EXPECT_EQ(same.laser.beams, 91u);
  EXPECT_EQ(same.laser.sigma, 0.02);
  EXPECT_EQ(same.seed, 7u);
  EXPECT_TRUE(same.removed_walls.empty() && same.added_walls.empty());
  // A world of its own has no base and no changes.
  const World box = parseWorld(kBase, "box.yaml");
  EXPECT_TRUE(box.based_on.empty() && box.removed_walls.empty() && box.added_walls.empty());
}

TEST(WorldChanges, BaseRelativeToTheFileAndChains)
{
  TempDir dir("world_changes");
  dir.write("base.yaml", kBase);
  // Relative to the directory of the file (the test runs in the package directory).
  dir.write("later.yaml", "based_on: base.yaml\nchanges:\n  add:\n    - [0, 3, 1.5, 3]\n");
  const World later = loadWorld(dir.file("later.yaml"));
  EXPECT_EQ(later.name, "later");
  EXPECT_EQ(later.based_on, dir.file("base.yaml"));
  EXPECT_EQ(later.walls.size(), 7u);
  // A chain: the changes are relative to the direct base.
  dir.write("latest.yaml", "based_on: ./later.yaml\nchanges:\n  remove:\n    - [1.5, 3, 0, 3]\n");
  const World latest = loadWorld(dir.file("latest.yaml"));
  EXPECT_EQ(latest.based_on, dir.file("./later.yaml"));  // as resolved, not normalised
  EXPECT_EQ(latest.walls.size(), 6u);
  ASSERT_EQ(latest.removed_walls.size(), 1u);
  expectSegment(latest.removed_walls[0].segment, 0, 3, 1.5, 3);
  EXPECT_TRUE(latest.added_walls.empty());
}

TEST(WorldChanges, ErrorsNameTheFileTheKeyAndTheLine)
{
  TempDir dir("world_changes");
  const std::string base = dir.write("base.yaml", kBase);
  const std::string head = "based_on: " + base + "\n";  // line 1

  const std::string none = errorOf(head + "changes:\n  remove:\n    - [5, 3, 5, 0.1]\n");
  expectMentions(none, {"changed.yaml: changes/remove[0]: matches no wall of the base world", "base.yaml",
                        "[5, 3, 5, 0.1]", "(line 4)"});
  const std::string twice = errorOf(head + "changes:\n  remove:\n    - [5, 0, 5, 3]\n    - [5, 3, 5, 0]\n");
  expectMentions(twice, {"changed.yaml: changes/remove[1]: removes the wall [5, 3, 5, 0] again",
                         "changes/remove[0]", "(line 5)"});
  expectMentions(errorOf(head + "changes:\n  remove:\n    - [5, 0, 5]\n"),
                 {"changes/remove[0]: expected 4 numbers", "(line 4)"});
  expectMentions(errorOf(head + "changes:\n  move: []\n"), {"changes/move: unknown key", "(line 3)"});
  // An added wall across the path's leg from (8.5, 8.5) to (2, 8.5).
  expectMentions(errorOf(head + "changes:\n  add:\n    - [0, 3, 1, 3]\n    - [3, 10, 3, 7]\n"),
                 {"changed.yaml: changes/add[1]: the path's leg from waypoint 2 to waypoint 3 passes",
                  "path/clearance is 0.3 m", "(line 5)"});
  // An overridden path that runs into a base wall: validateWorld as for any world.
  expectMentions(errorOf(head + "path: {waypoints: [[2, 2], [8, 2]]}\n"),
                 {"changed.yaml: path/waypoints[0]", "walls[4]"});
  expectMentions(errorOf(head + "walls:\n  - [0, 0, 1, 0]\n"),
                 {"changed.yaml: walls: cannot be given with based_on", "(line 3)"});
  expectMentions(errorOf(head + "wall_thickness: 0.2\n"),
                 {"changed.yaml: wall_thickness: cannot be changed in a world based_on another", "(line 2)"});
  expectMentions(errorOf(head + "changes:\n  remove:\n    - [5, 0, 5, 3]\n  bogus: 1\n"),
                 {"changes/bogus: unknown key"});
  expectMentions(errorOf("based_on: no_such_world.yaml\n"),
                 {"changed.yaml: based_on: cannot open the base world file no_such_world.yaml", "(line 1)"});
  expectMentions(errorOf("based_on: [a, b]\n"), {"changed.yaml: based_on: expected the path", "(line 1)"});
  // An error of the base is the base's.
  const std::string bad_base = dir.write("bad_base.yaml", "walls: [[0, 0, 1, 0]]\n");
  expectMentions(errorOf("based_on: " + bad_base + "\n"), {"bad_base.yaml: path: missing key"});
}

TEST(WorldChanges, CyclesAreErrors)
{
  TempDir dir("world_changes");
  dir.write("self.yaml", "based_on: self.yaml\n");
  expectMentions(loadError(dir.file("self.yaml")),
                 {"self.yaml: based_on: a cycle of based_on: ", "self.yaml -> ", "(line 1)"});
  dir.write("a.yaml", "based_on: b.yaml\n");
  dir.write("b.yaml", "# b\nbased_on: ../" + dir.path().substr(dir.path().rfind('/') + 1) + "/a.yaml\n");
  const std::string cycle = loadError(dir.file("a.yaml"));
  expectMentions(cycle, {"b.yaml: based_on: a cycle of based_on: ", "a.yaml -> ", "b.yaml -> ", "(line 2)"});
}

TEST(WorldChanges, OfficeChangedLoads)
{
  const World office = loadWorld(kWorlds + "office.yaml");
  const World changed = loadWorld(kWorlds + "office_changed.yaml");
  EXPECT_EQ(changed.name, "office_changed");
  EXPECT_EQ(changed.based_on, kWorlds + "office.yaml");
  // The office's 61 walls less walls[40] (the central partition), [53..56] (the table), [57..60] (the
  // crate) and [6] (the partition that moves), plus the moved partition, the closed door, a partition
  // and a cabinet (4 sides).
  ASSERT_EQ(office.walls.size(), 61u);
  ASSERT_EQ(changed.removed_walls.size(), 10u);
  ASSERT_EQ(changed.added_walls.size(), 7u);
  ASSERT_EQ(changed.walls.size(), 61u - 10u + 7u);
  const std::vector<std::size_t> removed{40, 53, 54, 55, 56, 57, 58, 59, 60, 6};
  for (std::size_t i = 0; i < removed.size(); ++i)
  {
    EXPECT_EQ(changed.removed_walls[i].segment.start, office.walls[removed[i]].segment.start) << i;
    EXPECT_EQ(changed.removed_walls[i].segment.end, office.walls[removed[i]].segment.end) << i;
  }
  expectSegment(changed.removed_walls[0].segment, 15, 7, 15, 13);
  expectSegment(changed.removed_walls[1].segment, 20.9, 8.4, 22.1, 8.4);
  expectSegment(changed.removed_walls[5].segment, 2.6804, 4.3536, 3.7196, 4.9536);
  expectSegment(changed.removed_walls[9].segment, 15, 0, 15, 5);
  std::size_t k = 0;
  for (std::size_t i = 0; i < office.walls.size(); ++i)
  {
    if (std::find(removed.begin(), removed.end(), i) != removed.end()) continue;
    EXPECT_EQ(changed.walls[k].segment.start, office.walls[i].segment.start) << i;
    EXPECT_EQ(changed.walls[k].segment.end, office.walls[i].segment.end) << i;
    EXPECT_EQ(changed.walls[k].thickness, office.walls[i].thickness) << i;
    ++k;
  }
  ASSERT_EQ(k, 51u);
  for (std::size_t i = 0; i < 7; ++i)
  {
    EXPECT_EQ(changed.walls[51 + i].segment.start, changed.added_walls[i].segment.start) << i;
    EXPECT_EQ(changed.walls[51 + i].segment.end, changed.added_walls[i].segment.end) << i;
  }
  expectSegment(changed.added_walls[0].segment, 16.5, 0, 16.5, 5);
  EXPECT_EQ(changed.added_walls[0].thickness, 0.10);
  expectSegment(changed.added_walls[1].segment, 16.9, 5, 18.1, 5);
  expectSegment(changed.added_walls[2].segment, 5, 18.5, 6.5, 18.5);
  expectSegment(changed.added_walls[3].segment, 26, 14, 27.2, 14);
  EXPECT_EQ(changed.added_walls[3].thickness, 0.0);
  // Everything else is the office's.
  EXPECT_EQ(changed.path.waypoints, office.path.waypoints);
  EXPECT_EQ(changed.path.clearance, 0.3);
  EXPECT_EQ(changed.laser.beams, office.laser.beams);
  EXPECT_EQ(changed.laser.sigma, office.laser.sigma);
  EXPECT_EQ(changed.odometry.heading_bias, office.odometry.heading_bias);
  EXPECT_EQ(changed.seed, office.seed);
}

TEST(WorldChanges, OfficeChangesAreSeen)
{
  const SimulationResult before = simulate(loadWorld(kWorlds + "office.yaml"));
  const SimulationResult after = simulate(loadWorld(kWorlds + "office_changed.yaml"));
  ASSERT_EQ(before.truth.scans.size(), after.truth.scans.size());
  const World& w = after.world;
  // The walls taken out: in the office the path sees them, each in more than 10 scans (the table
  // and the crate from the sides facing it), in the changed office no face lies on them.
  const std::vector<std::size_t> removed_unseen{2, 5, 8};  // the table's x = 22.1, the crate's far sides
  for (std::size_t i = 0; i < w.removed_walls.size(); ++i)
  {
    const Wall& wall = w.removed_walls[i];
    const std::size_t seen = scansSeeing(before, wall);
    if (std::count(removed_unseen.begin(), removed_unseen.end(), i))
      EXPECT_EQ(seen, 0u) << "removed_walls[" << i << "]";
    else
      EXPECT_GT(seen, 10u) << "removed_walls[" << i << "]";
    EXPECT_GT(facesOn(before, wall), 0u) << "removed_walls[" << i << "]";
    EXPECT_EQ(facesOn(after, wall), 0u) << "removed_walls[" << i << "]";
  }
  // The walls put in, the moved partition and the closed door included: the path sees each in
  // more than 10 scans (the cabinet from three sides), the office has no face on them.
  for (std::size_t i = 0; i < w.added_walls.size(); ++i)
  {
    const Wall& wall = w.added_walls[i];
    const std::size_t seen = scansSeeing(after, wall);
    if (i == 5)  // the cabinet's back, y = 14.6
      EXPECT_EQ(seen, 0u) << "added_walls[" << i << "]";
    else
      EXPECT_GT(seen, 10u) << "added_walls[" << i << "]";
    EXPECT_GT(facesOn(after, wall), 0u) << "added_walls[" << i << "]";
    EXPECT_EQ(facesOn(before, wall), 0u) << "added_walls[" << i << "]";
  }
}
