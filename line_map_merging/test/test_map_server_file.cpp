// map_server's PGM + YAML pair, read back as map_server reads it: a minimal parser of the YAML keys
// and the P5 image, the thresholds applied to each pixel, the image's top row as the highest y.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "line_map_merging/map/map_server_file.hpp"

using line_map_merging::buildOccupancyGrid;
using line_map_merging::OccupancyGrid;
using line_map_merging::OccupancyGridParams;
using line_map_merging::writeMapServerFiles;
using linemap::Segment2;
using linemap::Vec2;

namespace
{
std::string tempBase(const std::string& name)
{
  return (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) + "grid_test_" +
         std::to_string(::getpid()) + "_" + name;
}

/// What map_server gets from the pair: the YAML's fields and the image as occupancy values.
struct LoadedMap
{
  std::map<std::string, std::string> fields;
  std::string image;
  double resolution = 0.0;
  double origin[3] = {0.0, 0.0, 0.0};
  int width = 0, height = 0, max_value = 0;
  std::vector<unsigned char> pixels;  // as stored: the top row first
  /// nav_msgs value of grid cell (column, row), row 0 at the bottom, as map_server computes it
  /// (negate 0: p = (255 - v) / 255, occupied above occupied_thresh, free below free_thresh).
  int cell(int column, int row) const
  {
    const unsigned char v = pixels[static_cast<std::size_t>(height - 1 - row) * width + column];
    const double p = (255.0 - v) / 255.0;
    if (p > std::stod(fields.at("occupied_thresh"))) return 100;
    if (p < std::stod(fields.at("free_thresh"))) return 0;
    return -1;
  }
};

/// PGM header tokens: whitespace-separated, '#' comments to the end of the line.
std::string pgmToken(std::istream& in)
{
  std::string token;
  char c;
  while (in.get(c))
  {
    if (c == '#')
    {
      std::string comment;
      std::getline(in, comment);
      if (!token.empty()) return token;
    }
    else if (std::isspace(static_cast<unsigned char>(c)))
    {
      if (!token.empty()) return token;
    }
    else
      token += c;
  }
  return token;
}

LoadedMap loadMapServerPair(const std::string& yaml_path)
{
  LoadedMap m;
  std::ifstream yaml(yaml_path);
  if (!yaml) throw std::runtime_error("cannot open " + yaml_path);
  std::string line;
  while (std::getline(yaml, line))
  {
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    m.fields[line.substr(0, colon)] = value;
  }
  m.image = m.fields.at("image");
  m.resolution = std::stod(m.fields.at("resolution"));
  std::string origin = m.fields.at("origin");
  if (origin.front() != '[' || origin.back() != ']')
    throw std::runtime_error("origin is not a list: " + origin);
  std::istringstream list(origin.substr(1, origin.size() - 2));
  for (double& o : m.origin)
  {
    std::string item;
    std::getline(list, item, ',');
    o = std::stod(item);
  }
  // The image is named relative to the YAML's directory.
  const std::size_t slash = yaml_path.find_last_of('/');
  const std::string image_path = (slash == std::string::npos ? "" : yaml_path.substr(0, slash + 1)) + m.image;
  std::ifstream pgm(image_path, std::ios::binary);
  if (!pgm) throw std::runtime_error("cannot open " + image_path);
  if (pgmToken(pgm) != "P5") throw std::runtime_error(image_path + " is not a binary PGM");
  m.width = std::stoi(pgmToken(pgm));
  m.height = std::stoi(pgmToken(pgm));
  m.max_value = std::stoi(pgmToken(pgm));  // the single whitespace after it is consumed too
  m.pixels.resize(static_cast<std::size_t>(m.width) * m.height);
  pgm.read(reinterpret_cast<char*>(m.pixels.data()), static_cast<std::streamsize>(m.pixels.size()));
  if (pgm.gcount() != static_cast<std::streamsize>(m.pixels.size()))
    throw std::runtime_error(image_path + " is short");
  if (pgm.peek() != EOF) throw std::runtime_error(image_path + " has bytes after the image");
  return m;
}

OccupancyGrid wallGrid()
{
  // One keyframe at the origin seeing x = 2, y in [-1, 1]: at 0.3 m with a 1.05 m margin, 15 x 14
  // cells from (-1.2, -2.1) (hand count in test_occupancy_grid.cpp).
  const Segment2 wall(Vec2(2.0, -1.0), Vec2(2.0, 1.0));
  OccupancyGridParams p;
  p.resolution = 0.3;
  p.margin = 1.05;
  return buildOccupancyGrid({wall}, {{Vec2(0.0, 0.0), wall}}, p);
}
}  // namespace

TEST(MapServerFile, ReadBackAsMapServerReadsIt)
{
  const OccupancyGrid grid = wallGrid();
  const std::string base = tempBase("wall");
  const auto files = writeMapServerFiles(grid, base);
  EXPECT_EQ(files.pgm, base + ".pgm");
  EXPECT_EQ(files.yaml, base + ".yaml");

  const LoadedMap m = loadMapServerPair(files.yaml);
  EXPECT_EQ(m.image, base.substr(base.find_last_of('/') + 1) + ".pgm");
  EXPECT_EQ(m.fields.at("negate"), "0");
  EXPECT_EQ(m.fields.at("occupied_thresh"), "0.65");
  EXPECT_EQ(m.fields.at("free_thresh"), "0.196");
  EXPECT_DOUBLE_EQ(m.resolution, 0.3);
  EXPECT_NEAR(m.origin[0], -1.2, 1e-9);
  EXPECT_NEAR(m.origin[1], -2.1, 1e-9);
  EXPECT_EQ(m.origin[2], 0.0);
  EXPECT_EQ(m.width, 15);
  EXPECT_EQ(m.height, 14);
  EXPECT_EQ(m.max_value, 255);

  // Exactly the three grey levels of map_saver.
  std::map<int, int> levels;
  for (unsigned char v : m.pixels) ++levels[v];
  EXPECT_EQ(levels.size(), 3u);
  EXPECT_EQ(levels[0], 8);
  EXPECT_EQ(levels[254], 18);
  EXPECT_EQ(levels[205], 15 * 14 - 26);

  for (int row = 0; row < grid.height; ++row)
    for (int column = 0; column < grid.width; ++column)
      ASSERT_EQ(m.cell(column, row), grid.at(column, row)) << column << "," << row;

  // Rows flipped: the wall's top cell (world y in [0.9, 1.2), grid row 10) is image row 14 - 1 - 10 = 3,
  // and the image's first row (y in [1.8, 2.1)) is unknown throughout.
  EXPECT_EQ(m.pixels[3 * 15 + 10], 0);
  EXPECT_EQ(m.pixels[2 * 15 + 10], 205);
  for (int column = 0; column < 15; ++column) EXPECT_EQ(m.pixels[column], 205);
  // World (1, 0.1): column 7, grid row 7, image row 6.
  EXPECT_EQ(m.pixels[6 * 15 + 7], 254);
  std::remove(files.pgm.c_str());
  std::remove(files.yaml.c_str());
}

TEST(MapServerFile, ErrorsNameTheFile)
{
  try
  {
    writeMapServerFiles(wallGrid(), "/nonexistent_dir_for_linemap/out");
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir_for_linemap/out.pgm"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(writeMapServerFiles(OccupancyGrid(), tempBase("empty")), std::invalid_argument);
}
