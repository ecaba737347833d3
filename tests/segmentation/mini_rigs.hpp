#pragma once
// Procedural meshes and rigs with known answers for the segmentation tests: a closed tube around a
// chain of bones (the "capsule chain"), an icosphere, a flat grid, a cube.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "skinning/rig.hpp"

namespace skelcd::test {

struct MeshData {
  skinning::Positions V;
  skinning::Triangles F;
};

inline MeshData from_lists(const std::vector<Eigen::Vector3d>& vs,
                           const std::vector<Eigen::Vector3i>& fs) {
  MeshData m;
  m.V.resize(static_cast<Eigen::Index>(vs.size()), 3);
  m.F.resize(static_cast<Eigen::Index>(fs.size()), 3);
  for (std::size_t i = 0; i < vs.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = vs[i];
  for (std::size_t i = 0; i < fs.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) = fs[i];
  return m;
}

/// A closed tube along +x from x = 0 to x = length, `sides` vertices per ring, rings every
/// length / segments, closed by a fan at each end whose apex is `cap` beyond the end.
/// Outward-facing (counter-clockwise seen from outside).
inline MeshData closed_tube(double length, double radius, int segments, int sides, double cap,
                            const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  std::vector<Eigen::Vector3d> vs;
  std::vector<Eigen::Vector3i> fs;
  for (int r = 0; r <= segments; ++r) {
    const double x = length * r / segments;
    for (int s = 0; s < sides; ++s) {
      const double a = 2.0 * std::numbers::pi * s / sides;
      vs.push_back(offset + Eigen::Vector3d(x, radius * std::cos(a), radius * std::sin(a)));
    }
  }
  const auto ring = [&](int r, int s) { return r * sides + ((s % sides) + sides) % sides; };
  for (int r = 0; r < segments; ++r) {
    for (int s = 0; s < sides; ++s) {
      // Seen from outside (+radial), going around +angle and along +x: (r,s) → (r,s+1) is +angle.
      fs.emplace_back(ring(r, s), ring(r, s + 1), ring(r + 1, s + 1));
      fs.emplace_back(ring(r, s), ring(r + 1, s + 1), ring(r + 1, s));
    }
  }
  const int start = static_cast<int>(vs.size());
  vs.push_back(offset + Eigen::Vector3d(-cap, 0, 0));
  vs.push_back(offset + Eigen::Vector3d(length + cap, 0, 0));
  for (int s = 0; s < sides; ++s) {
    fs.emplace_back(start, ring(0, s + 1), ring(0, s));
    fs.emplace_back(start + 1, ring(segments, s), ring(segments, s + 1));
  }
  return from_lists(vs, fs);
}

/// Appends mesh b to mesh a (indices shifted).
inline MeshData concat(const MeshData& a, const MeshData& b) {
  MeshData m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + static_cast<std::int32_t>(a.V.rows())).matrix();
  return m;
}

/// Unit icosahedron subdivided `levels` times, projected on the sphere of `radius`.
inline MeshData icosphere(int levels, double radius = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> vs = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0},
                                     {0, -1, t}, {0, 1, t},  {0, -1, -t}, {0, 1, -t},
                                     {t, 0, -1}, {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> fs = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                     {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                     {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                     {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& v : vs) v.normalize();
  for (int l = 0; l < levels; ++l) {
    std::vector<Eigen::Vector3i> next;
    std::vector<std::pair<std::pair<int, int>, int>> mids;
    const auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      for (const auto& m : mids) {
        if (m.first == key) return m.second;
      }
      vs.push_back((vs[static_cast<std::size_t>(a)] + vs[static_cast<std::size_t>(b)]).normalized());
      mids.emplace_back(key, static_cast<int>(vs.size()) - 1);
      return static_cast<int>(vs.size()) - 1;
    };
    for (const auto& f : fs) {
      const int a = mid(f[0], f[1]), b = mid(f[1], f[2]), c = mid(f[2], f[0]);
      next.emplace_back(f[0], a, c);
      next.emplace_back(f[1], b, a);
      next.emplace_back(f[2], c, b);
      next.emplace_back(a, b, c);
    }
    fs = std::move(next);
  }
  for (auto& v : vs) v *= radius;
  return from_lists(vs, fs);
}

/// A flat n × n grid of unit squares in the z = 0 plane, each split in two triangles (normal +z).
/// Interior vertices are displaced in-plane by a fixed pseudo-random pattern when `jitter` > 0.
inline MeshData flat_grid(int n, double jitter = 0.0) {
  std::vector<Eigen::Vector3d> vs;
  std::vector<Eigen::Vector3i> fs;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      Eigen::Vector3d p(i, j, 0);
      if (jitter > 0 && i > 0 && j > 0 && i < n && j < n) {
        p.x() += jitter * std::sin(12.9898 * i + 78.233 * j);
        p.y() += jitter * std::cos(39.3468 * i + 11.135 * j);
      }
      vs.push_back(p);
    }
  }
  const auto id = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      fs.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      fs.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  }
  return from_lists(vs, fs);
}

