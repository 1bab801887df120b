// Where the tools find config/*.yaml: one search for all of them, so that each runs on the same parameter
// files from wherever it is started.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>
#include <vector>

namespace line_map_eval
{
/// The pipeline's parameter files in a config directory, in the order linemap_batch reads them; the first
/// marks a config directory.
inline constexpr const char* kPipelineConfigFiles[] = {"line_extraction.yaml", "line_map_merging.yaml",
                                                       "line_map_eval.yaml"};

/// The repository's config directory: explicit, $LINEMAP_CONFIG_DIR, $LINEMAP_ROOT/config, or the first
/// config/ holding the first pipeline file searched upwards from the executable (devel/lib/line_map_eval/
/// inside a build directory of the repository) and from the working directory; empty when none is found.
inline std::filesystem::path findConfigDir(const std::string& explicit_dir = "")
{
  namespace fs = std::filesystem;
  const auto has_config = [](const fs::path& dir) { return fs::exists(dir / kPipelineConfigFiles[0]); };
  if (!explicit_dir.empty()) return explicit_dir;
  if (const char* env = std::getenv("LINEMAP_CONFIG_DIR")) return env;
  if (const char* root = std::getenv("LINEMAP_ROOT"))
    if (has_config(fs::path(root) / "config")) return fs::path(root) / "config";
  std::vector<fs::path> starts;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) starts.push_back(exe.parent_path());
  starts.push_back(fs::current_path(ec));
  for (fs::path dir : starts)
    for (; !dir.empty(); dir = dir.parent_path())
    {
      if (has_config(dir / "config")) return dir / "config";
      if (dir == dir.parent_path()) break;
    }
  return {};
}

/// The parameter files to read for `name` (e.g. "slam.yaml"): `given` when set, else `name` in the config
/// directory. When there is none, `tool` says so on stderr and the parameters' built-in defaults apply.
inline std::vector<std::string> configFiles(const std::string& given, const std::string& name,
                                            const std::string& tool)
{
  if (!given.empty()) return {given};
  const std::filesystem::path dir = findConfigDir();
  if (!dir.empty() && std::filesystem::exists(dir / name)) return {(dir / name).string()};
  std::cerr << tool << ": config/" << name
            << " not found (give its file, or set LINEMAP_ROOT or LINEMAP_CONFIG_DIR); running on its "
               "built-in defaults\n";
  return {};
}
}  // namespace line_map_eval
