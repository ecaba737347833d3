// The whole segmentation on generated rigs with known geometry and on real characters: every
// triangle in exactly one edge-connected cluster, segments on their own bones, refinement never
// worse, determinism, both weight sources, bad input.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>
#include <set>
#include <stdexcept>
#include <tuple>

#include "segmentation/atomic_clusters.hpp"
#include "segmentation/face_graph.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/segmentation/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace {

using namespace skelcd::segmentation;
using skelcd::skinning::Rig;

// Checks the structural invariants of a segmentation of `rig`; returns a failure message.
::testing::AssertionResult well_formed(const Rig& rig, const Segmentation& seg) {
  const auto nf = rig.mesh.num_triangles();
  if (static_cast<std::int64_t>(seg.triangle_cluster.size()) != nf) {
    return ::testing::AssertionFailure() << "triangle_cluster has " << seg.triangle_cluster.size()
                                         << " entries for " << nf << " triangles";
  }
  // Exactly one cluster per triangle, and the cluster lists agree with triangle_cluster.
  std::vector<int> seen(static_cast<std::size_t>(nf), 0);
  for (std::size_t c = 0; c < seg.clusters.size(); ++c) {
    const auto& cl = seg.clusters[c];
    if (cl.triangles.empty()) return ::testing::AssertionFailure() << "cluster " << c << " empty";
    if (cl.bone < 0 || cl.bone >= rig.skeleton.num_bones()) {
      return ::testing::AssertionFailure() << "cluster " << c << " has bone " << cl.bone;
    }
    if (!std::is_sorted(cl.triangles.begin(), cl.triangles.end())) {
      return ::testing::AssertionFailure() << "cluster " << c << " triangles not sorted";
    }
    for (const auto f : cl.triangles) {
      ++seen[static_cast<std::size_t>(f)];
      if (seg.triangle_cluster[static_cast<std::size_t>(f)] != static_cast<std::int32_t>(c)) {
        return ::testing::AssertionFailure() << "triangle " << f << " listed in " << c;
      }
    }
  }
  for (std::int64_t f = 0; f < nf; ++f) {
    if (seen[static_cast<std::size_t>(f)] != 1) {
      return ::testing::AssertionFailure() << "triangle " << f << " in " << seen[static_cast<std::size_t>(f)]
                                           << " clusters";
    }
  }
  // Each cluster edge-connected (on the welded mesh).
  const auto topo = skelcd::skinning::build_topology(rig.mesh);
  const auto graph = face_graph(topo.welded_triangles);
  for (std::size_t c = 0; c < seg.clusters.size(); ++c) {
    const auto& tris = seg.clusters[c].triangles;
    std::set<std::int32_t> reached = {tris.front()};
    std::vector<std::int32_t> stack = {tris.front()};
    while (!stack.empty()) {
      const auto f = stack.back();
      stack.pop_back();
      for (auto k = graph.offsets[static_cast<std::size_t>(f)];
           k < graph.offsets[static_cast<std::size_t>(f) + 1]; ++k) {
        const auto g = graph.neighbours[static_cast<std::size_t>(k)];
        if (seg.triangle_cluster[static_cast<std::size_t>(g)] == static_cast<std::int32_t>(c) &&
            reached.insert(g).second) {
          stack.push_back(g);
        }
      }
    }
    if (reached.size() != tris.size()) {
      return ::testing::AssertionFailure() << "cluster " << c << " not edge-connected: "
                                           << reached.size() << " of " << tris.size();
    }
  }
  // Graph: ordered pairs of distinct existing clusters, each with at least one shared edge.
  for (const auto& e : seg.graph) {
    if (!(e.a >= 0 && e.a < e.b && e.b < static_cast<std::int32_t>(seg.clusters.size())) ||
        e.shared_edges < 1 || !e.joint.allFinite()) {
      return ::testing::AssertionFailure() << "bad graph edge " << e.a << "-" << e.b;
    }
  }
  if (seg.stats.atomic_clusters != static_cast<std::int32_t>(seg.clusters.size()) ||
      seg.stats.point_observers + seg.stats.line_observers != seg.stats.atomic_clusters) {
    return ::testing::AssertionFailure() << "stats disagree with clusters";
  }
  return ::testing::AssertionSuccess();
}

