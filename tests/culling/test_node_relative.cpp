// Relative boxes at the nodes (Bvh::refit_end_boxes, end_boxes_meet; docs/culling.md "Relative
// boxes at the nodes"): the wide nodes' boxes at both ends of an interval hold every corner of
// their triangles, a refit drops them, two lanes that meet in the relative motion are never told
// apart, and on a body carried far while it moves the traversal prunes most node pairs while
// `kdop` keeps exactly `bvh`'s contacts (`dynamic`'s: tests/clustering, the real clips).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/cluster_checks.hpp"
#include "culling/feature_topology.hpp"
#include "culling/method.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/welded_character.hpp"

namespace skelcd::culling {
namespace {

using Model = test::WeldedCharacter;

/// The triangle pairs of a self traversal of `bvh` refit over x0 → x1, with or without its end
/// boxes, and its volume tests.
struct Traversed {
  std::vector<TrianglePair> pairs;
  std::int64_t bv_tests = 0;
};
Traversed traverse(
    Bvh<3>& bvh,
    const FeatureTopology& ft,
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    bool end_boxes) {
  FeatureBounds<3> bounds;
  swept_vertex_bounds<3>(x0, x1, 0.0, bounds.vertices);
  bounds.derive(ft, /*with_edges=*/false);
  bvh.refit(bounds.triangles);
  if (end_boxes) {
    std::vector<NodeEndBoxes> vertices;
    vertex_end_boxes(x0, x1, 0.0, vertices);
    bvh.refit_end_boxes(ft.welded_triangles(), vertices);
  }
  EXPECT_EQ(bvh.end_boxes().empty(), !end_boxes);
  TraversalScratch scratch;
  Traversed t;
  self_traverse<3>(bvh, bounds.triangles, scratch, t.pairs, t.bv_tests);
  std::sort(t.pairs.begin(), t.pairs.end());
  return t;
}

/// CesiumMan's samples 0 → 20 (its walk moves every part), its tree over the rest pose and the
/// triangles' swept volumes of that interval (the tree not refit yet).
/// The 12 rows of a tree's slot end boxes (Bvh::slot_ends) one after the other; fewer when a row
/// is missing (a failure is recorded).
std::vector<float> slot_end_rows(const Bvh<3>& tree) {
  std::vector<float> r;
  for (int k = 0; k < 12; ++k) {
    const float* row = tree.slot_ends(k);
    EXPECT_NE(row, nullptr);
    if (row == nullptr) return r;
    r.insert(r.end(), row, row + tree.triangle_order().size());
  }
  return r;
}

/// Copies of two samples with every `step`-th vertex given a coordinate where the rounding has
/// edges — zeros of both signs, a subnormal, a float subnormal, beyond the float range and its
/// edge — in the first sample at vertex v, axis v % 3, and in the second at vertex v + shift[0],
/// axis (v + shift[1]) % 3, the edge (v + shift[2]) % 6.
std::pair<skinning::Positions, skinning::Positions> with_edge_coordinates(
    const skinning::Positions& x0,
    const skinning::Positions& x1,
    Eigen::Index step,
    const std::array<Eigen::Index, 3>& shift) {
  std::pair<skinning::Positions, skinning::Positions> edgy{x0, x1};
  const std::array<double, 6> edges{0.0, -0.0, 1e-310, -1e-41, 1e39, -3.4028235e38};
  for (Eigen::Index v = 0; v < x0.rows(); v += step) {
    edgy.first(v, v % 3) = edges[static_cast<std::size_t>(v % 6)];
    edgy.second((v + shift[0]) % x1.rows(), (v + shift[1]) % 3) =
        edges[static_cast<std::size_t>((v + shift[2]) % 6)];
  }
  return edgy;
}

/// A float's bits (a zero's sign and every NaN told apart).
std::uint32_t bits_of(float f) { return std::bit_cast<std::uint32_t>(f); }

/// Two trees over the same triangles have the same wide nodes' and slots' float volumes, bit for
/// bit (`what` names the case in a failure).
template <int N>
void expect_same_float_volumes(const Bvh<N>& a, const Bvh<N>& b, const std::string& what) {
  const auto wide_a = a.wide_nodes();
  const auto wide_b = b.wide_nodes();
  ASSERT_EQ(wide_a.size(), wide_b.size());
  ASSERT_GT(wide_a.size(), 1u);
  for (std::size_t n = 0; n < wide_a.size(); ++n) {
    for (int i = 0; i < wide_a[n].num_children; ++i) {
      const auto l = static_cast<std::size_t>(i);
      for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
        ASSERT_EQ(bits_of(wide_a[n].lo[k][l]), bits_of(wide_b[n].lo[k][l])) << what << " " << n;
        ASSERT_EQ(bits_of(wide_a[n].hi[k][l]), bits_of(wide_b[n].hi[k][l])) << what << " " << n;
      }
    }
  }
  const std::size_t stride = a.slot_stride();
  ASSERT_EQ(stride, b.slot_stride());
  for (int k = 0; k < Bvh<N>::kSlotAxes; ++k) {
    EXPECT_EQ(std::memcmp(a.slot_lo(k), b.slot_lo(k), stride * sizeof(float)), 0)
        << what << " axis " << k;
    EXPECT_EQ(std::memcmp(a.slot_hi(k), b.slot_hi(k), stride * sizeof(float)), 0)
        << what << " axis " << k;
  }
}

struct SweptCesium {
  Model m{"CesiumMan.glb"};
  FeatureTopology ft{*m.loaded.mesh, m.topology};
  skinning::Positions x0 = m.sample(0);
  skinning::Positions x1 = m.sample(20);
  Bvh<3> bvh{ft.welded_triangles(), m.rest};
  FeatureBounds<3> bounds;
  SweptCesium() {
    swept_vertex_bounds<3>(x0, x1, 0.0, bounds.vertices);
    bounds.derive(ft, /*with_edges=*/false);
  }
};

// Without a half width the vertices' end boxes are each coordinate's float_below and float_above
// bit for bit (the SSE2 path converts four lanes at once): on CesiumMan's moving samples and on
// coordinates where the rounding has edges — zeros of both signs, subnormals and the smallest
// normals, halfway and just-off float values, beyond the float range.
TEST(NodeRelative, VertexEndBoxesAreTheScalarRoundingsBitForBit) {
  const auto bits = [](float f) {
    std::uint32_t b = 0;
    std::memcpy(&b, &f, sizeof b);
    return b;
  };
  const auto check = [&](const skinning::Positions& x0, const skinning::Positions& x1) {
    std::vector<NodeEndBoxes> ends;
    vertex_end_boxes(x0, x1, 0.0, ends);
    ASSERT_EQ(ends.size(), static_cast<std::size_t>(x0.rows()));
    for (Eigen::Index v = 0; v < x0.rows(); ++v) {
      const NodeEndBoxes& e = ends[static_cast<std::size_t>(v)];
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(bits(e.lo0[k]), bits(float_below(x0(v, k)))) << v << " " << k << " " << x0(v, k);
        ASSERT_EQ(bits(e.hi0[k]), bits(float_above(x0(v, k)))) << v << " " << k << " " << x0(v, k);
        ASSERT_EQ(bits(e.lo1[k]), bits(float_below(x1(v, k)))) << v << " " << k << " " << x1(v, k);
        ASSERT_EQ(bits(e.hi1[k]), bits(float_above(x1(v, k)))) << v << " " << k << " " << x1(v, k);
      }
      EXPECT_EQ(e.lo0[3], 0.0f);
      EXPECT_EQ(e.hi1[3], 0.0f);
    }
  };
  Model m{"CesiumMan.glb"};
  check(m.sample(0), m.sample(20));
  const double fmin = std::numeric_limits<float>::min();
  const double fmax = std::numeric_limits<float>::max();
  const double f1 = 1.0 + std::ldexp(1.0, -23);  // the float after 1
  const std::vector<double> edges{
      0.0,
      -0.0,
      1e-310,
      -1e-310,
      std::ldexp(fmin, -3),
      -std::ldexp(fmin, -3),
      fmin,
      -fmin,
      std::nextafter(fmin, 0.0),
      -std::nextafter(fmin, 0.0),
      1.0,
      -1.0,
      0.5 * (1.0 + f1),
      -0.5 * (1.0 + f1),
      std::nextafter(0.5 * (1.0 + f1), 2.0),
      0.1,
      -0.1,
      1.0 / 3.0,
      -1e7 / 3.0,
      fmax,
      -fmax,
      2.0 * fmax,
      -2.0 * fmax,
      1e300,
      -1e300,
      std::nextafter(fmax, 1e300)};
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, edges.size() - 1);
  skinning::Positions x0(64, 3), x1(64, 3);
  for (Eigen::Index v = 0; v < 64; ++v) {
    for (int k = 0; k < 3; ++k) {
      x0(v, k) = edges[pick(rng)];
      x1(v, k) = edges[pick(rng)];
    }
  }
  check(x0, x1);
}

