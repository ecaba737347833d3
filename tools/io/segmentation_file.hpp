#pragma once
// A saved segmentation (`skelcd preprocess -o SEG.h5`): the atomic clusters, their observers, the
// cluster graph, the parameters and statistics, and the content hash of the model it was made
// from, so that `check` and `bench` can reuse it when the model has not changed.
// Layout: docs/segmentation.md. HDF5 stays inside the .cpp.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "segmentation/bone_segment.hpp"
#include "segmentation/orientation_stats.hpp"
#include "segmentation/segmentation.hpp"
#include "tools/io/file_hash.hpp"  // model_identity

namespace skelcd::tools {

/// Value of the root attribute `format` that marks a file as a skelcd segmentation.
inline constexpr const char* kSegmentationFormatName = "skelcd-segmentation";
/// Version written by this build; readers accept versions <= this.
inline constexpr std::int64_t kSegmentationFormatVersion = 1;

/// What the file records beside the segmentation itself.
struct SegmentationRecord {
  std::int64_t format_version = kSegmentationFormatVersion;
  std::string skelcd_version;
  std::string input_path;  ///< the model as given on the command line
  std::string input_hash;  ///< model_identity of the model ("fnv1a64:…" or "gen:…")
  std::vector<std::string> bone_names;           ///< #B
  std::vector<segmentation::BoneSegment> bones;  ///< #B rest segments with parents
  /// |H⁻| / |Hᵘ| over a clip, when one was classified.
  std::optional<segmentation::ClipOrientationStats> clip;
};

struct SegmentationFile {
  segmentation::Segmentation segmentation;
  SegmentationRecord record;
};

/// Writes `segmentation` to `path`: first to a temporary file beside it, renamed over `path` only
/// when complete (a failed or interrupted write leaves nothing half-written).
/// @throws IoError when the file cannot be written, or `path` exists and is not a skelcd
///   segmentation (it is never clobbered).
void write_segmentation(
    const std::filesystem::path& path,
    const segmentation::Segmentation& segmentation,
    const SegmentationRecord& record);

/// Reads a segmentation written by write_segmentation (any format version <= ours). Clusters'
/// triangle lists are rebuilt from the per-triangle clusters.
/// @throws IoError when the file is missing, not HDF5, not a skelcd segmentation, of a newer
///   version, or inconsistent (a cluster or triangle index out of range).
[[nodiscard]] SegmentationFile read_segmentation(const std::filesystem::path& path);

/// Reads `path` and checks that it was made from `model`: same model_identity.
/// @throws InvalidInput naming both files when the hashes differ (the model changed since);
///   IoError as above.
[[nodiscard]] SegmentationFile read_segmentation(
    const std::filesystem::path& path, const std::string& model);

/// True when `path` is a readable skelcd segmentation made from `model` (same model_identity):
/// the test `check` and `bench` use to reuse a saved segmentation or compute a new one.
[[nodiscard]] bool segmentation_matches(
    const std::filesystem::path& path, const std::string& model);

}  // namespace skelcd::tools
