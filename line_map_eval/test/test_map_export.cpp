// Map exports read back by independent readers: DXF by dxflib's reader, GeoJSON by nlohmann::json,
// the PGM + YAML pair by a minimal map_server-format parser, SVG minimally; bad map files and bad
// options through exportMap and through the linemap_export tool itself.
#include <dl_creationadapter.h>
#include <dl_dxf.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "eval_test_helpers.hpp"
#include "line_map_eval/batch/map_export.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

using line_map_eval::exportMap;
using line_map_eval::ExportOptions;
using line_map_eval::ExportSummary;
using line_map_merging::CaeRlsm;
using line_map_merging::Keyframe;
using line_map_merging::MapFileError;
using line_map_merging::MapSegment;
using linemap::Pose2;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
using line_map_eval::test_helpers::TempDir;

std::string slurp(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A room corner seen from two keyframes: the wall x = 2, y in [-1, 1] and the wall y = 1.5,
/// x in [-1, 1.5], two originals each; plus a 0.3 m piece seen once, which the map withholds.
std::string writeMapFile(const TempDir& dir)
{
  CaeRlsm cae;
  Keyframe first;
  first.index = 0;
  first.pose = Pose2(0.0, 0.0, 0.0);
  first.segments = {Segment2(Vec2(2.0, -1.0), Vec2(2.0, 1.0)), Segment2(Vec2(1.5, 1.5), Vec2(-1.0, 1.5)),
                    Segment2(Vec2(1.0, -1.5), Vec2(1.3, -1.5))};
  Keyframe second;
  second.index = 1;
  second.stamp = 1.0;
  second.pose = Pose2(0.5, 0.0, 0.0);  // the same two walls, in its own laser frame
  second.segments = {Segment2(Vec2(1.5, -1.0), Vec2(1.5, 1.0)), Segment2(Vec2(1.0, 1.5), Vec2(-1.5, 1.5))};
  cae.addKeyframe(first);
  cae.addKeyframe(second);
  const std::string path = dir.file("map.yaml");
  cae.save(path);
  return path;
}

std::vector<MapSegment> loadedMap(const std::string& path)
{
  CaeRlsm cae;
  cae.load(path);
  return cae.map();
}

struct LineCollector : DL_CreationAdapter
{
  struct Line
  {
    std::string layer;
    double x1, y1, z1, x2, y2, z2;
  };
  std::vector<Line> lines;
  void addLine(const DL_LineData& d) override
  {
    lines.push_back({getAttributes().getLayer(), d.x1, d.y1, d.z1, d.x2, d.y2, d.z2});
  }
};

std::size_t countOf(const std::string& text, const std::string& what)
{
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// Runs the tool; returns its exit status and (in `output`) its stdout and stderr.
int runTool(const std::string& args, std::string& output)
{
  FILE* pipe = ::popen((std::string(LINEMAP_EXPORT_TOOL) + " " + args + " 2>&1").c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed");
  output.clear();
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
}  // namespace

TEST(MapExport, TheHandMadeMapHasTwoWalls)
{
  TempDir dir;
  const std::vector<MapSegment> map = loadedMap(writeMapFile(dir));
  ASSERT_EQ(map.size(), 2u);  // the piece seen once is withheld
  EXPECT_NEAR((map[0].segment.midpoint() - Vec2(2.0, 0.0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(map[0].segment.length(), 2.0, 1e-6);
  EXPECT_NEAR((map[1].segment.midpoint() - Vec2(0.25, 1.5)).norm(), 0.0, 1e-6);
  EXPECT_NEAR(map[1].segment.length(), 2.5, 1e-6);
  EXPECT_EQ(map[0].merged_count, 2u);
  EXPECT_EQ(map[1].merged_count, 2u);
}

TEST(MapExport, DxfReadBackByDxflib)
{
  TempDir dir;
  const std::string map_file = writeMapFile(dir);
  ExportOptions options;
  options.formats = line_map_eval::kExportDxf;
  const ExportSummary s = exportMap(map_file, dir.file("out"), options);
  ASSERT_EQ(s.files, std::vector<std::string>{dir.file("out.dxf")});

  LineCollector collector;
  DL_Dxf dxf;
  ASSERT_TRUE(dxf.in(dir.file("out.dxf"), &collector));
  const std::vector<MapSegment> map = loadedMap(map_file);
  ASSERT_EQ(collector.lines.size(), map.size());  // one LINE per map segment, nothing else
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    const auto& l = collector.lines[i];
    EXPECT_EQ(l.layer, line_map_eval::kDxfLayer);
    EXPECT_NEAR(l.x1, map[i].segment.start.x(), 1e-6);
    EXPECT_NEAR(l.y1, map[i].segment.start.y(), 1e-6);
    EXPECT_NEAR(l.x2, map[i].segment.end.x(), 1e-6);
    EXPECT_NEAR(l.y2, map[i].segment.end.y(), 1e-6);
    EXPECT_EQ(l.z1, 0.0);
    EXPECT_EQ(l.z2, 0.0);
  }
  // The hand-made walls, start and end as the map has them (free side on the left).
  EXPECT_NEAR(collector.lines[0].x1, 2.0, 1e-6);
  EXPECT_NEAR(std::abs(collector.lines[0].y1), 1.0, 1e-6);
  EXPECT_NEAR(collector.lines[1].y1, 1.5, 1e-6);
  EXPECT_NEAR(collector.lines[1].y2, 1.5, 1e-6);
  EXPECT_NEAR(std::abs(collector.lines[1].x2 - collector.lines[1].x1), 2.5, 1e-6);
}

TEST(MapExport, GeoJsonReadBackByAJsonParser)
{
  TempDir dir;
  const std::string map_file = writeMapFile(dir);
  ExportOptions options;
  options.formats = line_map_eval::kExportGeoJson;
  exportMap(map_file, dir.file("out"), options);

  const nlohmann::json doc = nlohmann::json::parse(slurp(dir.file("out.geojson")));
  EXPECT_EQ(doc.at("type"), "FeatureCollection");
  const auto& features = doc.at("features");
  const std::vector<MapSegment> map = loadedMap(map_file);
  ASSERT_EQ(features.size(), map.size());
  for (std::size_t i = 0; i < map.size(); ++i)
  {
    const auto& f = features[i];
    EXPECT_EQ(f.at("type"), "Feature");
    EXPECT_EQ(f.at("geometry").at("type"), "LineString");
    const auto& c = f.at("geometry").at("coordinates");
    ASSERT_EQ(c.size(), 2u);
    EXPECT_NEAR(c[0][0].get<double>(), map[i].segment.start.x(), 1e-9);
    EXPECT_NEAR(c[0][1].get<double>(), map[i].segment.start.y(), 1e-9);
    EXPECT_NEAR(c[1][0].get<double>(), map[i].segment.end.x(), 1e-9);
    EXPECT_NEAR(c[1][1].get<double>(), map[i].segment.end.y(), 1e-9);
    EXPECT_EQ(f.at("properties").at("id").get<std::uint64_t>(), map[i].id);
    EXPECT_EQ(f.at("properties").at("originals").get<int>(), 2);
  }
  EXPECT_NEAR(features[0].at("properties").at("length").get<double>(), 2.0, 1e-6);
  EXPECT_NEAR(features[1].at("properties").at("length").get<double>(), 2.5, 1e-6);
}

TEST(MapExport, PgmAndYamlAsMapServerReadsThem)
{
  TempDir dir;
  ExportOptions options;
  options.formats = line_map_eval::kExportPgm;
  options.resolution = 0.1;
  const ExportSummary s = exportMap(writeMapFile(dir), dir.file("grid"), options);
  ASSERT_EQ(s.files, (std::vector<std::string>{dir.file("grid.pgm"), dir.file("grid.yaml")}));

  // YAML: map_server's keys, the origin a multiple of the resolution below the content minus the
  // 0.25 m margin: x from floor(-1.25 / 0.1) = -13, y from floor(-1.75 / 0.1) = -18 (the withheld
  // piece at y = -1.5 still bounds the grid: it was seen, so its free triangle is drawn).
  std::map<std::string, std::string> fields;
  std::istringstream yaml(slurp(dir.file("grid.yaml")));
  for (std::string line; std::getline(yaml, line);)
    fields[line.substr(0, line.find(':'))] = line.substr(line.find(':') + 2);
  EXPECT_EQ(fields["image"], "grid.pgm");
  EXPECT_DOUBLE_EQ(std::stod(fields["resolution"]), 0.1);
  std::smatch m;
  ASSERT_TRUE(std::regex_match(fields["origin"], m, std::regex(R"(\[([-0-9.e]+), ([-0-9.e]+), 0\.0\])")))
      << fields["origin"];
  EXPECT_NEAR(std::stod(m[1]), -1.3, 1e-9);
  EXPECT_NEAR(std::stod(m[2]), -1.8, 1e-9);
  EXPECT_EQ(fields["negate"], "0");
  EXPECT_EQ(fields["occupied_thresh"], "0.65");
  EXPECT_EQ(fields["free_thresh"], "0.196");

  // PGM: P5, columns -13 .. floor(2.25 / 0.1) = 22 (36), rows -18 .. floor(1.75 / 0.1) = 17 (36).
  const std::string pgm = slurp(dir.file("grid.pgm"));
  std::istringstream header(pgm);
  std::string magic, comment;
  int width = 0, height = 0, max_value = 0;
  header >> magic >> std::ws;
  while (header.peek() == '#') std::getline(header, comment);
  header >> width >> height >> max_value;
  header.get();  // the single whitespace before the pixels
  EXPECT_EQ(magic, "P5");
  EXPECT_EQ(width, 36);
  EXPECT_EQ(height, 36);
  EXPECT_EQ(max_value, 255);
  ASSERT_EQ(pgm.size() - static_cast<std::size_t>(header.tellg()), 36u * 36u);
  EXPECT_EQ(s.grid_width, 36);
  EXPECT_EQ(s.grid_height, 36);
  EXPECT_EQ(s.occupied + s.free + s.unknown, 36u * 36u);
  const char* pixels = pgm.data() + header.tellg();
  // The pixel of world (x, y) as map_server places it: column from the origin's x, image row from the
  // top (highest y). The origin as read, so a wall on a cell boundary lands where the grid put it.
  const double origin_x = std::stod(m[1]), origin_y = std::stod(m[2]),
               resolution = std::stod(fields["resolution"]);
  const auto pixel = [&](const Vec2& p)
  {
    const int column = static_cast<int>(std::floor((p.x() - origin_x) / resolution));
    const int row = static_cast<int>(std::floor((p.y() - origin_y) / resolution));
    return static_cast<int>(static_cast<unsigned char>(pixels[(height - 1 - row) * width + column]));
  };
  const std::vector<MapSegment> map = loadedMap(dir.file("map.yaml"));
  for (const MapSegment& wall : map)
    for (double t = 0.0; t <= 1.0; t += 0.05)
      EXPECT_EQ(pixel(wall.segment.start + t * (wall.segment.end - wall.segment.start)), 0)
          << wall.id << " " << t;
  EXPECT_EQ(pixel(Vec2(1.0, 0.05)), 254);   // seen through
  EXPECT_EQ(pixel(Vec2(2.55, 0.05)), 205);  // behind the wall
  EXPECT_EQ(pixel(Vec2(-1.25, -1.75)), 205);
  EXPECT_EQ(pixel(Vec2(1.15, -1.45)), 254);  // in front of the withheld piece (no wall: seen once)
  EXPECT_EQ(pixel(Vec2(1.15, -1.55)), 205);  // beyond it
  // Every wall cell the map has, and nothing else, is occupied: 2 m and 2.5 m at 0.1 m.
  EXPECT_GE(s.occupied, 20u + 25u);
  EXPECT_LE(s.occupied, 20u + 25u + 4u);
}

TEST(MapExport, SvgIsAWellFormedFigureOfTheMap)
{
  TempDir dir;
  ExportOptions options;
  options.formats = line_map_eval::kExportSvg;
  exportMap(writeMapFile(dir), dir.file("out"), options);
  const std::string svg = slurp(dir.file("out.svg"));
  ASSERT_FALSE(svg.empty());
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  // Every group opened is closed (a truncated file is not).
  EXPECT_EQ(countOf(svg, "<g>") + countOf(svg, "<g "), countOf(svg, "</g>"));

  // The map is the longest stroked path in the map colour (figures.cpp's dark blue; the legend has a
  // short sample line in it too): one "M x y L x y" per segment, at one scale for both walls, so
  // their drawn lengths keep the 2 m : 2.5 m ratio.
  const std::regex path_element(R"re(<path style="([^"]*)" d="([^"]*)")re");
  std::vector<double> lengths;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), path_element); it != std::sregex_iterator();
       ++it)
  {
    if ((*it)[1].str().find("stroke:rgb(5%,10%,45%)") == std::string::npos) continue;
    std::istringstream d((*it)[2].str());
    std::vector<double> mine;
    std::string move, line;
    double x1, y1, x2, y2;
    while (d >> move >> x1 >> y1 >> line >> x2 >> y2 && move == "M" && line == "L")
      mine.push_back(std::hypot(x2 - x1, y2 - y1));
    if (mine.size() > lengths.size()) lengths = mine;
  }
  ASSERT_EQ(lengths.size(), 2u);
  EXPECT_NEAR(lengths[0] / lengths[1], 2.0 / 2.5, 1e-3);
}

TEST(MapExport, AllFormatsAtOnce)
{
  TempDir dir;
  const ExportSummary s = exportMap(writeMapFile(dir), dir.file("out"));
  EXPECT_EQ(s.files, (std::vector<std::string>{dir.file("out.pgm"), dir.file("out.yaml"), dir.file("out.dxf"),
                                               dir.file("out.geojson"), dir.file("out.svg")}));
  EXPECT_EQ(s.segments, 2u);
  EXPECT_EQ(s.originals, 5u);
  for (const std::string& f : s.files) EXPECT_FALSE(slurp(f).empty()) << f;
}

TEST(MapExport, BadInputNamesTheFile)
{
  TempDir dir;
  const std::string bad = dir.file("broken_map.yaml");
  {
    std::ofstream out(bad);
    out << "format_version: 3\nmethod: cae\nparameters: [1, 2\n";
  }
  try
  {
    exportMap(bad, dir.file("out"));
    FAIL() << "no exception";
  }
  catch (const MapFileError& e)
  {
    const std::string what = e.what();
    EXPECT_NE(what.find(bad), std::string::npos) << what;
    EXPECT_NE(what.find(" line "), std::string::npos) << what;
  }
  EXPECT_THROW(exportMap(dir.file("missing.yaml"), dir.file("out")), MapFileError);
  ExportOptions options;
  options.resolution = -0.05;
  EXPECT_THROW(exportMap(writeMapFile(dir), dir.file("out"), options), std::invalid_argument);
  EXPECT_THROW(line_map_eval::parseExportFormat("png"), std::invalid_argument);
  EXPECT_EQ(line_map_eval::parseExportFormat("geojson"), line_map_eval::kExportGeoJson);
  // Nothing was written for the failed exports.
  EXPECT_FALSE(std::ifstream(dir.file("out.pgm")).good());
}

TEST(MapExport, ToolExitsNonZeroNamingTheFile)
{
  TempDir dir;
  const std::string bad = dir.file("broken_map.yaml");
  {
    std::ofstream out(bad);
    out << "format_version: 3\nmethod: cae\n";  // cut short
  }
  std::string output;
  EXPECT_EQ(runTool("'" + bad + "' '" + dir.file("out") + "'", output), 1);
  EXPECT_NE(output.find(bad), std::string::npos) << output;
  EXPECT_EQ(runTool("'" + writeMapFile(dir) + "' '" + dir.file("out") + "' --format xyz", output), 2);
  EXPECT_NE(output.find("xyz"), std::string::npos) << output;
  EXPECT_EQ(runTool("'" + writeMapFile(dir) + "' '" + dir.file("out") + "' --resolution abc", output), 2);
  EXPECT_NE(output.find("abc"), std::string::npos) << output;

  ASSERT_EQ(
      runTool("'" + writeMapFile(dir) + "' '" + dir.file("out") + "' --format dxf --resolution 0.1", output),
      0)
      << output;
  EXPECT_NE(output.find("2 map segments from 5 originals"), std::string::npos) << output;
  EXPECT_TRUE(std::ifstream(dir.file("out.dxf")).good());
  EXPECT_FALSE(std::ifstream(dir.file("out.pgm")).good());
}
