// Reading algorithm parameters with range checks; errors name the parameter.
#pragma once

#include <cmath>
#include <cstddef>
#include <string>

#include "linemap/params.hpp"

namespace line_extraction
{
/// Throws ParameterError "parameter '<key>' must be <what>" unless `ok`.
inline void requireParam(bool ok, const std::string& key, const char* what)
{
  if (!ok) throw linemap::ParameterError("parameter '" + key + "' must be " + what);
}

/// A finite value > 0.
inline double positiveParam(const linemap::ParamSet& ps, const std::string& key, double fallback)
{
  const double v = ps.getDouble(key, fallback);
  if (!(v > 0.0 && std::isfinite(v)))
    throw linemap::ParameterError("parameter '" + key + "' must be a finite number > 0, got " +
                                  std::to_string(v));
  return v;
}

/// A value >= 0 (infinity allowed, meaning "no limit").
inline double nonNegativeParam(const linemap::ParamSet& ps, const std::string& key, double fallback)
{
  const double v = ps.getDouble(key, fallback);
  if (!(v >= 0.0))
    throw linemap::ParameterError("parameter '" + key + "' must be >= 0, got " + std::to_string(v));
  return v;
}

/// An integer >= minimum.
inline int intParamAtLeast(const linemap::ParamSet& ps, const std::string& key, int fallback, int minimum)
{
  const int v = ps.getInt(key, fallback);
  if (v < minimum)
    throw linemap::ParameterError("parameter '" + key + "' must be >= " + std::to_string(minimum) + ", got " +
                                  std::to_string(v));
  return v;
}

/// A count >= minimum.
inline std::size_t countParam(const linemap::ParamSet& ps, const std::string& key, std::size_t fallback,
                              int minimum)
{
  return static_cast<std::size_t>(intParamAtLeast(ps, key, static_cast<int>(fallback), minimum));
}

/// The pipeline's point noise "range_sigma" [m], used by the algorithms' covariances.
inline double rangeSigmaParam(const linemap::ParamSet& ps)
{
  return positiveParam(ps, "range_sigma", 0.01);
}

}  // namespace line_extraction
