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

/// Sorts `contacts` canonically (CcdContact::before: kind, a, b), stably, by a radix sort on the
/// key (kind, a, b) packed as for sort_pairs: the cloth-ball step's 113,854 contacts in 4 passes
/// over them instead of n log n comparisons. Below 256 contacts an insertion sort.
/// @param contacts ids >= 0.
/// @note Spans of 256 contacts or more go through a buffer of their size, kept per thread for
/// the next call: it holds what the findings hold, once more.
void sort_contacts(std::span<CcdContact> contacts);

}  // namespace skelcd::culling
