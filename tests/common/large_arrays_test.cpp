#include "qm3d/common/large_arrays.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>

namespace qm3d {
namespace {

TEST(LargeArray, ResizeWithAValueFillsAndGrowsKeepTheElements) {
  LargeArray<double> a;
  a.resize(3, 1.5);
  a.push_back(2.5);
  a.resize(5u << 20, -1.0);  // 40 MiB: huge pages advised
  ASSERT_EQ(a.size(), 5u << 20);
  EXPECT_EQ(a[0], 1.5);
  EXPECT_EQ(a[3], 2.5);
  EXPECT_EQ(a[4], -1.0);
  EXPECT_EQ(a.back(), -1.0);
  const LargeArray<double> copy = a;
  EXPECT_EQ(copy, a);
}

TEST(LargeArray, ElementsWrittenAfterAnUninitialisedResizeReadBack) {
  LargeArray<std::array<double, 3>> a(1u << 20);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = {double(i), 0, -double(i)};
  EXPECT_EQ(a[12345][0], 12345.0);
  EXPECT_EQ(a.back()[2], -double(a.size() - 1));
}

TEST(LargeArray, NonTrivialElementsAreConstructed) {
  LargeArray<std::string> a(4);
  for (const auto& s : a) EXPECT_TRUE(s.empty());
  a.emplace_back(3, 'x');
  EXPECT_EQ(a.back(), "xxx");
}

TEST(HugePages, AdviceIsAHintForAnyRange) {
  advise_huge_pages(nullptr, 1u << 30);
  std::vector<std::uint8_t> small(100);
  advise_huge_pages(small.data(), small.size());
  std::vector<std::uint8_t> big;
  reserve_with_huge_pages(big, 9u << 20);
  EXPECT_GE(big.capacity(), 9u << 20);
  big.resize(9u << 20);
  EXPECT_EQ(big.size(), 9u << 20);
  EXPECT_EQ(big[123], 0);  // std::vector's resize still value-initialises
  big[5] = 7;
  reserve_with_huge_pages(big, 20u << 20);  // grows, keeping the elements
  EXPECT_GE(big.capacity(), 20u << 20);
  EXPECT_EQ(big.size(), 9u << 20);
  EXPECT_EQ(big[5], 7);
  reserve_with_huge_pages(big, 1);  // already room: nothing changes
  EXPECT_EQ(big[5], 7);
}

}  // namespace
}  // namespace qm3d
