// A sort by a real key in linear time for keys spread over an interval (points along a line).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace line_extraction
{
/// Sorts `items` into the order std::sort(items, less) gives, where `less` orders by `key(item)` (a double)
/// first and breaks ties itself. A counting sort into about one bucket per item, then each bucket by `less`:
/// the bucket of a key never decreases with it (rounding is monotone), so the buckets concatenate in order.
/// `scratch` is working space (its contents are replaced). Short inputs and non-finite keys fall back to
/// std::sort.
template <class T, class Key, class Less>
void bucketSortByKey(std::vector<T>& items, std::vector<T>& scratch, Key key, Less less)
{
  constexpr std::size_t kShortest = 64;  // below this a comparison sort is as fast
  if (items.size() < kShortest)
  {
    std::sort(items.begin(), items.end(), less);
    return;
  }
  double from = key(items.front()), to = from;
  for (const T& item : items)
  {
    from = std::min(from, key(item));
    to = std::max(to, key(item));
  }
  const double span = to - from;
  if (!std::isfinite(span))
  {
    std::sort(items.begin(), items.end(), less);
    return;
  }
  const std::size_t buckets = items.size();
  const double per_unit = span > 0.0 ? static_cast<double>(buckets) / span : 0.0;
  const auto bucket_of = [&](const T& item)
  { return std::min(buckets - 1, static_cast<std::size_t>((key(item) - from) * per_unit)); };
  std::vector<std::uint32_t> starts(buckets + 1, 0);
  for (const T& item : items) ++starts[bucket_of(item) + 1];
  for (std::size_t b = 0; b < buckets; ++b) starts[b + 1] += starts[b];
  scratch.resize(items.size());
  std::vector<std::uint32_t> next(starts.begin(), starts.end() - 1);
  for (const T& item : items) scratch[next[bucket_of(item)]++] = item;
  for (std::size_t b = 0; b < buckets; ++b)
    if (starts[b + 1] - starts[b] > 1)
      std::sort(scratch.begin() + starts[b], scratch.begin() + starts[b + 1], less);
  items.swap(scratch);
}
}  // namespace line_extraction
