// libFuzzer target: the CARMEN log parser on arbitrary text (strict and lenient), and the file
// reader's gzip/bzip2 detection on arbitrary bytes behind the magic numbers.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "fuzz_check.hpp"
#include "line_map_eval/datasets/carmen_log.hpp"

namespace
{
const std::string& tempPath()
{
  static const std::string path = "/tmp/linemap_fuzz_carmen_" + std::to_string(::getpid());
  return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  if (size == 0) return 0;
  // First byte: mode; the rest is the log (or compressed file) text.
  const std::uint8_t mode = data[0];
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  line_map_eval::CarmenReadOptions options;
  options.lenient = (mode & 1) != 0;
  options.max_scans = (mode >> 1) & 3;
  options.max_line_length = (mode & 8) ? 64 : (1 << 16);
  try
  {
    line_map_eval::CarmenLog log;
    if ((mode & 0x30) == 0)
    {
      log = line_map_eval::parseCarmenLog(text, "fuzz", options);
    }
    else
    {
      // Through the file reader: prefix gzip or bzip2 magic so the decompressors see the bytes.
      std::string bytes = text;
      if ((mode & 0x30) == 0x10) bytes = std::string("\x1f\x8b\x08", 3) + text;
      if ((mode & 0x30) == 0x20) bytes = "BZh9" + text;
      FILE* f = std::fopen(tempPath().c_str(), "wb");
      if (!f) return 0;
      std::fwrite(bytes.data(), 1, bytes.size(), f);
      std::fclose(f);
      log = line_map_eval::readCarmenLog(tempPath(), options);
    }
    if (options.max_scans > 0) check(log.scans.size() <= options.max_scans);
    if (!options.lenient) check(log.skipped_bad == 0);
  }
  catch (const std::runtime_error&)
  {
    // A malformed line or undecodable file, reported with its name and line: the expected outcome.
  }
  return 0;
}
