// Walls with thickness: the faces of their solids (hand-computed), ray casting that stops at the
// near face, and a simulated 10 cm wall seen from both sides as two true lines.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "line_map_eval/datasets/world.hpp"
#include "line_map_eval/metrics/ground_truth_metrics.hpp"
#include "line_map_eval/simulation/simulator.hpp"
#include "line_map_eval/simulation/wall_faces.hpp"

namespace
{
using linemap::kPi;
using linemap::Segment2;
using linemap::Vec2;
using namespace line_map_eval;

void expectSegment(const Segment2& s, const Vec2& a, const Vec2& b, const char* what)
{
  EXPECT_NEAR((s.start - a).norm(), 0.0, 1e-12) << what << ": start " << s.start.transpose();
  EXPECT_NEAR((s.end - b).norm(), 0.0, 1e-12) << what << ": end " << s.end.transpose();
}

/// Whether p lies strictly inside the rectangle of a thick wall (its centre line's extent, without
/// the extension at joined ends).
bool insideSolid(const Vec2& p, const std::vector<Wall>& walls)
{
  for (const Wall& w : walls)
  {
    const Vec2 u = (w.segment.end - w.segment.start).normalized(), q = p - w.segment.start;
    const double along = u.dot(q), across = u.x() * q.y() - u.y() * q.x();
    if (along > 0.0 && along < w.segment.length() && std::abs(across) < 0.5 * w.thickness) return true;
  }
  return false;
}

/// Every face has free space on its left and the solid on its right, just beside its midpoint.
void expectOutwardLeft(const std::vector<WallFace>& faces, const std::vector<Wall>& walls)
{
  for (std::size_t i = 0; i < faces.size(); ++i)
  {
    const Segment2& f = faces[i].segment;
    const Vec2 u = (f.end - f.start).normalized(), left(-u.y(), u.x());
    EXPECT_FALSE(insideSolid(f.midpoint() + 0.01 * left, walls)) << "face " << i;
    EXPECT_TRUE(insideSolid(f.midpoint() - 0.01 * left, walls)) << "face " << i;
  }
}

const Wall kBar{Segment2(Vec2(0, 0), Vec2(4, 0)), 0.10};  // 4 m long, 10 cm thick, free ends
}  // namespace

TEST(WallFaces, FreeStandingWallIsARectangleWalkedClockwise)
{
  const auto faces = wallFaces({kBar});
  ASSERT_EQ(faces.size(), 4u);
  // Left side (y = +0.05) along the wall, end cap, right side back, start cap.
  expectSegment(faces[0].segment, Vec2(0, 0.05), Vec2(4, 0.05), "left side");
  expectSegment(faces[1].segment, Vec2(4, 0.05), Vec2(4, -0.05), "end cap");
  expectSegment(faces[2].segment, Vec2(4, -0.05), Vec2(0, -0.05), "right side");
  expectSegment(faces[3].segment, Vec2(0, -0.05), Vec2(0, 0.05), "start cap");
  expectOutwardLeft(faces, {kBar});
  // The two long faces: 10 cm apart, opposite directions.
  EXPECT_NEAR(linemap::distanceToLine(faces[2].segment.start, faces[0].segment.start, faces[0].segment.end),
              0.10, 1e-12);
  EXPECT_NEAR(std::abs(linemap::normalizeAngle(faces[0].segment.heading() - faces[2].segment.heading())), kPi,
              1e-12);
}

TEST(WallFaces, ThinWallIsOneLinePerDirection)
{
  const auto faces = wallFaces({Wall{kBar.segment, 0.0}});
  ASSERT_EQ(faces.size(), 2u);
  expectSegment(faces[0].segment, Vec2(0, 0), Vec2(4, 0), "forward");
  expectSegment(faces[1].segment, Vec2(4, 0), Vec2(0, 0), "backward");
}

