// The extractor interface, the factory of every algorithm, and the full
// per-scan pipeline (preprocess -> optional clustering -> algorithm -> merge -> filter).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "line_extraction/types.hpp"
#include "linemap/params.hpp"

namespace line_extraction
{
/// One line extraction algorithm. Implementations keep their scratch buffers
/// between calls (no allocation once warmed up) and, when randomised, reseed
/// from their `seed` parameter at every call so results are deterministic.
class Extractor
{
 public:
  virtual ~Extractor() = default;
  virtual const char* name() const = 0;
  /// Appends to `out` the segments found among scan points [range.begin, range.end).
  virtual void extractRange(const PreparedScan& scan, PointRange range, ExtractionResult& out) = 0;
};

/// Creates the algorithm `name` (e.g. "srg", "hough") from parameters
/// "<name>/<param>"; throws linemap::ParameterError naming a bad parameter or name.
std::unique_ptr<Extractor> makeExtractor(const std::string& name, const linemap::ParamSet& params);

/// Names accepted by makeExtractor, in the order of the comparison tables.
const std::vector<std::string>& extractorNames();

}  // namespace line_extraction
