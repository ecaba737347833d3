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

/// Per calling thread, reused: grows to the most pairs (contacts) it has sorted, so that a
/// query's steady state allocates nothing (tests/culling/test_allocation.cpp). It holds what the
/// findings it sorts hold, once more.
thread_local std::vector<TrianglePair> tl_pair_scratch;
thread_local std::vector<CcdContact> tl_contact_scratch;

/// Sorts `items` by key(item), a key below 2^key_bits, least significant digit first, in passes
/// of nearly equal digits; each pass is stable, so the last leaves them ordered by the whole key.
template <class T, class Key>
void radix_sort(std::span<T> items, const Key& key, int key_bits, std::vector<T>& scratch) {
  const std::size_t n = items.size();
  assert(n <= UINT32_MAX);
  const int passes = (key_bits + kDigitBits - 1) / kDigitBits;
  const int digit_bits = (key_bits + passes - 1) / passes;
  const std::uint64_t mask = (std::uint64_t{1} << digit_bits) - 1;
  const std::size_t digits = std::size_t{1} << digit_bits;
  if (scratch.size() < n) scratch.resize(n);
  T* from = items.data();
  T* to = scratch.data();
  std::array<std::uint32_t, (std::size_t{1} << kDigitBits) + 1> start{};
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * digit_bits;
    std::fill(start.begin(), start.begin() + static_cast<std::ptrdiff_t>(digits + 1), 0u);
    for (std::size_t i = 0; i < n; ++i) ++start[((key(from[i]) >> shift) & mask) + 1];
    for (std::size_t d = 0; d < digits; ++d) start[d + 1] += start[d];
    for (std::size_t i = 0; i < n; ++i) to[start[(key(from[i]) >> shift) & mask]++] = from[i];
    std::swap(from, to);
  }
  if (from != items.data()) std::memcpy(items.data(), from, n * sizeof(T));
}

}  // namespace

void sort_pairs(std::span<TrianglePair> pairs) {
  if (pairs.size() < kRadixFrom) {
    std::sort(pairs.begin(), pairs.end());
    return;
  }
  // The key (a << bits) | b orders as (a, b) when every id fits in `bits` bits.
  std::uint32_t largest = 0;
  for (const TrianglePair& p : pairs) {
    assert(p.a >= 0 && p.b >= 0);
    largest |= static_cast<std::uint32_t>(p.a) | static_cast<std::uint32_t>(p.b);
  }
  const int bits = std::max(1, static_cast<int>(std::bit_width(largest)));
  radix_sort(
      pairs,
      [bits](const TrianglePair& p) {
        return (static_cast<std::uint64_t>(p.a) << bits) | static_cast<std::uint64_t>(p.b);
      },
      2 * bits,
      tl_pair_scratch);
}

void sort_contacts(std::span<CcdContact> contacts) {
  // The key (kind << 2 bits) | (a << bits) | b orders as (kind, a, b) when every id fits in
  // `bits` bits and the kind in one.
  static_assert(
      static_cast<int>(CcdContact::Kind::vf) == 0 && static_cast<int>(CcdContact::Kind::ee) == 1,
      "the key gives the kind one bit");
  std::uint32_t largest = 0;
  for (const CcdContact& c : contacts) {
    assert(c.a >= 0 && c.b >= 0);
    largest |= static_cast<std::uint32_t>(c.a) | static_cast<std::uint32_t>(c.b);
  }
  const int bits = std::max(1, static_cast<int>(std::bit_width(largest)));
  const auto key = [bits](const CcdContact& c) {
    return (static_cast<std::uint64_t>(c.kind) << (2 * bits)) |
           (static_cast<std::uint64_t>(c.a) << bits) | static_cast<std::uint64_t>(c.b);
  };
  if (contacts.size() < kRadixFrom) {
    // Insertion, stable as the radix sort is (no allocation, as std::stable_sort would make).
    for (std::size_t i = 1; i < contacts.size(); ++i) {
      const CcdContact c = contacts[i];
      const std::uint64_t k = key(c);
      std::size_t j = i;
      for (; j > 0 && k < key(contacts[j - 1]); --j) contacts[j] = contacts[j - 1];
      contacts[j] = c;
    }
    return;
  }
  radix_sort(contacts, key, 2 * bits + 1, tl_contact_scratch);
}

}  // namespace skelcd::culling
