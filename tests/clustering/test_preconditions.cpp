// What the radial-view argument does not cover, on a hand-made closed mesh with one cluster seen
// from one fixed point: a U-shaped slab whose upper arm is pushed down through its lower arm.
// - Clean start: the argument guarantees the *first* contact (the upper arm's underside, H⁻,
//   meeting the lower arm's top, H⁺) but not the later ones between two H⁺ faces (the upper
//   arm's top passing the lower arm's top). Bare, the method misses those; guarded, it re-tests
//   the skipped pairs of a component with a self-contact and matches `brute`.
// - Intersecting start: the argument does not apply at all. Guarded, the DCD pass at the start
//   marks the component and nothing is skipped there.
// docs/radial-view.md ("Preconditions") explains both.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <memory>

#include "clustering/radial_view_method.hpp"
#include "culling/method.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace skelcd::clustering {
namespace {

using V3 = Eigen::Vector3d;

struct USlab {
  skinning::Mesh mesh;
  skinning::Topology topology;
  std::vector<bool> upper;  ///< #V: vertex of the upper half (moves)
};

/// The cross-section P0 … P7 (x, z), counter-clockwise: a U lying on its side, arms along x,
/// the bridge at x in [lb, l], extruded along y in [0, w] with `strips` strips. Outward normals.
USlab make_slab(int strips) {
  const double l = 4.0, lb = 3.2, w = 2.0;
  const std::array<std::array<double, 2>, 8> p{
      {{0, 0}, {l, 0}, {l, 1}, {0, 1}, {0, 0.8}, {lb, 0.8}, {lb, 0.2}, {0, 0.2}}};
  USlab s;
  std::vector<V3> vs;
  std::vector<std::array<std::int32_t, 3>> fs;
  const auto id = [&](int corner, int level) { return level * 8 + corner; };
  for (int level = 0; level <= strips; ++level) {
    const double y = w * level / strips;
    for (const auto& c : p) vs.emplace_back(c[0], y, c[1]);
  }
  // Sides: quad (A, B, C, D) = (Pi at y_k, Pj at y_k, Pj at y_k+1, Pi at y_k+1), faces (A,C,B),
  // (A,D,C) point outwards for a counter-clockwise section.
  for (int i = 0; i < 8; ++i) {
    const int j = (i + 1) % 8;
    for (int k = 0; k < strips; ++k) {
      const int a = id(i, k), b = id(j, k), c = id(j, k + 1), d = id(i, k + 1);
      fs.push_back({a, c, b});
      fs.push_back({a, d, c});
    }
  }
  // Caps: the section in three convex pieces; counter-clockwise in (x, z) faces −y at y = 0.
  const std::array<std::array<int, 3>, 6> cap{
      {{0, 1, 6}, {0, 6, 7}, {1, 2, 5}, {1, 5, 6}, {2, 3, 4}, {2, 4, 5}}};
  for (const auto& t : cap) {
    fs.push_back({id(t[0], 0), id(t[1], 0), id(t[2], 0)});
    fs.push_back({id(t[0], strips), id(t[2], strips), id(t[1], strips)});
  }
  auto& m = s.mesh;
  m.rest_positions.resize(static_cast<Eigen::Index>(vs.size()), 3);
  for (std::size_t i = 0; i < vs.size(); ++i) m.rest_positions.row(static_cast<Eigen::Index>(i)) = vs[i];
  m.triangles.resize(static_cast<Eigen::Index>(fs.size()), 3);
  for (std::size_t f = 0; f < fs.size(); ++f) {
    for (int k = 0; k < 3; ++k) m.triangles(static_cast<Eigen::Index>(f), k) = fs[f][static_cast<std::size_t>(k)];
  }
  m.face_part.assign(fs.size(), 0);
  m.face_index_in_part.resize(fs.size());
  for (std::size_t f = 0; f < fs.size(); ++f) m.face_index_in_part[f] = static_cast<std::int32_t>(f);
  m.vertex_part.assign(vs.size(), 0);
  m.vertex_index_in_part.resize(vs.size());
  for (std::size_t v = 0; v < vs.size(); ++v) m.vertex_index_in_part[v] = static_cast<std::int32_t>(v);
  m.part_names = {"slab"};
  s.topology = skinning::build_topology(m);
  for (const auto& v : vs) s.upper.push_back(v.z() > 0.5);
  return s;
}

/// A finer U-slab (the same section, gridded: cells of 0.2 × 0.2 in (x, z), `strips` strips of
/// width 1/strips along y in [0, 1]), so that patches of the surface lie away from its cuts: the
/// section is the union of the cells inside the U, the caps are those cells, the sides their
/// boundary edges extruded. Outward, closed, one component.
/// `hole`: (cell i, strip) of the upper arm's underside left out (a hole in the surface).
USlab make_grid_slab(int strips, const std::vector<std::array<int, 2>>& hole = {}) {
  constexpr int nx = 20, nz = 5;
  const auto inside = [&](int i, int k) {
    if (i < 0 || k < 0 || i >= nx || k >= nz) return false;
    const double xc = 0.2 * (i + 0.5), zc = 0.2 * (k + 0.5);
    return zc < 0.2 || zc > 0.8 || xc > 3.2;
  };
  USlab s;
  std::vector<V3> vs;
  std::vector<std::array<std::int32_t, 3>> fs;
  std::map<std::array<int, 3>, std::int32_t> ids;
  const auto id = [&](int i, int k, int level) {
    const auto [it, added] = ids.try_emplace({i, k, level}, static_cast<std::int32_t>(vs.size()));
    if (added) vs.emplace_back(0.2 * i, static_cast<double>(level) / strips, 0.2 * k);
    return it->second;
  };
  for (int i = 0; i < nx; ++i) {
    for (int k = 0; k < nz; ++k) {
      if (!inside(i, k)) continue;
      // Corners counter-clockwise in (x, z): the cap at y = 0 faces −y, the one at y = 1 +y.
      const std::array<std::array<int, 2>, 4> c{{{i, k}, {i + 1, k}, {i + 1, k + 1}, {i, k + 1}}};
      const auto at = [&](int corner, int level) {
        return id(
            c[static_cast<std::size_t>(corner)][0], c[static_cast<std::size_t>(corner)][1], level);
      };
      fs.push_back({at(0, 0), at(1, 0), at(2, 0)});
      fs.push_back({at(0, 0), at(2, 0), at(3, 0)});
      fs.push_back({at(0, strips), at(2, strips), at(1, strips)});
      fs.push_back({at(0, strips), at(3, strips), at(2, strips)});
      // Boundary edges (P → Q counter-clockwise, the neighbour across it outside), extruded.
      const std::array<std::array<int, 2>, 4> across{
          {{i, k - 1}, {i + 1, k}, {i, k + 1}, {i - 1, k}}};
      for (int e = 0; e < 4; ++e) {
        if (inside(
                across[static_cast<std::size_t>(e)][0], across[static_cast<std::size_t>(e)][1])) {
          continue;
        }
        for (int level = 0; level < strips; ++level) {
          const bool underside = k == 4 && e == 0;
          if (underside &&
              std::find(hole.begin(), hole.end(), std::array<int, 2>{i, level}) != hole.end()) {
            continue;
          }
          const std::int32_t a = at(e, level), b = at((e + 1) % 4, level);
          const std::int32_t cc = at((e + 1) % 4, level + 1), d = at(e, level + 1);
          fs.push_back({a, cc, b});
          fs.push_back({a, d, cc});
        }
      }
    }
  }
  skinning::Positions x(static_cast<Eigen::Index>(vs.size()), 3);
  for (std::size_t i = 0; i < vs.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = vs[i];
  skinning::Triangles t(static_cast<Eigen::Index>(fs.size()), 3);
  for (std::size_t f = 0; f < fs.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      t(static_cast<Eigen::Index>(f), k) = fs[f][static_cast<std::size_t>(k)];
    }
  }
  s.mesh = test::single_part_mesh(std::move(x), std::move(t), "grid slab");
  s.topology = skinning::build_topology(s.mesh);
  for (const auto& v : vs) s.upper.push_back(v.z() > 0.5);
  return s;
}

/// Positions with the upper half moved by `shift`.
skinning::Positions moved(const USlab& s, const V3& shift) {
  skinning::Positions x = s.mesh.rest_positions;
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    if (s.upper[static_cast<std::size_t>(v)]) x.row(v) += shift.transpose();
  }
  return x;
}

