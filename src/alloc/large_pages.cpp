// large_pages.cpp: the operator new of hbil and of its tests and benchmark, for the large
// blocks a frame allocates and frees: its planes, 1 to 75 MB each at 1920x1080, made afresh
// every frame. Fresh memory costs a page fault and a page cleared by the kernel for every
// page on first touch: a third of the system time of a 1920x1080 run. So, for every block of
// at least 1 MiB (kLarge):
//  - huge pages: the kernel here gives transparent huge pages (2 MiB) only to memory that
//    asks for them, and 4 KiB pages cost 512 times the faults. The whole huge pages inside
//    the block are asked for (what glibc's tunable glibc.malloc.hugetlb=1 does for every
//    block, done here for the large ones).
//  - reuse: a freed block is kept, up to kCacheBytes in all, and handed to the next request
//    that it fits within an eighth, so that the next frame's planes are the last frame's
//    memory, neither faulted nor cleared again. The oldest blocks go first when it is full.
//    A request that no block fits first frees at least its own size of cached blocks, the
//    oldest first (or all of them). So live and cached memory together grow on a large
//    request only when the cache is empty, and then only to what is live: the cache does not
//    raise the peak that large blocks make.
// The blocks still come from malloc and go back through free; what a program sees of new and
// delete is unchanged (new memory is not cleared, as before). And glibc's heap keeps what is
// freed (keep_the_heap below), so that blocks the cache gives back are not fresh memory to
// the next request either: over a 1920x1080 sequence that lowers the system time and the
// peak (one arena instead of one per thread).
//
// Not under AddressSanitizer, which has its own operator new and would see our blocks come
// from malloc and go to its operator delete.
#include "alloc/large_pages.h"

#include <malloc.h>
#include <sys/mman.h>

#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
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
constexpr std::size_t kLarge = std::size_t(1) << 20;
// What the cache may hold: about ten 1920x1080 planes of three floats. A large request that
// no block fits frees cached memory first (Cache::take), so the cache adds to a run's peak
// memory only what requests under kLarge take while it holds blocks.
constexpr std::size_t kCacheBytes = std::size_t(256) << 20;
constexpr int kSlots = 32;

struct Block {
  void* p;
  std::size_t size;  // malloc_usable_size
};
// Constant-initialised and never destroyed, so that a delete during the program's exit
// finds it whole (std::mutex is trivially destructible with glibc).
struct Cache {
  std::mutex m;
  Block blocks[kSlots] = {};  // oldest first
  int n = 0;
  std::size_t bytes = 0;

  void remove(int k) {
    bytes -= blocks[k].size;
    for (int i = k + 1; i < n; ++i) blocks[i - 1] = blocks[i];
    --n;
  }
  // Frees the oldest block; its size.
  std::size_t free_oldest() {
    const std::size_t size = blocks[0].size;
    std::free(blocks[0].p);
    remove(0);
    return size;
  }
  // The smallest cached block of at least `want` bytes and at most want + want/8, taken out.
  // Where none fits, the oldest blocks are freed until they make up `want` (or none is
  // left), so that the memory the caller then gets from malloc replaces cached memory
  // instead of adding to it (see above).
  void* take(std::size_t want) {
    std::lock_guard<std::mutex> lock(m);
    int best = -1;
    for (int k = 0; k < n; ++k)
      if (blocks[k].size >= want && blocks[k].size - want <= want / 8 &&
          (best < 0 || blocks[k].size < blocks[best].size))
        best = k;
    if (best >= 0) {
      void* p = blocks[best].p;
      remove(best);
      return p;
    }
    for (std::size_t freed = 0; n > 0 && freed < want;) freed += free_oldest();
    return nullptr;
  }
  // Keeps p (usable size `size`), freeing the oldest blocks to make room.
  void give(void* p, std::size_t size) {
    if (size > kCacheBytes) return std::free(p);
    std::lock_guard<std::mutex> lock(m);
    while (n > 0 && (n == kSlots || bytes + size > kCacheBytes)) free_oldest();
    blocks[n++] = {p, size};
    bytes += size;
  }
};
constinit Cache cache;

// glibc's heap, set before main: blocks up to 32 MiB (the most glibc allows; most of a
// 1920x1080 frame's planes) come from the heap instead of a mapping of their own, the heap is
// never given back to the kernel, and every thread allocates from one arena. What a frame
// frees, the next frame's blocks then take without a page fault or a page cleared: every
// block of a mapping of its own is fresh memory each time, as is a heap that was trimmed.
// One arena: freed memory of one thread serves the next allocation of any thread (with an
// arena per thread, the reader's blocks and the computing threads' would not meet).
[[gnu::constructor]] void keep_the_heap() {
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, INT_MAX);
}

void advise_huge_pages(void* p, std::size_t n) {
  // The whole huge pages inside the block; a madvise that fails changes nothing.
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t lo = (a + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t hi = (a + n) & ~(kHugePage - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
}

void* allocate(std::size_t n) {
  if (n == 0) n = 1;
  if (n >= kLarge)
    if (void* p = cache.take(n)) return p;
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

void release(void* p) {
  if (!p) return;
  const std::size_t size = malloc_usable_size(p);
  if (size >= kLarge) return cache.give(p, size);
  std::free(p);
}

}  // namespace

void* operator new(std::size_t n) {
  return allocate(n);
}
void* operator new[](std::size_t n) {
  return allocate(n);
}
void operator delete(void* p) noexcept {
  release(p);
}
void operator delete[](void* p) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  release(p);
}

namespace hbil::alloc {
bool large_pages_active() {
  return true;
}
std::size_t cached_bytes() {
  std::lock_guard<std::mutex> lock(cache.m);
  return cache.bytes;
}
}  // namespace hbil::alloc
#else
namespace hbil::alloc {
bool large_pages_active() {
  return false;
}
std::size_t cached_bytes() {
  return 0;
}
}  // namespace hbil::alloc
#endif
