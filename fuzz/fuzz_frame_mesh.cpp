// libFuzzer harness: one OBJ or PLY frame file (skinning/frame_sequence.hpp, read_frame_mesh).
// Inputs that start with "ply" are written as input.ply, everything else as input.obj, so the
// seed corpus holds real files unchanged and each reader sees the inputs meant for it.
// A thrown std::exception is the reader refusing the input (fine); crashes, sanitizer reports,
// hangs and memory blow-ups are findings.

#include <cstddef>
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_input.hpp"
#include "skinning/frame_sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const bool ply = skelcd::fuzz::as_text(data, size).starts_with("ply");
  const auto path = skelcd::fuzz::write_input(data, size, ply ? ".ply" : ".obj");
  try {
    const auto mesh = skelcd::skinning::read_frame_mesh(path);
    // The documented postcondition: every index is a vertex of the file.
    const auto n = mesh.positions.rows();
    for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f) {
      for (Eigen::Index c = 0; c < 3; ++c) {
        if (mesh.triangles(f, c) < 0 || mesh.triangles(f, c) >= n) __builtin_trap();
      }
    }
  } catch (const std::exception&) {
  }
  return 0;
}
