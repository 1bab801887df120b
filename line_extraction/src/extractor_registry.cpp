// The table behind makeExtractor/extractorNames, filled by static
// ExtractorRegistration objects during library initialisation.
#include "line_extraction/extractor_registry.hpp"

#include <algorithm>

namespace line_extraction
{
namespace
{
struct Entry
{
  std::string name;
  int order;
  ExtractorFactory make;
};

struct Registry
{
  std::vector<Entry> entries;  // sorted by order
  std::vector<std::string> names;
};

// Function-local static: constructed on first use, whatever the order in which
// the translation units' registrations run.
Registry& registry()
{
  static Registry r;
  return r;
}
}  // namespace

ExtractorRegistration::ExtractorRegistration(const char* name, int order, ExtractorFactory make)
{
  Registry& r = registry();
  auto it = std::find_if(r.entries.begin(), r.entries.end(), [&](const Entry& e) { return e.order > order; });
  r.entries.insert(it, Entry{name, order, make});
  r.names.clear();
  for (const Entry& e : r.entries) r.names.push_back(e.name);
}

const std::vector<std::string>& extractorNames()
{
  return registry().names;
}

std::unique_ptr<Extractor> makeExtractor(const std::string& name, const linemap::ParamSet& params)
{
  for (const Entry& e : registry().entries)
    if (e.name == name) return e.make(params);
  std::string known;
  for (const std::string& n : registry().names) known += (known.empty() ? "" : ", ") + n;
  throw linemap::ParameterError("parameter 'algorithm': unknown extractor '" + name + "' (known: " + known +
                                ")");
}

}  // namespace line_extraction
