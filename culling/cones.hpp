#pragma once
// Cones of directions for the cone culling methods (normal-cone, dual-cone, enhanced-dual-cone):
// the surface normal cone (SNC) of every hierarchy node — of the static normals for DCD, of the
// continuous normal n(t) over an interval for CCD — and the binormal cone (BNC) of a set of
// vectors. A cone here is only ever used to prove "every bounded vector has a positive dot product
// with the axis", so a cone whose half-angle may reach π/2 is stored as `full` (useless), and every
// stored half-angle is an upper bound with its rounding errors accounted for (docs/dual-cone.md,
// "Cones").

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/feature_topology.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// A cone (axis, θ) with θ < π/2 that contains (as exact real vectors) every vector it bounds:
/// angle(x, axis) ≤ θ. `cos_angle` is a lower bound of cos θ (> 0), `sin_angle` an upper bound of
/// sin θ, both with rounding accounted for; `axis` is a unit vector to within 3 ulp.
struct DirectionCone {
  enum class Kind : std::uint8_t {
    empty,    ///< bounds no vector (e.g. the BNC of a node without boundary edges)
    bounded,  ///< bounds its vectors within θ < π/2
    full,     ///< may bound vectors at π/2 or more from any axis: proves nothing
  };
  Kind kind = Kind::empty;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double cos_angle = 1.0;
  double sin_angle = 0.0;

  [[nodiscard]] static DirectionCone empty_cone() { return {}; }
  [[nodiscard]] static DirectionCone full_cone() {
    DirectionCone c;
    c.kind = Kind::full;
    c.cos_angle = -1.0;
    c.sin_angle = 1.0;
    return c;
  }
  [[nodiscard]] bool is_empty() const { return kind == Kind::empty; }
  [[nodiscard]] bool is_full() const { return kind == Kind::full; }
  /// True when every bounded vector x has x · axis > 0 (the surface normal test, §3.3). Holds
  /// for every bounded cone (θ < π/2 by construction).
  [[nodiscard]] bool in_open_half_space() const { return kind == Kind::bounded; }
  /// The half-angle in radians (an upper bound; π/2 for full, 0 for empty). For reports.
  [[nodiscard]] double angle() const;
  /// True when the exact vector `x` (non-zero) lies inside: x · axis ≥ |x| cos θ, evaluated with
  /// a tolerance of a few ulp in the cone's favour. For tests and assertions.
  [[nodiscard]] bool contains(const Eigen::Vector3d& x) const;
};

/// The cone of one vector: the exact vector lies within Euclidean distance `error` of `v`.
/// Full when that ball may reach 30° from v (a nearly degenerate normal): the culling tests then
/// fail at every node holding it, which is the safe side.
[[nodiscard]] DirectionCone cone_of_vector(const Eigen::Vector3d& v, double error);

/// The smallest cone around the given unit `axis` that contains cones a and b (either may be
/// empty), conservative: cos(θ_a + ∠(axis, a.axis)) bounded from below, etc. Full when that
/// half-angle may reach π/2.
[[nodiscard]] DirectionCone enclose_around(
    const Eigen::Vector3d& axis, const DirectionCone& a, const DirectionCone& b);

/// A cone containing a and b with a near-optimal axis (the minimal enclosing cone of two cones:
/// half-angle (α + θ_a + θ_b)/2), then made conservative by enclose_around.
[[nodiscard]] DirectionCone merge(const DirectionCone& a, const DirectionCone& b);

/// Unit vector along v (v / |v|), or zero when |v| is zero or not finite.
[[nodiscard]] Eigen::Vector3d unit_or_zero(const Eigen::Vector3d& v);