/// One cluster, one bone far below the slab, a point observer at its middle.
std::shared_ptr<const segmentation::Segmentation> one_cluster(const USlab& s) {
  auto seg = std::make_shared<segmentation::Segmentation>();
  const auto nf = static_cast<std::size_t>(s.mesh.num_triangles());
  seg->triangle_cluster.assign(nf, 0);
  segmentation::AtomicCluster c;
  c.bone = 0;
  c.observer.kind = segmentation::ObserverKind::point;
  c.observer.segment.head = V3(2.0, 1.0, -60.0);
  c.observer.segment.tail = V3(2.0, 1.0, -40.0);
  for (std::size_t f = 0; f < nf; ++f) c.triangles.push_back(static_cast<std::int32_t>(f));
  seg->clusters.push_back(c);
  return seg;
}

std::shared_ptr<BonePoses> still_bone() {
  auto poses = std::make_shared<BonePoses>();
  const std::vector<skinning::BoneTransform> identity{skinning::BoneTransform::Identity()};
  poses->set(identity, identity);
  return poses;
}

using Keys = std::vector<std::tuple<int, std::int32_t, std::int32_t>>;
Keys keys(const culling::FrameResult& r) {
  Keys k;
  for (const auto& c : r.contacts) k.emplace_back(static_cast<int>(c.kind), c.a, c.b);
  return k;
}

