// What several line_map_eval tests share: a scratch directory, a check on error messages and a lookup table's
// parameters.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include "line_map_eval/datasets/recording.hpp"
#include "line_map_eval/metrics/lookup_table.hpp"

namespace line_map_eval::test_helpers
{
/// A fresh directory /tmp/PREFIX_XXXXXX, removed with its contents at the end of the scope.
class TempDir
{
 public:
  explicit TempDir(const std::string& prefix = "line_map_eval_test")
  {
    std::string tmpl = "/tmp/" + prefix + "_XXXXXX";
    const char* d = mkdtemp(&tmpl[0]);
    if (!d) throw std::runtime_error("mkdtemp failed");
    path_ = d;
  }
  ~TempDir() { std::system(("rm -rf '" + path_ + "'").c_str()); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  /// The path of `name` inside the directory.
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  /// Writes `content` to `name` inside the directory and returns its path.
  std::string write(const std::string& name, const std::string& content) const
  {
    const std::string p = file(name);
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }

 private:
  std::string path_;
};

/// A lookup table's parameters with the kernel cut at 3 sigma, whatever the shipped defaults become.
inline LookupTableParams lookupTableParams(double resolution, double sigma)
{
  LookupTableParams p;
  p.resolution = resolution;
  p.sigma = sigma;
  p.kernel_radius = 3.0;
  return p;
}

/// Expects `message` to contain every one of `parts`.
inline void expectMentions(const std::string& message, std::initializer_list<const char*> parts)
{
  for (const char* part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' in: " << message;
}
/// The first keyframe past the middle of a drive where the robot is back in a place it saw (within 1 m of a
/// true position at least 5 m of path before): where a saved session can be continued and found. 0: none.
inline std::size_t revisitPastTheMiddle(const std::vector<CorrectedKeyframe>& truth, std::size_t scans)
{
  for (std::size_t k = 0; k < truth.size(); ++k)
  {
    if (truth[k].scan_index < scans / 2) continue;
    double path = 0.0;
    for (std::size_t j = k; j-- > 0;)
    {
      path += (truth[j + 1].pose.translation() - truth[j].pose.translation()).norm();
      if (path >= 5.0 && (truth[j].pose.translation() - truth[k].pose.translation()).norm() <= 1.0) return k;
    }
  }
  return 0;
}

}  // namespace line_map_eval::test_helpers
