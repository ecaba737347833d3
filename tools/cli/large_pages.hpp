// Large allocations on transparent huge pages (docs/cli.md, "Large allocations"). The skelcd
// executable replaces the global `operator new`: an allocation of at least kLargePageMin bytes is
// placed on a 2 MiB boundary and the whole huge pages inside it are advised MADV_HUGEPAGE, so that
// its first touch costs one fault per 2 MiB instead of one per 4 KiB (on a VM a fault is dear:
// docs/benchmarks.md, "Large allocations on huge pages"), in both forms, plain and over-aligned.
// Everything else is allocated as before, and every block is still released by free().
// SKELCD_LARGE_PAGES=0 in the environment turns it off for the process.
#pragma once

#include <cstddef>
#include <cstdint>

#include "skinning/detail/import_guard.hpp"

namespace skelcd::tools {

/// The size of one transparent huge page on x86-64 (the kernel's PMD size).
inline constexpr std::size_t kHugePage = std::size_t{1} << 21;

/// Allocations from this size on are placed and advised (smaller ones hold no whole huge page).
inline constexpr std::size_t kLargePageMin = kHugePage;

/// The rounding a block may take on to end on a huge page: at most a quarter of what was asked.
inline constexpr std::size_t kMaxRoundingShare = 4;

/// The bytes to take for an allocation of `bytes` (at least kLargePageMin): rounded up to whole
/// huge pages when that adds at most bytes / kMaxRoundingShare, so that its last huge page is
/// advised too instead of up to 511 small pages faulted one by one; else `bytes`.
std::size_t large_block_size(std::size_t bytes) noexcept;

/// Whether the environment's SKELCD_LARGE_PAGES value (nullptr when unset) leaves large pages on:
/// only "0", "off" and "no" turn them off.
bool large_pages_wanted(const char* env) noexcept;

/// The address space heap_on_huge_pages() advises at the heap's top: the import's child's own
/// (skinning/detail/import_guard.hpp), more than a character's check takes there. The cloth-ball
/// step's heap outgrows it by about 6 MiB, on small pages; advising 62 MiB halved that check's
/// faults (3.9k → 1.9k) for 10–14 MiB more peak RSS (docs/benchmarks.md).
inline constexpr std::size_t kHeapOnHugePages = skinning::detail::kHeapOnHugePages;

/// The meshes whose check puts its heap on huge pages (heap_on_huge_pages), by triangles. A huge
/// page is resident whole from its first touch: the heap's last one is 1 MiB too many on average
/// and the top is never trimmed, 2-3 MiB more peak RSS per check (up to 6.7 MiB with two threads)
/// for 1.03-1.18x on the whole check. Against issue 14's 1 KiB per triangle, on the 18-28k
/// triangle inputs that sit near it, that fixed cost broke the bound (CesiumMan-dense `kdop` 1.00
/// -> 1.08 KiB); from 64Ki triangles on 2 MiB is at most 0.03 KiB per triangle
/// (docs/benchmarks.md, "The heap on huge pages for large meshes only").
inline constexpr std::int64_t kHeapOnHugePagesMinTriangles = std::int64_t{1} << 16;

/// Whether a check of a mesh of `triangles` triangles puts its heap on huge pages.
constexpr bool heap_on_huge_pages_pays(std::int64_t triangles) noexcept {
  return triangles >= kHeapOnHugePagesMinTriangles;
}

/// Puts the blocks malloc serves from its heap on transparent huge pages, for every thread
/// (docs/cli.md, "Large allocations"): grows the main heap by `bytes` at once (address space only:
/// nothing is touched), advises its whole 2 MiB pages MADV_HUGEPAGE and frees the block back to
/// the heap's top, which is then never trimmed below it; and makes every thread allocate from
/// that heap (M_ARENA_MAX 1), whose top alone is advised. A check first-touches what it allocates
/// there a 2 MiB page at a time instead of 4 KiB. Leaves the mmap threshold at 32 MiB: the
/// caller sets its own after. Below two huge pages, or where malloc refuses, nothing is advised.
void heap_on_huge_pages(std::size_t bytes) noexcept;

/// The whole huge pages of an allocation of `bytes` bytes at `begin`: the bytes to advise from
/// `begin` (rounded down to kHugePage; the tail stays on small pages, so nothing beyond the
/// allocation is advised). `begin` is expected on a kHugePage boundary; 0 when it is not.
std::size_t advised_length(const void* begin, std::size_t bytes) noexcept;

}  // namespace skelcd::tools
