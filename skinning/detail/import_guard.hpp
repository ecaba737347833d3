#pragma once
// Keeps a broken file from taking skelcd down with it (internal; skinning/ for model files, and
// tools/io/log/ for logs, whose HDF5 library crashes on some malformed files). assimp trusts
// the counts a file declares (a 300-byte OFF file asks for 15 GB) and crashes on some malformed
// files; skelcd must answer every input with a result or one line.

#include <cstddef>
#include <filesystem>
#include <functional>

namespace skelcd::skinning::detail {

struct ImportLimits {
  /// Address space the probe may add to what the process already maps, bytes.
  std::size_t memory_bytes = 0;
  /// Wall-clock time the probe may take, seconds (<= 0: no limit).
  double time_s = 0.0;
  /// Who reads the file, for the messages ("the importer (assimp)", "HDF5").
  const char* reader = "the importer (assimp)";
};

/// Refuses a file whose header declares more elements than its size can hold, before any
/// importer allocates for them. Knows the formats whose importers reserve by the declared count:
/// OFF and PLY (ASCII and binary). Other files pass.
/// @throws InvalidInput "<file>: declares … but its N bytes hold at most …".
void check_declared_counts(const std::filesystem::path& file);

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

}  // namespace skelcd::skinning::detail
