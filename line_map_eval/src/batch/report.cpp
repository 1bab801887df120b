// Console table, JSON (yaml-cpp's emitter in JSON-compatible flow style) and Markdown reports.
#include "line_map_eval/batch/report.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace line_map_eval
{
namespace
{
constexpr double kMm = 1000.0;

std::string fixed(double value, int decimals)
{
  if (!std::isfinite(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  return buf;
}

struct Column
{
  std::string header;
  bool left = false;
};

/// The full table of report.md.
std::vector<Column> columns()
{
  return {{"merger", true},
          {"scans"},
          {"orig segs"},
          {"orig min mm"},
          {"orig max mm"},
          {"orig mean mm"},
          {"map segs"},
          {"map min mm"},
          {"map max mm"},
          {"map mean mm"},
          {"quality %"},
          {"error mm"},
          {"unassigned"},
          {"point cov %"},
          {"length cov %"},
          {"structure cov %"},
          {"unmapped structure m"},
          {"redundant pairs"},
          {"redundant overlap m"},
          {"crossing pairs"},
          {"frame ms"},
          {"total ms"}};
}

/// The full table's cells of one merger, coverages to `coverage_decimals`.
std::vector<std::string> row(const MergerRun& r, int coverage_decimals = 2)
{
  return {r.name,
          std::to_string(r.scans),
          std::to_string(r.original_segments),
          fixed(r.originals.shortest * kMm, 1),
          fixed(r.originals.longest * kMm, 1),
          fixed(r.originals.mean * kMm, 1),
          std::to_string(r.map_segments),
          fixed(r.map.shortest * kMm, 1),
          fixed(r.map.longest * kMm, 1),
          fixed(r.map.mean * kMm, 1),
          fixed(r.quality.quality, 2),
          fixed(r.error.mean_error * kMm, 2),
          std::to_string(r.error.unassigned),
          fixed(r.point_coverage.fraction() * 100.0, coverage_decimals),
          fixed(r.length_coverage.fraction() * 100.0, coverage_decimals),
          fixed(r.structure_coverage.fraction() * 100.0, coverage_decimals),
          fixed(r.structure_coverage.unmapped_length, coverage_decimals),
          std::to_string(r.redundancy.pairs),
          fixed(r.redundancy.overlap_length, 2),
          std::to_string(r.crossing_pairs.size()),
          fixed(r.per_frame_ms, 3),
          fixed(r.total_ms, 1)};
}

/// The terminal table: what decides between maps, within 80 columns (two header lines, columns one
/// space apart, coverages to 0.1 %).
std::vector<std::pair<Column, std::string>> compactColumns()
{
  return {{{"merger", true}, ""}, {{"map"}, "segs"},      {{"qual."}, "%"},    {{"error"}, "mm"},
          {{"unass."}, "orig."},  {{"point"}, "cov %"},   {{"len."}, "cov %"}, {{"struct"}, "cov %"},
          {{"unmap."}, "m"},      {{"redund."}, "pairs"}, {{"cross"}, "pairs"}};
}

/// The terminal table's cells: those of the full table's columns it shows (see compactColumns).
std::vector<std::string> compactRow(const MergerRun& r)
{
  const std::vector<std::string> full = row(r, 1);
  static constexpr std::size_t kShown[] = {0, 6, 10, 11, 12, 13, 14, 15, 16, 17, 19};
  std::vector<std::string> cells;
  for (const std::size_t i : kShown) cells.push_back(full[i]);
  return cells;
}

/// Rounds for the JSON output so that the files stay readable; keeps null for non-finite values.
void number(YAML::Emitter& out, double value, int decimals = 3)
{
  if (!std::isfinite(value))
  {
    out << YAML::Null;
    return;
  }
  const double scale = std::pow(10.0, decimals);
  out << std::round(value * scale) / scale;
}

void key(YAML::Emitter& out, const char* k)
{
  out << YAML::Key << k << YAML::Value;
}

/// key: value for counts, strings and flags, written as they are.
template <typename T>
void field(YAML::Emitter& out, const char* k, const T& value)
{
  key(out, k);
  out << value;
}

/// key: value for measures, rounded by number().
void measure(YAML::Emitter& out, const char* k, double value, int decimals = 3)
{
  key(out, k);
  number(out, value, decimals);
}

/// Shortest, longest and mean length [mm] under keys PREFIX shortest_mm, PREFIX longest_mm and
/// PREFIX mean_length_mm.
void emitLengths(YAML::Emitter& out, const std::string& prefix, const LengthStatistics& s)
{
  measure(out, (prefix + "shortest_mm").c_str(), s.shortest * kMm);
  measure(out, (prefix + "longest_mm").c_str(), s.longest * kMm);
  measure(out, (prefix + "mean_length_mm").c_str(), s.mean * kMm);
}

/// Segment counts, lengths, quality and error of one map.
void emitSegmentsAndError(YAML::Emitter& out, const MergerRun& r)
{
  field(out, "scans", r.scans);
  field(out, "original_segments", r.original_segments);
  emitLengths(out, "original_", r.originals);
  field(out, "map_segments", r.map_segments);
  emitLengths(out, "", r.map);
  measure(out, "quality_pct", r.quality.quality);
  measure(out, "error_mm", r.error.mean_error * kMm);
  measure(out, "max_error_mm", r.error.max_error * kMm);
  field(out, "error_assignment", r.error_assignment);
  field(out, "assigned_originals", r.error.assigned);
  field(out, "unassigned_originals", r.error.unassigned);
}

/// The coverages, redundancy and crossings of one map.
void emitCoverage(YAML::Emitter& out, const MergerRun& r)
{
  field(out, "scan_points", r.point_coverage.points);
  field(out, "covered_scan_points", r.point_coverage.covered);
  measure(out, "point_coverage_pct", r.point_coverage.fraction() * 100.0);
  measure(out, "original_length_m", r.length_coverage.total);
  measure(out, "covered_original_length_m", r.length_coverage.covered);
  measure(out, "length_coverage_pct", r.length_coverage.fraction() * 100.0);
  field(out, "redundant_pairs", r.redundancy.pairs);
  measure(out, "redundant_overlap_m", r.redundancy.overlap_length);
  field(out, "structure_points", r.structure_coverage.points);
  field(out, "covered_structure_points", r.structure_coverage.covered);
  measure(out, "structure_coverage_pct", r.structure_coverage.fraction() * 100.0);
  measure(out, "structure_point_coverage_pct", r.structure_coverage.pointFraction() * 100.0);
  measure(out, "structure_length_m", r.structure_coverage.length);
  measure(out, "unmapped_structure_length_m", r.structure_coverage.unmapped_length);
  field(out, "crossing_pairs", r.crossing_pairs.size());
}

/// Runtimes and how the map came about.
void emitRunning(YAML::Emitter& out, const MergerRun& r)
{
  measure(out, "per_frame_ms", r.per_frame_ms, 4);
  measure(out, "per_frame_p99_ms", r.per_frame_p99_ms, 4);
  measure(out, "total_ms", r.total_ms);
  measure(out, "adjust_ms", r.adjust_ms);
  measure(out, "keyframe_ms", r.keyframe_ms);
  field(out, "trajectories", r.trajectories);
  field(out, "adjustments", r.adjustments);
  field(out, "rebuilds", r.rebuilds);
  field(out, "retired_originals", r.retired);
  field(out, "map_level_lines", r.map_level_lines);
  measure(out, "map_level_ms", r.map_level_ms);
  measure(out, "evaluation_ms", r.evaluation_ms);
  field(out, "online", r.online);
  field(out, "provenance", r.provenance);
  measure(out, "quality_before_adjust_pct",
          r.quality_before_adjust ? *r.quality_before_adjust : std::nan(""));
  if (r.step_ms.empty()) return;
  out << YAML::Key << "step_ms" << YAML::Value << YAML::BeginMap;
  for (const auto& [step, ms] : r.step_ms) measure(out, step.c_str(), ms);
  out << YAML::EndMap;
}

void emitGroundTruth(YAML::Emitter& out, const GroundTruthResult& g)
{
  key(out, "ground_truth");
  out << YAML::BeginMap;
  measure(out, "coverage_pct", g.coverage * 100.0);
  field(out, "undetected_walls", g.undetected_walls);
  measure(out, "max_endpoint_error_mm", g.max_endpoint_error * kMm);
  measure(out, "mean_endpoint_error_mm", g.mean_endpoint_error * kMm);
  field(out, "unmapped_ends", g.unmapped_ends);
  field(out, "unseen_faces", g.unseen_walls);
  measure(out, "mean_vertex_error_mm", g.mean_vertex_error * kMm);
  field(out, "missed_corners", g.missed_corners);
  field(out, "corners", g.corners.size());
  field(out, "walls", g.walls.size());
  // Each seen face: which walls a map misses, and where.
  key(out, "faces");
  out << YAML::BeginSeq;
  for (const WallScore& w : g.walls)
  {
    out << YAML::Flow << YAML::BeginMap;
    field(out, "face", w.face);
    key(out, "start");
    out << YAML::Flow << YAML::BeginSeq << w.segment.start.x() << w.segment.start.y() << YAML::EndSeq;
    key(out, "end");
    out << YAML::Flow << YAML::BeginSeq << w.segment.end.x() << w.segment.end.y() << YAML::EndSeq;
    measure(out, "seen_m", w.seen_length);
    measure(out, "coverage_pct", w.coverage * 100.0);
    field(out, "segments", w.associated);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
}

void emitRun(YAML::Emitter& out, const MergerRun& r)
{
  out << YAML::BeginMap;
  emitSegmentsAndError(out, r);
  emitCoverage(out, r);
  emitRunning(out, r);
  if (r.ground_truth) emitGroundTruth(out, *r.ground_truth);
  key(out, "files");
  out << YAML::BeginSeq;
  for (const auto& f : r.files) out << f;
  out << YAML::EndSeq;
  out << YAML::EndMap;
}

/// What was run on which data, and the originals all mergers share.
void emitDataset(YAML::Emitter& out, const BatchResult& result)
{
  field(out, "dataset", result.dataset);
  field(out, "kind", result.kind);
  field(out, "extractor", result.extractor);
  field(out, "loop_closure", result.loop_closure);
  field(out, "adjust_every", result.adjust_every);
  field(out, "candidate_scans", result.candidate_scans);
  field(out, "scans", result.keyframes);
  field(out, "original_segments", result.originals.count);
  emitLengths(out, "original_", result.originals);
  measure(out, "original_fit_rms_mm", result.original_fit_rms * kMm);
  measure(out, "original_line_sigma_mm", result.original_line_sigma * kMm);
  field(out, "scan_points", result.scan_points);
  measure(out, "extraction_ms", result.extraction_ms);
  measure(out, "table_ms", result.table_ms);
  measure(out, "structure_ms", result.structure_ms);
}

void writeFile(const std::filesystem::path& path, const std::string& text)
{
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write the report");
}

}  // namespace

std::string formatTable(const BatchResult& result)
{
  std::vector<Column> cols;
  std::vector<std::vector<std::string>> cells(2);
  for (const auto& [c, second] : compactColumns())
  {
    cols.push_back(c);
    cells[0].push_back(c.header);
    cells[1].push_back(second);
  }
  for (const auto& r : result.mergers) cells.push_back(compactRow(r));
  std::vector<std::size_t> width(cols.size(), 0);
  for (const auto& line : cells)
    for (std::size_t i = 0; i < line.size(); ++i) width[i] = std::max(width[i], line[i].size());
  std::ostringstream out;
  for (const auto& line : cells)
  {
    for (std::size_t i = 0; i < line.size(); ++i)
    {
      const std::string pad(width[i] - line[i].size(), ' ');
      out << (i ? " " : "") << (cols[i].left ? line[i] + pad : pad + line[i]);
    }
    out << '\n';
  }
  return out.str();
}

std::string toJson(const BatchResult& result)
{
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out.SetStringFormat(YAML::DoubleQuoted);
  out.SetBoolFormat(YAML::TrueFalseBool);
  out.SetBoolFormat(YAML::LowerCase);
  out.SetNullFormat(YAML::LowerNull);
  out.SetDoublePrecision(12);
  out << YAML::BeginMap;
  emitDataset(out, result);
  // The whole evaluation of one map: the shared table and structure classification plus that map's
  // metrics.
  key(out, "map_evaluation_ms");
  out << YAML::BeginMap;
  for (const auto& r : result.mergers)
  {
    out << YAML::Key << r.name << YAML::Value;
    number(out, result.table_ms + result.structure_ms + r.evaluation_ms);
  }
  out << YAML::EndMap;
  key(out, "parameters");
  out << YAML::BeginMap;
  for (const auto& [k, v] : result.parameters.values())
  {
    out << YAML::Key << k << YAML::Value << v;
  }
  out << YAML::EndMap;
  key(out, "mergers");
  out << YAML::BeginMap;
  for (const auto& r : result.mergers)
  {
    out << YAML::Key << r.name << YAML::Value;
    emitRun(out, r);
  }
  out << YAML::EndMap;
  out << YAML::EndMap;
  if (!out.good()) throw std::runtime_error(std::string("report.json: ") + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

namespace
{
/// The dataset, extractor and the figures every merger shares.
void markdownHeader(std::ostringstream& md, const BatchResult& result)
{
  md << "# Line map comparison: " << result.dataset << "\n\n";
  md << "- dataset kind: " << result.kind
     << (result.loop_closure
             ? " (online mergers run through the online mapper as in the nodelets: on odometry until the "
               "first of " +
                   std::to_string(result.trajectories) +
                   " trajectories, then on its nodes; offline mergers get the final poses)"
             : " (the poses are final for every merger)")
     << "\n";
  md << "- extractor: " << result.extractor << "; " << result.keyframes
     << " keyframes chosen by the online path of " << result.candidate_scans << " candidates; extraction "
     << fixed(result.extraction_ms, 1) << " ms\n";
  md << "- accuracy at the source: the originals fit their own points with an RMS residual of "
     << fixed(result.original_fit_rms * kMm, 2) << " mm on average (line position standard error "
     << fixed(result.original_line_sigma * kMm, 2)
     << " mm); the error column measures them against their map segment, so what it adds beyond these "
        "comes from registration (the poses) and merging\n";
  md << "- lookup table: " << result.scan_points << " registered scan points under the final poses, built in "
     << fixed(result.table_ms, 1) << " ms\n";
  if (!result.mergers.empty())
  {
    const StructureCoverage& s = result.mergers.front().structure_coverage;
    md << "- straight structure: " << s.points << " of the registered points (" << fixed(s.length, 1)
       << " m), classified in " << fixed(result.structure_ms, 1) << " ms\n";
  }
  md << "\n";
}

/// The full table, one row per merger.
void markdownTable(std::ostringstream& md, const BatchResult& result)
{
  const auto cols = columns();
  md << "|";
  for (const auto& c : cols) md << " " << c.header << " |";
  md << "\n|";
  for (const auto& c : cols) md << (c.left ? "---|" : "---:|");
  md << "\n";
  for (const auto& r : result.mergers)
  {
    md << "|";
    for (const auto& cell : row(r)) md << " " << cell << " |";
    md << "\n";
  }
}

void groundTruthNote(std::ostringstream& md, const GroundTruthResult& g)
{
  md << "; ground truth over the " << g.walls.size() << " seen faces (" << g.unseen_walls
     << " never seen, not scored): coverage " << fixed(g.coverage * 100.0, 1) << " %, " << g.undetected_walls
     << " undetected, endpoint error mean " << fixed(g.mean_endpoint_error * kMm, 1) << " / max "
     << fixed(g.max_endpoint_error * kMm, 1) << " mm, " << g.unmapped_ends
     << " seen ends no segment reaches, mean vertex error " << fixed(g.mean_vertex_error * kMm, 1) << " mm, "
     << g.missed_corners << " of " << g.corners.size() << " corners missed";
}

/// One merger's bullet: error assignment, timings, ground truth and its files.
void mergerNote(std::ostringstream& md, const MergerRun& r)
{
  md << "- **" << r.name << "** (" << (r.online ? "online" : "offline") << "): error from "
     << r.error_assignment << " (" << r.error.assigned << " originals assigned, " << r.error.unassigned
     << " without a map segment; max " << fixed(r.error.max_error * kMm, 1) << " mm); evaluation "
     << fixed(r.evaluation_ms, 1) << " ms";
  if (r.adjustments) md << "; " << r.adjustments << " adjustments, " << fixed(r.adjust_ms, 1) << " ms";
  if (r.rebuilds) md << "; rebuilt from the nodes of the first trajectory";
  if (r.retired) md << "; " << r.retired << " originals of the saved map retired (seen through)";
  if (r.map_level_lines)
    md << "; " << r.map_level_lines << " map-level lines (" << fixed(r.map_level_ms, 1)
       << " ms of the merging time)";
  if (!r.step_ms.empty())
  {
    md << "; steps";
    for (const auto& [step, ms] : r.step_ms)
      md << (&step == &r.step_ms.front().first ? " " : ", ") << step << " " << fixed(ms, 1) << " ms";
  }
  if (r.quality_before_adjust)
    md << "; quality before the last trajectory " << fixed(*r.quality_before_adjust, 2) << " %";
  if (r.ground_truth) groundTruthNote(md, *r.ground_truth);
  md << "\n";
  for (const auto& f : r.files) md << "  - `" << f << "`\n";
  // The map figure inline, relative to report.md (which sits in the output directory).
  for (const auto& f : r.files)
    if (std::filesystem::path(f).filename() == "map.png")
      md << "\n  ![" << r.name << "](" << r.name << "/map.png)\n";
}
}  // namespace

std::string toMarkdown(const BatchResult& result)
{
  std::ostringstream md;
  markdownHeader(md, result);
  markdownTable(md, result);
  md << "\nOriginal segments and their lengths are those of Table I of the CAE-RLSM paper, map segments "
        "those of Table III. Quality is the correlation quality against the lookup table of the registered "
        "scans; error the mean distance of the originals' midpoints to their map segment's line, over the "
        "originals assigned to one (unassigned: the others). Point coverage is the share of the registered "
        "scan points within one lookup-table sigma of a map segment; length coverage the share of the "
        "originals' length lying within d_max and theta_max of a map segment. Structure coverage is the "
        "share of the length of straight structure in the registered points (straight, continuous bands of "
        "points, thin or smeared across by the poses: walls, not clutter) that the map covers; unmapped "
        "structure the length left uncovered (a structure point is covered within that same radius of a "
        "map segment, or, on a smeared band, when its foot on the band's line is within the band's width). "
        "Redundant pairs are pairs of map segments meeting the "
        "fusion conditions with each other (overlap: their summed overlap along the line); crossing pairs "
        "are map segments crossing in an X, both running on past the crossing by more than the "
        "point-coverage radius. Per-frame runtime is the median addKeyframe time of online mergers; total "
        "runtime covers every addKeyframe, adjust and the final map.\n\n";
  md << "## Notes per merger\n\n";
  for (const auto& r : result.mergers) mergerNote(md, r);
  md << "\n## Parameters\n\n";
  for (const auto& [k, v] : result.parameters.values()) md << "- `" << k << "`: `" << v << "`\n";
  return md.str();
}

void writeReports(const BatchResult& result, const std::string& dir)
{
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the directory: " + ec.message());
  writeFile(std::filesystem::path(dir) / "report.json", toJson(result));
  writeFile(std::filesystem::path(dir) / "report.md", toMarkdown(result));
}

}  // namespace line_map_eval
