#pragma once
// Continuous orientation classes (paper 002, §3.1): a triangle whose vertices move linearly over
// t in [0,1] is positively oriented to its observer (H⁺) when the observer stays behind it for
// the whole interval, negatively oriented (H⁻) when it stays in front, uncertain (Hᵘ) otherwise.
// Decided with the conservative Bernstein sign of ccd/: H⁺ and H⁻ are proven, Hᵘ is the safe
// answer. docs/radial-view.md says why these classes let the intra-cluster check skip pairs, and
// how a line observer is handled so that the argument still holds.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string_view>

#include "ccd/coplanarity_screen.hpp"

namespace skelcd::clustering {

/// H⁺, H⁻, Hᵘ. The values are bit positions of a class mask (culling/cluster_checks.hpp).
enum class OrientationClass : std::uint8_t {
  positive = 0,   ///< H⁺: f(t) > 0 on all of [0,1], proven
  negative = 1,   ///< H⁻: f(t) < 0 on all of [0,1], proven
  uncertain = 2,  ///< Hᵘ: neither proven
};

[[nodiscard]] std::string_view to_string(OrientationClass c);

/// A triangle (a, b, c), counter-clockwise seen from outside, each corner moving linearly.
struct MovingTriangle {
  Eigen::Vector3d a_t0, b_t0, c_t0;  ///< at t = 0
  Eigen::Vector3d a_t1, b_t1, c_t1;  ///< at t = 1
};

/// An observer point moving linearly from `t0` to `t1`.
struct MovingPoint {
  Eigen::Vector3d t0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d t1 = Eigen::Vector3d::Zero();
};

/// An observer segment q1 q2 whose endpoints move linearly (they may move differently: a bone
/// that rotates within the interval).
struct MovingSegment {
  Eigen::Vector3d q1_t0 = Eigen::Vector3d::Zero(), q2_t0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d q1_t1 = Eigen::Vector3d::Zero(), q2_t1 = Eigen::Vector3d::Zero();
};

/// Class of `triangle` seen from a moving point: the sign over [0,1] of the cubic
/// f(t) = (a(t) − q(t)) · n(t), n = (b − a) × (c − a).
/// @note positive/negative are never wrong (any finite input); non-finite input is uncertain.
[[nodiscard]] OrientationClass classify(const MovingTriangle& triangle, const MovingPoint& observer);

/// classify(triangle k, observer) for four triangles at once where the screen of their cubics
/// settles them: bit k of `settled` set, classes[k] what classify gives. The cubics are the
/// vertex-face coplanarity cubics of (observer; a, b, c) screened four to a vector
/// (ccd::vertex_face_screen_x4): their first difference is q − a where classify's is a − q, so each
/// is classify's cubic negated exactly — every product and sum flips its sign without changing
/// its magnitude — with the same error bound, and a settled lane is exactly a triangle whose
/// screen classify finds certain. Lanes not settled need classify itself.
/// @param corners_t0,corners_t1 triangle k's corners a, b, c at each end (three doubles each).
struct ScreenedClasses {
  unsigned settled = 0;
  std::array<OrientationClass, 4> classes{};
};
[[nodiscard]] ScreenedClasses screen_classes_x4(
    const ccd::FaceCorners& corners_t0,
    const ccd::FaceCorners& corners_t1,
    const MovingPoint& observer);

/// classify(triangle k, observer) for a segment observer, four triangles at once, where the
/// screens of both endpoints' cubics (as screen_classes_x4 screens a point's) settle them with
/// one and the same sign — classify's answer then, from its own two screens. Lanes not settled
/// need classify itself.
[[nodiscard]] ScreenedClasses screen_classes_x4(
    const ccd::FaceCorners& corners_t0,
    const ccd::FaceCorners& corners_t1,
    const MovingSegment& observer);

/// Class of `triangle` seen from a moving segment, each point x of the triangle viewed from its
/// nearest point c(x) on the segment (the vertex projected onto the bone and clamped, §4.2):
/// positive when h(x, t) = (x − c(x)) · n(t) > 0 for every x of the triangle and every t in [0,1].
/// Decided without assuming anything of the endpoints' relative motion: with σ(x) ∈ [0,1] the
/// clamped projection parameter, h = (1 − σ)·f₁ + σ·f₂ where f₁, f₂ are the cubics of the two
/// endpoints, so the class is proven from f₁ and f₂ alone when they agree, and otherwise from the
/// two cubics at the ends of a proven enclosure [σ_lo, σ_hi] of σ over the triangle and the
/// interval (docs/radial-view.md, "Line observers").
/// @note positive/negative are never wrong; a segment whose length may vanish within the interval
///       falls back to the enclosure [0, 1] (positive only if positive for both endpoints).
[[nodiscard]] OrientationClass classify(
    const MovingTriangle& triangle,
    const MovingSegment& observer);

/// The enclosure [lo, hi] ⊆ [0,1] of the clamped projection parameter of the corners of
/// `triangle` onto the segment, over t in [0,1], with rounding accounted for (lo rounded down,
/// hi rounded up). Exposed for tests.
struct ProjectionRange {
  double lo = 0.0;
  double hi = 1.0;
};
[[nodiscard]] ProjectionRange projection_range(
    const MovingTriangle& triangle,
    const MovingSegment& observer);

}  // namespace skelcd::clustering
