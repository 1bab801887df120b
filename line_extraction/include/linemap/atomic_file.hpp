// Writing a file so that a crash or a kill leaves either the old file or the new one, never a mix: the
// bytes go to a temporary file beside it, are fsynced, and the temporary is renamed over the target.
#pragma once

#include <stdexcept>
#include <string>

namespace linemap
{
/// Writes `bytes` to `path` atomically. Throws std::runtime_error "<kind> '<path>': <what failed>" and
/// leaves no temporary file behind.
void writeFileAtomically(const std::string& path, const std::string& bytes, const std::string& kind);

/// The whole file's bytes. Throws std::runtime_error "<kind> '<path>': cannot open: <reason>".
std::string readWholeFile(const std::string& path, const std::string& kind);

}  // namespace linemap
