#include "culling/pair_sort.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace skelcd::culling {
namespace {

/// Below this many pairs comparisons cost less than the passes' counting.
constexpr std::size_t kRadixFrom = 256;
/// Bits per pass at most: 2,048 counters (8 KiB) stay in the L1 cache.
constexpr int kDigitBits = 11;

/// Per calling thread, reused: grows to the most pairs it has sorted, so that a query's steady
/// state allocates nothing (tests/culling/test_allocation.cpp). It holds what the findings it sorts
/// hold, once more.
thread_local std::vector<TrianglePair> tl_scratch;

}  // namespace

void sort_pairs(std::span<TrianglePair> pairs) {
  const std::size_t n = pairs.size();
  if (n < kRadixFrom) {
    std::sort(pairs.begin(), pairs.end());
    return;
  }
  assert(n <= UINT32_MAX);
  // The key (a << bits) | b orders as (a, b) when every id fits in `bits` bits.
  std::uint32_t largest = 0;
  for (const TrianglePair& p : pairs) {
    assert(p.a >= 0 && p.b >= 0);
    largest |= static_cast<std::uint32_t>(p.a) | static_cast<std::uint32_t>(p.b);
  }
  const int bits = std::max(1, static_cast<int>(std::bit_width(largest)));
  const auto key = [bits](const TrianglePair& p) {
    return (static_cast<std::uint64_t>(p.a) << bits) | static_cast<std::uint64_t>(p.b);
  };
  // Least significant digit first, in passes of nearly equal digits; each pass is stable, so the
  // last leaves the pairs ordered by the whole key.
  const int passes = (2 * bits + kDigitBits - 1) / kDigitBits;
  const int digit_bits = (2 * bits + passes - 1) / passes;
  const std::uint64_t mask = (std::uint64_t{1} << digit_bits) - 1;
  const std::size_t digits = std::size_t{1} << digit_bits;
  if (tl_scratch.size() < n) tl_scratch.resize(n);
  TrianglePair* from = pairs.data();
  TrianglePair* to = tl_scratch.data();
  std::array<std::uint32_t, (std::size_t{1} << kDigitBits) + 1> start{};
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * digit_bits;
    std::fill(start.begin(), start.begin() + static_cast<std::ptrdiff_t>(digits + 1), 0u);
    for (std::size_t i = 0; i < n; ++i) ++start[((key(from[i]) >> shift) & mask) + 1];
    for (std::size_t d = 0; d < digits; ++d) start[d + 1] += start[d];
    for (std::size_t i = 0; i < n; ++i) to[start[(key(from[i]) >> shift) & mask]++] = from[i];
    std::swap(from, to);
  }
  if (from != pairs.data()) std::memcpy(pairs.data(), from, n * sizeof(TrianglePair));
}

}  // namespace skelcd::culling
