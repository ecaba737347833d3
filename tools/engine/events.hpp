#pragma once
// What the animation causes: every finding of a check is labelled against a baseline (what the
// rig already had, e.g. at its rest pose) and the user's allowances, and the new findings are
// grouped into collision events tracked over consecutive samples (docs/events.md).

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "skinning/mesh.hpp"
#include "skinning/motion.hpp"
#include "skinning/rig.hpp"
#include "skinning/topology.hpp"
#include "tools/io/event_record.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::culling {
class FeatureTopology;
class HierarchyCache;
}  // namespace skelcd::culling

namespace skelcd::tools {

/// What a check compares its findings with (`--baseline`, a scene's `baseline` key).
struct BaselineSpec {
  enum class Kind : std::uint8_t {
    rest,    ///< the rig's rest (bind) pose; a frame sequence's rest mesh
    sample,  ///< the clip's sample `sample`
    none,    ///< nothing: every finding is new
    log,     ///< every finding of a log of this model (`log_path`)
  };
  Kind kind = Kind::rest;
  std::int32_t sample = 0;
  std::string log_path;
};

/// "rest" | "sample:K" | "none" | a path ending in .h5 → BaselineSpec.
/// @throws InvalidInput quoting `text` when it is none of these.
[[nodiscard]] BaselineSpec parse_baseline(std::string_view text);
/// "rest pose", "sample 12", "none", "log PATH" — the log header's `baseline`.
[[nodiscard]] std::string describe(const BaselineSpec& baseline);

/// Default rings of triangles (over shared vertices) a baseline region may slide by.
inline constexpr std::int32_t kDefaultBaselineSlack = 2;

/// Pairs of parts or bones whose findings are allowed (counted apart, never new).
struct Allowances {
  /// "A:B": names of parts or bones (a robot's links), either order; "A:A" allows A with itself.
  std::vector<std::string> rules;
  /// Pairs of triangles driven by the same bone or by a bone and its parent.
  bool adjacent_bones = false;
};

/// The baseline's findings in the mesh's own triangle ids (Mesh::triangles rows): intersecting
/// pairs, and for a log baseline also the triangles its CCD contacts touch (each contact as a pair
/// of triangles).
struct BaselineFindings {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
};

/// Labels every finding of a run (FrameReport rows in run order) against the baseline and the
/// allowances and groups the new ones into events (docs/events.md). Rows go in through push()
/// and come out labelled, in the same order; a CCD row is held until the DCD row of the sample
/// that ends its interval has arrived (both belong to the same step of the event tracking), in a
/// run that has DCD rows.
class EventTracker {
 public:
  /// Posed file positions of a sample (for the depth measure).
  using PositionsAt = std::function<void(std::int32_t sample, skinning::Positions& out)>;

  /// Whether the run has DCD rows. Without them (`--query ccd`) a CCD row has nothing to wait
  /// for and comes out labelled at once: the same labels as when it was held until the next row
  /// (it is labelled without a DCD row either way, and in the same order), but the run no longer
  /// holds two intervals' findings at a time.
  enum class DcdRows : std::uint8_t { expected, none };

  /// `rig` may be null (no bones: a frame sequence). `mesh`, `topology` and `rig` must outlive
  /// the tracker. @throws InvalidInput for an allowance naming neither a part nor a bone.
  EventTracker(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const skinning::Rig* rig,
      const BaselineFindings& baseline,
      const Allowances& allowances,
      std::int32_t baseline_slack,
      PositionsAt positions_at,
      DcdRows dcd_rows = DcdRows::expected);
  ~EventTracker();
  EventTracker(const EventTracker&) = delete;
  EventTracker& operator=(const EventTracker&) = delete;

  /// Takes the next row of the run; returns the rows now labelled (possibly none), in order.
  [[nodiscard]] std::vector<FrameReport> push(FrameReport report);
  /// Ends the run: returns any rows still held, labelled.
  [[nodiscard]] std::vector<FrameReport> flush();

  /// The events so far (complete after flush()), by id.
  [[nodiscard]] const std::vector<EventRecord>& events() const;
  /// The name of the bone (node, link) driving triangle f, "" when none.
  [[nodiscard]] const std::string& triangle_bone(std::int32_t f) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  DcdRows dcd_rows_;
};

/// The baseline findings a spec asks for, from DCD at the baseline's pose or from a log.
/// `positions_at` poses a sample of the clip; `dcd` returns the intersecting pairs (mesh triangle
/// ids) at file positions.
/// @throws InvalidInput naming the log when it is not of this model (triangles, parts differ),
///         or a sample outside the clip.
[[nodiscard]] BaselineFindings baseline_findings(
    const BaselineSpec& spec,
    const skinning::Mesh& mesh,
    std::int32_t num_samples,
    const EventTracker::PositionsAt& positions_at,
    const std::function<
        std::vector<std::pair<std::int32_t, std::int32_t>>(const skinning::Positions&)>& dcd);

/// The baseline findings of `spec` for `motion`: DCD (`bvh`, exact) at the rest pose or at a
/// sample of the motion, nothing for none, a log's findings. `topology` is the motion mesh's;
/// `features`, when given and built from the two (culling::FeatureTopology::built_from), is the
/// `bvh`'s instead of one of its own (a serial check shares it with its runner). `hierarchies`,
/// when given, is where the `bvh` takes its hierarchy from (a parallel check's runner builds
/// the same one beside it: culling::HierarchyCache).
/// @throws as above.
[[nodiscard]] BaselineFindings baseline_findings(
    const BaselineSpec& spec,
    const skinning::Motion& motion,
    const skinning::Topology& topology,
    std::shared_ptr<const culling::FeatureTopology> features = {},
    std::shared_ptr<culling::HierarchyCache> hierarchies = {});

/// Length of the segment along which triangles (p0, p1, p2) and (q0, q1, q2) intersect (0 when
/// they do not, or are coplanar): the depth measure of an event.
[[nodiscard]] double intersection_length(
    const Eigen::Vector3d& p0,
    const Eigen::Vector3d& p1,
    const Eigen::Vector3d& p2,
    const Eigen::Vector3d& q0,
    const Eigen::Vector3d& q1,
    const Eigen::Vector3d& q2);

}  // namespace skelcd::tools