// motion_scale is its definition computed term by term in order, bit for bit (the SSE2 path
// takes each term's maxima two coordinates at a time): on CesiumMan's intervals, still and moving.
TEST(NodeRelative, MotionScaleIsItsDefinitionBitForBit) {
  Model m{"CesiumMan.glb"};
  FeatureTopology ft{*m.loaded.mesh, m.topology};
  const auto definition = [&](const skinning::Positions& x0, const skinning::Positions& x1) {
    double moved = 0.0;
    for (Eigen::Index v = 0; v < x0.rows(); ++v) {
      double d = 0.0;
      for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(x1(v, k) - x0(v, k)));
      moved += d;
    }
    double size = 0.0;
    for (std::int32_t f = 0; f < ft.num_triangles(); ++f) {
      double side = 0.0;
      for (int k = 0; k < 3; ++k) {
        double lo = std::numeric_limits<double>::infinity();
        double hi = -lo;
        for (const std::int32_t v : ft.triangle(f)) {
          lo = std::min(lo, x0(v, k));
          hi = std::max(hi, x0(v, k));
        }
        side = std::max(side, hi - lo);
      }
      size += side;
    }
    return (moved / static_cast<double>(x0.rows())) /
           (size / static_cast<double>(ft.num_triangles()));
  };
  int moving = 0;
  for (const auto& [s0, s1] :
       std::vector<std::pair<int, int>>{{0, 0}, {0, 1}, {3, 4}, {0, 20}, {10, 30}}) {
    const skinning::Positions x0 = m.sample(s0);
    const skinning::Positions x1 = m.sample(s1);
    const double got = motion_scale(ft, x0, x1);
    const double want = definition(x0, x1);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(got), std::bit_cast<std::uint64_t>(want))
        << s0 << " → " << s1 << ": " << got << " vs " << want;
    moving += got > 0.0;
  }
  EXPECT_EQ(moving, 4);
}

