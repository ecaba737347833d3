// Incremental DCD (culling/incremental_dcd.hpp) against the full DCD, its reference: the pairs at
// the end of an interval, updated from the pairs at its start and the interval's CCD contacts, must
// be exactly the pairs a full DCD finds there — on small meshes moving between grid points (exact
// touching, coplanar and collapsing triangles at the ends), on the cases of the proof in
// docs/culling.md, and on real characters' clips.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "culling/incremental_dcd.hpp"
#include "culling/method.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

struct Outcome {
  std::size_t changed = 0;     ///< pairs whose status differs between the two ends
  std::size_t affected = 0;    ///< pairs the update tested again
  std::size_t candidates = 0;  ///< candidate pairs of the full DCD at the end
};

/// Full DCD at x0 and x1, CCD x0 → x1 by `method` (a `bvh` of the mesh at some accuracy), the
/// update; expects the updated pairs to be the full DCD's at x1.
Outcome expect_update_is_full_dcd(
    CullingMethod& method,
    DcdUpdater& updater,
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    const std::string& what) {
  FrameResult start, end, interval, updated;
  method.detect_dcd(x0, start);
  method.detect_dcd(x1, end);
  method.detect_ccd(x0, x1, interval);
  updater.update(start.dcd_pairs, interval.contacts, x1, ElementaryTests{}, updated);
  EXPECT_EQ(updated.dcd_pairs, end.dcd_pairs) << what;
  EXPECT_EQ(updated.counters.dcd_pairs, static_cast<std::int64_t>(end.dcd_pairs.size())) << what;
  std::vector<TrianglePair> changed;
  std::set_symmetric_difference(
      start.dcd_pairs.begin(),
      start.dcd_pairs.end(),
      end.dcd_pairs.begin(),
      end.dcd_pairs.end(),
      std::back_inserter(changed));
  return {
      changed.size(),
      static_cast<std::size_t>(updated.counters.candidate_pairs),
      static_cast<std::size_t>(end.counters.candidate_pairs)};
}

skinning::Positions rows(std::initializer_list<Eigen::RowVector3d> points) {
  skinning::Positions x(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const auto& p : points) x.row(i++) = p;
  return x;
}

// The cases the proof walks through (docs/culling.md "Incremental DCD"), each of which changes a
// pair's status between the two ends.
TEST(IncrementalDcd, CasesOfTheProof) {
  struct Case {
    const char* what;
    skinning::Triangles f;
    skinning::Positions x0, x1;
  };
  skinning::Triangles two_fan(2, 3);
  two_fan << 0, 1, 2, 0, 3, 4;
  skinning::Triangles apart(2, 3);
  apart << 0, 1, 2, 3, 4, 5;
  const std::vector<Case> cases{
      // Neighbours at v = 0: A's angle at v swings from +y (through B, which crosses A's plane
      // along +y) to -y. The pair stops intersecting when A is flat through v — an edge of A
      // sweeping over v, met by B's edges at v.
      {"shared vertex, fold through",
       two_fan,
       rows({{0, 0, 0}, {-1, 0.5, 0}, {1, 0.5, 0}, {0.1, 1, 0.3}, {-0.1, 1, -0.3}}),
       rows({{0, 0, 0}, {-1, -0.5, 0}, {1, -0.5, 0}, {0.1, 1, 0.3}, {-0.1, 1, -0.3}})},
      // The same in one plane: A's angle closes over B's.
      {"shared vertex, coplanar",
       two_fan,
       rows({{0, 0, 0}, {-1, 0.5, 0}, {1, 0.5, 0}, {0.1, 1, 0}, {-0.1, 1, 0}}),
       rows({{0, 0, 0}, {-1, -0.5, 0}, {1, -0.5, 0}, {0.1, 1, 0}, {-0.1, 1, 0}})},
      // A vertex arrives on the other triangle exactly at the end (touching counts).
      {"touching at the end",
       apart,
       rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1}, {2, 2, 2}, {3, 2, 2}}),
       rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 0}, {2, 2, 2}, {3, 2, 2}})},
      // ... and leaves from touching at the start.
      {"touching at the start",
       apart,
       rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 0}, {2, 2, 2}, {3, 2, 2}}),
       rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1}, {2, 2, 2}, {3, 2, 2}})},
      // An edge of A collapses onto the shared vertex inside B (A ends as a segment in B).
      {"collapsing onto the shared vertex",
       two_fan,
       rows({{0, 0, 0}, {0.3, 0.3, 1}, {-0.3, 0.3, 1}, {1, 1, 0}, {-1, 1, 0}}),
       rows({{0, 0, 0}, {0.3, 0.3, 1}, {0, 0.5, 0}, {1, 1, 0}, {-1, 1, 0}})},
  };
  for (const auto& c : cases) {
    skinning::Positions rest(c.x0.rows(), 3);
    for (Eigen::Index i = 0; i < rest.rows(); ++i)
      rest.row(i) << 10.0 * static_cast<double>(i), 0, 0;
    const skinning::Mesh mesh = test::single_part_mesh(rest, c.f);
    const skinning::Topology topology = skinning::build_topology(mesh);
    DcdUpdater updater(mesh, topology);
    for (const auto accuracy : {ccd::Accuracy::conservative, ccd::Accuracy::exact}) {
      const auto method = make_method("bvh", mesh, topology, MethodOptions{.accuracy = accuracy});
      const Outcome o = expect_update_is_full_dcd(
          *method,
          updater,
          c.x0,
          c.x1,
          std::string(c.what) + " " + std::string(ccd::to_string(accuracy)));
      EXPECT_EQ(o.changed, 1u) << c.what << ": the case must change the pair's status";
    }
  }
}

