#pragma once
// Sorting triangle pairs by (a, b): a DCD's findings, in their canonical order.

#include <span>

#include "culling/frame_result.hpp"

namespace skelcd::culling {

/// Sorts `pairs` by (a, b), as std::sort with TrianglePair's order does, keeping repeated pairs.
/// A least-significant-digit radix sort on the key (a, b) packed into the bits the largest id
/// needs: a DCD's pairs (100k on the cloth-ball step) sort in a few passes over the array instead
/// of n log n comparisons.
/// @param pairs ids >= 0.
/// @note Spans of 256 pairs or more go through a buffer of their size, kept per thread for the
/// next call (so that repeated queries allocate nothing).
void sort_pairs(std::span<TrianglePair> pairs);

/// Sorts `contacts` canonically (CcdContact::before: kind, a, b), contacts of one pair by their
/// times (toi_lower, then toi_upper), so that the order is total and never depends on the order
/// they came in. In place, without a buffer: one radix pass on the key (kind, a, b)'s top digit
/// (packed as for sort_pairs) into buckets, then each bucket by comparisons (the cloth-ball step's
/// 113,854 contacts: buckets of about 56). Below 256 contacts an insertion sort.
/// @param contacts ids >= 0.
void sort_contacts(std::span<CcdContact> contacts);

}  // namespace skelcd::culling
