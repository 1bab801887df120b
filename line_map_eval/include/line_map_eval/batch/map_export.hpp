// Exports of a saved line map for the tools people already run (ROS-free): map_server's occupancy
// grid (PGM + YAML), DXF for CAD, GeoJSON for GIS and scripts, SVG for documents. `linemap_export`
// is the command-line front end.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "line_map_merging/mergers/merger.hpp"

namespace line_map_eval
{
enum ExportFormat : unsigned
{
  kExportPgm = 1u,  ///< OUT.pgm + OUT.yaml
  kExportDxf = 2u,
  kExportGeoJson = 4u,
  kExportSvg = 8u,
  kExportAll = 15u,
};

/// "pgm", "dxf", "geojson", "svg" or "all". Throws std::invalid_argument naming the accepted names.
unsigned parseExportFormat(const std::string& name);

struct ExportOptions
{
  unsigned formats = kExportAll;
  double resolution = 0.05;  ///< [m] of the occupancy grid
};

/// The DXF layer the map segments are drawn on.
extern const char* const kDxfLayer;

/// One LINE entity per segment on layer kDxfLayer, in metres (AutoCAD 2000 ASCII DXF through dxflib).
/// Throws std::runtime_error naming the file when it cannot be written.
void writeDxf(const std::vector<line_map_merging::MapSegment>& segments, const std::string& path);

/// A FeatureCollection with one LineString per segment, properties "id", "originals" (the number of
/// original segments fused into it) and "length" [m]. Coordinates are the map frame's metres, not
/// longitude and latitude. Throws std::runtime_error naming the file.
void writeGeoJson(const std::vector<line_map_merging::MapSegment>& segments, const std::string& path);

/// The map figure of figures.hpp (segments, start and end discs, scale bar, caption) as SVG.
void writeSvg(const std::vector<line_map_merging::MapSegment>& segments, const std::string& caption,
              const std::string& path);

struct ExportSummary
{
  std::vector<std::string> files;  ///< in the order written
  std::size_t segments = 0;        ///< map segments exported (the ones the map shows)
  std::size_t originals = 0;       ///< original segments in the provenance
  /// The occupancy grid, when written.
  int grid_width = 0, grid_height = 0;
  std::size_t occupied = 0, free = 0, unknown = 0;
};

/// Loads the CAE-RLSM map file and writes the chosen formats next to `out` (OUT.pgm, OUT.yaml,
/// OUT.dxf, OUT.geojson, OUT.svg). Throws line_map_merging::MapFileError (naming the file and
/// line) for a bad map file, std::invalid_argument for bad options and std::runtime_error naming
/// the file for a write failure.
ExportSummary exportMap(const std::string& map_file, const std::string& out,
                        const ExportOptions& options = {});

}  // namespace line_map_eval
