#pragma once
// Keeps a broken file from taking skelcd down with it (internal; skinning/ for model files, and
// tools/io/log/ for logs, whose HDF5 library crashes on some malformed files). assimp trusts
// the counts a file declares (a 300-byte OFF file asks for 15 GB) and crashes on some malformed
// files; skelcd must answer every input with a result or one line.

#include <cstddef>
#include <deque>
#include <filesystem>
#include <functional>
#include <vector>

namespace skelcd::skinning::detail {

struct ImportLimits {
  /// Memory the probe may take, bytes: address space it may add to what the process already
  /// maps, less the heap the process freed but still maps (which the probe allocates in first).
  std::size_t memory_bytes = 0;
  /// Wall-clock time the probe may take, seconds (<= 0: no limit).
  double time_s = 0.0;
  /// Who reads the file, for the messages ("the importer (assimp)", "HDF5").
  const char* reader = "the importer (assimp)";
  /// Grow the child's heap at once and advise it as huge pages (import_guard.cpp): assimp's
  /// imports only. A reader whose known crashes depend on the heap's layout (HDF5's fuzzed
  /// logs) keeps the plain heap.
  bool heap_on_huge_pages = false;
  /// Run by this process once the child has started, before it waits for the child's answer
  /// (ImportOptions::while_importing); what it throws is dropped.
  std::function<void()> while_waiting{};
};

/// The heap the import's child grows at once and advises (ImportLimits::heap_on_huge_pages), and
/// what `skelcd check` advises of its own once it has imported a large mesh
/// (tools/cli/large_pages.hpp).
inline constexpr std::size_t kHeapOnHugePages = std::size_t{30} << 20;

/// Grows malloc's main heap by `bytes` at once (address space only: nothing is touched), advises
/// its whole 2 MiB pages MADV_HUGEPAGE and frees the block back as the heap's top, which is then
/// not trimmed below it (M_TRIM_THRESHOLD 2 × bytes): what malloc later serves from the top is
/// first touched a 2 MiB page at a time, where the kernel offers them. Leaves the mmap threshold
/// at 32 MiB, for the caller to set. Below two huge pages, or where malloc refuses (over a
/// limit), nothing is advised and the heap grows as it would have.
void grow_heap_on_huge_pages(std::size_t bytes) noexcept;

/// Refuses a file whose header declares more elements than its size can hold, before any
/// importer allocates for them. Knows the formats whose importers reserve by the declared count:
/// OFF and PLY (ASCII and binary). Other files pass.
/// @throws InvalidInput "<file>: declares … but its N bytes hold at most …".
void check_declared_counts(const std::filesystem::path& file);

/// Where a probe run by run_isolated_with_answer sends its answer: bytes written in order reach the
/// parent in that order (buffered in the child; the parent drains the pipe while the child writes,
/// so an answer of any size goes through).
using AnswerSink = std::function<void(const void* data, std::size_t size)>;

/// The bytes a child process answered with, in the pieces they arrived in. Reading releases each
/// piece once it has been read through, so that decoding the answer into its own structures does
/// not hold the whole answer twice.
class ChildAnswer {
 public:
  /// Appends `piece` after the bytes already held.
  void append(std::vector<char> piece);
  /// Bytes not yet read.
  [[nodiscard]] std::size_t size() const { return size_; }
  /// Copies the next `n` bytes into `out` and returns true; returns false and reads nothing when
  /// fewer than `n` bytes are left.
  [[nodiscard]] bool read(void* out, std::size_t n);

 private:
  std::deque<std::vector<char>> pieces_;
  std::size_t offset_ = 0;  // into pieces_.front()
  std::size_t size_ = 0;
};

/// Runs `probe` in a child process under `limits` (POSIX fork; the address-space limit is
/// RLIMIT_AS, skipped under AddressSanitizer, whose own allocator limit applies there) and
/// returns when it succeeded. The child's outcome becomes the parent's:
/// - `probe` threw IoError or InvalidInput: the same exception, same message, is thrown here;
/// - it ran out of memory (std::bad_alloc, or killed for it): InvalidInput naming the limit;
/// - it crashed (a signal) or exceeded the time: IoError naming the signal or the time.
/// Every message starts with `file`. The caller holds whatever lock `probe` would take.
void run_isolated(
    const std::filesystem::path& file,
    const ImportLimits& limits,
    const std::function<void()>& probe);

/// run_isolated for a probe that also answers: what `probe` writes to its sink comes back here
/// (the child's own import is then the only one). Every outcome but success is reported as by
/// run_isolated; besides, an answer larger than `limits.memory_bytes` (when set) is refused as
/// over the memory limit, and a child that exits without completing its answer is an IoError.
/// @note The answer is the child's bytes as sent: the caller decodes and validates them (a
///       truncated answer, e.g. from a child killed while writing, is the caller's to detect when
///       the child's exit does not already say so).
[[nodiscard]] ChildAnswer run_isolated_with_answer(
    const std::filesystem::path& file,
    const ImportLimits& limits,
    const std::function<void(const AnswerSink& send)>& probe);

}  // namespace skelcd::skinning::detail
