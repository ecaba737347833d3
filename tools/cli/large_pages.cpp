// The skelcd executable's global `operator new` (large_pages.hpp): linked into the executable and
// its own test only, never into the libraries (python/ and the other tests keep the default one).
#include "tools/cli/large_pages.hpp"

#include <malloc.h>
#include <sys/mman.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>

#include "skinning/detail/import_guard.hpp"

namespace skelcd::tools {

bool large_pages_wanted(const char* env) noexcept {
  if (env == nullptr) return true;
  return std::strcmp(env, "0") != 0 && std::strcmp(env, "off") != 0 && std::strcmp(env, "no") != 0;
}

std::size_t advised_length(const void* begin, std::size_t bytes) noexcept {
  if (reinterpret_cast<std::uintptr_t>(begin) % kHugePage != 0) return 0;
  return bytes - bytes % kHugePage;
}

std::size_t large_block_size(std::size_t bytes) noexcept {
  const std::size_t tail = bytes % kHugePage;
  if (tail == 0) return bytes;
  const std::size_t extra = kHugePage - tail;
  return extra <= bytes / kMaxRoundingShare ? bytes + extra : bytes;
}

void heap_on_huge_pages(std::size_t bytes) noexcept {
  if (bytes < 2 * kHugePage) return;
  // One heap for all threads: a worker's own arena is mapped apart and would first-touch 4 KiB at
  // a time. The rows allocate a few dozen blocks per interval (BCN_Epileptic: 3.7k mallocs over
  // 99 intervals), so its lock is not where threads wait.
  mallopt(M_ARENA_MAX, 1);
  // The import's child's own growth, here for this process's heap.
  skinning::detail::grow_heap_on_huge_pages(bytes);
}

namespace {

bool large_pages_on() noexcept {
  static const bool on = large_pages_wanted(std::getenv("SKELCD_LARGE_PAGES"));
  return on;
}

/// A block of `bytes` (alignment `align`, a power of two) on a huge-page boundary with its whole
/// huge pages advised, when it is large, its alignment allows it and large pages are on; nullptr
/// otherwise or when posix_memalign fails (the caller then goes the ordinary way).
void* allocate_large(std::size_t bytes, std::size_t align) noexcept {
  if (bytes < kLargePageMin || align > kHugePage || !large_pages_on()) return nullptr;
  void* p = nullptr;
  const std::size_t size = large_block_size(bytes);
  if (posix_memalign(&p, kHugePage, size) != 0) return nullptr;
  // Advice only: a kernel without transparent huge pages answers EINVAL and the pages stay small.
  if (const std::size_t length = advised_length(p, size); length != 0) {
    madvise(p, length, MADV_HUGEPAGE);
  }
  return p;
}

/// `allocate()` until it gives a block, calling the new_handler between tries; bad_alloc when
/// there is none ([new.delete.single]).
template <class Allocate>
void* allocate_or_throw(Allocate allocate) {
  for (;;) {
    if (void* p = allocate()) return p;
    const std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

}  // namespace
}  // namespace skelcd::tools

// The replaceable allocation functions ([new.delete.single]): the nothrow and array forms of
// libstdc++ call these, and its operator delete calls free(), which releases both kinds.
void* operator new(std::size_t bytes) {
  if (void* p = skelcd::tools::allocate_large(bytes, 0)) return p;
  return skelcd::tools::allocate_or_throw([bytes] { return std::malloc(bytes == 0 ? 1 : bytes); });
}

void* operator new[](std::size_t bytes) { return ::operator new(bytes); }

// The over-aligned forms (types declared alignas(64): the feature stage's per-triangle records and
// per-vertex end positions) the same way; below 2 MiB as libstdc++'s own, whose aligned delete
// calls free() too.
void* operator new(std::size_t bytes, std::align_val_t alignment) {
  const auto align = std::max(static_cast<std::size_t>(alignment), sizeof(void*));
  if (void* p = skelcd::tools::allocate_large(bytes, align)) return p;
  return skelcd::tools::allocate_or_throw([bytes, align]() -> void* {
    void* p = nullptr;
    return posix_memalign(&p, align, bytes == 0 ? 1 : bytes) == 0 ? p : nullptr;
  });
}

void* operator new[](std::size_t bytes, std::align_val_t alignment) {
  return ::operator new(bytes, alignment);
}
