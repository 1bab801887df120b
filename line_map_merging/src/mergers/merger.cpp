// The merger factory.
#include "line_map_merging/mergers/merger.hpp"

#include "line_map_merging/mergers/cae_offline.hpp"
#include "line_map_merging/mergers/cae_rlsm.hpp"
#include "line_map_merging/mergers/li2023.hpp"
#include "line_map_merging/mergers/ms_rlsm.hpp"
#include "line_map_merging/mergers/o2to_ilsm.hpp"
#include "line_map_merging/mergers/oto_ilsm.hpp"

namespace line_map_merging
{
const std::vector<std::string>& mergerNames()
{
  static const std::vector<std::string> names{"cae", "cae_offline", "oto", "o2to", "ms", "li2023"};
  return names;
}

std::unique_ptr<Merger> makeMerger(const std::string& name, const linemap::ParamSet& params)
{
  if (name == "cae") return std::make_unique<CaeRlsm>(CaeParams::fromParams(params));
  if (name == "cae_offline") return std::make_unique<CaeOffline>(CaeParams::fromParams(params));
  if (name == "oto") return std::make_unique<OtoIlsm>(FusionParams::fromParams(params));
  if (name == "o2to") return std::make_unique<O2toIlsm>(FusionParams::fromParams(params));
  if (name == "ms") return std::make_unique<MsRlsm>(MsParams::fromParams(params));
  if (name == "li2023") return std::make_unique<Li2023>(Li2023Params::fromParams(params));
  std::string known;
  for (const auto& n : mergerNames()) known += (known.empty() ? "" : ", ") + n;
  throw linemap::ParameterError("parameter 'method': unknown merger '" + name + "' (known: " + known + ")");
}

}  // namespace line_map_merging
