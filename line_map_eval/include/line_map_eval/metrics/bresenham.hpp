// Bresenham's line rasterisation on an integer grid (ROS-free).
#pragma once

#include <cstdlib>
#include <vector>

namespace line_map_eval
{
/// An integer grid cell.
struct Cell
{
  int x = 0;
  int y = 0;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
  bool operator!=(const Cell& o) const { return !(*this == o); }
};

/// Calls f(x, y) for every cell of the 8-connected digital line from (x0, y0) to (x1, y1),
/// both ends included, in order from the start: one cell per step along the major axis,
/// the minor coordinate being the one nearest to the ideal line. At an exact half the minor
/// coordinate steps early (in walking direction), so only such ties depend on the direction.
template <typename F>
void forEachBresenhamCell(int x0, int y0, int x1, int y1, F&& f)
{
  const int dx = std::abs(x1 - x0);
  const int dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1;
  const int sy = y0 < y1 ? 1 : -1;
  // err = dx + dy tracks (twice) the signed distance of the next candidate cells to the line.
  long err = static_cast<long>(dx) + dy;
  int x = x0, y = y0;
  for (;;)
  {
    f(x, y);
    if (x == x1 && y == y1) break;
    const long e2 = 2 * err;
    if (e2 >= dy)
    {
      err += dy;
      x += sx;
    }
    if (e2 <= dx)
    {
      err += dx;
      y += sy;
    }
  }
}

/// Appends the cells of the digital line from a to b (both included) to `out`.
void bresenhamLine(const Cell& a, const Cell& b, std::vector<Cell>& out);

/// The cells of the digital line from a to b (both included).
std::vector<Cell> bresenhamLine(const Cell& a, const Cell& b);

}  // namespace line_map_eval
