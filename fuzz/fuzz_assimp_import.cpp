// libFuzzer harness: the assimp import path as we drive it (skinning/assimp_import.hpp,
// import_rig), in process. The first byte of an input picks the file extension — and so which
// assimp loader reads the rest (kExtensions[byte % size]); the seed corpus is real files with
// that byte prepended (scripts/fuzz.sh seeds, docs/fuzzing.md).
// assimp 5.2 itself crashes on many malformed files: scripts/fuzz.sh runs this harness with
// -fork=1 -ignore_crashes=1 and keeps each crashing input, to be sorted into libassimp's
// crashes and ours by the top of the stack.
// A thrown std::exception is the importer refusing the input (fine).

#include <array>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "fuzz/fuzz_input.hpp"
#include "skinning/assimp_import.hpp"

namespace {

constexpr std::array<std::string_view, 11> kExtensions = {
    ".obj", ".off", ".ply", ".stl", ".dae", ".gltf", ".glb", ".fbx", ".x", ".ms3d", ".md5mesh"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const auto extension = kExtensions[data[0] % kExtensions.size()];
  const auto path = skelcd::fuzz::write_input(data + 1, size - 1, extension);
  // In this process (coverage, sanitizers), not in the forked child that guards the CLI.
  skelcd::skinning::ImportOptions options;
  options.isolate = false;
  try {
    (void)skelcd::skinning::import_rig(path, options);
  } catch (const std::exception&) {
  }
  return 0;
}