// A capsule chain bent by `degrees` about z at the joint between bone `joint − 1` and `joint`:
// vertices blend from 0 to the full rotation over ±`blend` around the joint (a smooth elbow), the
// bones beyond turn rigidly.
Rig bent_chain(int bones, int joint, double degrees, double blend) {
  Rig rig = skelcd::test::capsule_chain(bones, 1.0, 0.25, 8, 16);
  const Eigen::Vector3d J(joint, 0, 0);
  const double full = degrees * std::numbers::pi / 180.0;
  for (Eigen::Index v = 0; v < rig.mesh.rest_positions.rows(); ++v) {
    const Eigen::Vector3d p = rig.mesh.rest_positions.row(v).transpose();
    const double s = std::clamp((p.x() - (joint - blend)) / (2.0 * blend), 0.0, 1.0);
    const double a = full * s * s * (3.0 - 2.0 * s);
    rig.mesh.rest_positions.row(v) = (J + Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) * (p - J)).transpose();
  }
  const Eigen::AngleAxisd R(full, Eigen::Vector3d::UnitZ());
  for (int b = joint; b < bones; ++b) {
    auto& bone = rig.skeleton.bones[static_cast<std::size_t>(b)];
    bone.rest_head = J + R * (bone.rest_head - J);
    bone.rest_tail = J + R * (bone.rest_tail - J);
  }
  return rig;
}

TEST(Segmentation, CapsuleChainOneClusterPerBoneOnItsOwnSpan) {
  const int n = 6;
  const Rig rig = skelcd::test::capsule_chain(n);
  for (const auto source : {WeightSource::heat, WeightSource::rig}) {
    SegmentationOptions options;
    options.weights = source;
    const auto seg = segment(rig, options);
    ASSERT_TRUE(well_formed(rig, seg));
    ASSERT_EQ(seg.stats.atomic_clusters, n);
    EXPECT_TRUE(seg.stats.bones_without_cluster.empty());
    // A straight tube is seen from inside by any point of its axis: nothing non-positive.
    EXPECT_EQ(seg.stats.h_minus, 0);
    EXPECT_EQ(seg.stats.h_uncertain, 0);
    for (Eigen::Index f = 0; f < rig.mesh.num_triangles(); ++f) {
      // Heat: the span holding the centroid (the weights split evenly at the joint planes).
      // Rig: the bone that two of the three corners are rigidly bound to.
      double cx = 0.0;
      int votes[16] = {};
      for (int c = 0; c < 3; ++c) {
        const double x = rig.mesh.rest_positions(rig.mesh.triangles(f, c), 0);
        cx += x / 3.0;
        ++votes[std::clamp(static_cast<int>(std::floor(x)), 0, n - 1)];
      }
      const int expected = source == WeightSource::heat
                               ? std::clamp(static_cast<int>(std::floor(cx)), 0, n - 1)
                               : static_cast<int>(std::max_element(votes, votes + n) - votes);
      const auto& cluster = seg.clusters[static_cast<std::size_t>(seg.triangle_cluster[static_cast<std::size_t>(f)])];
      ASSERT_EQ(cluster.bone, expected) << "triangle " << f << " at x " << cx;
    }
    // The graph is the chain, meeting at the joints x = 1 … n−1 (the child's head).
    ASSERT_EQ(seg.graph.size(), static_cast<std::size_t>(n - 1));
    for (const auto& e : seg.graph) {
      const auto ba = seg.clusters[static_cast<std::size_t>(e.a)].bone;
      const auto bb = seg.clusters[static_cast<std::size_t>(e.b)].bone;
      ASSERT_EQ(std::abs(ba - bb), 1);
      EXPECT_EQ(e.ancestor_bone, std::min(ba, bb));
      EXPECT_TRUE(skelcd::test::expect_matrix_near(e.joint, Eigen::Vector3d(std::max(ba, bb), 0, 0), 0));
      // Heat: the ring at the joint (16 edges). Rig: the joint ring's row of quads zigzags between
      // the bones, each quad giving its diagonal and one side (32 edges).
      EXPECT_EQ(e.shared_edges, source == WeightSource::heat ? 16 : 32);
    }
  }
}

