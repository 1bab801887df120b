// Figures: every format is written, the PNG has the laid-out size and the endpoint colours; a SLAM
// run's layers.
#include <cairo.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>

#include "line_map_eval/batch/figures.hpp"
#include "line_map_eval/batch/slam_figure.hpp"

using line_map_eval::drawComparison;
using line_map_eval::drawLookupTable;
using line_map_eval::drawMap;
using line_map_eval::FigureLayout;
using line_map_eval::FigureStyle;
using line_map_eval::layoutFigure;
using line_map_eval::MapFigure;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
std::string tempDir()
{
  std::string tmpl = ::testing::TempDir() + "linemap_figuresXXXXXX";
  char* dir = mkdtemp(&tmpl[0]);
  if (!dir) return ::testing::TempDir();
  return dir;
}

std::string readFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

FigureStyle testStyle()
{
  FigureStyle s;
  s.pixels_per_metre = 50.0;
  s.margin = 20.0;
  s.caption_height = 28.0;
  s.legend_height = 22.0;
  s.padding = 0.25;
  s.endpoint_radius = 3.0;
  return s;
}

// Two 4 m walls, 2 m apart, drawn in opposite directions; points every 2 cm 4 cm inside them.
MapFigure testFigure()
{
  MapFigure f;
  f.segments = {Segment2(Vec2(0, 0), Vec2(4, 0)), Segment2(Vec2(4, 2), Vec2(0, 2))};
  for (int i = 0; i <= 200; ++i)
  {
    f.scan_points.emplace_back(0.02 * i, 0.04);
    f.scan_points.emplace_back(0.02 * i, 1.96);
  }
  f.scan_points.emplace_back(2.0, 1.0);
  f.caption = "test room - true walls";
  return f;
}

struct Rgb
{
  int r, g, b;
};

Rgb pixel(cairo_surface_t* img, int x, int y)
{
  const unsigned char* data = cairo_image_surface_get_data(img);
  const int stride = cairo_image_surface_get_stride(img);
  const std::uint32_t v = reinterpret_cast<const std::uint32_t*>(data + y * stride)[x];
  return {static_cast<int>((v >> 16) & 0xFF), static_cast<int>((v >> 8) & 0xFF), static_cast<int>(v & 0xFF)};
}

/// Expects the pixel at (x, y) to be exactly (r, g, b).
void expectPixel(cairo_surface_t* img, int x, int y, int r, int g, int b)
{
  const Rgb c = pixel(img, x, y);
  EXPECT_EQ(c.r, r) << "red at " << x << ", " << y;
  EXPECT_EQ(c.g, g) << "green at " << x << ", " << y;
  EXPECT_EQ(c.b, b) << "blue at " << x << ", " << y;
}

/// `f` drawn with the test style as the PNG `name` in a fresh directory and read back; null (after a
/// failure) when either fails.
cairo_surface_t* drawnPng(const MapFigure& f, const std::string& name)
{
  const auto files = drawMap(f, tempDir() + "/" + name, line_map_eval::kFigurePng, testStyle());
  EXPECT_EQ(files.size(), 1u);
  if (files.size() != 1u) return nullptr;
  cairo_surface_t* img = cairo_image_surface_create_from_png(files[0].c_str());
  if (cairo_surface_status(img) == CAIRO_STATUS_SUCCESS) return img;
  ADD_FAILURE() << files[0] << ": " << cairo_status_to_string(cairo_surface_status(img));
  cairo_surface_destroy(img);
  return nullptr;
}

bool isRed(const Rgb& c)
{
  return c.r > 200 && c.g < 60 && c.b < 60;
}
bool isGreen(const Rgb& c)
{
  return c.g > 140 && c.r < 60 && c.b < 60;
}

/// The layer colours of a figure on white: 'k' black, 'g' green, 'o' orange, 'r' red, 'b' blue, else 0.
char colourName(const Rgb& c)
{
  if (c.r < 40 && c.g < 40 && c.b < 40) return 'k';
  if (c.g > c.r + 80 && c.g > c.b + 80) return 'g';
  if (c.r > 200 && c.g > c.b + 40 && c.g < c.r - 40) return 'o';
  if (isRed(c)) return 'r';
  if (c.b > c.r + 40 && c.b > c.g + 40) return 'b';
  return 0;
}
}  // namespace