TEST(WallFaces, WallsMeetingAtACornerFormASolidCorner)
{
  // An L of two 10 cm walls meeting at (4, 0): each extends 5 cm into the other, so the union is
  // an L-shaped polygon of six edges, with the inner corner at (3.95, 0.05) and the outer one at
  // (4.05, -0.05); the pieces on one line (the right side of the first wall and the start cap of
  // the second, the end cap of the first and the right side of the second) are one face each.
  const std::vector<Wall> walls = {kBar, Wall{Segment2(Vec2(4, 0), Vec2(4, 3)), 0.10}};
  const auto faces = wallFaces(walls);
  ASSERT_EQ(faces.size(), 6u);
  // A joined face takes the place of its first piece (the first wall's end cap, then its right side).
  expectSegment(faces[0].segment, Vec2(0, 0.05), Vec2(3.95, 0.05), "inside of the first wall");
  expectSegment(faces[1].segment, Vec2(4.05, 3), Vec2(4.05, -0.05), "outside of the second wall");
  expectSegment(faces[2].segment, Vec2(4.05, -0.05), Vec2(0, -0.05), "outside of the first wall");
  expectSegment(faces[3].segment, Vec2(0, -0.05), Vec2(0, 0.05), "start cap of the first wall");
  expectSegment(faces[4].segment, Vec2(3.95, 0.05), Vec2(3.95, 3), "inside of the second wall");
  expectSegment(faces[5].segment, Vec2(3.95, 3), Vec2(4.05, 3), "end cap of the second wall");
  EXPECT_EQ(faces[1].wall, 0u);  // joined from both walls: the lower index
  expectOutwardLeft(faces, walls);

  // A T: a partition ending on the middle of the first wall cuts its inside face in two.
  const std::vector<Wall> tee = {kBar, Wall{Segment2(Vec2(2, 0), Vec2(2, 2)), 0.10}};
  const auto tee_faces = wallFaces(tee);
  ASSERT_EQ(tee_faces.size(), 8u);  // inside split in two, outside, two caps; partition: 2 sides + cap
  expectSegment(tee_faces[0].segment, Vec2(0, 0.05), Vec2(1.95, 0.05), "inside, left of the partition");
  expectSegment(tee_faces[1].segment, Vec2(2.05, 0.05), Vec2(4, 0.05), "inside, right of the partition");
  expectOutwardLeft(tee_faces, tee);
}

TEST(WallFaces, BadWallsAreNamed)
{
  try
  {
    wallFaces({kBar, Wall{Segment2(Vec2(1, 1), Vec2(1, 1)), 0.1}});
    FAIL() << "accepted a zero-length wall";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("walls[1]"), std::string::npos) << e.what();
  }
  EXPECT_THROW(wallFaces({Wall{kBar.segment, -0.1}}), std::invalid_argument);
  EXPECT_THROW(wallFaces({Wall{kBar.segment, std::nan("")}}), std::invalid_argument);
}

