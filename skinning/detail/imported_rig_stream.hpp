#pragma once
// An ImportedRig as bytes, from the import's child process to its parent (internal): the child's
// import is then the only one (skinning/assimp_import.cpp). Native byte order and sizes: a
// message between two processes of the same program, not a file format.

#include <string>

#include "skinning/assimp_import.hpp"
#include "skinning/detail/import_guard.hpp"

namespace skelcd::skinning::detail {

/// Sends every field of `imported` to `send` (doubles bit for bit), in the order
/// read_imported_rig reads them.
/// @note A field added to ImportedRig, Rig, Mesh, Skeleton, Clip or their members must be added
///       here and in read_imported_rig, and to tests/skinning/test_imported_rig_stream.cpp's
///       comparison: a field left out comes back default-constructed from an isolated import.
void write_imported_rig(const ImportedRig& imported, const AnswerSink& send);

/// Reads what write_imported_rig sent, releasing `bytes` as it goes. Every count is checked
/// against the bytes left before anything is allocated for it, and the rig's structure (array
/// lengths that must agree, the weights' sparse layout) before it is returned; the data then
/// pass validate_rig as the child's did.
/// @param file  named in the messages.
/// @throws IoError "<file>: the import's answer from its child process is damaged (…)" when the
///         bytes end early, carry more than the rig, or do not describe a rig.
[[nodiscard]] ImportedRig read_imported_rig(ChildAnswer& bytes, const std::string& file);

}  // namespace skelcd::skinning::detail
