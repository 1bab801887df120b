// The structure-coverage and crossing-pair columns of the batch reports: terminal table, report.json and
// report.md, on a hand-made result (values chosen, so every expected cell is known).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <sstream>
#include <string>

#include "line_map_eval/batch/report.hpp"

using namespace line_map_eval;

namespace
{
MergerRun run(const std::string& name, std::size_t covered, std::size_t crossings, double unmapped)
{
  MergerRun r;
  r.name = name;
  r.scans = 906;
  r.map_segments = 1472;  // as wide as the widest of the real tables
  r.quality.quality = 95.83;
  r.error.mean_error = 0.01841;
  r.error.unassigned = 1905;
  r.point_coverage.points = 1000;
  r.point_coverage.covered = 690;
  r.length_coverage.total = 100.0;
  r.length_coverage.covered = 97.8;
  r.structure_coverage.points = 800;
  r.structure_coverage.covered = covered;
  r.structure_coverage.length = 4938.24;
  r.structure_coverage.unmapped_length = unmapped;
  r.redundancy.pairs = 93;
  for (std::size_t k = 0; k < crossings; ++k)
    r.crossing_pairs.push_back({static_cast<int>(k), static_cast<int>(k + 1), linemap::Vec2(1.0, 2.0)});
  r.per_frame_ms = 0.005;
  r.total_ms = 28.7;
  return r;
}

BatchResult result()
{
  BatchResult b;
  b.dataset = "intel";
  b.kind = "carmen+corrected";
  b.extractor = "srg";
  b.scan_points = 1000;
  b.table_ms = 10.0;
  b.structure_ms = 150.0;
  // Unmapped 1234.56 m (wider than any real one) and 617.28 m of 4938.24: 75 % and 87.5 % covered.
  b.mergers = {run("cae", 600, 0, 1234.56), run("cae_offline", 700, 12, 617.28)};
  b.mergers[1].evaluation_ms = 40.0;
  return b;
}
}  // namespace

TEST(ReportStructure, TerminalTableFitsAndShowsTheNewColumns)
{
  const std::string table = formatTable(result());
  std::istringstream lines(table);
  std::vector<std::string> rows;
  for (std::string line; std::getline(lines, line);) rows.push_back(line);
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& line : rows) EXPECT_LE(line.size(), 80u) << line;
  EXPECT_NE(rows[0].find("struct"), std::string::npos);
  EXPECT_NE(rows[0].find("unmap."), std::string::npos);
  EXPECT_NE(rows[0].find("cross"), std::string::npos);
  // 1 - 1234.56 / 4938.24 = 75.0 %, 1 - 617.28 / 4938.24 = 87.5 %; lengths to 0.1 m; point coverage
  // 69.0 % as before.
  EXPECT_NE(rows[2].find(" 75.0 1234.6 "), std::string::npos) << rows[2];
  EXPECT_NE(rows[3].find(" 87.5  617.3 "), std::string::npos) << rows[3];
  EXPECT_NE(rows[2].find(" 69.0 "), std::string::npos) << rows[2];
  // The last column: crossing pairs.
  EXPECT_EQ(rows[2].back(), '0');
  EXPECT_EQ(rows[3].substr(rows[3].size() - 2), "12");
}

TEST(ReportStructure, JsonKeys)
{
  const YAML::Node json = YAML::Load(toJson(result()));
  EXPECT_DOUBLE_EQ(json["structure_ms"].as<double>(), 150.0);
  // The shared table and classification, plus the map's own metrics.
  EXPECT_DOUBLE_EQ(json["map_evaluation_ms"]["cae_offline"].as<double>(), 200.0);
  const YAML::Node cae = json["mergers"]["cae"], offline = json["mergers"]["cae_offline"];
  EXPECT_EQ(cae["structure_points"].as<std::size_t>(), 800u);
  EXPECT_EQ(cae["covered_structure_points"].as<std::size_t>(), 600u);
  EXPECT_DOUBLE_EQ(cae["structure_coverage_pct"].as<double>(), 75.0);
  EXPECT_DOUBLE_EQ(offline["structure_coverage_pct"].as<double>(), 87.5);
  // The share of the structure points: 600 / 800, 700 / 800.
  EXPECT_DOUBLE_EQ(cae["structure_point_coverage_pct"].as<double>(), 75.0);
  EXPECT_DOUBLE_EQ(offline["structure_point_coverage_pct"].as<double>(), 87.5);
  EXPECT_DOUBLE_EQ(cae["structure_length_m"].as<double>(), 4938.24);
  EXPECT_DOUBLE_EQ(cae["unmapped_structure_length_m"].as<double>(), 1234.56);
  EXPECT_EQ(cae["crossing_pairs"].as<std::size_t>(), 0u);
  EXPECT_EQ(offline["crossing_pairs"].as<std::size_t>(), 12u);
  // Point coverage is kept as it was.
  EXPECT_DOUBLE_EQ(cae["point_coverage_pct"].as<double>(), 69.0);
}

TEST(ReportStructure, MarkdownColumns)
{
  const std::string md = toMarkdown(result());
  for (const char* header : {"| structure cov % |", "| unmapped structure m |", "| crossing pairs |"})
    EXPECT_NE(md.find(header), std::string::npos) << header;
  EXPECT_NE(md.find("| 75.00 | 1234.56 |"), std::string::npos);
  EXPECT_NE(md.find("straight structure: 800 of the registered points (4938.2 m)"), std::string::npos);
}