// Small meshes (a vertex fan, a strip and a loose triangle) moving between points of a coarse
// grid: the ends are full of exact degeneracies — touching, coplanar, collinear and collapsed
// triangles — where a gap in the argument would show.
TEST(IncrementalDcd, GridMotionsAgreeWithTheFullDcd) {
  skinning::Triangles f(6, 3);
  f << 0, 1, 2, 0, 2, 3, 0, 3, 4, 1, 2, 5, 2, 5, 6, 7, 8, 9;
  skinning::Positions rest(10, 3);
  for (Eigen::Index i = 0; i < rest.rows(); ++i) rest.row(i) << static_cast<double>(i), 0, 0;
  const skinning::Mesh mesh = test::single_part_mesh(rest, f);
  const skinning::Topology topology = skinning::build_topology(mesh);
  ASSERT_EQ(topology.num_welded_vertices(), 10);
  DcdUpdater updater(mesh, topology);
  const auto conservative =
      make_method("bvh", mesh, topology, MethodOptions{.accuracy = ccd::Accuracy::conservative});
  const auto exact =
      make_method("bvh", mesh, topology, MethodOptions{.accuracy = ccd::Accuracy::exact});
  std::mt19937_64 rng(14);
  std::uniform_int_distribution<int> coord(-2, 2);
  const auto grid_positions = [&] {
    skinning::Positions x(10, 3);
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      x.row(i) << 0.5 * coord(rng), 0.5 * coord(rng), 0.5 * coord(rng);
    }
    return x;
  };
  std::size_t changed = 0, affected = 0, candidates = 0;
  for (int n = 0; n < 600; ++n) {
    const skinning::Positions x0 = grid_positions();
    skinning::Positions x1 = grid_positions();
    if (n % 3 == 0) x1.topRows(5) = x0.topRows(5);  // part of the mesh stays, the rest moves
    CullingMethod& method = n % 4 == 0 ? *exact : *conservative;
    const Outcome o =
        expect_update_is_full_dcd(method, updater, x0, x1, "case " + std::to_string(n));
    if (::testing::Test::HasFailure()) return;
    changed += o.changed;
    affected += o.affected;
    candidates += 15;  // C(6, 2) triangle pairs
  }
  EXPECT_GT(changed, 500u) << "the motions must change pairs' status often";
  EXPECT_LT(affected, candidates) << "some pairs must keep their status without a test";
}

