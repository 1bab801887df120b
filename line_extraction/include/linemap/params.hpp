// A flat, typed parameter set shared by the nodelets, the config files and the
// batch tool's `--param key=value`. Keys are "block/name" as in config/*.yaml.
#pragma once

#include <map>
#include <stdexcept>
#include <string>

namespace linemap
{
/// Thrown for a missing, malformed or impossible parameter; what() names it.
struct ParameterError : std::invalid_argument
{
  using std::invalid_argument::invalid_argument;
};

class ParamSet
{
 public:
  void set(const std::string& key, const std::string& value) { values_[key] = value; }
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  const std::map<std::string, std::string>& values() const { return values_; }

  /// Value of `key`, or `fallback` when absent; throws ParameterError naming the key if malformed.
  double getDouble(const std::string& key, double fallback) const;
  /// getDouble, and throws ParameterError naming the key unless the value is finite and >= 0.
  double getNonNegative(const std::string& key, double fallback) const;
  int getInt(const std::string& key, int fallback) const;
  bool getBool(const std::string& key, bool fallback) const;
  std::string getString(const std::string& key, const std::string& fallback) const;

  /// From now on every getter also notes, by key, the fallback it was asked with: what the code uses where
  /// the files are silent (test_shipped_config compares these with config/*.yaml). Different fallbacks
  /// of one key are joined by '|'. Null: no notes.
  void noteFallbacks(std::map<std::string, std::string>* into) { fallbacks_ = into; }

 private:
  void note(const std::string& key, const std::string& fallback) const;
  std::map<std::string, std::string> values_;
  std::map<std::string, std::string>* fallbacks_ = nullptr;
};

}  // namespace linemap