TEST(Segmentation, RefinementNeverIncreasesNonPositiveTriangles) {
  // A sharp elbow: the inner side of the bend faces away from the upper bone's observer.
  for (const double degrees : {100.0, 135.0, 150.0}) {
    const Rig rig = bent_chain(3, 1, degrees, 0.2);
    const auto seg = segment(rig);
    ASSERT_TRUE(well_formed(rig, seg));
    const auto& r = seg.stats.refinement;
    EXPECT_GT(r.non_positive_before, 0) << degrees;  // the case does exercise the refinement
    EXPECT_LE(r.non_positive_after, r.non_positive_before) << degrees;
    EXPECT_EQ(r.removed, r.non_positive_before);
    EXPECT_EQ(r.removed, r.regrown_positive + r.regrown_unconstrained + r.restored);
    // Without refinement (RVBC's plain split), the final count is not better.
    SegmentationOptions plain;
    plain.refine = false;
    const auto unrefined = segment(rig, plain);
    ASSERT_TRUE(well_formed(rig, unrefined));
    EXPECT_LE(seg.stats.h_minus + seg.stats.h_uncertain,
              unrefined.stats.h_minus + unrefined.stats.h_uncertain)
        << degrees;
  }
}

TEST(Segmentation, RefineLabelsByHand) {
  // A sphere; label 0 watched from the centre (every triangle positive to it), label 1 from far
  // outside on +x. Label 1 holds exactly the triangles that are not positive to its observer:
  // all are removed, and all grow back into label 0, positively.
  const auto sphere = skelcd::test::icosphere(2);
  const auto graph = face_graph(sphere.F);
  const std::vector<Observer> observers = {
      {ObserverKind::point, {Eigen::Vector3d(-0.1, 0, 0), Eigen::Vector3d(0.1, 0, 0)}},
      {ObserverKind::point, {Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(5, 0, 0)}}};
  std::vector<std::int32_t> labels(static_cast<std::size_t>(sphere.F.rows()));
  for (Eigen::Index f = 0; f < sphere.F.rows(); ++f) {
    labels[static_cast<std::size_t>(f)] =
        orientation(observers[1], sphere.V, sphere.F, f) == Orientation::positive ? 0 : 1;
  }
  const Eigen::MatrixXd W = Eigen::MatrixXd::Constant(sphere.V.rows(), 2, 0.5);
  const auto stats = refine_labels(sphere.V, sphere.F, graph, observers, W, labels);
  EXPECT_GT(stats.removed, 0);
  EXPECT_EQ(stats.non_positive_after, 0);
  EXPECT_EQ(stats.regrown_positive, stats.removed);
  for (const auto l : labels) EXPECT_EQ(l, 0);
}

