#pragma once
// Importing rigged (or plain) models through assimp into a Rig: every mesh of the file becomes a
// part of one Mesh, the node hierarchy becomes the Skeleton, skins become bones and weights,
// animations become clips.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "skinning/rig.hpp"

namespace skelcd::skinning {

/// 4 GiB: a 60k-triangle character imports in well under 200 MB; a file that needs more is
/// either huge or lying about its size (`--import-memory` raises it).
inline constexpr std::size_t kDefaultImportMemoryLimit = std::size_t{4} << 30;

struct ImportOptions {
  /// Merge identical vertices within each mesh of the file (assimp's JoinIdenticalVertices:
  /// same position, normal, UV, …). Never merges across meshes: parts stay apart.
  bool join_identical_vertices = true;
  /// With join_identical_vertices: let assimp's step move the bones' weights itself (quadratic in
  /// a bone's weights in assimp 5.2.4) instead of moving them here, linearly, to the same result.
  /// For the test that the two agree.
  bool assimp_moves_weights = false;
  /// Convert the file's unit to metres when the file declares one assimp does not apply itself
  /// (FBX: GlobalSettings UnitScaleFactor, in centimetres). glTF is in metres by definition and
  /// assimp applies Collada's <unit>; other formats carry no unit and are taken as they are.
  bool convert_to_metres = true;
  /// Import the file in a child process, which sends the result back, so that a file on which
  /// assimp crashes, loops or allocates without bound costs one line, not the process
  /// (skinning/detail/import_guard.hpp, imported_rig_stream.hpp). The file is read once either
  /// way. Off only for fuzzing the importer in-process.
  bool isolate = true;
  /// Address space that importing one file may use, bytes (checked in the child process).
  std::size_t memory_limit_bytes = kDefaultImportMemoryLimit;
  /// Time that importing one file may take in the child process, seconds.
  double time_limit_s = 120.0;
  /// Work of this process's own, done while the child imports (with isolate; nothing without):
  /// its wait for the child is otherwise idle. `skelcd check` starts its thread pool there
  /// (tools::warm_up_workers). Must not throw: what it throws is dropped, the import goes on.
  std::function<void()> while_importing{};
};

/// A clip of the file that could not be used (keys out of order, non-finite keys, …). The rest
/// of the file, and its other clips, are imported all the same.
struct RefusedClip {
  std::string name;
  /// Why, without the file's name: "node 'Hips', rotation key 12 (t = 0.4 s) is earlier than …".
  std::string reason;
};

/// What import_rig returns. A field added here must also cross from the import's child process to
/// its parent: skinning/detail/imported_rig_stream.cpp, and the comparison in its test.
struct ImportedRig {
  Rig rig;
  /// Clips left out of rig.clips because their data are unusable (each also has a line in
  /// `problems`).
  std::vector<RefusedClip> refused_clips;
  /// What was found and handled, one sentence each (dropped points/lines, normalised weights,
  /// unnamed clips, assimp warnings, …). Faults that make the data unusable throw instead.
  std::vector<std::string> problems;
  /// Scale applied to the file's coordinates (Skeleton::root_transform's scale).
  double unit_scale = 1.0;
  /// Largest distance (object units) between a skinned vertex at its bind position and where the
  /// file's own node rest pose puts it; 0 when the file stores its hierarchy in the bind pose
  /// (up to the file's float precision) or has no skin.
  double rest_pose_deviation = 0.0;
};

/// Imports `file` with assimp (triangulated; points and lines dropped and reported).
/// Mesh::vertex_index_in_part and face_index_in_part number vertices and faces as assimp hands
/// them over: faces as in the file, vertices after JoinIdenticalVertices when that is on.
///
/// Object space is the file's scene space with the unit scale applied: an unskinned mesh is
/// placed by its node's global transform and follows that node rigidly (Rig::part_attachments);
/// a skinned mesh is placed in its bind pose and follows its bones, with weights normalised to
/// sum 1 (any number of influences). Bones are the nodes that skins reference, sorted parents
/// first; nodes without a channel in a clip keep their static transform. Times are seconds.
///
/// @throws IoError when the file is missing, unreadable or assimp cannot parse it (the message
///         names the file and repeats assimp's reason), or when assimp crashed or exceeded
///         `time_limit_s` reading it in the child process, or when the rig the child sent back
///         arrives damaged (it never does but for a bug: every count is checked on arrival).
/// @throws InvalidInput also when the file declares more elements than its size can hold, or
///         importing it needs more than `memory_limit_bytes`.
/// @throws InvalidInput when the data are unusable: non-finite coordinates, transforms or
///         weights, indices out of range (also when assimp reports it dropped such faces), no
///         triangle at all, a node hierarchy with a cycle. A clip with unusable keys (out of
///         order, non-finite) does not throw: it is refused alone (ImportedRig::refused_clips).
[[nodiscard]] ImportedRig import_rig(
    const std::filesystem::path& file, const ImportOptions& options = {});

}  // namespace skelcd::skinning
