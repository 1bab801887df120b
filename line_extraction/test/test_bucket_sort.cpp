// bucketSortByKey against std::sort, the reference: the same order for every spread of keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "line_extraction/bucket_sort.hpp"

namespace
{
struct Item
{
  std::uint32_t id;
  double key;
};

bool byKeyThenId(const Item& a, const Item& b)
{
  return a.key < b.key || (a.key == b.key && a.id < b.id);
}

/// Sorts a shuffled copy both ways; the ids must come out in the same order.
void expectSameOrderAsStdSort(std::vector<Item> items, std::mt19937& rng)
{
  std::shuffle(items.begin(), items.end(), rng);
  std::vector<Item> expected = items, scratch;
  std::sort(expected.begin(), expected.end(), byKeyThenId);
  line_extraction::bucketSortByKey(
      items, scratch, [](const Item& i) { return i.key; }, byKeyThenId);
  ASSERT_EQ(items.size(), expected.size());
  for (std::size_t k = 0; k < items.size(); ++k)
    ASSERT_EQ(items[k].id, expected[k].id) << "position " << k << " of " << items.size();
}

std::vector<Item> numbered(const std::vector<double>& keys)
{
  std::vector<Item> items;
  for (std::size_t i = 0; i < keys.size(); ++i) items.push_back({static_cast<std::uint32_t>(i), keys[i]});
  return items;
}
}  // namespace

TEST(BucketSort, OrdersSpreadKeysWithTiesAsStdSortDoes)
{
  std::mt19937 rng(7);
  // Millimetre steps over 100 m, drawn from fewer values than items: many ties, broken by id.
  std::uniform_int_distribution<int> mm(-50000, 50000);
  for (const std::size_t n : {64u, 65u, 1000u, 20000u})
  {
    std::vector<double> keys;
    for (std::size_t i = 0; i < n; ++i) keys.push_back(0.001 * (mm(rng) % 997));
    expectSameOrderAsStdSort(numbered(keys), rng);
  }
}

TEST(BucketSort, OrdersClusteredKeysAndAFarOutlierAsStdSortDoes)
{
  // All but one key within a millimetre, one a kilometre off: nearly every item in one bucket.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> tiny(0.0, 0.001);
  std::vector<double> keys;
  for (int i = 0; i < 3000; ++i) keys.push_back(tiny(rng));
  keys.push_back(1000.0);
  expectSameOrderAsStdSort(numbered(keys), rng);
}

TEST(BucketSort, EqualKeysComeOutInIdOrder)
{
  std::mt19937 rng(3);
  expectSameOrderAsStdSort(numbered(std::vector<double>(500, -2.5)), rng);
}

TEST(BucketSort, ShortInputsAndNonFiniteKeysFallBackToAComparisonSort)
{
  std::mt19937 rng(5);
  expectSameOrderAsStdSort(numbered({3.0, -1.0, 2.0, 2.0, 0.5}), rng);
  std::vector<double> keys;
  for (int i = 0; i < 200; ++i) keys.push_back(0.01 * i);
  keys.push_back(std::numeric_limits<double>::infinity());
  keys.push_back(-std::numeric_limits<double>::infinity());
  expectSameOrderAsStdSort(numbered(keys), rng);
}
