// Figures of line maps with Cairo (ROS-free): SVG, PDF and PNG. World y points up; every
// figure has a scale bar of a round number of metres and a caption line.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "line_map_eval/metrics/lookup_table.hpp"
#include "linemap/geometry.hpp"

namespace line_map_eval
{
enum FigureFormat : unsigned
{
  kFigureSvg = 1u,
  kFigurePdf = 2u,
  kFigurePng = 4u,
  kFigureAllFormats = 7u,
};

/// Sizes are in PNG pixels, which are points in SVG and PDF.
struct FigureStyle
{
  double pixels_per_metre = 0.0;  ///< 0: fit the larger side of the map area into max_size
  double max_size = 1600.0;       ///< map area's larger side when fitting
  double margin = 20.0;           ///< blank border around each map area
  double caption_height = 28.0;   ///< band below the map area with the caption and the scale bar
  double legend_height = 22.0;    ///< band below the caption with the legend (0: no legend)
  double padding = 0.25;          ///< world border around the content [m]
  double line_width = 1.5;
  double endpoint_radius = 2.5;
  double font_size = 13.0;
};

/// One map panel. Segments are drawn dark blue with a red disc at each start and a green disc
/// at each end, over the scan points in light grey, over the lookup table (if any) in greys
/// (white for 0 to grey 40 % for 1, so the dark blue map stays visible on it). With
/// show_coverage, the uncovered scan points are drawn orange over the grey ones and both segments
/// of every redundant pair get a wide translucent magenta band under the map; uncovered points on
/// straight structure (structure_coverage.hpp) are listed apart and drawn cyan: a wall the map left
/// out, while the orange ones are then clutter. The legend names the layers the panel has.
struct MapFigure
{
  std::vector<linemap::Segment2> segments;
  std::vector<linemap::Vec2> scan_points;
  const LookupTable* lookup = nullptr;  ///< not owned; must outlive the draw call
  std::string caption;                  ///< e.g. "intel - CAE-RLSM"
  bool show_coverage = false;           ///< draw (and list in the legend) the two layers below, even empty
  std::vector<linemap::Vec2> uncovered_points;  ///< scan points farther than the coverage radius from the map
  /// Uncovered scan points on straight structure (then not also in uncovered_points).
  std::vector<linemap::Vec2> uncovered_structure_points;
  std::vector<std::pair<linemap::Segment2, linemap::Segment2>> redundant_pairs;
  /// A SLAM run (slam_figure.hpp), over the scan points and under the map: the trajectory as a black
  /// polyline, loop closures as lines between their two keyframes' positions (accepted green, rejected
  /// orange) and relations whose error exceeds bad_relation red between their two scans' positions
  /// (shown when show_relations). With show_slam the legend lists these layers (with their counts)
  /// instead of the map's when the figure has no segments.
  bool show_slam = false;
  std::vector<linemap::Vec2> trajectory;
  std::vector<linemap::Segment2> accepted_closures, rejected_closures;
  bool show_relations = false;
  double bad_relation = 0.3;  ///< [m], for the legend
  std::vector<linemap::Segment2> bad_relations;
};

/// Placement shared by the panels of a figure: the world box [min_x, max_x] x [min_y, max_y]
/// (content bounds plus padding, the union over all panels, so panels share one scale) maps
/// to a map area of map_width x map_height; panel k's area starts at x = k * panel_width + margin,
/// y = margin. The canvas is panels * panel_width x (map_height + 2 margin + caption_height +
/// legend_height).
struct FigureLayout
{
  double min_x = 0.0, max_x = 0.0, min_y = 0.0, max_y = 0.0;
  double pixels_per_metre = 1.0;
  double margin = 0.0, caption_height = 0.0, legend_height = 0.0;
  double map_width = 0.0, map_height = 0.0, panel_width = 0.0;
  double width = 0.0, height = 0.0;
  int panels = 1;

  /// Canvas coordinates (y down) of a world point in panel k.
  linemap::Vec2 toCanvas(const linemap::Vec2& world, int panel = 0) const
  {
    return {panel * panel_width + margin + (world.x() - min_x) * pixels_per_metre,
            margin + (max_y - world.y()) * pixels_per_metre};
  }
  /// PNG size: the canvas size rounded up to whole pixels.
  int pixelWidth() const;
  int pixelHeight() const;
};

FigureLayout layoutFigure(const std::vector<const MapFigure*>& panels, const FigureStyle& style);

/// The labels of the panel's legend, left to right, as drawn (with their counts; a narrow panel clips
/// the last ones).
std::vector<std::string> legendLabels(const MapFigure& figure, const FigureStyle& style = {});

/// Length of the scale bar for a map `width` metres wide: the largest 1, 2 or 5 times a power
/// of ten that is at most a quarter of it.
double scaleBarLength(double width);

/// Writes the figure. `path` either ends in .svg, .pdf or .png (exactly that file is written)
/// or has no such extension (path + ".svg"/".pdf"/".png" for each format in `formats`).
/// Returns the files written; throws std::runtime_error naming the file when Cairo fails.
std::vector<std::string> drawMap(const MapFigure& figure, const std::string& path,
                                 unsigned formats = kFigureAllFormats, const FigureStyle& style = {});

/// The lookup table as a greyscale image with the map on top.
std::vector<std::string> drawLookupTable(const LookupTable& table, const std::vector<linemap::Segment2>& map,
                                         const std::string& caption, const std::string& path,
                                         unsigned formats = kFigureAllFormats, const FigureStyle& style = {});

/// Two maps side by side at the same scale (e.g. before and after map adjustment).
std::vector<std::string> drawComparison(const MapFigure& left, const MapFigure& right,
                                        const std::string& path, unsigned formats = kFigureAllFormats,
                                        const FigureStyle& style = {});

}  // namespace line_map_eval