TEST(Figures, ScaleBarIsARoundNumberOfMetres)
{
  EXPECT_DOUBLE_EQ(line_map_eval::scaleBarLength(4.5), 1.0);
  EXPECT_DOUBLE_EQ(line_map_eval::scaleBarLength(9.0), 2.0);
  EXPECT_DOUBLE_EQ(line_map_eval::scaleBarLength(25.0), 5.0);
  EXPECT_DOUBLE_EQ(line_map_eval::scaleBarLength(40.0), 10.0);
  EXPECT_DOUBLE_EQ(line_map_eval::scaleBarLength(1.0), 0.2);
}

TEST(Figures, MapInAllFormatsWithEndpointColours)
{
  const std::string dir = tempDir();
  const auto files = drawMap(testFigure(), dir + "/map", line_map_eval::kFigureAllFormats, testStyle());
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0], dir + "/map.svg");
  EXPECT_EQ(files[1], dir + "/map.pdf");
  EXPECT_EQ(files[2], dir + "/map.png");
  const std::string svg = readFile(dir + "/map.svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_EQ(readFile(dir + "/map.pdf").rfind("%PDF", 0), 0u);

  cairo_surface_t* img = cairo_image_surface_create_from_png((dir + "/map.png").c_str());
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  // World box [-0.25, 4.25] x [-0.25, 2.25] at 50 px/m: 225 x 125 px, plus 2 x 20 margin, 28 caption
  // and 22 legend.
  EXPECT_EQ(cairo_image_surface_get_width(img), 265);
  EXPECT_EQ(cairo_image_surface_get_height(img), 215);
  // canvas x = 20 + (x + 0.25) * 50, y = 20 + (2.25 - y) * 50 (y up).
  EXPECT_TRUE(isRed(pixel(img, 32, 132)));     // start (0, 0)
  EXPECT_TRUE(isGreen(pixel(img, 232, 132)));  // end (4, 0)
  EXPECT_TRUE(isRed(pixel(img, 232, 32)));     // start (4, 2)
  EXPECT_TRUE(isGreen(pixel(img, 32, 32)));    // end (0, 2)
  const Rgb line = pixel(img, 132, 132);       // (2, 0): dark blue
  EXPECT_LT(line.r, 80);
  EXPECT_GT(line.b, line.r + 40);
  expectPixel(img, 132, 82, 0xB4, 0xB4, 0xB4);  // the lone scan point (2, 1): light grey
  expectPixel(img, 82, 82, 255, 255, 255);      // (1, 1): nothing there
  cairo_surface_destroy(img);
}

TEST(Figures, ExtensionSelectsTheFormatAndComparisonSharesTheScale)
{
  const std::string dir = tempDir();
  const auto files = drawMap(testFigure(), dir + "/only.png", line_map_eval::kFigureAllFormats, testStyle());
  ASSERT_EQ(files.size(), 1u);
  struct stat st;
  EXPECT_NE(stat((dir + "/only.svg").c_str(), &st), 0);

  MapFigure after = testFigure();
  after.segments = {Segment2(Vec2(0, 0), Vec2(4, 0))};
  after.caption = "after";
  const auto cmp = drawComparison(testFigure(), after, dir + "/cmp", line_map_eval::kFigurePng, testStyle());
  ASSERT_EQ(cmp.size(), 1u);
  cairo_surface_t* img = cairo_image_surface_create_from_png(cmp[0].c_str());
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(cairo_image_surface_get_width(img), 2 * 265);
  EXPECT_EQ(cairo_image_surface_get_height(img), 215);
  EXPECT_TRUE(isRed(pixel(img, 265 + 32, 132)));     // the right panel's start (0, 0)
  EXPECT_TRUE(isGreen(pixel(img, 265 + 232, 132)));  // and end (4, 0)
  cairo_surface_destroy(img);
}

