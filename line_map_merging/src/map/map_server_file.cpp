// map_server's PGM + YAML pair of an occupancy grid (see map_server_file.hpp).
#include "line_map_merging/map/map_server_file.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace line_map_merging
{
namespace
{
constexpr std::uint8_t kPgmOccupied = 0;
constexpr std::uint8_t kPgmFree = 254;
constexpr std::uint8_t kPgmUnknown = 205;

/// Shortest text that reads back as the same double (0.05 rather than 0.050000000000000003).
std::string shortest(double v)
{
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

void finish(std::ofstream& out, const std::string& path)
{
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
}

std::string fileName(const std::string& path)
{
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}
}  // namespace

std::uint8_t pgmValue(std::int8_t cell)
{
  if (cell == OccupancyGrid::kOccupied) return kPgmOccupied;
  if (cell == OccupancyGrid::kFree) return kPgmFree;
  return kPgmUnknown;
}

MapServerFiles writeMapServerFiles(const OccupancyGrid& grid, const std::string& base)
{
  if (grid.width <= 0 || grid.height <= 0 ||
      grid.cells.size() != static_cast<std::size_t>(grid.width) * grid.height)
    throw std::invalid_argument("map_server files '" + base +
                                "': the grid is empty (no segment and no original)");
  const MapServerFiles files{base + ".pgm", base + ".yaml"};

  std::ofstream pgm(files.pgm, std::ios::binary | std::ios::trunc);
  if (!pgm) throw std::runtime_error("cannot create '" + files.pgm + "': " + std::strerror(errno));
  pgm << "P5\n# linemap occupancy grid, " << shortest(grid.resolution) << " m/cell\n"
      << grid.width << ' ' << grid.height << "\n255\n";
  std::vector<char> line(static_cast<std::size_t>(grid.width));
  for (int row = grid.height - 1; row >= 0; --row)  // image row 0 is the top, the highest y
  {
    for (int column = 0; column < grid.width; ++column)
      line[static_cast<std::size_t>(column)] = static_cast<char>(pgmValue(grid.at(column, row)));
    pgm.write(line.data(), static_cast<std::streamsize>(line.size()));
  }
  finish(pgm, files.pgm);

  std::ofstream yaml(files.yaml, std::ios::trunc);
  if (!yaml) throw std::runtime_error("cannot create '" + files.yaml + "': " + std::strerror(errno));
  yaml << "image: " << fileName(files.pgm) << "\n"
       << "resolution: " << shortest(grid.resolution) << "\n"
       << "origin: [" << shortest(grid.origin.x()) << ", " << shortest(grid.origin.y()) << ", 0.0]\n"
       << "negate: 0\n"
       << "occupied_thresh: 0.65\n"
       << "free_thresh: 0.196\n";
  finish(yaml, files.yaml);
  return files;
}

}  // namespace line_map_merging
