#include "linemap/params.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "linemap/small_helpers.hpp"

namespace linemap
{
void ParamSet::note(const std::string& key, const std::string& fallback) const
{
  // Two readers of one key with different fallbacks are both noted: "a|b".
  auto [it, inserted] = fallbacks_->emplace(key, fallback);
  if (!inserted && ("|" + it->second + "|").find("|" + fallback + "|") == std::string::npos)
    it->second += "|" + fallback;
}

double ParamSet::getDouble(const std::string& key, double fallback) const
{
  if (fallbacks_)
  {
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", fallback);
    note(key, text);
  }
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  const std::optional<double> v = toNumber(it->second);
  if (!v) throw ParameterError("parameter '" + key + "': '" + it->second + "' is not a number");
  return *v;
}

double ParamSet::getNonNegative(const std::string& key, double fallback) const
{
  const double v = getDouble(key, fallback);
  if (!std::isfinite(v) || v < 0.0)
    throw ParameterError("parameter '" + key + "' must be finite and >= 0, got " + std::to_string(v));
  return v;
}

int ParamSet::getInt(const std::string& key, int fallback) const
{
  if (fallbacks_) note(key, std::to_string(fallback));
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  const char* begin = it->second.c_str();
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(begin, &end, 10);
  if (end == begin || *end != '\0' || errno == ERANGE || v < -2147483647L || v > 2147483647L)
    throw ParameterError("parameter '" + key + "': '" + it->second + "' is not an integer");
  return static_cast<int>(v);
}

bool ParamSet::getBool(const std::string& key, bool fallback) const
{
  if (fallbacks_) note(key, fallback ? "true" : "false");
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  const std::string& s = it->second;
  if (s == "true" || s == "True" || s == "1") return true;
  if (s == "false" || s == "False" || s == "0") return false;
  throw ParameterError("parameter '" + key + "': '" + s + "' is not a boolean");
}

std::string ParamSet::getString(const std::string& key, const std::string& fallback) const
{
  if (fallbacks_) note(key, fallback);
  auto it = values_.find(key);
  return it == values_.end() ? fallback : it->second;
}

}  // namespace linemap