// Every lane's boxes hold its triangles' corners at t = 0 and t = 1, grown by the half width;
// the next refit drops them (a traversal of another interval must not read them).
TEST(NodeRelative, EndBoxesHoldEveryCornerAndARefitDropsThem) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  bvh.refit(bounds.triangles);
  EXPECT_TRUE(bvh.end_boxes().empty());
  const double half_width = 1e-3;
  std::vector<NodeEndBoxes> vertices;
  vertex_end_boxes(x0, x1, half_width, vertices);
  bvh.refit_end_boxes(ft.welded_triangles(), vertices);
  const auto ends = bvh.end_boxes();
  ASSERT_EQ(ends.size(), bvh.wide_nodes().size());
  const auto order = bvh.triangle_order();
  std::int64_t checked = 0;
  for (std::size_t n = 0; n < ends.size(); ++n) {
    const auto& w = bvh.wide_nodes()[n];
    for (int i = 0; i < w.num_children; ++i) {
      const BvhNode& node = bvh.nodes()[static_cast<std::size_t>(w.node[i])];
      float tight[3][4];  // the tightest float box of the lane at t = 0 on each axis: lo, hi
      for (auto& row : tight) {
        row[0] = row[2] = std::numeric_limits<float>::infinity();
        row[1] = row[3] = -std::numeric_limits<float>::infinity();
      }
      for (std::int32_t s = node.begin; s < node.end; ++s) {
        for (const std::int32_t v : ft.triangle(order[static_cast<std::size_t>(s)])) {
          for (int k = 0; k < 3; ++k) {
            const double p0 = x0(v, k);
            const double p1 = x1(v, k);
            EXPECT_LE(ends[n].lo0[k][i], p0 - half_width);
            EXPECT_GE(ends[n].hi0[k][i], p0 + half_width);
            EXPECT_LE(ends[n].lo1[k][i], p1 - half_width);
            EXPECT_GE(ends[n].hi1[k][i], p1 + half_width);
            ++checked;
          }
        }
      }
    }
    for (int i = w.num_children; i < 4; ++i) {
      EXPECT_GT(ends[n].lo0[0][i], ends[n].hi0[0][i]) << "an unused lane is empty";
    }
  }
  EXPECT_GT(checked, 3 * 3 * ft.num_triangles());
  // A traversal-only tree (`kdop`'s, without binary node volumes) has the same shape and gets the
  // same boxes, bit for bit.
  Bvh<3> wide_only(ft.welded_triangles(), m.rest, BvhOptions{.node_volumes = false});
  wide_only.refit(bounds.triangles);
  wide_only.refit_end_boxes(ft.welded_triangles(), vertices);
  ASSERT_EQ(wide_only.end_boxes().size(), ends.size());
  EXPECT_EQ(
      std::memcmp(wide_only.end_boxes().data(), ends.data(), ends.size() * sizeof(WideEndBoxes)),
      0);
  bvh.refit(bounds.triangles);
  EXPECT_TRUE(bvh.end_boxes().empty());
}

// The nodes' and the slots' end boxes from one gather of the corners (refit_end_boxes with
// with_slot_ends, which `dynamic` and `kdop` use when they want both) are what the two refits
// give apart, bit for bit, on a tree with binary node volumes and on a traversal-only one; and
// without with_slot_ends the slots' rows stay as they were (absent after a refit).
TEST(NodeRelative, NodeAndSlotEndBoxesFromOneGatherAreTheTwoRefitsBitForBit) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  for (const bool node_volumes : {true, false}) {
    for (const double half_width : {0.0, 1e-3}) {
      std::vector<NodeEndBoxes> vertices;
      vertex_end_boxes(x0, x1, half_width, vertices);
      // Two fresh trees: neither has rows left from an earlier interval.
      const BvhOptions options{.node_volumes = node_volumes};
      Bvh<3> apart(ft.welded_triangles(), m.rest, options);
      Bvh<3> together(ft.welded_triangles(), m.rest, options);
      apart.refit(bounds.triangles);
      apart.refit_end_boxes(ft.welded_triangles(), vertices);
      EXPECT_EQ(apart.slot_ends(0), nullptr);
      apart.refit_slot_ends(ft.welded_triangles(), vertices);
      together.refit(bounds.triangles);
      together.refit_end_boxes(ft.welded_triangles(), vertices, /*with_slot_ends=*/true);
      ASSERT_EQ(together.end_boxes().size(), apart.end_boxes().size());
      ASSERT_GT(apart.end_boxes().size(), 1u);
      EXPECT_EQ(
          std::memcmp(
              together.end_boxes().data(),
              apart.end_boxes().data(),
              apart.end_boxes().size() * sizeof(WideEndBoxes)),
          0)
          << node_volumes << " " << half_width;
      const std::vector<float> apart_rows = slot_end_rows(apart);
      const std::vector<float> together_rows = slot_end_rows(together);
      ASSERT_EQ(apart_rows.size(), 12 * static_cast<std::size_t>(ft.num_triangles()));
      ASSERT_EQ(together_rows.size(), apart_rows.size());
      EXPECT_EQ(
          std::memcmp(together_rows.data(), apart_rows.data(), apart_rows.size() * sizeof(float)),
          0)
          << node_volumes << " " << half_width;
      together.refit(bounds.triangles);
      EXPECT_EQ(together.slot_ends(0), nullptr) << "a refit drops them";
    }
  }
}

