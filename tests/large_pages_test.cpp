// The programs' operator new for large blocks (src/alloc/large_pages.cpp): a freed plane is
// the next plane of its size, blocks of another size are not handed out for it, and blocks
// survive being passed between threads. Not under AddressSanitizer, where the sanitizer's own
// operator new is in place.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kOwnNew = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kOwnNew = false;
#else
constexpr bool kOwnNew = true;
#endif
#else
constexpr bool kOwnNew = true;
#endif

constexpr size_t kPlane = 1920 * 1080;  // floats: 8.3 MB

TEST(LargePages, AFreedPlaneIsTheNextPlaneOfItsSize) {
  if (!kOwnNew) GTEST_SKIP() << "the sanitizer's operator new is in place";
  const float* first;
  {
    std::vector<float> a(kPlane, 1.f);
    first = a.data();
  }
  std::vector<float> b(kPlane);  // value-initialised: the reused block is cleared
  EXPECT_EQ(b.data(), first);
  EXPECT_EQ(b[0], 0.f);
  EXPECT_EQ(b[kPlane - 1], 0.f);
}

TEST(LargePages, ABlockIsNotHandedToARequestMuchSmallerThanIt) {
  if (!kOwnNew) GTEST_SKIP() << "the sanitizer's operator new is in place";
  const char* big;
  {
    std::unique_ptr<char[]> a(new char[16 << 20]);
    big = a.get();
  }
  // 12 MiB: the cached 16 MiB block would waste a third of itself; nor may malloc return it,
  // since it is still held by the cache.
  std::unique_ptr<char[]> b(new char[12 << 20]);
  EXPECT_NE(b.get(), big);
  // Within an eighth it is reused.
  std::unique_ptr<char[]> c(new char[15 << 20]);
  EXPECT_EQ(c.get(), big);
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
