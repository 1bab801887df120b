// A flat, typed parameter set shared by the nodelets, the config files and the
// batch tool's `--param key=value`. Keys are "block/name" as in config/*.yaml.
#pragma once

#include <initializer_list>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>

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

/// A key and the field of a parameter struct P it sets; the field's type picks the getter.
template <class P>
struct ParamField
{
  const char* key;
  std::variant<double P::*, int P::*, bool P::*> field;
};

/// Sets each listed field of `p` from its key in turn; an absent key keeps the field's value (its default),
/// which is also the fallback the getters note.
template <class P>
void readFields(const ParamSet& params, std::initializer_list<ParamField<P>> fields, P& p)
{
  for (const ParamField<P>& f : fields)
    std::visit(
        [&](auto field)
        {
          auto& value = p.*field;
          using Value = std::decay_t<decltype(value)>;
          if constexpr (std::is_same_v<Value, double>)
            value = params.getDouble(f.key, value);
          else if constexpr (std::is_same_v<Value, int>)
            value = params.getInt(f.key, value);
          else
            value = params.getBool(f.key, value);
        },
        f.field);
}

/// A P of its defaults, the listed fields read over them, then validated (P::validate throws
/// ParameterError): the whole of a fromParams that reads only plain fields.
template <class P>
P readValidated(const ParamSet& params, std::initializer_list<ParamField<P>> fields)
{
  P p;
  readFields(params, fields, p);
  p.validate();
  return p;
}

}  // namespace linemap