// The end boxes read from the corners' positions (the overloads `bvh` and `kdop` use: no #W
// vertex boxes held) are the vertex boxes' bit for bit — nodes and slots, with and without a
// half width — on CesiumMan's motion and with some coordinates set to zeros of both signs,
// subnormals and values beyond the float range, where the rounding has edges.
TEST(NodeRelative, EndBoxesFromPositionsAreTheVertexBoxesBitForBit) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  const auto [edgy0, edgy1] = with_edge_coordinates(x0, x1, 7, {1, 2, 3});
  const auto same_nodes = [](const Bvh<3>& a, const Bvh<3>& b) {
    return a.end_boxes().size() == b.end_boxes().size() && !a.end_boxes().empty() &&
           std::memcmp(
               a.end_boxes().data(),
               b.end_boxes().data(),
               a.end_boxes().size() * sizeof(WideEndBoxes)) == 0;
  };
  for (const bool edgy : {false, true}) {
    const skinning::Positions& p0 = edgy ? edgy0 : x0;
    const skinning::Positions& p1 = edgy ? edgy1 : x1;
    FeatureBounds<3> b;
    swept_vertex_bounds<3>(p0, p1, 0.0, b.vertices);
    b.derive(ft, /*with_edges=*/false);
    for (const double half_width : {0.0, 1e-3}) {
      for (const bool with_slots : {false, true}) {
        std::vector<NodeEndBoxes> vertices;
        vertex_end_boxes(p0, p1, half_width, vertices);
        Bvh<3> from_vertices(ft.welded_triangles(), m.rest);
        Bvh<3> from_positions(ft.welded_triangles(), m.rest);
        from_vertices.refit(b.triangles);
        from_positions.refit(b.triangles);
        from_vertices.refit_end_boxes(ft.welded_triangles(), vertices, with_slots);
        from_positions.refit_end_boxes(ft.welded_triangles(), p0, p1, half_width, with_slots);
        EXPECT_TRUE(same_nodes(from_vertices, from_positions))
            << edgy << " " << half_width << " " << with_slots;
        if (with_slots) {
          const std::vector<float> a = slot_end_rows(from_vertices);
          const std::vector<float> b_rows = slot_end_rows(from_positions);
          ASSERT_EQ(a.size(), b_rows.size());
          EXPECT_EQ(std::memcmp(a.data(), b_rows.data(), a.size() * sizeof(float)), 0)
              << edgy << " " << half_width;
        } else {
          EXPECT_EQ(from_positions.slot_ends(0), nullptr);
        }
      }
    }
    // The slots' rows alone (no width: the leaves' test).
    std::vector<NodeEndBoxes> vertices;
    vertex_end_boxes(p0, p1, 0.0, vertices);
    Bvh<3> from_vertices(ft.welded_triangles(), m.rest);
    Bvh<3> from_positions(ft.welded_triangles(), m.rest);
    from_vertices.refit(b.triangles);
    from_positions.refit(b.triangles);
    from_vertices.refit_slot_ends(ft.welded_triangles(), vertices);
    from_positions.refit_slot_ends(ft.welded_triangles(), p0, p1);
    const std::vector<float> expected = slot_end_rows(from_vertices);
    ASSERT_EQ(expected.size(), 12 * static_cast<std::size_t>(ft.num_triangles()));
    const std::vector<float> got = slot_end_rows(from_positions);
    ASSERT_EQ(got.size(), expected.size());
    EXPECT_EQ(std::memcmp(expected.data(), got.data(), expected.size() * sizeof(float)), 0) << edgy;
  }
}

// `dynamic`'s one pass (Bvh::refit_swept_and_ends) is refit() over the swept volumes from the
// corners followed by refit_end_boxes() without a width, bit for bit: the slots' and the wide
// nodes' float volumes, the end boxes and the slots' rows, and the root's double volume, on
// CesiumMan's motion and on the coordinates where the rounding has edges.
TEST(NodeRelative, OnePassRefitIsTheRefitAndItsEndBoxesBitForBit) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  const auto [edgy0, edgy1] = with_edge_coordinates(x0, x1, 5, {2, 1, 1});
  const BvhOptions wide_only{.node_volumes = false};
  for (const bool edgy : {false, true}) {
    const skinning::Positions& p0 = edgy ? edgy0 : x0;
    const skinning::Positions& p1 = edgy ? edgy1 : x1;
    FeatureBounds<3> swept;
    swept.swept_triangles(ft, p0, p1);
    for (const bool with_slots : {false, true}) {
      Bvh<3> two_passes(ft.welded_triangles(), m.rest, wide_only);
      Bvh<3> one_pass(ft.welded_triangles(), m.rest, wide_only);
      two_passes.refit(swept.triangles);
      two_passes.refit_end_boxes(ft.welded_triangles(), p0, p1, 0.0, with_slots);
      // A refit of another interval first: everything the pass fills is overwritten.
      one_pass.refit(bounds.triangles);
      one_pass.refit_swept_and_ends(ft.welded_triangles(), p0, p1, with_slots);
      const std::string what = std::to_string(edgy) + " " + std::to_string(with_slots);
      expect_same_float_volumes(two_passes, one_pass, what);
      ASSERT_EQ(two_passes.end_boxes().size(), one_pass.end_boxes().size());
      EXPECT_EQ(
          std::memcmp(
              two_passes.end_boxes().data(),
              one_pass.end_boxes().data(),
              one_pass.end_boxes().size() * sizeof(WideEndBoxes)),
          0)
          << what;
      if (with_slots) {
        const std::vector<float> a = slot_end_rows(two_passes);
        const std::vector<float> b = slot_end_rows(one_pass);
        ASSERT_EQ(a.size(), 12 * static_cast<std::size_t>(ft.num_triangles()));
        ASSERT_EQ(b.size(), a.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << what;
      } else {
        EXPECT_EQ(one_pass.slot_ends(0), nullptr) << what;
      }
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(two_passes.root_bounds().lo[k], one_pass.root_bounds().lo[k]) << what;
        EXPECT_EQ(two_passes.root_bounds().hi[k], one_pass.root_bounds().hi[k]) << what;
      }
    }
  }
}

