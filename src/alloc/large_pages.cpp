// large_pages.cpp: the operator new of hbil and of its tests and benchmark, which asks the
// kernel for transparent huge pages (2 MiB) for every block of at least 4 MiB: a frame's
// planes (8 to 75 MB at 1920x1080) are allocated afresh every frame, and each of their 4 KiB
// pages costs a page fault on first touch (a third of the system time of a 1920x1080 run,
// where the kernel's default is to give huge pages only to memory that asks for them). What
// glibc's tunable glibc.malloc.hugetlb=1 does for every block, done here for the large ones,
// from inside the program. The blocks still come from malloc and go back through free: only
// the pages under them change.
//
// Not under AddressSanitizer, which has its own operator new and would see our blocks come
// from malloc and go to its operator delete.
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define HBIL_LARGE_PAGES 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HBIL_LARGE_PAGES 0
#endif
#endif
#ifndef HBIL_LARGE_PAGES
#define HBIL_LARGE_PAGES 1
#endif

#if HBIL_LARGE_PAGES && defined(MADV_HUGEPAGE)
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kLarge = 2 * kHugePage;

void advise_huge_pages(void* p, std::size_t n) {
  // The whole huge pages inside the block; a madvise that fails changes nothing.
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t lo = (a + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t hi = (a + n) & ~(kHugePage - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
}

void* allocate(std::size_t n) {
  if (n == 0) n = 1;
  for (;;) {
    if (void* p = std::malloc(n)) {
      if (n >= kLarge) advise_huge_pages(p, n);
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

void* operator new(std::size_t n) {
  return allocate(n);
}
void* operator new[](std::size_t n) {
  return allocate(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#endif
