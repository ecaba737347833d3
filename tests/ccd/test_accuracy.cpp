#include "ccd/accuracy.hpp"

#include <gtest/gtest.h>

namespace skelcd::ccd {
namespace {

TEST(Accuracy, NamesRoundTrip) {
  for (auto a : {Accuracy::exact, Accuracy::conservative, Accuracy::fast}) {
    const auto parsed = parse_accuracy(to_string(a));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, a);
  }
}

TEST(Accuracy, UnknownNameIsRefused) {
  EXPECT_FALSE(parse_accuracy("precise").has_value());
  EXPECT_FALSE(parse_accuracy("").has_value());
}

}  // namespace
}  // namespace skelcd::ccd
