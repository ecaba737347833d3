#pragma once
// Building blocks shared by the generators (internal to skinning/generators*.cpp): a mesh
// builder, bone chains with smooth blend weights, clips of joint rotations, sizing helpers.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include "skinning/generators.hpp"
#include "skinning/rig.hpp"

namespace skelcd::skinning::generators {

/// Triangles added counter-clockwise as seen from the side their normal points to.
struct MeshBuilder {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;

  std::int32_t add(const Eigen::Vector3d& p) {
    vertices.push_back(p);
    return static_cast<std::int32_t>(vertices.size() - 1);
  }
  void tri(std::int32_t a, std::int32_t b, std::int32_t c) { triangles.push_back({a, b, c}); }
  /// The quad a b c d (in order around it) as (a, b, c) and (a, c, d).
  void quad(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    tri(a, b, c);
    tri(a, c, d);
  }
};

/// Skeleton and weights under construction. Every node is a bone.
class RigBuilder {
 public:
  /// Adds a node (and its bone) with static transform `rest_local` relative to `parent`.
  std::int32_t add_node(const std::string& name, std::int32_t parent, const Eigen::Affine3d& rest_local);
  /// Rest global transform of a node (object space).
  [[nodiscard]] const Eigen::Affine3d& rest_global(std::int32_t node) const {
    return rest_global_[static_cast<std::size_t>(node)];
  }
  /// Adds weight `w` of vertex `v` on bone (= node) `node`.
  void weight(std::int32_t v, std::int32_t node, double w) {
    if (w > 0) triplets_.emplace_back(v, node, w);
  }
  /// Sets each bone's rest segment (head at its node, tail at its first child or `tail_length`
  /// along its x axis), inverse bind matrices, and assembles the Rig.
  [[nodiscard]] Rig finish(MeshBuilder&& mesh, const std::string& part_name, Clip&& clip, const std::string& source);

  [[nodiscard]] const Skeleton& skeleton() const { return skeleton_; }

 private:
  Skeleton skeleton_;
  std::vector<Eigen::Affine3d> rest_global_;
  std::vector<Eigen::Triplet<double>> triplets_;
};

/// A chain of bones along a straight line: joint j at arc length joint_s[j] (joint_s[0] = 0 is
/// the chain's root), bone j from joint j to joint j + 1 (the last to `length`).
struct Chain {
  std::vector<double> joint_s;
  double length = 0.0;
  std::vector<std::int32_t> nodes;  ///< node of bone j
};

/// Smooth blend weights at arc length s: rigid on bone j away from its joints; around joint j
/// (j >= 1) bones j − 1 and j blend with a C1 smoothstep over [joint_s[j] − h, joint_s[j] + h],
/// h = blend × (the shorter adjacent bone) / 2. Returns (bone index in the chain, weight) pairs.
[[nodiscard]] std::vector<std::pair<std::int32_t, double>> chain_weights(
    const Chain& chain,
    double s,
    double blend);

/// Adds a chain of nodes to `builder`: the root node at `root_local` relative to `parent`, then
/// one node per further joint, translated along the local x axis. Names are prefix + index.
Chain add_chain(
    RigBuilder& builder,
    const std::string& prefix,
    std::int32_t parent,
    const Eigen::Affine3d& root_local,
    std::vector<double> joint_s,
    double length);

/// A clip of `frames` keys at kGeneratorFrameRateHz: node k of `nodes` turns about its local
/// `axes[k]` by angle(k, tau) at tau = i / (frames − 1) (its translation stays at rest).
[[nodiscard]] Clip rotation_clip(
    const std::string& name,
    const RigBuilder& builder,
    const std::vector<std::int32_t>& nodes,
    const std::vector<Eigen::Vector3d>& axes,
    int frames,
    const std::function<double(std::size_t, double)>& angle);

/// #frames posed positions of the rig's clip 0 at its key times (pose evaluation + linear blend
/// skinning, as RigMotion does), for the known answers.
void posed_frames(const Rig& rig, int frames, const std::function<void(int, const Positions&)>& visit);

/// Fills last_free_frame / first_intersecting_frame from per-frame margins: a frame is decided
/// free when its margin < −tolerance and intersecting when > +tolerance.
void decide(KnownAnswer& answer, double tolerance);

/// Smallest integer >= 1 nearest to x.
[[nodiscard]] std::int64_t round_at_least(double x, std::int64_t lo);

}  // namespace skelcd::skinning::generators
