// Self-registration of extraction algorithms: each algorithm's .cpp defines one
// static ExtractorRegistration, so makeExtractor/extractorNames find it without a
// central list to edit.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "line_extraction/extractor.hpp"

namespace line_extraction
{
using ExtractorFactory = std::unique_ptr<Extractor> (*)(const linemap::ParamSet& params);

/// Registers `make` under `name`; `order` places the name in extractorNames()
/// (srg 10, split_merge 20, iepf 30, smsm 40, incremental 50, line_regression 60,
/// hough 70, ransac 80, em 90, wsac_ge 100).
struct ExtractorRegistration
{
  ExtractorRegistration(const char* name, int order, ExtractorFactory make);
};

/// The factory of an algorithm whose constructor takes the parameters: `&makeExtractorOf<MyAlgorithm>`.
template <typename T>
std::unique_ptr<Extractor> makeExtractorOf(const linemap::ParamSet& params)
{
  return std::make_unique<T>(params);
}

}  // namespace line_extraction
