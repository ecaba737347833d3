#pragma once
// Procedural rigs with known answers: a coiling rope, an octopus and a hand whose limbs bend into
// each other, a folding pipe and cloth (open boundaries), and the Panda reaching for its base.
// Any size from about 1k to 200k triangles, deterministic, each with a clip and the frames where
// self-intersection is known to be absent and present. Usable wherever a MODEL is taken, as a
// spec string `gen:NAME?triangles=N&frames=N`.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "skinning/rig.hpp"

namespace skelcd::skinning {

struct LoadedModel;
struct LoadOptions;

/// What a generator makes, for `skelcd generate --list`.
struct GeneratorInfo {
  std::string name;
  std::string description;
  std::int64_t default_triangles = 0;  ///< 0 for a fixed-size rig (panda)
  int default_frames = 0;
  bool closed = false;                 ///< every part closed (no boundary edge)
  std::string known_answer;            ///< the rule that decides which frames intersect
};

/// The generators, in the order `--list` shows them.
[[nodiscard]] const std::vector<GeneratorInfo>& generator_list();

struct GeneratorSpec {
  std::string name;
  std::int64_t triangles = 0;  ///< requested triangle count; 0 = the generator's default
  int frames = 0;              ///< number of frames (samples) of the clip; 0 = default
};

/// True when `model` starts with "gen:".
[[nodiscard]] bool is_generator_spec(std::string_view model);

/// Parses `gen:NAME[?triangles=N][&frames=N]`.
/// @throws InvalidInput naming the spec for an unknown generator or parameter, a value that is
///   not a positive integer, triangles outside [100, 5'000'000], frames outside [2, 100'000], or
///   triangles given to a fixed-size generator.
[[nodiscard]] GeneratorSpec parse_generator_spec(std::string_view spec);

/// The canonical spec string of `spec` with defaults filled in, e.g. "gen:rope?triangles=48000&frames=60".
[[nodiscard]] std::string to_string(const GeneratorSpec& spec);

/// Frames where a vertex-disjoint pair of triangles is known not to intersect / to intersect.
/// Frames 0 … last_free_frame have no intersecting pair of triangles (pairs sharing a vertex
/// included: they intersect only if they overlap beyond the shared vertex or edge); frames
/// first_intersecting_frame … #frames − 1 have at least one. Frames in between (none at the
/// default sizes) are not decided by the rule.
struct KnownAnswer {
  int last_free_frame = -1;
  int first_intersecting_frame = -1;
  /// The rule and the quantity it measured, in one sentence.
  std::string rule;
  /// Per frame: the signed measure the rule thresholds at 0 (negative: free, positive:
  /// intersecting), in the rig's length unit.
  std::vector<double> margin;
};

struct GeneratedRig {
  Rig rig;  ///< mesh + skeleton + weights + one clip, sampled at 30 Hz: frame i at i / 30 s
  KnownAnswer answer;
  GeneratorSpec spec;  ///< with defaults filled in
};

/// Frame rate of every generated clip (keys per second).
inline constexpr double kGeneratorFrameRateHz = 30.0;

/// Runs the generator `spec` names. Deterministic: the same spec gives the same rig, bit for bit.
/// @throws InvalidInput as parse_generator_spec; IoError when the panda's bundled URDF is missing.
[[nodiscard]] GeneratedRig generate(const GeneratorSpec& spec);

/// The load_model() entry point for `gen:` specs: the generated rig as a LoadedModel
/// (ModelKind::rig, path = the canonical spec).
/// @throws InvalidInput when a trajectory, SRDF or package path is given.
[[nodiscard]] LoadedModel load_generated_model(std::string_view spec, const LoadOptions& options);

}  // namespace skelcd::skinning