/// Normal n = (b − a) × (c − a) of a triangle computed in floating point from the corner
/// positions, and a bound on the Euclidean distance to the exact normal (docs/dual-cone.md).
struct BoundedNormal {
  Eigen::Vector3d n;
  double error = 0.0;
};
[[nodiscard]] BoundedNormal triangle_normal(
    const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// The Bernstein control vectors of the continuous normal n(t) of a triangle whose corners move
/// linearly over [0,1]: n(t) = B0 (1−t)² + B1 2t(1−t) + B2 t², each with its error bound. Since
/// the Bernstein basis is non-negative, n(t) lies in the conic hull of B0, B1, B2 — inside any
/// cone with θ < π/2 that contains them.
[[nodiscard]] std::array<BoundedNormal, 3> continuous_normal_control_vectors(
    const Eigen::Vector3d& a_t0,
    const Eigen::Vector3d& b_t0,
    const Eigen::Vector3d& c_t0,
    const Eigen::Vector3d& a_t1,
    const Eigen::Vector3d& b_t1,
    const Eigen::Vector3d& c_t1);

/// FASTCD's binormal cone of the boundary sides of one triangle (corners p, moving linearly from
/// p_t0 to p_t1): b = n × e for each side k whose bit is set in `sides` (side k runs from corner k
/// to corner k+1, e its vector, n the triangle's normal); over an interval the Bernstein control
/// vectors of the cubic n(t) × e(t). Plain floating point: the `dual-cone` baseline is approximate
/// by design. Empty when no bit is set.
[[nodiscard]] DirectionCone boundary_binormal_cone(
    const std::array<Eigen::Vector3d, 3>& p_t0,
    const std::array<Eigen::Vector3d, 3>& p_t1,
    std::uint8_t sides,
    bool continuous);

/// Surface normal cones of every node of a hierarchy over the welded triangles, refit bottom-up
/// per instant (static normals, DCD) or per interval (continuous normals, CCD). A node's cone
/// contains the (continuous) normal of each of its triangles; a parent's axis is its triangles'
/// mean normal, or the optimal merge axis of its children when that gives a smaller cone.
class NormalConeTree {
 public:
  /// Static normals at positions x (#W × 3). Allocation-free after the first call.
  /// @note The tree keeps references to `topology` and `x` (no copy of any normal): they must
  /// outlive the queries below until the next refit.
  void refit(const AabbBvh& bvh, const FeatureTopology& topology, const skinning::Positions& x);
  /// Continuous normals over x_t0 → x_t1 (#W × 3 each). Allocation-free after the first call.
  /// @note As above: `topology`, `x_t0` and `x_t1` must outlive the queries until the next refit.
  void refit(
      const AabbBvh& bvh,
      const FeatureTopology& topology,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1);

  /// The node's mean normal direction (unit; zero when its normals cancel): the sum of its
  /// triangles' normals (of their control vectors for CCD), i.e. area-weighted.
  /// @param bvh the hierarchy of the last refit (a leaf's is summed from its triangles).
  [[nodiscard]] Eigen::Vector3d mean_normal(const AabbBvh& bvh, std::int32_t node) const;
  /// True when every normal of the node's triangles (every Bernstein control vector for CCD) is
  /// proven to have a positive dot product with `v`: the surface normal test done triangle by
  /// triangle, for a node whose hierarchical cone is too loose. Stops at the first failure.
  [[nodiscard]] bool normals_in_half_space(
      const AabbBvh& bvh, std::int32_t node, const Eigen::Vector3d& v) const;

  /// The cone of a node of the hierarchy of the last refit (node ids of AabbBvh::nodes()): it
  /// contains the (continuous) normal of each of the node's triangles.
  /// @note Only the cones of nodes with an internal child are stored; a leaf's, or a node's whose
  /// children are leaves, is formed from its triangles' normals by the same code the refit merges
  /// it with (so it is the cone the refit used).
  [[nodiscard]] DirectionCone node_cone(const AabbBvh& bvh, std::int32_t node) const;

 private:
  void refit_nodes(const AabbBvh& bvh);
  /// Triangle f's normal ([0], static) or its three Bernstein control vectors (continuous), at
  /// the last refit's positions: formed when needed, never stored (bounded memory).
  [[nodiscard]] std::array<BoundedNormal, 3> triangle_normals(std::int32_t f) const;
  /// The cone and the normal sum of triangle f (of its control vectors for CCD).
  [[nodiscard]] DirectionCone triangle_cone(const std::array<BoundedNormal, 3>& normals) const;
  [[nodiscard]] Eigen::Vector3d triangle_sum(const std::array<BoundedNormal, 3>& normals) const;
  /// A leaf's cone and normal sum.
  void leaf_cone(
      const AabbBvh& bvh, std::int32_t leaf, DirectionCone& cone, Eigen::Vector3d& sum) const;
  /// The cone and sum of a node without a record (a leaf, or a node whose children are leaves).
  void unstored_cone(
      const AabbBvh& bvh, std::int32_t node, DirectionCone& cone, Eigen::Vector3d& sum) const;
  /// A parent's cone and sum from its two children's.
  static void combine(
      const std::array<DirectionCone, 2>& cones,
      const std::array<Eigen::Vector3d, 2>& sums,
      DirectionCone& cone,
      Eigen::Vector3d& sum);

  // The last refit's triangles and positions (x_t1_ null for static normals): the normals are
  // formed from them, by the same functions the refit used, whenever a query needs them.
  const FeatureTopology* topology_ = nullptr;
  const skinning::Positions* x_t0_ = nullptr;
  const skinning::Positions* x_t1_ = nullptr;
  int vectors_per_triangle_ = 1;
  // Per node, the index of its record (-1 for a leaf or a node whose children are both leaves:
  // theirs are formed from their triangles when needed), and per record the node's cone and the
  // sum of its triangles' normals.
  std::vector<std::int32_t> internal_index_;
  std::vector<DirectionCone> node_cones_;
  std::vector<Eigen::Vector3d> node_sums_;
};

}  // namespace skelcd::culling
