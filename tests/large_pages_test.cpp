// The programs' operator new for large blocks (src/alloc/large_pages.cpp): a freed plane is
// the next plane of its size, a block is reused within an eighth of its size, a request that
// no block fits frees as much cached memory, and blocks survive being passed between
// threads. Not under AddressSanitizer, where the sanitizer's own operator new is in place.
#include "alloc/large_pages.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace {

using hbil::alloc::cached_bytes;
constexpr size_t kPlane = 1920 * 1080;  // floats: 8.3 MB
constexpr size_t kMiB = size_t(1) << 20;

// A block of n bytes, written to and seen to escape, so that the compiler cannot leave out
// its allocation.
std::unique_ptr<char[]> block(size_t n) {
  std::unique_ptr<char[]> p(new char[n]);
  p[0] = 1;
  asm volatile("" : : "g"(p.get()) : "memory");
  return p;
}

TEST(LargePages, AFreedPlaneIsTheNextPlaneOfItsSize) {
  if (!hbil::alloc::large_pages_active())
    GTEST_SKIP() << "the sanitizer's operator new is in place";
  const float* first;
  size_t held;
  {
    std::vector<float> a(kPlane, 1.f);
    first = a.data();
    held = cached_bytes();
  }
  EXPECT_GE(cached_bytes(), held + kPlane * sizeof(float));
  std::vector<float> b(kPlane);  // value-initialised: the reused block is cleared
  EXPECT_EQ(b.data(), first);
  EXPECT_EQ(cached_bytes(), held);
  EXPECT_EQ(b[0], 0.f);
  EXPECT_EQ(b[kPlane - 1], 0.f);
}

TEST(LargePages, ABlockIsReusedWithinAnEighthOfItsSize) {
  if (!hbil::alloc::large_pages_active())
    GTEST_SKIP() << "the sanitizer's operator new is in place";
  const char* big;
  {
    std::unique_ptr<char[]> a = block(16 * kMiB);
    big = a.get();
  }
  std::unique_ptr<char[]> c = block(15 * kMiB);
  EXPECT_EQ(c.get(), big);
}

TEST(LargePages, ARequestNoBlockFitsFreesAsMuchCachedMemory) {
  if (!hbil::alloc::large_pages_active())
    GTEST_SKIP() << "the sanitizer's operator new is in place";
  { std::unique_ptr<char[]> a = block(16 * kMiB); }
  const size_t before = cached_bytes();
  ASSERT_GE(before, 16 * kMiB);
  // 12 MiB: the 16 MiB block would waste a third of itself. Cached blocks of at least 12 MiB
  // in all are freed, so that the new block does not add to the memory held.
  std::unique_ptr<char[]> b = block(12 * kMiB);
  EXPECT_LE(cached_bytes() + 12 * kMiB, before);
}

TEST(LargePages, BlocksPassedBetweenThreadsKeepTheirContents) {
  // Planes made on one thread, filled and freed on others, many times over: every one holds
  // what its last writer wrote (this runs with any operator new).
  constexpr int kRounds = 24;
  std::vector<std::vector<std::uint32_t>> planes(4);
  for (int round = 0; round < kRounds; ++round) {
    for (auto& p : planes) p.assign(kPlane / 2 + 4096 * size_t(round % 3), 0u);
    tbb::parallel_for(0, int(planes.size()), [&](int k) {
      auto& p = planes[size_t(k)];
      for (size_t i = 0; i < p.size(); ++i) p[i] = std::uint32_t(i) ^ std::uint32_t(k + round);
    });
    for (size_t k = 0; k < planes.size(); ++k) {
      const auto& p = planes[k];
      size_t wrong = 0;
      for (size_t i = 0; i < p.size(); ++i)
        wrong += p[i] != (std::uint32_t(i) ^ std::uint32_t(int(k) + round));
      ASSERT_EQ(wrong, 0u) << "round " << round << ", plane " << k;
    }
    tbb::parallel_for(0, int(planes.size()),
                      [&](int k) { std::vector<std::uint32_t>().swap(planes[size_t(k)]); });
  }
}

}  // namespace