// The one pass fills no binary node volumes: on a tree that has them it refuses and changes
// nothing (the end boxes refit_end_boxes gave stay readable, the root is refit()'s).
TEST(NodeRelative, OnePassRefitRefusesATreeWithNodeVolumes) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  Bvh<3> with_nodes(ft.welded_triangles(), m.rest);
  with_nodes.refit(bounds.triangles);
  with_nodes.refit_end_boxes(ft.welded_triangles(), x0, x1, 0.0, true);
  const auto root = with_nodes.root_bounds();
  EXPECT_THROW(
      with_nodes.refit_swept_and_ends(ft.welded_triangles(), x0, x1, true), std::logic_error);
  EXPECT_FALSE(with_nodes.end_boxes().empty());
  EXPECT_NE(with_nodes.slot_ends(0), nullptr);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(with_nodes.root_bounds().lo[k], root.lo[k]);
    EXPECT_EQ(with_nodes.root_bounds().hi[k], root.hi[k]);
  }
}

// Bvh::refit_swept computes each slot's swept volume from its corners where it rounds it, instead
// of reading FeatureBounds::swept_triangles' by triangle id: the slots' and wide nodes' floats and
// the root are refit()'s over those volumes bit for bit, and the slots' diagonal axes are each
// volume's own rounded outwards — on CesiumMan's motion and on coordinates where the rounding has
// edges, for 16-DOPs and AABBs (which have no diagonal rows). A refit() drops the whole slots.
template <int N>
void expect_refit_swept_is_refit_bit_for_bit() {
  const Model m("CesiumMan.glb");
  const FeatureTopology ft(*m.loaded.mesh, m.topology);
  const skinning::Positions x0 = m.sample(0);
  const skinning::Positions x1 = m.sample(20);
  const auto [edgy0, edgy1] = with_edge_coordinates(x0, x1, 5, {2, 1, 1});
  const BvhOptions wide_only{.node_volumes = false};
  constexpr auto kN = static_cast<std::size_t>(N);
  for (const bool edgy : {false, true}) {
    const skinning::Positions& p0 = edgy ? edgy0 : x0;
    const skinning::Positions& p1 = edgy ? edgy1 : x1;
    FeatureBounds<N> swept;
    swept.swept_triangles(ft, p0, p1);
    Bvh<N> stored(ft.welded_triangles(), m.rest, wide_only);
    Bvh<N> computed(ft.welded_triangles(), m.rest, wide_only);
    stored.refit(swept.triangles);
    computed.refit_swept(ft.welded_triangles(), p0, p1);
    EXPECT_FALSE(stored.slot_volumes_whole());
    ASSERT_TRUE(computed.slot_volumes_whole());
    expect_same_float_volumes(stored, computed, std::to_string(edgy));
    for (std::size_t k = 0; k < kN; ++k) {
      EXPECT_EQ(stored.root_bounds().lo[k], computed.root_bounds().lo[k]) << edgy << " " << k;
      EXPECT_EQ(stored.root_bounds().hi[k], computed.root_bounds().hi[k]) << edgy << " " << k;
    }
    // The diagonal rows: each slot's triangle volume rounded outwards, on the axes past three.
    const auto order = computed.triangle_order();
    for (int d = 0; d < Bvh<N>::kSlotDiagonals; ++d) {
      const float* lo = computed.slot_diagonal_lo(d);
      const float* hi = computed.slot_diagonal_hi(d);
      ASSERT_NE(lo, nullptr);
      ASSERT_NE(hi, nullptr);
      EXPECT_EQ(stored.slot_diagonal_lo(d), nullptr);
      for (std::size_t s = 0; s < order.size(); ++s) {
        std::array<float, kN> rlo;
        std::array<float, kN> rhi;
        round_outwards(swept.triangles[static_cast<std::size_t>(order[s])], rlo, rhi);
        const auto k = static_cast<std::size_t>(Bvh<N>::kSlotAxes + d);
        ASSERT_EQ(bits_of(lo[s]), bits_of(rlo[k])) << edgy << " slot " << s << " axis " << k;
        ASSERT_EQ(bits_of(hi[s]), bits_of(rhi[k])) << edgy << " slot " << s << " axis " << k;
      }
    }
    computed.refit(swept.triangles);
    EXPECT_FALSE(computed.slot_volumes_whole());
    if constexpr (Bvh<N>::kSlotDiagonals > 0) {
      EXPECT_EQ(computed.slot_diagonal_lo(0), nullptr);
    }
  }
}

TEST(WholeSlots, RefitSweptIsRefitOverTheSweptVolumesBitForBitOnKdops) {
  expect_refit_swept_is_refit_bit_for_bit<8>();
}

TEST(WholeSlots, RefitSweptIsRefitOverTheSweptVolumesBitForBitOnAabbs) {
  expect_refit_swept_is_refit_bit_for_bit<3>();
}

/// CesiumMan's samples 0 → 20 and the triangles' swept 16-DOPs of that interval.
struct SweptCesiumKdops {
  Model m{"CesiumMan.glb"};
  FeatureTopology ft{*m.loaded.mesh, m.topology};
  skinning::Positions x0 = m.sample(0);
  skinning::Positions x1 = m.sample(20);
  FeatureBounds<8> swept;
  SweptCesiumKdops() { swept.swept_triangles(ft, x0, x1); }
};

