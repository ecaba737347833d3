#pragma once
// Frame sequences: OBJ/PLY files with one topology (simulator output, baked cloth), one file per
// sample, as a Motion. The first frame is the rest mesh.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "skinning/mesh.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/motion.hpp"

namespace skelcd::skinning {

struct LoadedModel;
struct LoadOptions;

/// Sample rate of a frame sequence when none is asked for (Hz).
inline constexpr double kDefaultFrameRateHz = 30.0;

/// One frame file as read: positions in double precision exactly as written (binary float or
/// double, or ASCII decimal), vertices and faces in file order, nothing welded or reordered;
/// polygons split into a fan (0, k, k + 1).
struct FrameMesh {
  Positions positions;  ///< #V × 3
  Triangles triangles;  ///< #F × 3
};

/// Reads an OBJ (`v`, `f` lines; other lines ignored) or PLY (ASCII, binary little/big endian;
/// vertex x, y, z of any numeric type; face list `vertex_indices`/`vertex_index`) file.
/// We read these ourselves rather than through assimp because Debian's assimp stores coordinates
/// as float: a double-precision PLY would lose the bits the exact ground truth is computed from.
/// @throws IoError naming the file when it cannot be read, is truncated or malformed.
/// @throws InvalidInput naming the file and index for a non-finite coordinate, a face with fewer
///   than three corners or an index out of range.
[[nodiscard]] FrameMesh read_frame_mesh(const std::filesystem::path& file);

/// True when `a` sorts before `b` in natural order: runs of digits compare by value
/// ("frame2" < "frame10"), everything else character by character.
[[nodiscard]] bool natural_less(std::string_view a, std::string_view b);

/// The frame files `spec` names, in natural order of their file names: a folder (every .obj
/// and .ply file in it) or a glob pattern (`*`, `?`, `[...]` in the file-name part only).
/// @throws IoError when the folder does not exist; InvalidInput when nothing matches.
[[nodiscard]] std::vector<std::filesystem::path> list_frame_files(const std::filesystem::path& spec);

/// A sequence keeps its frames in memory while they take at most this many bytes per triangle
/// (a quarter of the 1 KiB per triangle a check may use, docs/benchmarks.md): the two frames of a
/// cloth step (24 bytes per triangle), not a long simulation, whose frames are read again from
/// their files when a sample asks.
inline constexpr std::size_t kKeptFrameBytesPerTriangle = 256;

struct FrameSequenceOptions {
  /// Frames per second: sample i is at time i / rate_hz.
  double rate_hz = kDefaultFrameRateHz;
  /// Frames kept in memory while #frames × #V × 24 ≤ this × #F; else only the first (the rest
  /// pose) is, and positions() reads a frame's file again (0: always read again).
  std::size_t kept_bytes_per_triangle = kKeptFrameBytesPerTriangle;
  /// The order mesh() and positions() hold the vertices and triangles in (skinning/mesh_order.hpp):
  /// the file's, or spatial_order of the first frame. Mesh::face_index_in_part and
  /// vertex_index_in_part give each element's index in the files either way.
  MeshOrder order = MeshOrder::file;
};

/// Every frame read and checked once at construction; kept in memory when they are few
/// (FrameSequenceOptions::kept_bytes_per_triangle), else read again by positions(), so that a
/// long sequence holds one frame per caller at a time.
class FrameSequenceMotion final : public Motion {
 public:
  /// Reads `files` (in this order).
  /// @throws InvalidInput naming the frame file when its vertex count or triangles differ from
  ///   the first frame's, it has a non-finite coordinate, or the rate is not positive and finite;
  ///   IoError / InvalidInput from read_frame_mesh.
  FrameSequenceMotion(
      std::vector<std::filesystem::path> files,
      const FrameSequenceOptions& options = {},
      std::string name = {});

  /// The first frame: one part named after the sequence, in FrameSequenceOptions::order.
  [[nodiscard]] const Mesh& mesh() const override { return data_->mesh; }
  [[nodiscard]] int num_samples() const override { return static_cast<int>(data_->files.size()); }
  [[nodiscard]] double sample_time(int i) const override { return i / rate_hz_; }
  [[nodiscard]] std::string name() const override { return data_->name; }
  /// Frame i's positions (in mesh()'s vertex order): from memory, or read again from its file
  /// (thread-safe either way).
  /// @throws IoError naming the file when it cannot be read again or its bytes are no longer
  ///   those read at construction.
  void positions(int i, Positions& out) const override;
  /// Frame i as held in memory (frames_in_memory()), else nullptr.
  [[nodiscard]] const Positions* held_positions(int i) const override;
  /// True when every frame is held in memory (else each but the first is read when asked for).
  [[nodiscard]] bool frames_in_memory() const { return !data_->frames.empty(); }

  [[nodiscard]] const std::filesystem::path& frame_file(int i) const {
    return data_->files[static_cast<std::size_t>(i)];
  }
  [[nodiscard]] double rate_hz() const override { return rate_hz_; }
  /// The same frames (shared, not copied) at another rate.
  /// @throws InvalidInput when the rate is not positive and finite.
  [[nodiscard]] std::unique_ptr<FrameSequenceMotion> with_rate(double rate_hz) const;

 private:
  struct Data {
    std::vector<std::filesystem::path> files;
    std::vector<Positions> frames;       ///< every frame, or none (read again: positions())
    std::vector<std::size_t> checksums;  ///< of each file's bytes, as read at construction
    /// Held in a spatial order: vertex v of mesh() is the files' vertex
    /// mesh.vertex_index_in_part[v] (one part), which a frame read again is gathered by.
    bool reordered = false;
    Mesh mesh;
    std::string name;
  };
  FrameSequenceMotion(std::shared_ptr<const Data> data, double rate_hz);

  std::shared_ptr<const Data> data_;
  double rate_hz_;
};

/// list_frame_files + FrameSequenceMotion; the name is the folder name or the pattern.
[[nodiscard]] FrameSequenceMotion load_frame_sequence(
    const std::filesystem::path& spec,
    const FrameSequenceOptions& options = {});

/// The load_model() entry point for frame sequences (ModelKind::frame_sequence): the mesh at rest
/// is the first frame; one clip named after the sequence with duration (#frames − 1) / rate;
/// motions sample every frame at MotionRequest::rate_hz (0: kDefaultFrameRateHz).
/// @throws InvalidInput when a trajectory, SRDF or package path is given (robots only).
[[nodiscard]] LoadedModel load_frame_sequence_model(
    const std::filesystem::path& spec,
    const LoadOptions& options);

}  // namespace skelcd::skinning