TEST(Observer, LineWinsOnACorrugatedTubeAndTiesGoToThePoint) {
  // One bone along x in a tube whose rings alternate between radius 0.3 and 0.1: the steep cone
  // walls far from the middle face away from the midpoint along x, but the line sees every wall
  // from the foot of its own corner's perpendicular (radially), hence from behind.
  auto tube = skelcd::test::closed_tube(1.0, 0.3, 16, 12, 0.1);
  for (Eigen::Index v = 0; v < tube.V.rows() - 2; ++v) {
    if ((v / 12) % 2 == 1) tube.V.row(v).tail<2>() /= 3.0;
  }
  const BoneSegment bone{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  const Eigen::MatrixXd W = Eigen::MatrixXd::Ones(tube.V.rows(), 1);
  std::vector<std::int32_t> all(static_cast<std::size_t>(tube.F.rows()));
  std::iota(all.begin(), all.end(), 0);
  const std::vector<std::int32_t> subtree = {0};
  const auto corrugated = choose_observer(tube.V, tube.F, all, bone, W, subtree, 10.0 * std::numbers::pi / 180.0);
  EXPECT_EQ(corrugated.poses, 7);
  EXPECT_GT(corrugated.mean_positive_line, corrugated.mean_positive_point);
  EXPECT_EQ(corrugated.kind, ObserverKind::line);
  // With W = 1 on the bone's subtree the test poses are rigid motions of cluster and bone
  // together: the counts are those of the rest pose, exactly.
  const Observer line{ObserverKind::line, bone};
  int rest_positive = 0;
  for (const auto f : all) rest_positive += orientation(line, tube.V, tube.F, f) == Orientation::positive;
  EXPECT_EQ(corrugated.mean_positive_line, rest_positive);
  // A straight tube: both see everything; the tie goes to the point.
  const auto straight = skelcd::test::closed_tube(1.0, 0.3, 16, 12, 0.1);
  const auto plain = choose_observer(straight.V, straight.F, all, bone, W, subtree, 0.2);
  EXPECT_EQ(plain.mean_positive_point, static_cast<double>(all.size()));
  EXPECT_EQ(plain.mean_positive_line, static_cast<double>(all.size()));
  EXPECT_EQ(plain.kind, ObserverKind::point);
}

// A triangle's positive counts depend on it and the bone, not on the other triangles of the
// cluster (what segment_mesh's reuse of step 2's counts in step 4 relies on), and summed they are
// choose_observer's answer. Weights that vary along the tube make the test poses non-rigid.
TEST(Observer, PositiveCountsDoNotDependOnTheCluster) {
  auto tube = skelcd::test::closed_tube(1.0, 0.3, 16, 12, 0.1);
  for (Eigen::Index v = 0; v < tube.V.rows() - 2; ++v) {
    if ((v / 12) % 3 == 1) tube.V.row(v).tail<2>() *= 0.5;
  }
  const BoneSegment bone{Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d(1, 0, 0)};
  Eigen::MatrixXd W(tube.V.rows(), 1);
  for (Eigen::Index v = 0; v < tube.V.rows(); ++v) W(v, 0) = std::clamp(tube.V(v, 0), 0.0, 1.0);
  const std::vector<std::int32_t> subtree = {0};
  const double theta = 40.0 * std::numbers::pi / 180.0;
  std::vector<std::int32_t> all(static_cast<std::size_t>(tube.F.rows()));
  std::iota(all.begin(), all.end(), 0);
  std::vector<PositiveCounts> whole(all.size());
  positive_counts(tube.V, tube.F, all, bone, W, subtree, theta, whole);
  std::int64_t point = 0, line = 0;
  std::set<int> seen;
  for (const auto& c : whole) {
    EXPECT_LE(c.point, 7);
    EXPECT_LE(c.line, 7);
    point += c.point;
    line += c.line;
    seen.insert(c.point);
  }
  EXPECT_GT(seen.size(), 1u) << "every triangle counted alike: the poses test nothing";
  const auto chosen = choose_observer(tube.V, tube.F, all, bone, W, subtree, theta);
  const auto summed = observer_choice(point, line);
  EXPECT_EQ(chosen.kind, summed.kind);
  EXPECT_EQ(chosen.mean_positive_point, summed.mean_positive_point);
  EXPECT_EQ(chosen.mean_positive_line, summed.mean_positive_line);
  // Every third triangle, and the others: the counts of the whole, triangle by triangle.
  for (const int part : {0, 1}) {
    std::vector<std::int32_t> some;
    for (const auto f : all) {
      if ((f % 3 == 0) == (part == 0)) some.push_back(f);
    }
    std::vector<PositiveCounts> counts(some.size());
    positive_counts(tube.V, tube.F, some, bone, W, subtree, theta, counts);
    for (std::size_t i = 0; i < some.size(); ++i) {
      const auto& expected = whole[static_cast<std::size_t>(some[i])];
      EXPECT_EQ(counts[i].point, expected.point) << some[i];
      EXPECT_EQ(counts[i].line, expected.line) << some[i];
    }
  }
}

// Every list of two face graphs equal.
void expect_same_graph(const FaceGraph& given, const FaceGraph& expected) {
  EXPECT_EQ(given.edge_offsets, expected.edge_offsets);
  EXPECT_EQ(given.edge_faces, expected.edge_faces);
  EXPECT_EQ(given.offsets, expected.offsets);
  EXPECT_EQ(given.neighbours, expected.neighbours);
}

// The same on a mesh with a folded triangle (a, a, b), a non-manifold edge (three faces) and
// a boundary.
TEST(FaceGraph, FromTheTopologyWithFoldedAndNonManifoldFaces) {
  skelcd::skinning::Positions x(6, 3);
  x << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0, 1, 0, 1;
  skelcd::skinning::Triangles f(5, 3);
  f << 0, 1, 2, 0, 2, 3, 2, 1, 4, 0, 0, 1, 1, 2, 5;
  const auto topology =
      skelcd::skinning::build_topology(skelcd::test::single_part_mesh(std::move(x), std::move(f)));
  const auto expected = face_graph(topology.welded_triangles);
  const auto given = face_graph(topology);
  expect_same_graph(given, expected);
  // Face 0 meets faces 1 (edge 0-2), 2 and 4 (edge 1-2, non-manifold) and 3 (edge 0-1).
  const std::vector<std::int32_t> of_0(
      given.neighbours.begin() + given.offsets[0], given.neighbours.begin() + given.offsets[1]);
  EXPECT_EQ(of_0, (std::vector<std::int32_t>{1, 2, 3, 4}));
}

TEST(Segmentation, DeterministicAndIndependentOfThreads) {
  const Rig rig = bent_chain(4, 2, 120.0, 0.15);
  SegmentationOptions serial;
  serial.heat.parallel = false;
  const auto a = segment(rig);
  const auto b = segment(rig);
  const auto c = segment(rig, serial);
  EXPECT_EQ(a.triangle_cluster, b.triangle_cluster);
  EXPECT_EQ(a.triangle_cluster, c.triangle_cluster);
  ASSERT_EQ(a.clusters.size(), c.clusters.size());
  for (std::size_t k = 0; k < a.clusters.size(); ++k) {
    EXPECT_EQ(a.clusters[k].observer.kind, c.clusters[k].observer.kind);
  }
}

TEST(Segmentation, BadInput) {
  Rig no_bones = skelcd::test::capsule_chain(2);
  no_bones.skeleton.bones.clear();
  EXPECT_THROW_MESSAGE(std::ignore = segment(no_bones), skelcd::InvalidInput, "no bones");

  Rig no_triangles = skelcd::test::capsule_chain(2);
  no_triangles.mesh.triangles.resize(0, 3);
  no_triangles.mesh.face_part.clear();
  no_triangles.mesh.face_index_in_part.clear();
  EXPECT_THROW_MESSAGE(std::ignore = segment(no_triangles), skelcd::InvalidInput, "no triangles");

  // Rig weights asked for, but the rig has none.
  Rig unweighted = skelcd::test::capsule_chain(2);
  unweighted.weights.resize(0, 0);
  SegmentationOptions rig_weights;
  rig_weights.weights = WeightSource::rig;
  EXPECT_THROW_MESSAGE(std::ignore = segment(unweighted, rig_weights), skelcd::InvalidInput,
                       "weights");

  SegmentationOptions bad_theta;
  bad_theta.theta_deg = -5;
  EXPECT_THROW_MESSAGE(std::ignore = segment(skelcd::test::capsule_chain(2), bad_theta),
                       skelcd::InvalidInput, "theta");
}

TEST(Segmentation, FarAwayAndZeroLengthBonesAreHandled) {
  Rig rig = skelcd::test::capsule_chain(3);
  // Bone 3: far outside the mesh; bone 4: zero length at the middle joint.
  for (int k = 0; k < 2; ++k) {
    skelcd::skinning::SkeletonNode node;
    node.name = "extra" + std::to_string(k);
    rig.skeleton.nodes.push_back(node);
    skelcd::skinning::Bone bone;
    bone.name = node.name;
    bone.node = static_cast<std::int32_t>(rig.skeleton.nodes.size()) - 1;
    bone.rest_head = k == 0 ? Eigen::Vector3d(100, 100, 100) : Eigen::Vector3d(1.5, 0, 0);
    bone.rest_tail = k == 0 ? Eigen::Vector3d(101, 100, 100) : Eigen::Vector3d(1.5, 0, 0);
    rig.skeleton.bones.push_back(bone);
  }
  rig.weights.conservativeResize(rig.weights.rows(), 5);
  const auto seg = segment(rig);
  ASSERT_TRUE(well_formed(rig, seg));
  // The far bone owns nothing and is reported.
  EXPECT_NE(std::find(seg.stats.bones_without_cluster.begin(), seg.stats.bones_without_cluster.end(), 3),
            seg.stats.bones_without_cluster.end());
  EXPECT_EQ(seg.stats.heat.fallback_vertices, 0);
}

// Real characters, loaded once per suite.
class RealCharacters : public ::testing::TestWithParam<const char*> {};

std::filesystem::path character_path(const std::string& name) {
  if (name.ends_with(".X")) return skelcd::test::assimp_model("X/" + name);
  return skelcd::test::asset("characters/" + name);
}

TEST_P(RealCharacters, HeatAndRigWeightsBothPartitionTheMesh) {
  const auto model = skelcd::skinning::load_model(character_path(GetParam()));
  ASSERT_TRUE(model.rig);
  const Rig& rig = *model.rig;
  for (const auto source : {WeightSource::heat, WeightSource::rig}) {
    SegmentationOptions options;
    options.weights = source;
    const auto seg = segment(rig, options);
    ASSERT_TRUE(well_formed(rig, seg)) << GetParam();
    EXPECT_LE(seg.stats.refinement.non_positive_after, seg.stats.refinement.non_positive_before);
    EXPECT_GE(seg.stats.atomic_clusters, rig.skeleton.num_bones() -
                                             static_cast<std::int32_t>(seg.stats.bones_without_cluster.size()));
    std::cout << GetParam() << (source == WeightSource::heat ? " heat" : " rig ")
              << ": tris " << seg.stats.triangles << " clusters " << seg.stats.atomic_clusters
              << " (split " << seg.stats.split_clusters << ", empty bones "
              << seg.stats.bones_without_cluster.size() << ") H- " << seg.stats.h_minus << " Hu "
              << seg.stats.h_uncertain << " before " << seg.stats.refinement.non_positive_before
              << " after " << seg.stats.refinement.non_positive_after << " fallback "
              << seg.stats.heat.fallback_vertices << " clamped " << seg.stats.heat.clamped_weights
              << " weights " << seg.stats.weights_s << " s decomposition "
              << seg.stats.decomposition_ms << " ms\n";
  }
}

// A check welds the mesh once and hands that topology to the segmentation: the same clusters,
// observers and counts as welding it here; a topology of another mesh is refused.
TEST_P(RealCharacters, TheCallersTopologyGivesTheSameSegmentation) {
  const auto model = skelcd::skinning::load_model(character_path(GetParam()));
  ASSERT_TRUE(model.rig);
  const Rig& rig = *model.rig;
  SegmentationOptions options;
  options.weights = WeightSource::rig;
  const auto own = segment(rig, options);
  const auto given = segment(rig, options, skelcd::skinning::build_topology(rig.mesh));
  EXPECT_EQ(given.triangle_cluster, own.triangle_cluster);
  ASSERT_EQ(given.clusters.size(), own.clusters.size());
  for (std::size_t c = 0; c < own.clusters.size(); ++c) {
    EXPECT_EQ(given.clusters[c].bone, own.clusters[c].bone) << c;
    EXPECT_EQ(given.clusters[c].triangles, own.clusters[c].triangles) << c;
    EXPECT_EQ(given.clusters[c].observer.kind, own.clusters[c].observer.kind) << c;
  }
  EXPECT_EQ(given.stats.h_minus, own.stats.h_minus);
  EXPECT_EQ(given.stats.h_uncertain, own.stats.h_uncertain);
  const auto other = skelcd::skinning::build_topology(skelcd::test::capsule_chain(2).mesh);
  EXPECT_THROW(std::ignore = segment(rig, options, other), std::invalid_argument);
}

// The face graph from a topology's edge lists is the one from sorting the triangles' sides.
TEST_P(RealCharacters, TheFaceGraphFromTheTopologyIsTheFaceGraph) {
  const auto model = skelcd::skinning::load_model(character_path(GetParam()));
  const auto topology = skelcd::skinning::build_topology(*model.mesh);
  const auto expected = face_graph(topology.welded_triangles);
  const auto given = face_graph(topology);
  expect_same_graph(given, expected);
  EXPECT_GT(given.neighbours.size(), 0u);
}

// positive_counts decides most orientations with one cross product per triangle for both
// observers (a floating-point filter): the counts are those of the exact orientation() on each
// triangle of each test pose, posed here as the segmentation poses it (the LBS blend of R and the
// identity about the bone's head), for every bone of a real character with its own weights.
TEST_P(RealCharacters, PositiveCountsAreTheExactOrientationsOfEachPose) {
  const auto model = skelcd::skinning::load_model(character_path(GetParam()));
  ASSERT_TRUE(model.rig);
  const Rig& rig = *model.rig;
  const auto& V = rig.mesh.rest_positions;
  const auto& F = rig.mesh.triangles;
  const Eigen::MatrixXd W = Eigen::MatrixXd(rig.weights);
  const auto bones = bone_segments(rig.skeleton);
  ASSERT_EQ(W.cols(), static_cast<Eigen::Index>(bones.size()));
  const double theta = 25.0 * std::numbers::pi / 180.0;
  std::vector<std::int32_t> all(static_cast<std::size_t>(F.rows()));
  std::iota(all.begin(), all.end(), 0);
  std::int64_t compared = 0;
  std::set<int> seen;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    std::vector<std::int32_t> subtree;  // b and its descendants
    for (std::size_t k = 0; k < bones.size(); ++k) {
      for (auto j = static_cast<std::int32_t>(k); j >= 0;
           j = bones[static_cast<std::size_t>(j)].parent) {
        if (j == static_cast<std::int32_t>(b)) {
          subtree.push_back(static_cast<std::int32_t>(k));
          break;
        }
      }
    }
    std::vector<PositiveCounts> counts(all.size());
    positive_counts(V, F, all, bones[b], W, subtree, theta, counts);
    std::vector<PositiveCounts> expected(all.size());
    std::vector<Eigen::Matrix3d> rotations = {Eigen::Matrix3d::Identity()};
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {1.0, -1.0}) {
        rotations.push_back(
            Eigen::AngleAxisd(sign * theta, Eigen::Vector3d::Unit(axis)).toRotationMatrix());
      }
    }
    const Eigen::Vector3d q1 = bones[b].head;
    for (std::size_t r = 0; r < rotations.size(); ++r) {
      const Eigen::Matrix3d& R = rotations[r];
      BoneSegment posed_bone = bones[b];
      posed_bone.tail = q1 + R * (bones[b].tail - q1);
      skelcd::skinning::Positions posed = V;
      for (Eigen::Index v = 0; v < V.rows() && r > 0; ++v) {
        double follow = 0.0;
        for (const auto k : subtree) follow += W(v, k);
        follow = std::min(1.0, follow);
        const Eigen::Vector3d x = V.row(v).transpose();
        posed.row(v) =
            Eigen::Vector3d(q1 + follow * (R * (x - q1)) + (1.0 - follow) * (x - q1)).transpose();
      }
      for (std::size_t f = 0; f < all.size(); ++f) {
        const auto i = static_cast<Eigen::Index>(f);
        expected[f].point = static_cast<std::uint8_t>(
            expected[f].point +
            (orientation(Observer{ObserverKind::point, posed_bone}, posed, F, i) ==
             Orientation::positive));
        expected[f].line = static_cast<std::uint8_t>(
            expected[f].line +
            (orientation(Observer{ObserverKind::line, posed_bone}, posed, F, i) ==
             Orientation::positive));
      }
    }
    for (std::size_t f = 0; f < all.size(); ++f) {
      ASSERT_EQ(counts[f].point, expected[f].point)
          << GetParam() << " bone " << b << " triangle " << f;
      ASSERT_EQ(counts[f].line, expected[f].line)
          << GetParam() << " bone " << b << " triangle " << f;
      seen.insert(counts[f].point);
      ++compared;
    }
  }
  EXPECT_GT(compared, 0);
  EXPECT_GT(seen.size(), 2u) << "the poses change no orientation: they test nothing";
}

