#include "line_map_eval/datasets/relations.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace line_map_eval
{
std::vector<Relation> readRelations(const std::string& path)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the relations file");
  std::vector<Relation> out;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line))
  {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
      continue;
    std::istringstream fields(line);
    double t1, t2, dx, dy, dz, roll, pitch, yaw;
    if (!(fields >> t1 >> t2 >> dx >> dy >> dz >> roll >> pitch >> yaw) || !std::isfinite(t1) ||
        !std::isfinite(t2) || !std::isfinite(dx) || !std::isfinite(dy) || !std::isfinite(yaw))
      throw std::runtime_error(path + ":" + std::to_string(number) +
                               ": expected 't1 t2 dx dy dz roll pitch yaw' (8 finite numbers)");
    out.push_back({t1, t2, {dx, dy, linemap::normalizeAngle(yaw)}});
  }
  return out;
}

std::vector<RelationResidual> relationResiduals(const std::vector<Relation>& relations,
                                                const std::vector<std::pair<double, linemap::Pose2>>& poses,
                                                double tolerance)
{
  std::vector<std::pair<double, linemap::Pose2>> sorted(poses);
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  auto at = [&](double t) -> std::optional<linemap::Pose2>
  {
    auto it = std::lower_bound(sorted.begin(), sorted.end(), t,
                               [](const auto& e, double v) { return e.first < v; });
    const std::pair<double, linemap::Pose2>* best = nullptr;
    if (it != sorted.end()) best = &*it;
    if (it != sorted.begin() && (!best || t - std::prev(it)->first < best->first - t)) best = &*std::prev(it);
    if (!best || std::fabs(best->first - t) > tolerance) return std::nullopt;
    return best->second;
  };
  std::vector<RelationResidual> out;
  for (std::size_t i = 0; i < relations.size(); ++i)
  {
    const auto a = at(relations[i].t1), b = at(relations[i].t2);
    if (!a || !b) continue;
    const linemap::Pose2 error = relations[i].delta.inverse() * (a->inverse() * *b);
    out.push_back({i, *a, *b, std::hypot(error.x, error.y), std::fabs(error.theta)});
  }
  return out;
}

RelationsError relationsError(const std::vector<Relation>& relations,
                              const std::vector<std::pair<double, linemap::Pose2>>& poses, double tolerance)
{
  RelationsError r;
  r.relations = relations.size();
  std::vector<double> te, re;
  for (const RelationResidual& e : relationResiduals(relations, poses, tolerance))
  {
    te.push_back(e.translation);
    re.push_back(e.rotation);
  }
  r.used = te.size();
  auto stats = [](const std::vector<double>& v, double& mean, double& sd, double& max)
  {
    if (v.empty()) return;
    double s = 0.0;
    for (double x : v) s += x;
    mean = s / static_cast<double>(v.size());
    double q = 0.0;
    for (double x : v) q += (x - mean) * (x - mean);
    sd = std::sqrt(q / static_cast<double>(v.size()));
    max = *std::max_element(v.begin(), v.end());
  };
  stats(te, r.translation_mean, r.translation_std, r.translation_max);
  stats(re, r.rotation_mean, r.rotation_std, r.rotation_max);
  return r;
}

}  // namespace line_map_eval
