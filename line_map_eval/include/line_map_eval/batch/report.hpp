// Reports of a batch run (ROS-free): the console table, report.json and report.md.
#pragma once

#include <string>

#include "line_map_eval/batch/batch.hpp"

namespace line_map_eval
{
/// The terminal table, within 80 columns: one row per merger with map segments, quality, error,
/// unassigned originals, point, length and structure coverage, unmapped structure length, redundant
/// and crossing pairs, under two header lines.
/// The full table (Tables I and III, lengths, runtimes) is in toMarkdown().
std::string formatTable(const BatchResult& result);

/// The whole result as JSON: dataset, extractor, parameters and one object per merger under
/// "mergers" (keys scans, original_segments, map_segments, shortest_mm, longest_mm, mean_length_mm,
/// quality_pct, error_mm, unassigned_originals, point_coverage_pct, length_coverage_pct, redundant_pairs,
/// redundant_overlap_m, structure_points, covered_structure_points, structure_coverage_pct,
/// structure_length_m, unmapped_structure_length_m, crossing_pairs, per_frame_ms, total_ms, ...).
/// Non-finite numbers are null.
std::string toJson(const BatchResult& result);

/// The table and the notes (error assignment, ground truth, runtimes) as Markdown.
std::string toMarkdown(const BatchResult& result);

/// Writes DIR/report.json and DIR/report.md (creating DIR); throws std::runtime_error naming the file.
void writeReports(const BatchResult& result, const std::string& dir);

}  // namespace line_map_eval