TEST(RayCasting, ARayStopsAtTheNearFace)
{
  const auto faces = wallFaces({kBar});
  const auto segments = faceSegments(faces);
  // Straight down from (2, 1): the face y = 0.05, 0.95 m away; straight up from (2, -1) likewise
  // the face y = -0.05; the two hits are different faces.
  const RayHit down = castRay(segments, Vec2(2, 1), -kPi / 2);
  const RayHit up = castRay(segments, Vec2(2, -1), kPi / 2);
  EXPECT_NEAR(down.range, 0.95, 1e-12);
  EXPECT_NEAR(up.range, 0.95, 1e-12);
  EXPECT_EQ(down.face, 0);
  EXPECT_EQ(up.face, 2);
  // At 45 degrees from (1, 1): y = 0.05 is reached after 0.95 sqrt 2, at x = 1.95.
  const RayHit oblique = castRay(segments, Vec2(1, 1), -kPi / 4);
  EXPECT_NEAR(oblique.range, 0.95 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(oblique.face, 0);
  // Along the wall from beyond its end: the end cap at x = 4, 1 m away.
  const RayHit along = castRay(segments, Vec2(5, 0.02), kPi);
  EXPECT_NEAR(along.range, 1.0, 1e-12);
  EXPECT_EQ(along.face, 1);
  // A thin wall gives the same range from either side, on the face whose left the ray comes from.
  const auto thin = faceSegments(wallFaces({Wall{kBar.segment, 0.0}}));
  EXPECT_NEAR(castRay(thin, Vec2(2, 1), -kPi / 2).range, 1.0, 1e-12);
  EXPECT_EQ(castRay(thin, Vec2(2, 1), -kPi / 2).face, 0);
  EXPECT_NEAR(castRay(thin, Vec2(2, -1), kPi / 2).range, 1.0, 1e-12);
  EXPECT_EQ(castRay(thin, Vec2(2, -1), kPi / 2).face, 1);
}

TEST(Simulator, ThickWallSeenFromBothSidesGivesTwoTrueFaces)
{
  // The robot drives a 6 x 2 m rectangle around a lone 10 cm wall, without noise.
  const World world = parseWorld(
      "walls: [[0, 0, 4, 0]]\n"
      "wall_thickness: 0.1\n"
      "path: {waypoints: [[-1, -1], [5, -1], [5, 1], [-1, 1]], scan_period: 0.5}\n"
      "laser: {beams: 361, fov_deg: 360, sigma: 0.0}\n"
      "odometry: {translation_noise: 0}\n",
      "lone_wall");
  const SimulationResult sim = simulate(world);
  const GroundTruth& t = sim.truth;
  ASSERT_EQ(t.walls.size(), 4u);
  ASSERT_EQ(t.solids.size(), 1u);
  EXPECT_EQ(t.solids[0].thickness, 0.1);

  // Beams per face over the lap, and every sighting from the face's left (free) side.
  std::map<std::size_t, std::size_t> beams;
  for (const TruthScan& s : t.scans)
    for (const VisibleWall& v : s.visible)
    {
      const Segment2& f = t.walls[v.wall];
      const Vec2 d = f.end - f.start, q = s.pose.translation() - f.start;
      EXPECT_GT(d.x() * q.y() - d.y() * q.x(), 0.0) << "face " << v.wall << " seen from behind";
      beams[v.wall] += v.beams;
    }
  // Both long faces are seen: y = +0.05 directed +x and y = -0.05 directed -x, 10 cm apart.
  ASSERT_GT(beams[0], 100u);
  ASSERT_GT(beams[2], 100u);
  const Segment2 &top = t.walls[0], &bottom = t.walls[2];
  EXPECT_NEAR(top.start.y(), 0.05, 1e-12);
  EXPECT_NEAR(bottom.start.y(), -0.05, 1e-12);
  EXPECT_NEAR(linemap::distanceToLine(bottom.start, top.start, top.end), 0.10, 1e-12);
  EXPECT_NEAR(linemap::distanceToLine(bottom.end, top.start, top.end), 0.10, 1e-12);
  EXPECT_NEAR(top.heading(), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(bottom.heading()), kPi, 1e-12);

  // Noiseless ranges end on the near face: a beam hitting the wall from above reads the distance
  // to y = 0.05, not to the centre line.
  std::size_t checked = 0;
  for (std::size_t k = 0; k < t.scans.size(); ++k)
  {
    const linemap::Pose2& pose = t.scans[k].pose;
    const auto hits = castScan(t.walls, pose, world.laser);
    for (std::size_t i = 0; i < hits.size(); ++i)
    {
      if (hits[i].face != 0 && hits[i].face != 2) continue;
      const double a =
          pose.theta + world.laser.angleMin() + static_cast<double>(i) * world.laser.angleIncrement();
      const double face_y = hits[i].face == 0 ? 0.05 : -0.05;
      EXPECT_NEAR(hits[i].range, (face_y - pose.y) / std::sin(a), 1e-9);
      EXPECT_NEAR(sim.recording.scans[k].ranges[i], hits[i].range, 1e-6 * hits[i].range);
      ++checked;
    }
  }
  EXPECT_GT(checked, 100u);

  // The ground truth metrics score each face on its own: a map holding only the top face covers
  // the top face and nothing of the bottom one.
  GroundTruthParams p;
  p.min_seen_length = 0.0;
  const GroundTruthResult only_top = evaluateAgainstGroundTruth(t, {top}, p);
  const GroundTruthResult both = evaluateAgainstGroundTruth(t, {top, bottom}, p);
  double top_cov = -1.0, bottom_cov = -1.0;
  for (const WallScore& w : only_top.walls)
  {
    if (w.face == 0) top_cov = w.coverage;
    if (w.face == 2) bottom_cov = w.coverage;
  }
  EXPECT_DOUBLE_EQ(top_cov, 1.0);
  EXPECT_DOUBLE_EQ(bottom_cov, 0.0);
  EXPECT_EQ(only_top.undetected_walls, both.undetected_walls + 1);
}