// On whole slot volumes the walk tests floats only (no exact volume by triangle id): it keeps every
// pair the exact volumes keep, and each pair more has float volumes (rounded outwards from the
// exact ones) that overlap on every axis — the exact ones then are apart by less than a float
// step. On CesiumMan's 16-DOPs that is a handful of pairs in ten thousands.
TEST(WholeSlots, TheWalkOnWholeSlotsKeepsEveryExactPairAndOnlyFloatStepsMore) {
  const SweptCesiumKdops c;
  const auto& [m, ft, x0, x1, swept] = c;
  Bvh<8> bvh(ft.welded_triangles(), m.rest, BvhOptions{.node_volumes = false});
  const auto walk = [&](std::span<const Dop<8>> bounds) {
    TraversalScratch scratch;
    std::vector<TrianglePair> pairs;
    std::int64_t bv_tests = 0;
    self_traverse<8>(bvh, bounds, scratch, pairs, bv_tests);
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  };
  bvh.refit(swept.triangles);
  const std::vector<TrianglePair> exact = walk(swept.triangles);
  bvh.refit_swept(ft.welded_triangles(), x0, x1);
  const std::vector<TrianglePair> whole = walk({});  // no triangle volumes to read
  ASSERT_GT(exact.size(), 1000u);
  EXPECT_TRUE(std::includes(whole.begin(), whole.end(), exact.begin(), exact.end()));
  std::vector<TrianglePair> more;
  std::set_difference(
      whole.begin(), whole.end(), exact.begin(), exact.end(), std::back_inserter(more));
  EXPECT_LE(more.size() * 1000, exact.size()) << more.size() << " of " << exact.size();
  for (const TrianglePair& p : more) {
    std::array<float, 8> alo, ahi, blo, bhi;
    round_outwards(swept.triangles[static_cast<std::size_t>(p.a)], alo, ahi);
    round_outwards(swept.triangles[static_cast<std::size_t>(p.b)], blo, bhi);
    for (std::size_t k = 0; k < 8; ++k) {
      EXPECT_TRUE(alo[k] <= bhi[k] && blo[k] <= ahi[k]) << p.a << " " << p.b << " axis " << k;
    }
  }
  // A refit() makes the walk read the exact volumes again: the exact pairs.
  bvh.refit(swept.triangles);
  EXPECT_EQ(walk(swept.triangles), exact);
}

// refit_swept fills no binary node volumes: on a tree that has them it refuses and changes nothing.
TEST(WholeSlots, RefitSweptRefusesATreeWithNodeVolumes) {
  const SweptCesiumKdops c;
  const auto& [m, ft, x0, x1, swept] = c;
  Bvh<8> with_nodes(ft.welded_triangles(), m.rest);
  with_nodes.refit(swept.triangles);
  const auto root = with_nodes.root_bounds();
  EXPECT_THROW(with_nodes.refit_swept(ft.welded_triangles(), x0, x1), std::logic_error);
  EXPECT_FALSE(with_nodes.slot_volumes_whole());
  for (std::size_t k = 0; k < 8; ++k) {
    EXPECT_EQ(with_nodes.root_bounds().lo[k], root.lo[k]);
    EXPECT_EQ(with_nodes.root_bounds().hi[k], root.hi[k]);
  }
}

