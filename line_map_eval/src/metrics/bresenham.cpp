#include "line_map_eval/metrics/bresenham.hpp"

#include <algorithm>

namespace line_map_eval
{
void bresenhamLine(const Cell& a, const Cell& b, std::vector<Cell>& out)
{
  out.reserve(out.size() + static_cast<std::size_t>(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y))) + 1);
  forEachBresenhamCell(a.x, a.y, b.x, b.y, [&out](int x, int y) { out.push_back({x, y}); });
}

std::vector<Cell> bresenhamLine(const Cell& a, const Cell& b)
{
  std::vector<Cell> out;
  bresenhamLine(a, b, out);
  return out;
}

}  // namespace line_map_eval
