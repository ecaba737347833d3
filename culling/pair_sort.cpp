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

/// sort_contacts's buckets: at most 2^kBucketBits (2 × 256 KiB of counters, kept per calling
/// thread as the pairs' scratch is), a bucket of at most kInsertionUpTo contacts sorted by
/// insertion.
constexpr int kBucketBits = 16;
constexpr std::size_t kInsertionUpTo = 16;
thread_local std::vector<std::uint32_t> tl_bucket_counters;

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
  // The whole order: the key, then the times (equal keys are the same pair, which a query finds
  // once; the times only make the order total, so that it never depends on where a pair came in).
  const auto before = [&key](const CcdContact& x, const CcdContact& y) {
    const std::uint64_t kx = key(x);
    const std::uint64_t ky = key(y);
    if (kx != ky) return kx < ky;
    if (x.toi_lower != y.toi_lower) return x.toi_lower < y.toi_lower;
    return x.toi_upper < y.toi_upper;
  };
  const auto insertion_sort = [&before](std::span<CcdContact> part) {
    for (std::size_t i = 1; i < part.size(); ++i) {
      const CcdContact c = part[i];
      std::size_t j = i;
      for (; j > 0 && before(c, part[j - 1]); --j) part[j] = part[j - 1];
      part[j] = c;
    }
  };
  const std::size_t n = contacts.size();
  if (n < kRadixFrom) {
    insertion_sort(contacts);
    return;
  }
  // In place, without a buffer of their size: the contacts are moved into buckets of their key's
  // top digit by cycles of swaps (an "American flag" pass), then each bucket is sorted by the
  // whole order. About four contacts a bucket (a digit of bit_width(n) - 2 bits, at least
  // kDigitBits and at most kBucketBits): the cloth-ball step's 113,854 contacts into 2^15 buckets.
  // The least-significant-digit radix sort before 2026-12-06 went through a buffer of the
  // contacts' size, 3.6 MB more at the step's peak and, in a check's first interval, 3.6 MB first
  // touched.
  assert(n <= UINT32_MAX);
  const int key_bits = 2 * bits + 1;
  const int digit_bits = std::min(
      key_bits, std::clamp(static_cast<int>(std::bit_width(n)) - 2, kDigitBits, kBucketBits));
  const int shift = key_bits - digit_bits;
  const std::size_t digits = std::size_t{1} << digit_bits;
  const auto digit = [&key, shift](const CcdContact& c) {
    return static_cast<std::size_t>(key(c) >> shift);
  };
  // start[d]: bucket d's first contact (start[digits]: n); next[d]: its next free place.
  auto& counters = tl_bucket_counters;
  counters.assign(2 * digits + 1, 0u);
  const std::span<std::uint32_t> start(counters.data(), digits + 1);
  const std::span<std::uint32_t> next(counters.data() + digits + 1, digits);
  for (const CcdContact& c : contacts) ++start[digit(c) + 1];
  for (std::size_t d = 0; d < digits; ++d) start[d + 1] += start[d];
  std::copy(start.begin(), start.begin() + static_cast<std::ptrdiff_t>(digits), next.begin());
  for (std::size_t d = 0; d < digits; ++d) {
    while (next[d] < start[d + 1]) {
      CcdContact c = contacts[next[d]];
      for (std::size_t t = digit(c); t != d; t = digit(c)) std::swap(c, contacts[next[t]++]);
      contacts[next[d]++] = c;
    }
  }
  for (std::size_t d = 0; d < digits; ++d) {
    const std::span<CcdContact> bucket = contacts.subspan(start[d], start[d + 1] - start[d]);
    if (bucket.size() <= kInsertionUpTo) {
      insertion_sort(bucket);
    } else {
      std::sort(bucket.begin(), bucket.end(), before);
    }
  }
}

}  // namespace skelcd::culling