TEST(Figures, LookupTableFigureIsGreyscaleUnderTheMap)
{
  const std::string dir = tempDir();
  std::vector<Vec2> pts;
  for (int i = 0; i <= 400; ++i) pts.emplace_back(0.01 * i, 1.025);
  const line_map_eval::LookupTable t = line_map_eval::LookupTable::build(pts, {});  // 5 cm, sigma 5 cm
  const auto files = drawLookupTable(t, {Segment2(Vec2(0, 1.025), Vec2(4, 1.025))}, "lookup", dir + "/lut",
                                     line_map_eval::kFigureAllFormats, testStyle());
  ASSERT_EQ(files.size(), 3u);
  for (const std::string& f : files) EXPECT_GT(readFile(f).size(), 100u) << f;
  cairo_surface_t* img = cairo_image_surface_create_from_png((dir + "/lut.png").c_str());
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  // Window: cells x -4..84, y 16..24 (the points' cells 0..80 x 20 plus 3 + 1 each side), i.e.
  // [-0.2, 4.25] x [0.8, 1.25] m, padded 0.25 m: 4.95 m x 0.95 m = 247.5 x 47.5 px.
  EXPECT_EQ(cairo_image_surface_get_width(img), 288);   // ceil(247.5 + 40)
  EXPECT_EQ(cairo_image_surface_get_height(img), 138);  // ceil(47.5 + 40 + 28 + 22)
  // (2, 1.125) is two cells (2 sigma) above the wall: exp(-2) -> grey 255 (1 - 0.6 e^-2) = 234,
  // at canvas (20 + 2.45 * 50, 20 + (1.5 - 1.125) * 50) = (142.5, 38.75).
  const Rgb grey = pixel(img, 142, 38);
  EXPECT_EQ(grey.r, grey.g);
  EXPECT_EQ(grey.g, grey.b);
  EXPECT_NEAR(grey.r, 234, 1);
  cairo_surface_destroy(img);
}

TEST(Figures, UnwritableFileNamesTheFile)
{
  try
  {
    drawMap(testFigure(), "/nonexistent_dir_linemap/x.png", line_map_eval::kFigurePng, testStyle());
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir_linemap/x.png"), std::string::npos) << e.what();
  }
}

// Coverage layers: the lone scan point (2, 1) uncovered in orange, a redundant pair as a magenta band
// under the map, and the legend's first glyph (a map segment) in the band under the caption.
TEST(Figures, UncoveredPointsRedundantPairsAndLegend)
{
  MapFigure f = testFigure();
  f.show_coverage = true;
  f.uncovered_points = {Vec2(2.0, 1.0)};
  f.redundant_pairs = {{f.segments[0], Segment2(Vec2(1, 0.02), Vec2(3, 0.02))}};
  cairo_surface_t* img = drawnPng(f, "cov.png");
  ASSERT_NE(img, nullptr);
  expectPixel(img, 132, 82, 255, 128, 0);  // (2, 1): orange
  // 2 px below (2, 0), inside the 6 px band but off the 1.5 px line and the scan points: magenta at
  // 45 % over white, 255 (1 - 0.45) + 0.45 * 0.85 * 255 = 238 in red and blue, 140 in green.
  const Rgb band = pixel(img, 132, 134);
  EXPECT_NEAR(band.r, 238, 3);
  EXPECT_NEAR(band.g, 140, 3);
  EXPECT_NEAR(band.b, 238, 3);
  // Legend band: y from 20 + 125 + 20 + 28 = 193 to 215; the map-segment glyph spans x 22..32 at its middle.
  const Rgb glyph = pixel(img, 27, 204);
  EXPECT_LT(glyph.r, 80);
  EXPECT_GT(glyph.b, glyph.r + 40);
  cairo_surface_destroy(img);
}

// Uncovered points on straight structure are cyan (0, 180, 240), apart from the orange clutter.
TEST(Figures, UnmappedStructureInItsOwnColour)
{
  MapFigure f = testFigure();
  f.show_coverage = true;
  f.uncovered_structure_points = {Vec2(2.0, 1.0)};
  cairo_surface_t* img = drawnPng(f, "structure.png");
  ASSERT_NE(img, nullptr);
  expectPixel(img, 132, 82, 0, 180, 240);  // (2, 1): cyan
  cairo_surface_destroy(img);
}

