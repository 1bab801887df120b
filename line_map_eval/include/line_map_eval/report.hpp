// Reports of a batch run (ROS-free): the console table, report.json and report.md.
#pragma once

#include <string>

#include "line_map_eval/batch.hpp"

namespace line_map_eval
{
/// One row per merger: scans, original segments (Table I), map segments (Table III), quality,
/// error and runtimes, with a header line; lengths in mm.
std::string formatTable(const BatchResult& result);

/// The whole result as JSON: dataset, extractor, parameters and one object per merger under
/// "mergers" (keys scans, original_segments, map_segments, shortest_mm, longest_mm, mean_length_mm,
/// quality_pct, error_mm, per_frame_ms, total_ms, ...). Non-finite numbers are null.
std::string toJson(const BatchResult& result);

/// The table and the notes (error assignment, ground truth, runtimes) as Markdown.
std::string toMarkdown(const BatchResult& result);

/// Writes DIR/report.json and DIR/report.md (creating DIR); throws std::runtime_error naming the file.
void writeReports(const BatchResult& result, const std::string& dir);

}  // namespace line_map_eval