/// A rig: a closed tube of `bones` × `rings_per_bone` segments along +x, bone k from x = k ℓ to
/// (k+1) ℓ (a chain: bone k's parent is k−1), each vertex weighted fully to the bone whose span
/// holds it (caps to the end bones) — the "artist" weights for `--weights rig`.
inline skinning::Rig capsule_chain(int bones, double bone_length = 1.0, double radius = 0.25,
                                   int rings_per_bone = 6, int sides = 16) {
  skinning::Rig rig;
  rig.source = "capsule_chain(" + std::to_string(bones) + ")";
  const auto tube = closed_tube(bones * bone_length, radius, bones * rings_per_bone, sides,
                                0.5 * radius);
  rig.mesh.rest_positions = tube.V;
  rig.mesh.triangles = tube.F;
  const auto nv = tube.V.rows();
  const auto nf = tube.F.rows();
  rig.mesh.face_part.assign(static_cast<std::size_t>(nf), 0);
  rig.mesh.face_index_in_part.resize(static_cast<std::size_t>(nf));
  for (std::int32_t f = 0; f < nf; ++f) rig.mesh.face_index_in_part[static_cast<std::size_t>(f)] = f;
  rig.mesh.vertex_part.assign(static_cast<std::size_t>(nv), 0);
  rig.mesh.vertex_index_in_part.resize(static_cast<std::size_t>(nv));
  for (std::int32_t v = 0; v < nv; ++v) {
    rig.mesh.vertex_index_in_part[static_cast<std::size_t>(v)] = v;
  }
  rig.mesh.part_names = {"tube"};

  for (int b = 0; b < bones; ++b) {
    skinning::SkeletonNode node;
    node.name = "bone" + std::to_string(b);
    node.parent = b - 1;
    node.rest_local = Eigen::Translation3d(b == 0 ? 0.0 : bone_length, 0, 0);
    rig.skeleton.nodes.push_back(node);
    skinning::Bone bone;
    bone.name = node.name;
    bone.node = b;
    bone.parent = b - 1;
    bone.inverse_bind = Eigen::Translation3d(-b * bone_length, 0, 0);
    bone.rest_head = Eigen::Vector3d(b * bone_length, 0, 0);
    bone.rest_tail = Eigen::Vector3d((b + 1) * bone_length, 0, 0);
    rig.skeleton.bones.push_back(bone);
  }
  std::vector<Eigen::Triplet<double>> w;
  for (Eigen::Index v = 0; v < nv; ++v) {
    const double x = tube.V(v, 0);
    const int b = std::clamp(static_cast<int>(std::floor(x / bone_length)), 0, bones - 1);
    w.emplace_back(static_cast<int>(v), b, 1.0);
  }
  rig.weights.resize(nv, bones);
  rig.weights.setFromTriplets(w.begin(), w.end());
  return rig;
}

/// A capsule chain bent by `degrees` about z at every joint (alternating sign when `zigzag`),
/// each elbow smoothed over ±`blend` along the chain: a rope-like rig whose rest pose has concave
/// sides, so refinement and observer choice have work to do. Same weights as capsule_chain.
inline skinning::Rig bent_capsule_chain(int bones, double degrees, bool zigzag, double blend = 0.2,
                                        int rings_per_bone = 6, int sides = 16,
                                        double radius = 0.25) {
  skinning::Rig rig = capsule_chain(bones, 1.0, radius, rings_per_bone, sides);
  const double full = degrees * std::numbers::pi / 180.0;
  const auto angle = [&](int joint) { return (zigzag && joint % 2 == 0) ? -full : full; };
  // Forward kinematics in the straight frame: rotations about joints k = n−1 … 1, each by the
  // part of its angle that the point follows.
  const auto bend = [&](const Eigen::Vector3d& p, double x, bool rigid_tail) {
    Eigen::Vector3d q = p;
    for (int k = bones - 1; k >= 1; --k) {
      double s = std::clamp((x - (k - blend)) / (2.0 * blend), 0.0, 1.0);
      if (rigid_tail) s = x >= k ? 1.0 : 0.0;
      const double a = angle(k) * s * s * (3.0 - 2.0 * s);
      const Eigen::Vector3d J(k, 0, 0);
      q = J + Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) * (q - J);
    }
    return q;
  };
  for (Eigen::Index v = 0; v < rig.mesh.rest_positions.rows(); ++v) {
    const Eigen::Vector3d p = rig.mesh.rest_positions.row(v).transpose();
    rig.mesh.rest_positions.row(v) = bend(p, p.x(), false).transpose();
  }
  for (int b = 0; b < bones; ++b) {
    auto& bone = rig.skeleton.bones[static_cast<std::size_t>(b)];
    bone.rest_head = bend(Eigen::Vector3d(b, 0, 0), b, true);
    bone.rest_tail = bend(Eigen::Vector3d(b + 1, 0, 0), b + 0.5, true);
    bone.inverse_bind = Eigen::Translation3d(-bone.rest_head);  // translation-only bind frames
  }
  return rig;
}

}  // namespace skelcd::test