struct Runs {
  culling::FrameResult brute, guarded, bare;
  RadialViewStats guarded_stats, bare_stats;
};

/// brute, then rvbc guarded and bare (one cluster, the observer below), from file-vertex positions
/// p0 to p1.
Runs run_positions(const USlab& s, const skinning::Positions& p0, const skinning::Positions& p1) {
  skinning::Positions x0, x1;
  skinning::gather_welded(s.topology, p0, x0);
  skinning::gather_welded(s.topology, p1, x1);
  Runs r;
  culling::make_method("brute", s.mesh, s.topology)->detect_ccd(x0, x1, r.brute);
  const auto seg = one_cluster(s);
  const auto poses = still_bone();
  for (const bool guard : {true, false}) {
    RadialViewOptions o;
    o.clusters.merge = false;
    o.guard = guard;
    RadialViewMethod m("rvbc", s.mesh, s.topology, seg, poses, 1, {}, o);
    m.detect_ccd(x0, x1, guard ? r.guarded : r.bare);
    (guard ? r.guarded_stats : r.bare_stats) = m.last_stats();
  }
  return r;
}

Runs run_all(const USlab& s, const V3& shift_t0, const V3& shift_t1) {
  return run_positions(s, moved(s, shift_t0), moved(s, shift_t1));
}

