// Small helpers every package needs once: elapsed time, the median and percentiles, a path's file name and
// stem, a number from text.
#pragma once

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace linemap
{
/// Milliseconds on the steady clock since `start`.
inline double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The median (the mean of the middle two for an even count); NaN for no value.
inline double median(std::vector<double> values)
{
  if (values.empty()) return std::nan("");
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

/// The q-th quantile by nearest rank: the smallest value with at least a share q of the values at or
/// below it (q = 0.99: the 99th percentile); NaN for no value.
inline double percentile(std::vector<double> values, double q)
{
  if (values.empty()) return std::nan("");
  const double rank = std::ceil(q * static_cast<double>(values.size()));
  const std::size_t k = std::min(values.size(), static_cast<std::size_t>(std::max(1.0, rank))) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

/// The part of `path` after its last '/'.
inline std::string baseName(const std::string& path)
{
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// The file name without its extensions: "/logs/intel.clf.bz2" -> "intel" (a leading dot is kept).
inline std::string fileStem(const std::string& path)
{
  const std::string name = baseName(path);
  const std::size_t dot = name.find('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

/// `text` as a number when the whole of it is one (strtod's syntax: "inf" and "nan" too), nothing when
/// it is empty, has anything after the number, or is out of the double's range.
inline std::optional<double> toNumber(const std::string& text)
{
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (text.empty() || end == begin || *end != '\0' || errno == ERANGE) return std::nullopt;
  return v;
}
}  // namespace linemap
