// The merger factory.
#include "line_map_merging/merger.hpp"

#include "line_map_merging/cae_rlsm.hpp"

namespace line_map_merging
{
const std::vector<std::string>& mergerNames()
{
  static const std::vector<std::string> names{"cae"};
  return names;
}

std::unique_ptr<Merger> makeMerger(const std::string& name, const linemap::ParamSet& params)
{
  if (name == "cae") return std::make_unique<CaeRlsm>(CaeParams::fromParams(params));
  std::string known;
  for (const auto& n : mergerNames()) known += (known.empty() ? "" : ", ") + n;
  throw linemap::ParameterError("parameter 'method': unknown merger '" + name + "' (known: " + known + ")");
}

}  // namespace line_map_merging