TEST(Figures, StrayScanPointsDoNotStretchTheFrame)
{
  // 2000 points on the walls of a 10 m room and three returns 1 km away: the frame is the room's
  // (plus padding and 2 %), not a kilometre wide; a map segment far out is always inside.
  MapFigure f;
  for (int i = 0; i < 2000; ++i)
  {
    const double t = 10.0 * i / 1999.0;
    f.scan_points.push_back(i % 2 ? Vec2(t, 0.0) : Vec2(0.0, t));
    f.scan_points.push_back(i % 2 ? Vec2(t, 10.0) : Vec2(10.0, t));
  }
  for (int i = 0; i < 3; ++i) f.scan_points.push_back(Vec2(1000.0 + i, 500.0));
  FigureStyle style;
  FigureLayout l = layoutFigure({&f}, style);
  EXPECT_LT(l.max_x - l.min_x, 10.0 * 1.05 + 2.0 * style.padding);
  EXPECT_LT(l.max_y - l.min_y, 10.0 * 1.05 + 2.0 * style.padding);
  EXPECT_LE(l.min_x, 0.0);
  EXPECT_GE(l.max_x, 10.0);
  f.segments.push_back(Segment2(Vec2(0.0, 0.0), Vec2(30.0, 0.0)));
  l = layoutFigure({&f}, style);
  EXPECT_GE(l.max_x, 30.0);
}

namespace
{
// A SLAM run around three sides of a 2 m square: keyframes at (0,0), (2,0), (2,2), (0,2), each scan a
// half circle of 2 m; closure 3 -> 0 accepted, 2 -> 0 rejected; relation 1 -> 3 off by 0.5 m, 0 -> 1
// by 0.1 m.
struct SquareRun
{
  line_map_eval::Recording recording;
  line_map_eval::SlamRecordingResult slam;
  std::vector<line_map_eval::RelationResidual> residuals;
  SquareRun()
  {
    recording.geometry = {-linemap::kPi / 2, linemap::kPi / 180, 181, 0.0, 10.0};
    const std::vector<linemap::Pose2> poses = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    for (std::size_t i = 0; i < poses.size(); ++i)
    {
      line_map_eval::RecordedScan s;
      s.stamp = static_cast<double>(i);
      s.ranges.assign(181, 2.0f);
      recording.scans.push_back(s);
      slam.scan_poses.push_back(poses[i]);
      slam.keyframes.push_back({i, poses[i]});
    }
    using line_map_merging::ClosureOutcome;
    slam.closures = {{0, 3, ClosureOutcome::kAccepted, 0.7}, {0, 2, ClosureOutcome::kRejectedScore, 0.3}};
    residuals = {{0, poses[1], poses[3], 0.5, 0.0}, {1, poses[0], poses[1], 0.1, 0.0}};
  }
};
}  // namespace

