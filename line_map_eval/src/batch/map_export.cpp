// Exports of a saved line map: occupancy grid, DXF, GeoJSON, SVG (see map_export.hpp).
#include "line_map_eval/batch/map_export.hpp"

#include <dl_dxf.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "line_map_eval/batch/figures.hpp"
#include "line_map_merging/map/map_server_file.hpp"
#include "line_map_merging/map/occupancy_grid.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"

namespace line_map_eval
{
using line_map_merging::MapSegment;

const char* const kDxfLayer = "linemap";

unsigned parseExportFormat(const std::string& name)
{
  if (name == "pgm") return kExportPgm;
  if (name == "dxf") return kExportDxf;
  if (name == "geojson") return kExportGeoJson;
  if (name == "svg") return kExportSvg;
  if (name == "all") return kExportAll;
  throw std::invalid_argument("unknown format '" + name + "' (expected pgm, dxf, geojson, svg or all)");
}

void writeDxf(const std::vector<MapSegment>& segments, const std::string& path)
{
  // The section and table sequence dxflib documents for an AutoCAD 2000 file that CAD programs open:
  // header, the standard tables (with our layer), the model and paper space blocks, the entities,
  // and the objects section.
  DL_Dxf dxf;
  std::unique_ptr<DL_WriterA> out(dxf.out(path.c_str(), DL_Codes::AC1015));  // null when it cannot open
  if (!out) throw std::runtime_error("cannot create '" + path + "': " + std::strerror(errno));
  DL_WriterA& w = *out;
  dxf.writeHeader(w);
  w.sectionEnd();

  w.sectionTables();
  dxf.writeVPort(w);
  w.tableLinetypes(3);
  dxf.writeLinetype(w, DL_LinetypeData("BYBLOCK", "", 0, 0, 0.0));
  dxf.writeLinetype(w, DL_LinetypeData("BYLAYER", "", 0, 0, 0.0));
  dxf.writeLinetype(w, DL_LinetypeData("CONTINUOUS", "Solid line", 0, 0, 0.0));
  w.tableEnd();
  w.tableLayers(2);
  dxf.writeLayer(w, DL_LayerData("0", 0), DL_Attributes("", DL_Codes::black, 100, "CONTINUOUS", 1.0));
  dxf.writeLayer(w, DL_LayerData(kDxfLayer, 0), DL_Attributes("", DL_Codes::blue, 100, "CONTINUOUS", 1.0));
  w.tableEnd();
  w.tableStyle(1);
  dxf.writeStyle(w, DL_StyleData("standard", 0, 0.0, 1.0, 0.0, 0, 2.5, "txt", ""));
  w.tableEnd();
  dxf.writeView(w);
  dxf.writeUcs(w);
  w.tableAppid(1);
  dxf.writeAppid(w, "ACAD");
  w.tableEnd();
  dxf.writeDimStyle(w, 1, 1, 1, 1, 1);
  dxf.writeBlockRecord(w);
  w.tableEnd();
  w.sectionEnd();

  w.sectionBlocks();
  for (const char* block : {"*Model_Space", "*Paper_Space", "*Paper_Space0"})
  {
    dxf.writeBlock(w, DL_BlockData(block, 0, 0.0, 0.0, 0.0));
    dxf.writeEndBlock(w, block);
  }
  w.sectionEnd();

  w.sectionEntities();
  // Colour and line width follow the layer (256 = BYLAYER, -1 = BYLAYER).
  const DL_Attributes on_layer(kDxfLayer, 256, -1, "BYLAYER", 1.0);
  for (const MapSegment& m : segments)
  {
    const linemap::Segment2& s = m.segment;
    dxf.writeLine(w, DL_LineData(s.start.x(), s.start.y(), 0.0, s.end.x(), s.end.y(), 0.0), on_layer);
  }
  w.sectionEnd();
  dxf.writeObjects(w);
  dxf.writeObjectsEnd(w);
  w.dxfEOF();
  w.close();
}

void writeGeoJson(const std::vector<MapSegment>& segments, const std::string& path)
{
  nlohmann::json features = nlohmann::json::array();
  for (const MapSegment& m : segments)
  {
    const linemap::Segment2& s = m.segment;
    features.push_back(
        {{"type", "Feature"},
         {"geometry",
          {{"type", "LineString"}, {"coordinates", {{s.start.x(), s.start.y()}, {s.end.x(), s.end.y()}}}}},
         {"properties", {{"id", m.id}, {"originals", m.merged_count}, {"length", s.length()}}}});
  }
  const nlohmann::json collection = {{"type", "FeatureCollection"}, {"features", features}};
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw std::runtime_error("cannot create '" + path + "': " + std::strerror(errno));
  out << collection.dump(1) << "\n";  // one-space indent: readable, and diffs stay per coordinate
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
}

void writeSvg(const std::vector<MapSegment>& segments, const std::string& caption, const std::string& path)
{
  MapFigure figure;
  figure.caption = caption;
  for (const MapSegment& m : segments) figure.segments.push_back(m.segment);
  drawMap(figure, path, kFigureSvg);
}

ExportSummary exportMap(const std::string& map_file, const std::string& out, const ExportOptions& options)
{
  if ((options.formats & kExportAll) == 0) throw std::invalid_argument("no export format selected");
  line_map_merging::OccupancyGridParams grid_params;
  grid_params.resolution = options.resolution;
  grid_params.validate();  // before the load, so a bad option fails fast

  line_map_merging::CaeRlsm map;
  map.load(map_file);
  const std::vector<MapSegment> segments = map.map();
  ExportSummary summary;
  summary.segments = segments.size();
  summary.originals = map.leafCount();

  if (options.formats & kExportPgm)
  {
    const line_map_merging::OccupancyGrid grid = line_map_merging::buildOccupancyGrid(map, grid_params);
    const line_map_merging::MapServerFiles files = line_map_merging::writeMapServerFiles(grid, out);
    summary.files.push_back(files.pgm);
    summary.files.push_back(files.yaml);
    summary.grid_width = grid.width;
    summary.grid_height = grid.height;
    summary.occupied = grid.count(line_map_merging::OccupancyGrid::kOccupied);
    summary.free = grid.count(line_map_merging::OccupancyGrid::kFree);
    summary.unknown = grid.count(line_map_merging::OccupancyGrid::kUnknown);
  }
  if (options.formats & kExportDxf)
  {
    writeDxf(segments, out + ".dxf");
    summary.files.push_back(out + ".dxf");
  }
  if (options.formats & kExportGeoJson)
  {
    writeGeoJson(segments, out + ".geojson");
    summary.files.push_back(out + ".geojson");
  }
  if (options.formats & kExportSvg)
  {
    const std::size_t slash = map_file.find_last_of('/');
    const std::string caption = (slash == std::string::npos ? map_file : map_file.substr(slash + 1)) + " - " +
                                std::to_string(segments.size()) + " segments from " +
                                std::to_string(summary.originals) + " originals";
    writeSvg(segments, caption, out + ".svg");
    summary.files.push_back(out + ".svg");
  }
  return summary;
}

}  // namespace line_map_eval