// Two points that meet at t = 1/2, each the only content of a lane, on top of a common motion of
// up to 2^20 and with coordinates from 2^-30 to 2^20 (all sums exact in double): their lanes
// always meet (the rounding of the shifted ends is outwards), whatever the common motion and which
// side is the vector. A point carried with one of them, 4 away on every axis, is told apart
// from it, though their swept boxes overlap whenever the motion exceeds 4: the test prunes.
TEST(NodeRelative, LanesThatMeetInTheRelativeMotionAreNeverToldApart) {
  std::mt19937_64 rng(14);
  std::uniform_int_distribution<int> exponent(-10, 20);
  std::uniform_int_distribution<std::int64_t> mantissa(-(1 << 20), 1 << 20);
  // A dyadic number m · 2^(e − 20), |m| ≤ 2^20: a multiple of 2^-30 of magnitude ≤ 2^20.
  const auto dyadic = [&](int e) { return std::ldexp(static_cast<double>(mantissa(rng)), e - 20); };
  const auto point_lane = [](WideEndBoxes& b, int lane, const double p0[3], const double p1[3]) {
    for (int k = 0; k < 3; ++k) {
      b.lo0[k][lane] = float_below(p0[k]);
      b.hi0[k][lane] = float_above(p0[k]);
      b.lo1[k][lane] = float_below(p1[k]);
      b.hi1[k][lane] = float_above(p1[k]);
    }
  };
  const auto empty = [] {
    WideEndBoxes b;
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 4; ++i) {
        b.lo0[k][i] = b.lo1[k][i] = std::numeric_limits<float>::infinity();
        b.hi0[k][i] = b.hi1[k][i] = -std::numeric_limits<float>::infinity();
      }
    }
    return b;
  };
  int met = 0;
  int apart = 0;
  for (int trial = 0; trial < 100'000; ++trial) {
    // a(t) = a0 + t da, b(t) = b0 + t db with a(1/2) = b(1/2) = c; both carried by T.
    double a0[3], a1[3], b0[3], b1[3], c0[3], c1[3];
    for (int k = 0; k < 3; ++k) {
      const double c = dyadic(exponent(rng));
      const double da = dyadic(exponent(rng));
      const double db = dyadic(exponent(rng));
      const double carry = dyadic(exponent(rng));
      a0[k] = c - da;
      a1[k] = c + da + carry;
      b0[k] = c - db;
      b1[k] = c + db + carry;
      // A third point carried with a, 4 away.
      c0[k] = a0[k] + 4.0;
      c1[k] = a1[k] + 4.0;
    }
    WideEndBoxes w = empty();
    WideEndBoxes q = empty();
    const int lane = trial % 4;
    point_lane(w, lane, a0, a1);
    point_lane(q, 3 - lane, b0, b1);
    EXPECT_EQ(end_boxes_meet(w, q, 3 - lane), 1u << lane) << trial;
    EXPECT_EQ(end_boxes_meet(q, w, lane), 1u << (3 - lane)) << trial;
    met += end_boxes_meet(w, q, 3 - lane) == (1u << lane);
    WideEndBoxes r = empty();
    point_lane(r, 0, c0, c1);
    apart += end_boxes_meet(w, r, 0) == 0u;
  }
  EXPECT_EQ(met, 100'000);
  EXPECT_EQ(apart, 100'000);
}

// A body carried far over one interval while it moves (CesiumMan between two samples of its
// clip, the second shifted by 3 m): `kdop` (which tests node pairs in the relative motion at this
// motion) reports exactly `bvh`'s contacts, some; the pairs of the wide and of the masked binary
// traversals with end boxes are subsets of those without, far fewer, and hold the triangle pair
// of every one of those contacts.
TEST(NodeRelative, ABodyCarriedFarWhileItMovesKeepsItsContactsWithFarFewerPairs) {
  const Model m("CesiumMan.glb");
  const FeatureTopology ft(*m.loaded.mesh, m.topology);
  const skinning::Positions x0 = m.sample(5);
  skinning::Positions x1 = m.sample(25);
  x1.col(0).array() += 3.0;
  x1.col(1).array() -= 0.5;
  EXPECT_GE(motion_scale(ft, x0, x1), kNodeRelativeMotion);
  EXPECT_LT(motion_scale(ft, x0, x0), kNodeRelativeMotion);

  std::vector<CcdContact> reference;
  for (const std::string name : {"bvh", "kdop"}) {
    auto method = make_method(name, *m.loaded.mesh, m.topology);
    FrameResult r;
    method->detect_ccd(x0, x1, r);
    if (name == "bvh") {
      reference = r.contacts;
      EXPECT_GT(reference.size(), 0u);
    } else {
      EXPECT_EQ(r.contacts, reference) << name;
    }
  }
  // The triangle pair each of `bvh`'s contacts comes from (the owners of its two features, as
  // the feature stage derives them): a sound traversal emits every one of them.
  std::vector<TrianglePair> needed;
  for (const CcdContact& c : reference) {
    const std::int32_t ta =
        c.kind == CcdContact::Kind::vf ? ft.vertex_owner(c.a) : ft.edge_owner(c.a);
    const std::int32_t tb = c.kind == CcdContact::Kind::vf ? c.b : ft.edge_owner(c.b);
    needed.push_back({std::min(ta, tb), std::max(ta, tb)});
  }
  std::sort(needed.begin(), needed.end());
  needed.erase(std::unique(needed.begin(), needed.end()), needed.end());
  Bvh<3> bvh(ft.welded_triangles(), m.rest);
  const Traversed plain = traverse(bvh, ft, x0, x1, false);
  const Traversed relative = traverse(bvh, ft, x0, x1, true);
  EXPECT_TRUE(std::includes(
      plain.pairs.begin(), plain.pairs.end(), relative.pairs.begin(), relative.pairs.end()));
  EXPECT_LT(relative.pairs.size() * 4, plain.pairs.size());
  EXPECT_TRUE(
      std::includes(relative.pairs.begin(), relative.pairs.end(), needed.begin(), needed.end()));
  EXPECT_LT(relative.bv_tests * 2, plain.bv_tests);
  // The masked traversal over the binary nodes (radial view's intra- and inter-cluster checks),
  // every triangle "other" (nothing skipped by masks): the same subset, as few.
  {
    std::vector<std::uint8_t> tri_mask(static_cast<std::size_t>(ft.num_triangles()), kMaskOther);
    ClassMasks node_mask;
    node_class_masks<3>(bvh, tri_mask, node_mask);
    FeatureBounds<3> bounds;
    swept_vertex_bounds<3>(x0, x1, 0.0, bounds.vertices);
    bounds.derive(ft, /*with_edges=*/false);
    std::vector<TrianglePair> masked[2];
    for (const bool with_ends : {false, true}) {
      bvh.refit(bounds.triangles);
      if (with_ends) {
        std::vector<NodeEndBoxes> vertices;
        vertex_end_boxes(x0, x1, 0.0, vertices);
        bvh.refit_end_boxes(ft.welded_triangles(), vertices);
      }
      TraversalScratch scratch;
      std::int64_t tests = 0;
      auto& out = masked[with_ends ? 1 : 0];
      masked_self_traverse<3>(
          bvh, bounds.triangles, node_mask, MaskedPairs::tested, scratch, out, tests);
      std::sort(out.begin(), out.end());
    }
    EXPECT_EQ(masked[0], plain.pairs);
    EXPECT_TRUE(
        std::includes(masked[0].begin(), masked[0].end(), masked[1].begin(), masked[1].end()));
    EXPECT_LT(masked[1].size() * 4, masked[0].size());
    EXPECT_TRUE(std::includes(masked[1].begin(), masked[1].end(), needed.begin(), needed.end()));
  }
  // At rest the end boxes are the swept boxes: nothing is pruned.
  const Traversed still = traverse(bvh, ft, x0, x0, false);
  EXPECT_EQ(traverse(bvh, ft, x0, x0, true).pairs, still.pairs);
}

// The leaves' test (Bvh::refit_slot_ends, docs/culling.md "Apart at both ends in the leaves"):
// with the slots' end boxes a self traversal emits the pairs it emitted without them but those
// whose triangles lie apart on an axis at both ends — each one it drops is apart in the exact
// boxes (floats rounded outwards), it drops all but the few a float rounding keeps, it counts
// what it drops, and a refit takes the boxes away.
TEST(NodeRelative, LeavesDropThePairsApartAtBothEndsAndOnlyThose) {
  SweptCesium c;
  auto& [m, ft, x0, x1, bvh, bounds] = c;
  const auto run = [&](bool slot_ends, std::int64_t& dropped) {
    bvh.refit(bounds.triangles);
    EXPECT_EQ(bvh.slot_ends(0), nullptr) << "a refit drops the slot end boxes";
    if (slot_ends) {
      std::vector<NodeEndBoxes> vertices;
      vertex_end_boxes(x0, x1, 0.0, vertices);
      bvh.refit_slot_ends(ft.welded_triangles(), vertices);
      EXPECT_NE(bvh.slot_ends(11), nullptr);
    }
    TraversalScratch scratch;
    std::vector<TrianglePair> pairs;
    std::int64_t bv_tests = 0;
    self_traverse<3>(bvh, bounds.triangles, scratch, pairs, bv_tests);
    dropped = scratch.apart_at_both_ends;
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  };
  // Apart on an axis at both ends, in the exact boxes of the two triangles' corners.
  const auto apart = [&](const TrianglePair& p) {
    for (int k = 0; k < 3; ++k) {
      double lo[2][2], hi[2][2];  // [triangle][time]
      for (int which = 0; which < 2; ++which) {
        const auto& t = ft.triangle(which == 0 ? p.a : p.b);
        for (int time = 0; time < 2; ++time) {
          const skinning::Positions& x = time == 0 ? x0 : x1;
          lo[which][time] = std::min({x(t[0], k), x(t[1], k), x(t[2], k)});
          hi[which][time] = std::max({x(t[0], k), x(t[1], k), x(t[2], k)});
        }
      }
      if ((hi[0][0] < lo[1][0] && hi[0][1] < lo[1][1]) ||
          (hi[1][0] < lo[0][0] && hi[1][1] < lo[0][1])) {
        return true;
      }
    }
    return false;
  };
  std::int64_t none = -1;
  const std::vector<TrianglePair> all = run(false, none);
  EXPECT_EQ(none, 0);
  std::int64_t dropped = -1;
  const std::vector<TrianglePair> kept = run(true, dropped);
  EXPECT_EQ(static_cast<std::int64_t>(all.size() - kept.size()), dropped);
  EXPECT_TRUE(std::includes(all.begin(), all.end(), kept.begin(), kept.end()));
  std::int64_t apart_all = 0;
  std::int64_t apart_kept = 0;
  for (const auto& p : all) apart_all += apart(p) ? 1 : 0;
  for (const auto& p : kept) apart_kept += apart(p) ? 1 : 0;
  // Every dropped pair is apart; of the apart ones, the float boxes keep at most 1 %.
  EXPECT_EQ(apart_all - apart_kept, dropped);
  EXPECT_GT(dropped, static_cast<std::int64_t>(all.size() / 10)) << all.size();
  EXPECT_LE(apart_kept * 100, apart_all);
}

// `bvh` and `kdop` build the slots' end boxes when the last interval had two pairs apart at both
// ends per triangle, or once this one has (between the traversal's installments): the same rows
// whichever way. The same interval four times on one method — the first from a method that never
// had them, the second after an interval where they paid, the last after one where they did not
// (no motion) — gives the same counters and contacts each time.
TEST(NodeRelative, TheLeavesEndBoxesChangeNoCounterWhenEverTheyAreBuilt) {
  const Model m("CesiumMan.glb");
  const skinning::Positions x0 = m.sample(0);
  const skinning::Positions x1 = m.sample(20);
  const auto same = [](const FrameResult& a, const FrameResult& b) {
    EXPECT_EQ(a.contacts, b.contacts);
    // Every counter of the row (frame_result.hpp's list).
#define SKELCD_EXPECT_COUNTER(name, meaning) EXPECT_EQ(a.counters.name, b.counters.name) << #name;
    SKELCD_COUNTERS(SKELCD_EXPECT_COUNTER)
#undef SKELCD_EXPECT_COUNTER
  };
  for (const std::string name : {"bvh", "kdop"}) {
    auto method = make_method(name, *m.loaded.mesh, m.topology);
    const auto ccd = [&](const skinning::Positions& a, const skinning::Positions& b) {
      FrameResult r;
      method->detect_ccd(a, b, r);
      return r;
    };
    const FrameResult first = ccd(x0, x1);
    EXPECT_GT(first.contacts.size(), 0u) << name;
    same(ccd(x0, x1), first);
    EXPECT_TRUE(ccd(x0, x0).contacts.empty()) << name;
    same(ccd(x0, x1), first);
  }
}

}  // namespace
}  // namespace skelcd::culling
