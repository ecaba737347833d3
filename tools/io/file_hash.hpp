#pragma once
// Content hash of an input file, recorded in logs so a log can be matched to the exact model it
// checked.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace skelcd::tools {

/// 64-bit FNV-1a of `bytes`, continuing from `state` (start with kFnv1a64Offset).
[[nodiscard]] std::uint64_t fnv1a64(std::span<const unsigned char> bytes, std::uint64_t state);
inline constexpr std::uint64_t kFnv1a64Offset = 0xcbf29ce484222325ULL;

/// "fnv1a64:" followed by 16 lower-case hex digits: the 64-bit FNV-1a of the file's bytes.
/// @throws IoError naming `path` when it cannot be read.
[[nodiscard]] std::string file_content_hash(const std::filesystem::path& path);

/// What identifies a MODEL argument's content, for logs and segmentation files: the content hash
/// of a model or URDF file (file_content_hash); for a frame sequence (a folder or a glob), the
/// FNV-1a over its frame files in order, each file's name then its bytes ("fnv1a64:…"); for a
/// generated rig, its canonical spec ("gen:rope?…": generators are deterministic).
/// @throws IoError when a file cannot be read or a folder does not exist; InvalidInput for a bad
///   generator spec or a frame pattern that matches nothing.
[[nodiscard]] std::string model_identity(const std::string& model);

}  // namespace skelcd::tools