INSTANTIATE_TEST_SUITE_P(Models, RealCharacters,
                         ::testing::Values("CesiumMan.glb", "BCN_Epileptic.X", "Fox.glb"));

}  // namespace

namespace {

TEST(ClusterGraph, BoneJointsByHand) {
  using skelcd::segmentation::bone_joint;
  using skelcd::segmentation::BoneSegment;
  // 0 root (0,0,0)→(0,1,0); 1 and 2 children of 0 at (0,1,0) going ±x; 3 child of 1;
  // 4 a second root far away.
  const std::vector<BoneSegment> bones = {
      {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 1, 0), -1},
      {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(1, 1, 0), 0},
      {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(-1, 1, 0), 0},
      {Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(2, 1, 0), 1},
      {Eigen::Vector3d(5, 5, 5), Eigen::Vector3d(6, 5, 5), -1}};
  auto j = bone_joint(bones, 2, 2);  // pieces of one bone: its midpoint
  EXPECT_EQ(j.ancestor_bone, 2);
  EXPECT_EQ(j.joint, Eigen::Vector3d(-0.5, 1, 0));
  j = bone_joint(bones, 0, 1);  // parent and child: the child's head
  EXPECT_EQ(j.ancestor_bone, 0);
  EXPECT_EQ(j.joint, Eigen::Vector3d(0, 1, 0));
  j = bone_joint(bones, 3, 0);  // grandchild: the head of the child of 0 on the way (bone 1)
  EXPECT_EQ(j.ancestor_bone, 0);
  EXPECT_EQ(j.joint, Eigen::Vector3d(0, 1, 0));
  j = bone_joint(bones, 1, 2);  // siblings: their shared head
  EXPECT_EQ(j.ancestor_bone, 0);
  EXPECT_EQ(j.joint, Eigen::Vector3d(0, 1, 0));
  j = bone_joint(bones, 3, 2);  // cousins through 0: heads of 1 and 2
  EXPECT_EQ(j.ancestor_bone, 0);
  EXPECT_EQ(j.joint, Eigen::Vector3d(0, 1, 0));
  j = bone_joint(bones, 3, 4);  // different trees: the roots' heads' midpoint
  EXPECT_EQ(j.ancestor_bone, -1);
  EXPECT_EQ(j.joint, Eigen::Vector3d(2.5, 2.5, 2.5));
}

}  // namespace