// Real characters: consecutive samples of their clips, and the rest pose to a posed sample (one
// large motion): the update equals the full DCD at every end, tests far fewer pairs, and the
// clips do change pairs' status.
TEST(IncrementalDcd, IncidencesAreTheTopologysEdgeFacesAndEachVertexsDistinctTriangles) {
  // `dynamic` walks its patches and decides its masks on the updater's incidences instead of
  // copies of its own: an edge's triangles are Topology::edge_faces', a vertex's every triangle
  // with it as a corner, once (a degenerate triangle repeats a corner), ascending.
  for (const std::string file : {"CesiumMan.glb", "stormtrooper/stormtrooper.dae"}) {
    SCOPED_TRACE(file);
    const auto model = skinning::load_model(test::asset("characters/" + file));
    const skinning::Topology topology = skinning::build_topology(*model.mesh);
    const DcdUpdater updater(*model.mesh, topology);
    const auto num_edges = static_cast<std::int32_t>(topology.edge_face_offsets.size()) - 1;
    ASSERT_GT(num_edges, 0);
    for (std::int32_t e = 0; e < num_edges; ++e) {
      const auto i = static_cast<std::size_t>(e);
      const auto begin = topology.edge_faces.begin() + topology.edge_face_offsets[i];
      const auto end = topology.edge_faces.begin() + topology.edge_face_offsets[i + 1];
      const auto got = updater.edge_triangles(e);
      ASSERT_TRUE(std::equal(got.begin(), got.end(), begin, end)) << "edge " << e;
    }
    std::vector<std::vector<std::int32_t>> at(
        static_cast<std::size_t>(topology.num_welded_vertices()));
    for (std::int32_t f = 0; f < topology.welded_triangles.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        auto& list = at[static_cast<std::size_t>(topology.welded_triangles(f, k))];
        if (list.empty() || list.back() != f) list.push_back(f);
      }
    }
    for (std::int32_t v = 0; v < topology.num_welded_vertices(); ++v) {
      const auto got = updater.vertex_triangles(v);
      const auto& want = at[static_cast<std::size_t>(v)];
      ASSERT_TRUE(std::equal(got.begin(), got.end(), want.begin(), want.end())) << "vertex " << v;
    }
  }
}

TEST(IncrementalDcd, RealCharactersAgreeWithTheFullDcd) {
  struct Clip {
    std::string file;
    std::string clip;
  };
  const std::vector<Clip> clips{
      {"RobotExpressive.glb", "Dance"},
      {"CesiumMan.glb", ""},
      {"Fox.glb", "Run"},
      {"stormtrooper/stormtrooper.dae", ""},
  };
  std::size_t changed = 0;
  for (const auto& c : clips) {
    const auto model = skinning::load_model(test::asset("characters/" + c.file));
    const skinning::Mesh& mesh = *model.mesh;
    const skinning::Topology topology = skinning::build_topology(mesh);
    const auto motion = model.motion({.clip = c.clip});
    DcdUpdater updater(mesh, topology);
    const auto method = make_method("bvh", mesh, topology);
    skinning::Positions file_positions, x0, x1;
    skinning::gather_welded(topology, mesh.rest_positions, x0);
    const int n = motion->num_samples();
    std::size_t affected = 0, pairs = 0;
    // The rest pose to a third of the clip, then 8 consecutive samples from there.
    for (int k = n / 3; k < std::min(n, n / 3 + 9); ++k) {
      motion->positions(k, file_positions);
      skinning::gather_welded(topology, file_positions, x1);
      const Outcome o = expect_update_is_full_dcd(
          *method, updater, x0, x1, c.file + " to sample " + std::to_string(k));
      changed += o.changed;
      affected += o.affected;
      pairs += o.candidates;
      std::swap(x0, x1);
    }
    EXPECT_LT(affected * 4, pairs) << c.file << ": the update must test far fewer pairs";
  }
  EXPECT_GT(changed, 100u) << "the clips must change pairs' status";
}

}  // namespace
}  // namespace skelcd::culling
