#pragma once
// Vertex fans that cannot intersect themselves (issue 14, docs/culling.md "Vertex fans"): a DCD
// pair that shares a corner needs no triangle test when the fan of a shared vertex is certified
// at that instant.
//
// The fan of welded vertex v is certified when v is a manifold vertex (its triangles form one
// chain, consistently oriented, none degenerate: a cycle around a closed vertex, a path at a
// boundary vertex) and, in a projection onto a plane — first dropping the coordinate k where the
// fan's normal is largest, then, if that fails, along the fan's summed normal itself — (1) every
// triangle of the fan projects with the same strict orientation and (2) the projected sectors do
// not overlap: a closed fan winds exactly once around v (the ray from v through the first spoke
// lies in exactly one half-open sector), an open fan never comes back to that ray. Then the
// projection is injective on each triangle and the projected triangles only meet along the
// projected edges they share, so two triangles of the fan have no common point beyond their
// shared vertex or edge. Every sign comes from a static
// floating-point filter with a proven bound (ccd/orientation.hpp); a sign it cannot decide leaves
// the vertex uncertified, so the certificate is exact and costs no rational arithmetic.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::culling {

class VertexFans {
 public:
  VertexFans() = default;
  /// @param triangles welded corners of each triangle; @param num_vertices welded vertex count.
  VertexFans(std::span<const std::array<std::int32_t, 3>> triangles, std::int32_t num_vertices);

  /// The spokes of v's fan in order: triangle i is (v, spoke[i], spoke[i + 1]), oriented as in
  /// the mesh, wrapping around when closed(v) (m spokes for m triangles; m + 1 when open); empty
  /// when v is not a manifold vertex.
  [[nodiscard]] std::span<const std::int32_t> spokes(std::int32_t v) const {
    const auto i = static_cast<std::size_t>(v);
    return {spokes_.data() + offsets_[i], static_cast<std::size_t>(offsets_[i + 1] - offsets_[i])};
  }
  [[nodiscard]] bool closed(std::int32_t v) const {
    return closed_[static_cast<std::size_t>(v)] != 0;
  }
  /// Vertices with a fan (closed or open).
  [[nodiscard]] std::int32_t num_fans() const { return num_fans_; }

  /// Whether v's fan is certified at positions x (#W × 3 welded).
  [[nodiscard]] bool certified(const skinning::Positions& x, std::int32_t v) const;
  /// Every vertex's certificate at x, into out (resized to #W; 1 = certified): each closed fan
  /// first in the coordinate projection that certified() last chose for a vertex before it (a
  /// vertex's predecessors in a mesh are mostly neighbours, their normals along the same axis; no
  /// normal to sum), then as certified(x, v). Every projection is sound: out[v] is 1 wherever
  /// certified(x, v) is, and for a few fans more.
  void certify(const skinning::Positions& x, std::vector<std::uint8_t>& out) const;

  /// Whether v's fan is certified at every instant of the interval x_t0 → x_t1 (each vertex
  /// moving on a straight line): a closed fan, certified at x_t0 in some fixed projection, whose
  /// every triangle keeps its strict projected orientation throughout (docs/culling.md, "Vertex
  /// fans over an interval"). Then no two triangles of the fan meet beyond their shared vertex or
  /// edge at any instant, and no feature pair they own can come into contact.
  [[nodiscard]] bool certified_over(
      const skinning::Positions& x_t0, const skinning::Positions& x_t1, std::int32_t v) const;

 private:
  /// certified(x, v), a closed fan tried first in the coordinate projection that drops `axis`
  /// when axis < 3. When a normal is summed, `axis` becomes the axis along which it is largest
  /// (the projection certified() chose); else it is left as it was.
  bool certified(const skinning::Positions& x, std::int32_t v, std::size_t& axis) const;
  /// certified()'s second try for a closed fan of m ≥ 3 sectors: along its summed normal n, d its
  /// m spoke differences and d[m] = d[0].
  static bool closed_along_normal(
      std::span<const std::array<double, 3>> d, std::size_t m, const std::array<double, 3>& n);
  /// Conditions (1) and (2) of the certificate for the m triangles of a fan, given the sign of
  /// each projected spoke pair (orient(p, q) ∈ {−1, 1, kUndecided}; spoke m of a closed fan is
  /// spoke 0).
  template <class Orient>
  static bool winds_once(std::size_t m, bool closed, const Orient& orient);

  std::vector<std::int32_t> offsets_{0};
  std::vector<std::int32_t> spokes_;
  std::vector<std::uint8_t> closed_;
  std::int32_t num_fans_ = 0;
};

}  // namespace skelcd::culling