namespace {

// The limb a bone belongs to: "<model>_limb<k>_…" → k; −1 for a bone outside the limbs.
int limb_of(const std::string& bone_name) {
  const auto at = bone_name.find("_limb");
  if (at == std::string::npos) return -1;
  return std::stoi(bone_name.substr(at + 5));
}

class GeneratedLimbs : public ::testing::TestWithParam<const char*> {};

TEST_P(GeneratedLimbs, EachLimbsTrianglesLandOnThatLimbsBones) {
  // The generator's own weights bind each limb's vertices to that limb's chain; the heat
  // weights, computed from geometry alone, must give (almost) every limb triangle to a bone of
  // the same limb, and every triangle must end in exactly one connected cluster.
  const auto generated = skelcd::skinning::generate({GetParam(), 6000, 2});
  const Rig& rig = generated.rig;
  const auto seg = segment(rig);
  ASSERT_TRUE(well_formed(rig, seg));
  const auto topo = skelcd::skinning::build_topology(rig.mesh);
  const auto file_bones = largest_weight_bones(
      [&] {
        Eigen::MatrixXd W = Eigen::MatrixXd::Zero(topo.num_welded_vertices(), rig.skeleton.num_bones());
        for (Eigen::Index v = 0; v < rig.weights.outerSize(); ++v) {
          for (skelcd::skinning::SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
            W(topo.welded_of_vertex[static_cast<std::size_t>(v)], it.col()) = it.value();
          }
        }
        return W;
      }(),
      topo.welded_triangles);
  int limb_triangles = 0, agree = 0;
  for (std::size_t f = 0; f < file_bones.size(); ++f) {
    const int expected = limb_of(rig.skeleton.bones[static_cast<std::size_t>(file_bones[f])].name);
    if (expected < 0) continue;
    ++limb_triangles;
    const auto bone = seg.clusters[static_cast<std::size_t>(seg.triangle_cluster[f])].bone;
    agree += limb_of(rig.skeleton.bones[static_cast<std::size_t>(bone)].name) == expected;
  }
  ASSERT_GT(limb_triangles, 0) << "no bone named _limb: the test would check nothing";
  EXPECT_GE(agree, 0.97 * limb_triangles) << agree << " of " << limb_triangles;
  std::cout << GetParam() << ": " << agree << " of " << limb_triangles << " limb triangles on their limb, "
            << seg.stats.atomic_clusters << " clusters, H- " << seg.stats.h_minus << " Hu "
            << seg.stats.h_uncertain << "\n";
}

INSTANTIATE_TEST_SUITE_P(Generators, GeneratedLimbs, ::testing::Values("octopus", "hand"));

}  // namespace
