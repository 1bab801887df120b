// An occupancy grid as map_server's PGM + YAML pair (ROS-free), the files map_server, AMCL and the
// costmaps load: binary PGM (P5) with 0 = occupied, 254 = free, 205 = unknown, the top row first
// (highest y), and a YAML naming it with the resolution, the origin of the lower-left pixel and
// the thresholds map_saver writes (negate 0, occupied_thresh 0.65, free_thresh 0.196).
#pragma once

#include <cstdint>
#include <string>

#include "line_map_merging/map/occupancy_grid.hpp"

namespace line_map_merging
{
struct MapServerFiles
{
  std::string pgm;
  std::string yaml;
};

/// The PGM grey level of a cell value (anything other than free or occupied is unknown).
std::uint8_t pgmValue(std::int8_t cell);

/// Writes `base`.pgm and `base`.yaml; the YAML names the image by its file name, which map_server
/// resolves next to the YAML. Throws std::runtime_error naming the file on failure, and
/// std::invalid_argument for an empty grid.
MapServerFiles writeMapServerFiles(const OccupancyGrid& grid, const std::string& base);

}  // namespace line_map_merging
