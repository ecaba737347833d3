// sort_pairs (culling/pair_sort.hpp) orders triangle pairs exactly as std::sort does: on short and
// long spans, on ids that need few bits and on ids up to INT32_MAX, with repeated pairs, and on a
// part of a vector whose front is left alone. sort_contacts orders CCD contacts as std::sort by
// CcdContact::before and then the times does (a total order), each contact's times moving with it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <vector>

#include "culling/pair_sort.hpp"

namespace skelcd::culling {
namespace {

std::vector<TrianglePair> random_pairs(std::size_t n, std::int32_t largest, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::int32_t> id(0, largest);
  std::vector<TrianglePair> pairs(n);
  for (auto& p : pairs) {
    const std::int32_t x = id(rng);
    const std::int32_t y = id(rng);
    p = {std::min(x, y), std::max(x, y)};
  }
  return pairs;
}

void expect_sorted_like_std(std::vector<TrianglePair> pairs) {
  std::vector<TrianglePair> expected = pairs;
  std::sort(expected.begin(), expected.end());
  sort_pairs(pairs);
  EXPECT_EQ(pairs, expected);
}

TEST(PairSort, OrdersAsStdSortForEverySizeAndIdRange) {
  const std::int32_t kLargest[] = {
      0, 1, 3, 1000, 92229, 1 << 20, std::numeric_limits<std::int32_t>::max()};
  const std::size_t kSizes[] = {0, 1, 2, 255, 256, 257, 5000, 100000};
  std::uint32_t seed = 1;
  for (const std::int32_t largest : kLargest) {
    for (const std::size_t n : kSizes) {
      SCOPED_TRACE(testing::Message() << "largest id " << largest << ", " << n << " pairs");
      expect_sorted_like_std(random_pairs(n, largest, seed++));
    }
  }
}

TEST(PairSort, KeepsRepeatedPairsAndSortsAlreadyOrderedOrReversedInput) {
  std::vector<TrianglePair> pairs = random_pairs(3000, 40, 7);  // many repeats
  expect_sorted_like_std(pairs);
  std::sort(pairs.begin(), pairs.end());
  expect_sorted_like_std(pairs);
  std::reverse(pairs.begin(), pairs.end());
  expect_sorted_like_std(pairs);
}

TEST(PairSort, SortsOnlyTheSpanItIsGiven) {
  std::vector<TrianglePair> pairs = random_pairs(4000, 92229, 11);
  const std::vector<TrianglePair> front(pairs.begin(), pairs.begin() + 1000);
  std::vector<TrianglePair> back_sorted(pairs.begin() + 1000, pairs.end());
  std::sort(back_sorted.begin(), back_sorted.end());
  sort_pairs(std::span(pairs).subspan(1000));
  EXPECT_TRUE(std::equal(front.begin(), front.end(), pairs.begin()));
  EXPECT_TRUE(std::equal(back_sorted.begin(), back_sorted.end(), pairs.begin() + 1000));
}

std::vector<CcdContact> random_contacts(std::size_t n, std::int32_t largest, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::int32_t> id(0, largest);
  std::uniform_real_distribution<double> time(0.0, 1.0);
  std::vector<CcdContact> contacts(n);
  for (auto& c : contacts) {
    // Lower bounds repeat (three values) and upper bounds are drawn apart from them, so that a
    // pair's contacts are ordered by each of the two times in turn.
    const double lower = 0.25 * static_cast<double>(rng() % 3);
    const double upper = lower + 0.5 * time(rng);
    c = {
        rng() % 2 == 0 ? CcdContact::Kind::vf : CcdContact::Kind::ee,
        id(rng),
        id(rng),
        lower,
        upper};
  }
  return contacts;
}

/// CcdContact::before, then the times: sort_contacts's whole order.
bool before_then_times(const CcdContact& a, const CcdContact& b) {
  if (a.before(b)) return true;
  if (b.before(a)) return false;
  if (a.toi_lower != b.toi_lower) return a.toi_lower < b.toi_lower;
  return a.toi_upper < b.toi_upper;
}

void expect_contacts_sorted_like_std(std::vector<CcdContact> contacts) {
  std::vector<CcdContact> expected = contacts;
  std::sort(expected.begin(), expected.end(), before_then_times);
  sort_contacts(contacts);
  EXPECT_EQ(contacts, expected);  // the times too: each record moved whole
}

TEST(ContactSort, OrdersByBeforeThenTheTimesForEverySizeAndIdRange) {
  const std::int32_t kLargest[] = {0, 3, 92229, std::numeric_limits<std::int32_t>::max()};
  const std::size_t kSizes[] = {0, 1, 255, 256, 257, 120000};
  std::uint32_t seed = 100;
  for (const std::int32_t largest : kLargest) {
    for (const std::size_t n : kSizes) {
      SCOPED_TRACE(testing::Message() << "largest id " << largest << ", " << n << " contacts");
      expect_contacts_sorted_like_std(random_contacts(n, largest, seed++));
    }
  }
}

TEST(ContactSort, SortsOnlyTheSpanItIsGivenAndOrdersRepeatedPairsByTheirTimes) {
  std::vector<CcdContact> contacts = random_contacts(3000, 20, 5);  // many repeated (kind, a, b)
  const std::vector<CcdContact> front(contacts.begin(), contacts.begin() + 500);
  std::vector<CcdContact> back(contacts.begin() + 500, contacts.end());
  std::sort(back.begin(), back.end(), before_then_times);
  sort_contacts(std::span(contacts).subspan(500));
  EXPECT_TRUE(std::equal(front.begin(), front.end(), contacts.begin()));
  EXPECT_TRUE(std::equal(back.begin(), back.end(), contacts.begin() + 500));
  // The same contacts in another order sort the same: the order is total.
  std::vector<CcdContact> reversed(contacts.rbegin(), contacts.rend() - 500);
  sort_contacts(reversed);
  EXPECT_TRUE(std::equal(back.begin(), back.end(), reversed.begin()));
}

}  // namespace
}  // namespace skelcd::culling
