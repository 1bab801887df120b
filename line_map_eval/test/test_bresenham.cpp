// Bresenham rasterisation against hand-computed digital lines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "line_map_eval/metrics/bresenham.hpp"

using line_map_eval::bresenhamLine;
using line_map_eval::Cell;

namespace
{
using Cells = std::vector<Cell>;

void expectCells(const Cell& a, const Cell& b, const Cells& expected)
{
  const Cells got = bresenhamLine(a, b);
  ASSERT_EQ(got.size(), expected.size())
      << "from (" << a.x << "," << a.y << ") to (" << b.x << "," << b.y << ")";
  for (std::size_t i = 0; i < got.size(); ++i)
  {
    EXPECT_EQ(got[i].x, expected[i].x) << "cell " << i;
    EXPECT_EQ(got[i].y, expected[i].y) << "cell " << i;
  }
}
}  // namespace

// Slope 2/5: the ideal line y = 0.4 x passes 0, 0.4, 0.8, 1.2, 1.6, 2 -> nearest 0 0 1 1 2 2.
TEST(Bresenham, Octant1ShallowPositive)
{
  expectCells({0, 0}, {5, 2}, {{0, 0}, {1, 0}, {2, 1}, {3, 1}, {4, 2}, {5, 2}});
}
TEST(Bresenham, Octant2SteepPositive)
{
  expectCells({0, 0}, {2, 5}, {{0, 0}, {0, 1}, {1, 2}, {1, 3}, {2, 4}, {2, 5}});
}
TEST(Bresenham, Octant3SteepNegativeX)
{
  expectCells({0, 0}, {-2, 5}, {{0, 0}, {0, 1}, {-1, 2}, {-1, 3}, {-2, 4}, {-2, 5}});
}
TEST(Bresenham, Octant4ShallowNegativeX)
{
  expectCells({0, 0}, {-5, 2}, {{0, 0}, {-1, 0}, {-2, 1}, {-3, 1}, {-4, 2}, {-5, 2}});
}
TEST(Bresenham, Octant5ShallowNegativeBoth)
{
  expectCells({0, 0}, {-5, -2}, {{0, 0}, {-1, 0}, {-2, -1}, {-3, -1}, {-4, -2}, {-5, -2}});
}
TEST(Bresenham, Octant6SteepNegativeBoth)
{
  expectCells({0, 0}, {-2, -5}, {{0, 0}, {0, -1}, {-1, -2}, {-1, -3}, {-2, -4}, {-2, -5}});
}
TEST(Bresenham, Octant7SteepNegativeY)
{
  expectCells({0, 0}, {2, -5}, {{0, 0}, {0, -1}, {1, -2}, {1, -3}, {2, -4}, {2, -5}});
}
TEST(Bresenham, Octant8ShallowNegativeY)
{
  expectCells({0, 0}, {5, -2}, {{0, 0}, {1, 0}, {2, -1}, {3, -1}, {4, -2}, {5, -2}});
}

// Slope 3/7 from (3, 1): y = 1 + 3 (x - 3) / 7 = 1, 1.43, 1.86, 2.29, 2.71, 3.14, 3.57, 4.
TEST(Bresenham, OffsetStartAndBothDirections)
{
  const Cells forward = {{3, 1}, {4, 1}, {5, 2}, {6, 2}, {7, 3}, {8, 3}, {9, 4}, {10, 4}};
  expectCells({3, 1}, {10, 4}, forward);
  // No exact halves on this line, so walking it backwards visits the same cells in reverse.
  Cells backward(forward.rbegin(), forward.rend());
  expectCells({10, 4}, {3, 1}, backward);
}

TEST(Bresenham, AxisAlignedDiagonalAndSingleCell)
{
  expectCells({2, 2}, {2, 2}, {{2, 2}});
  expectCells({-1, 3}, {2, 3}, {{-1, 3}, {0, 3}, {1, 3}, {2, 3}});
  expectCells({4, 1}, {4, -2}, {{4, 1}, {4, 0}, {4, -1}, {4, -2}});
  expectCells({0, 0}, {-3, 3}, {{0, 0}, {-1, 1}, {-2, 2}, {-3, 3}});
}

TEST(Bresenham, EightConnectedWithOneCellPerMajorStep)
{
  for (int x1 = -9; x1 <= 9; ++x1)
    for (int y1 = -9; y1 <= 9; ++y1)
    {
      const Cells c = bresenhamLine({0, 0}, {x1, y1});
      ASSERT_EQ(c.size(), static_cast<std::size_t>(std::max(std::abs(x1), std::abs(y1)) + 1));
      EXPECT_EQ(c.front(), (Cell{0, 0}));
      EXPECT_EQ(c.back(), (Cell{x1, y1}));
      for (std::size_t i = 1; i < c.size(); ++i)
      {
        EXPECT_LE(std::abs(c[i].x - c[i - 1].x), 1);
        EXPECT_LE(std::abs(c[i].y - c[i - 1].y), 1);
        // Every cell is within half a cell of the ideal line along the minor axis.
        const double dist = std::abs(static_cast<double>(y1) * c[i].x - static_cast<double>(x1) * c[i].y) /
                            std::max(std::abs(x1), std::abs(y1));
        EXPECT_LE(dist, 0.5 + 1e-12) << "to (" << x1 << "," << y1 << ") cell " << i;
      }
    }
}
