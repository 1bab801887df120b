// linemap_export: a saved CAE-RLSM map file to map_server's occupancy grid (PGM + YAML), DXF,
// GeoJSON and SVG (map_export.hpp).
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_map_eval/batch/map_export.hpp"
#include "linemap/small_helpers.hpp"

namespace
{
void usage(std::ostream& out)
{
  out << "usage: linemap_export MAP_FILE OUT [--format pgm|dxf|geojson|svg|all] [--resolution R]\n"
         "Writes OUT.pgm + OUT.yaml (map_server's occupancy grid), OUT.dxf, OUT.geojson and OUT.svg.\n"
         "  --format F      one format, or all (default)\n"
         "  --resolution R  grid cell size [m] (default 0.05)\n";
}

double parseNumber(const std::string& option, const std::string& value)
{
  const std::optional<double> v = linemap::toNumber(value);
  if (!v) throw std::invalid_argument(option + " '" + value + "' is not a number");
  return *v;
}
}  // namespace

int main(int argc, char** argv)
{
  std::vector<std::string> positional;
  line_map_eval::ExportOptions options;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "-h" || arg == "--help")
      {
        usage(std::cout);
        return 0;
      }
      if ((arg == "--format" || arg == "--resolution") && i + 1 >= argc)
        throw std::invalid_argument(arg + " needs a value");
      if (arg == "--format")
        options.formats = line_map_eval::parseExportFormat(argv[++i]);
      else if (arg == "--resolution")
      {
        options.resolution = parseNumber("--resolution", argv[++i]);
        if (!(options.resolution > 0.0)) throw std::invalid_argument("--resolution must be positive");
      }
      else if (arg.rfind("--", 0) == 0)
        throw std::invalid_argument("unknown option " + arg);
      else
        positional.push_back(arg);
    }
    if (positional.size() != 2) throw std::invalid_argument("expected MAP_FILE and OUT");
  }
  catch (const std::exception& e)
  {
    std::cerr << "linemap_export: " << e.what() << "\n";
    usage(std::cerr);
    return 2;
  }

  try
  {
    const line_map_eval::ExportSummary s = line_map_eval::exportMap(positional[0], positional[1], options);
    std::cout << positional[0] << ": " << s.segments << " map segments from " << s.originals
              << " originals\n";
    if (s.grid_width > 0)
      std::cout << "grid " << s.grid_width << " x " << s.grid_height << " cells at " << options.resolution
                << " m: " << s.occupied << " occupied, " << s.free << " free, " << s.unknown << " unknown\n";
    for (const std::string& f : s.files)
      std::cout << "wrote " << f << " (" << std::filesystem::file_size(f) << " bytes)\n";
  }
  catch (const std::exception& e)
  {
    std::cerr << "linemap_export: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