// The SLAM run's layers: an accepted closure green, a rejected one orange, a relation above 0.3 m red,
// the one below it not drawn; the legend names the run's layers with their counts, not the map's.
TEST(Figures, SlamRunLayers)
{
  const SquareRun run;
  MapFigure f = line_map_eval::slamFigure(run.recording, run.slam, &run.residuals, "square - laser SLAM");
  EXPECT_EQ(f.scan_points.size(), 4u * 181u);
  EXPECT_EQ(f.trajectory.size(), 4u);
  ASSERT_EQ(f.accepted_closures.size(), 1u);
  ASSERT_EQ(f.rejected_closures.size(), 1u);
  ASSERT_EQ(f.bad_relations.size(), 1u);
  EXPECT_NEAR((f.accepted_closures[0].start - Vec2(0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.accepted_closures[0].end - Vec2(0, 2)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.bad_relations[0].start - Vec2(2, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((f.bad_relations[0].end - Vec2(0, 2)).norm(), 0.0, 1e-12);
  // The legend: the run's layers with their counts (one closure of each outcome, one relation above
  // 0.3 m: 0.5 m; 0.1 m is below), no map segment or end point (the figure has no segments).
  const std::vector<std::string> expected = {"scan point", "trajectory", "accepted closure (1)",
                                             "rejected closure (1)", "relation error > 0.3 m (1)"};
  EXPECT_EQ(line_map_eval::legendLabels(f), expected);
  f.scan_points.clear();  // the pixels below are of the lines alone
  FigureStyle style = testStyle();
  style.line_width = 5.0;  // closures 3 px, relations 5 px wide
  const std::string dir = tempDir();
  const auto files = drawMap(f, dir + "/slam.png", line_map_eval::kFigurePng, style);
  ASSERT_EQ(files.size(), 1u);
  cairo_surface_t* img = cairo_image_surface_create_from_png(files[0].c_str());
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  const FigureLayout l = layoutFigure({&f}, style);
  const auto at = [&](double x, double y)
  {
    const Vec2 c = l.toCanvas(Vec2(x, y));
    return pixel(img, static_cast<int>(c.x()), static_cast<int>(c.y()));
  };
  const Rgb accepted = at(0.0, 1.0), rejected = at(0.5, 0.5), bad = at(1.5, 0.5), trajectory = at(1.0, 0.0);
  EXPECT_GT(accepted.g, accepted.r + 80) << accepted.r << " " << accepted.g << " " << accepted.b;
  EXPECT_GT(accepted.g, accepted.b + 80);
  EXPECT_GT(rejected.r, 200) << rejected.r << " " << rejected.g << " " << rejected.b;
  EXPECT_GT(rejected.g, rejected.b + 40);
  EXPECT_LT(rejected.g, rejected.r - 40);
  EXPECT_TRUE(isRed(bad)) << bad.r << " " << bad.g << " " << bad.b;
  EXPECT_LT(trajectory.r + trajectory.g + trajectory.b, 150);
  // Relation 0 -> 1 (0.1 m) lies on the trajectory; (2, 1) is on the trajectory's second leg only.
  const Rgb leg = at(2.0, 1.0);
  EXPECT_LT(leg.r + leg.g + leg.b, 150);
  cairo_surface_destroy(img);
}

// drawSlamRun writes the SVG and the PNG (the default formats) with the legend's entries: in the legend
// band of the PNG (its glyphs' colours, in order) and in the SVG (its strokes in those colours, below the
// map area). A legend listing the map's layers instead draws a dark blue glyph first and no orange one.
TEST(Figures, SlamRunFilesAreWritten)
{
  const SquareRun run;
  const std::string dir = tempDir();
  const auto files =
      line_map_eval::drawSlamRun(run.recording, run.slam, &run.residuals, "square", dir + "/slam");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0], dir + "/slam.svg");
  EXPECT_EQ(files[1], dir + "/slam.png");
  const std::string svg = readFile(files[0]);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_EQ(readFile(files[1]).rfind("\x89PNG", 0), 0u);
  struct stat st;
  EXPECT_NE(stat((dir + "/slam.pdf").c_str(), &st), 0);

  // The legend's glyphs along the middle of its band, left to right: scan point (grey), trajectory
  // (black), accepted (green), rejected (orange), relation (red); the text between them is black too.
  const MapFigure f = line_map_eval::slamFigure(run.recording, run.slam, &run.residuals, "square");
  const FigureLayout l = layoutFigure({&f}, FigureStyle());
  const double middle = l.margin + l.map_height + l.margin + l.caption_height + 0.5 * l.legend_height;
  cairo_surface_t* img = cairo_image_surface_create_from_png(files[1].c_str());
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  std::string order;  // a letter per run of legend pixels of one glyph colour
  for (int x = static_cast<int>(l.margin); x < static_cast<int>(l.margin + l.map_width); ++x)
  {
    const char k = colourName(pixel(img, x, static_cast<int>(middle)));
    if (k != 'k' && k != 0 && (order.empty() || order.back() != k)) order.push_back(k);
  }
  cairo_surface_destroy(img);
  EXPECT_EQ(order, "gor");
  // The SVG: the legend's line glyphs are horizontal strokes through the band's middle, left to right
  // (cairo writes a stroke's colour as rgb(r%,g%,b%), its alpha apart).
  const std::regex stroke(
      R"re(stroke:rgb\(([0-9.]+)%,([0-9.]+)%,([0-9.]+)%\);[^"]*" d="M ([0-9.]+) ([0-9.]+) L ([0-9.]+) ([0-9.]+) ")re");
  std::string glyphs;
  for (std::sregex_iterator it(svg.begin(), svg.end(), stroke), end; it != end; ++it)
  {
    const auto& m = *it;
    if (std::fabs(std::stod(m[5]) - middle) > 0.5 || std::fabs(std::stod(m[7]) - middle) > 0.5) continue;
    const auto level = [&](int i) { return static_cast<int>(std::lround(2.55 * std::stod(m[i]))); };
    glyphs.push_back(colourName({level(1), level(2), level(3)}));
  }
  EXPECT_EQ(glyphs, "kgor");  // trajectory, accepted, rejected, relation; no map segment (blue)
}