TEST(Preconditions, SlabIsAClosedConsistentlyOrientedComponent) {
  const USlab s = make_slab(4);
  ASSERT_EQ(s.topology.components.size(), 1u);
  EXPECT_TRUE(s.topology.components[0].closed);
  const auto seg = one_cluster(s);
  const ClusterSet clusters(s.mesh, s.topology, *seg, 1);
  EXPECT_TRUE(clusters.component_ok(0));
  // Outward: the enclosed volume (divergence theorem) is the section's area times the width.
  double volume = 0;
  for (Eigen::Index f = 0; f < s.mesh.num_triangles(); ++f) {
    const V3 a = s.mesh.rest_positions.row(s.mesh.triangles(f, 0));
    const V3 b = s.mesh.rest_positions.row(s.mesh.triangles(f, 1));
    const V3 c = s.mesh.rest_positions.row(s.mesh.triangles(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(volume, (4.0 * 1.0 - 3.2 * 0.6) * 2.0, 1e-12);
}

TEST(Preconditions, OnlyTheFirstContactIsGuaranteed) {
  const USlab s = make_slab(4);
  // The upper arm goes down (and a little sideways, so that contacts are generic) through the
  // lower arm within one interval; the slab is free of self-intersection at t = 0.
  const Runs r = run_all(s, V3::Zero(), V3(-0.3, 0.07, -0.9));
  ASSERT_FALSE(r.brute.contacts.empty());
  // Bare radial view: a strict subset of the contacts (H⁺ against H⁺ of one cluster are lost).
  const Keys all = keys(r.brute);
  const Keys bare = keys(r.bare);
  EXPECT_LT(bare.size(), all.size());
  EXPECT_FALSE(bare.empty());  // ... but the first contact is there, as the theory says
  EXPECT_TRUE(std::includes(all.begin(), all.end(), bare.begin(), bare.end()));
  // Guarded: the self-contact sends the skipped pairs to the tests; everything is found.
  EXPECT_EQ(keys(r.guarded), all);
  EXPECT_EQ(r.guarded_stats.components_dcd, 1);  // no earlier interval: proven clean at t = 0
  EXPECT_EQ(r.guarded_stats.components_dirty, 0);
  EXPECT_EQ(r.guarded_stats.components_escalated, 1);
  EXPECT_EQ(r.guarded_stats.escalation_contacts,
            static_cast<std::int64_t>(all.size() - bare.size()));
}

TEST(Preconditions, IntersectingStartIsDetected) {
  const USlab s = make_slab(4);
  // At t = 0 the upper arm's underside is already below the lower arm's top.
  const Runs r = run_all(s, V3(-0.1, 0.02, -0.65), V3(-0.3, 0.07, -0.9));
  ASSERT_FALSE(r.brute.contacts.empty());
  EXPECT_EQ(keys(r.guarded), keys(r.brute));
  EXPECT_EQ(r.guarded_stats.components_dirty, 1);
  // The local guard keeps the cut triangles (and their patches' rims) out of the skipped pairs.
  EXPECT_GT(r.guarded_stats.triangles_cut, 0);
  EXPECT_GE(r.guarded_stats.triangles_kept_out, r.guarded_stats.triangles_cut);
  EXPECT_LT(keys(r.bare).size(), keys(r.brute).size());
}

TEST(Preconditions, NoContactNoWork) {
  // The upper arm moves down but stops short of the lower one: nothing to find, nothing
  // escalated, and the H⁺ × H⁺ pairs are skipped.
  const USlab s = make_slab(4);
  const Runs r = run_all(s, V3::Zero(), V3(0.05, 0.0, -0.3));
  EXPECT_TRUE(r.brute.contacts.empty());
  EXPECT_TRUE(r.guarded.contacts.empty());
  EXPECT_EQ(r.guarded_stats.components_escalated, 0);
  EXPECT_EQ(r.guarded_stats.components_culled, 1);
  EXPECT_LT(r.guarded.counters.candidate_pairs, r.brute.counters.candidate_pairs);
}

TEST(Preconditions, SkinInsideAnOverlapIsNotSkippedAgainstTheOuterSkin) {
  // The local guard's winding rule (docs/radial-view.md, "The local guard"): the upper arm of a
  // gridded U-slab is sunk into the lower arm at t = 0 (the bridge blends between them), so the
  // arm's underside lies inside the lower arm — a patch whose front winding number is 1, not the
  // outer skin's 0. During the interval only a bump in the middle of the lower arm's bottom rises
  // through that underside. Both faces face away from the observer below (H⁻) and, seen along a
  // ray, nothing lies between them: the alternation the theorem needs fails there, and no other
  // contact happens anywhere to trigger a re-test. Skipping by class alone (as if the underside
  // were outer skin) loses these contacts; the guard keeps the underside's patch out.
  const USlab s = make_grid_slab(10);
  ASSERT_EQ(s.topology.components.size(), 1u);
  ASSERT_TRUE(s.topology.components[0].closed);
  skinning::Positions p0 = s.mesh.rest_positions;
  for (Eigen::Index v = 0; v < p0.rows(); ++v) {
    const double t = std::clamp((p0(v, 2) - 0.2) / 0.6, 0.0, 1.0);
    p0.row(v) += t * V3(-0.1, 0.13, -0.73).transpose();
  }
  skinning::Positions p1 = p0;
  int bump = 0;
  for (Eigen::Index v = 0; v < p1.rows(); ++v) {
    const V3 r = s.mesh.rest_positions.row(v);
    const double d2 = (r.x() - 1.0) * (r.x() - 1.0) + (r.y() - 0.5) * (r.y() - 0.5);
    if (r.z() != 0.0 || d2 >= 0.35 * 0.35) continue;
    p1(v, 2) += 0.12 * (1.0 - d2 / (0.35 * 0.35));
    ++bump;
  }
  ASSERT_GT(bump, 10);
  const Runs r = run_positions(s, p0, p1);
  ASSERT_FALSE(r.brute.contacts.empty());
  const RadialViewStats& stats = r.guarded_stats;
  EXPECT_EQ(keys(r.guarded), keys(r.brute));
  EXPECT_EQ(stats.components_dirty, 1);
  EXPECT_EQ(stats.components_culled, 1);
  EXPECT_GT(stats.patches_classified, 1);
  // More kept out than the cut triangles: the off-value patches (the underside inside the lower
  // arm, the lower arm's top inside the upper one).
  EXPECT_GT(stats.triangles_kept_out, stats.triangles_cut + 40);
  EXPECT_EQ(stats.escalation_contacts, 0);  // found by the first pass, not by a re-test
  // Bare (everything of one class skipped), the contacts are lost: the test above can fail.
  EXPECT_LT(keys(r.bare).size(), keys(r.brute).size());
}

TEST(Preconditions, AGhostCapIsTheEnteringSheetAndItsContactTriggersTheRetest) {
  // The ghost caps' role in the proof (docs/radial-view.md, "Open parts with ghost triangles"):
  // the upper arm's underside has a hole, capped by a ghost fan. A spike rises from the lower arm's
  // top through the hole, without touching its rim, into the upper arm, and meets the upper arm's
  // top from inside. The spike's faces and the top face away from the observer below (H⁺), so
  // their pairs are skipped; seen along a ray the only sheet between them is the ghost cap, and
  // the spike's contacts with the ghost are the only ones that can trigger the re-test. Ghost
  // contacts are never reported, but they must escalate.
  const USlab s = make_grid_slab(10, {{{4, 4}, {5, 4}, {4, 5}, {5, 5}}});
  ASSERT_EQ(s.topology.components.size(), 1u);
  ASSERT_EQ(s.topology.boundary_loops.size(), 1u);
  skinning::Positions p0 = s.mesh.rest_positions;
  for (Eigen::Index v = 0; v < p0.rows(); ++v) {
    const double t = std::clamp((p0(v, 2) - 0.2) / 0.6, 0.0, 1.0);
    p0.row(v) += t * V3(0.03, 0.02, 0.0).transpose();  // the hole around the spike, off its centre
  }
  skinning::Positions p1 = p0;
  int spikes = 0;
  for (Eigen::Index v = 0; v < p1.rows(); ++v) {
    const V3 r = s.mesh.rest_positions.row(v);
    if (std::abs(r.x() - 1.0) < 1e-12 && std::abs(r.y() - 0.5) < 1e-12 &&
        std::abs(r.z() - 0.2) < 1e-12) {
      p1(v, 2) = 1.05;
      ++spikes;
    }
  }
  ASSERT_EQ(spikes, 1);
  const Runs r = run_positions(s, p0, p1);
  ASSERT_FALSE(r.brute.contacts.empty());
  const RadialViewStats& stats = r.guarded_stats;
  EXPECT_EQ(keys(r.guarded), keys(r.brute));
  EXPECT_EQ(stats.ghost_loops, 1);
  EXPECT_EQ(stats.components_open, 0);
  EXPECT_EQ(stats.components_culled, 1);
  EXPECT_GT(stats.ghost_contacts, 0);       // the spike through the cap: used, not reported
  EXPECT_GT(stats.escalation_contacts, 0);  // the spike against the top: found by the re-test
  EXPECT_LT(keys(r.bare).size(), keys(r.brute).size());
}

}  // namespace
}  // namespace skelcd::clustering
