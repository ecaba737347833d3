#pragma once
// Observer primitives (paper 002, §4.2): a cluster is watched from a point (its bone's midpoint)
// or from a line (its bone segment; each triangle is watched from its first corner projected onto
// the segment). A triangle is positively oriented to its observer when the observer sees its back:
// (p − q) · n > 0 with n the outward normal and p a corner.

#include <cstdint>
#include <span>
#include <string_view>

#include <Eigen/Core>

#include "segmentation/bone_segment.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::segmentation {

enum class ObserverKind : std::uint8_t { point = 0, line = 1 };

[[nodiscard]] std::string_view to_string(ObserverKind kind);

/// Orientation of a triangle to an observer at one instant. `uncertain` is the exact zero: the
/// observer lies in the triangle's plane (or the triangle has no area).
enum class Orientation : std::int8_t { negative = -1, uncertain = 0, positive = 1 };

struct Observer {
  ObserverKind kind = ObserverKind::point;
  /// The cluster's bone, rest pose, object space.
  BoneSegment segment;

  /// Where a triangle whose first corner is `a` is viewed from: the midpoint for a point
  /// observer; `a` projected onto the segment and clamped to it for a line observer (the head
  /// when the segment has zero length).
  [[nodiscard]] Eigen::Vector3d viewing_position(const Eigen::Vector3d& a) const {
    return kind == ObserverKind::point ? segment.midpoint() : segment.closest_point(a);
  }
};

/// Exact sign of (a − q) · ((b − a) × (c − a)) with q the viewing position for corner a
/// (a static floating-point filter, then ccd::orient3d — filtered, rational fallback — when it
/// cannot decide; exact for the rounded q).
[[nodiscard]] Orientation orientation(
    const Observer& observer,
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c);

/// Orientation of triangle f of (V, F) to `observer`.
[[nodiscard]] inline Orientation orientation(
    const Observer& observer,
    const skinning::Positions& V,
    const skinning::Triangles& F,
    Eigen::Index f) {
  return orientation(observer, V.row(F(f, 0)).transpose(), V.row(F(f, 1)).transpose(),
                     V.row(F(f, 2)).transpose());
}

struct ObserverChoice {
  ObserverKind kind = ObserverKind::point;
  /// Positively oriented triangles averaged over the test poses, for each candidate.
  double mean_positive_point = 0.0;
  double mean_positive_line = 0.0;
  /// Number of poses averaged: the rest pose and ±θ about x, y and z (7).
  int poses = 0;
};

/// Chooses the observer of a cluster (§4.2): the point if it keeps at least as many triangles
/// positively oriented on average as the line (ties go to the cheaper point), over the rest pose
/// and the bone rotated by ±θ about the world x, y and z axes around its head joint, else the
/// line.
/// In a test pose the bone and its descendants turn rigidly by R about the head q1, and each
/// vertex x of the cluster moves as linear blend skinning moves it: x' = q1 + (s R + (1 − s) I)
/// (x − q1), with s the vertex's summed weight on the bone's subtree (rotating the triangles and
/// the observer rigidly together would change no orientation at all).
/// @param V #W × 3 rest positions; @param F #F × 3; @param triangles the cluster's triangles.
/// @param W #W × #B weights; @param subtree the bone and its descendants (columns of W).
/// @param theta_rad rotation angle (radians).
[[nodiscard]] ObserverChoice choose_observer(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    std::span<const std::int32_t> triangles,
    const BoneSegment& bone,
    const Eigen::MatrixXd& W,
    std::span<const std::int32_t> subtree,
    double theta_rad);

/// For one triangle, how many of choose_observer's test poses leave it positively oriented to the
/// point observer and to the line observer (0 … 7 each).
struct PositiveCounts {
  std::uint8_t point = 0;
  std::uint8_t line = 0;
};

/// choose_observer's work per triangle: out[i] for triangles[i]. A triangle's counts depend on
/// the triangle and the bone alone (its corners' poses follow their own weights), not on the
/// cluster it is in, so a segmentation reuses them when a triangle is observed from the same bone
/// again. @param out as many entries as `triangles`.
void positive_counts(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    std::span<const std::int32_t> triangles,
    const BoneSegment& bone,
    const Eigen::MatrixXd& W,
    std::span<const std::int32_t> subtree,
    double theta_rad,
    std::span<PositiveCounts> out);

/// The choice from counts summed over a cluster's triangles: choose_observer's answer.
[[nodiscard]] ObserverChoice observer_choice(
    std::int64_t positive_point, std::int64_t positive_line);

}  // namespace skelcd::segmentation
