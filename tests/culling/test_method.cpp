// The methods behind make_method: hand-made cases with a known number of contacts, and `brute`,
// `bvh`, `kdop` agreeing on generated meshes with known collisions (DCD pairs and CCD VF/EE).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "culling/method.hpp"
#include "skinning/errors.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using ccd::Accuracy;

/// The methods of this issue (later issues add more names to method_names()).
const std::vector<std::string> kBaselines{"brute", "bvh", "kdop"};

FrameResult run_ccd(
    std::string_view method,
    const skinning::Mesh& mesh,
    const skinning::Topology& topo,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const MethodOptions& options = {}) {
  auto m = make_method(method, mesh, topo, options);
  FrameResult out;
  m->detect_ccd(x_t0, x_t1, out);
  return out;
}

FrameResult run_dcd(
    std::string_view method,
    const skinning::Mesh& mesh,
    const skinning::Topology& topo,
    const skinning::Positions& x,
    const MethodOptions& options = {}) {
  auto m = make_method(method, mesh, topo, options);
  FrameResult out;
  m->detect_dcd(x, out);
  return out;
}

// --- the interface -----------------------------------------------------------------------------

TEST(Method, NamesAndFactory) {
  const auto names = method_names();
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 3), kBaselines);
  const auto mesh = test::sheet(2, 2);
  const auto topo = test::simple_topology(mesh);
  for (const auto& name : names) EXPECT_EQ(make_method(name, mesh, topo)->name(), name);
  EXPECT_THROW_MESSAGE(
      (void)make_method("octree", mesh, topo),
      InvalidInput,
      "unknown method 'octree' (known: brute, bvh, kdop");
}

TEST(Method, RejectsBadOptionsAndPositions) {
  const auto mesh = test::sheet(2, 2);
  const auto topo = test::simple_topology(mesh);
  EXPECT_THROW_MESSAGE(
      (void)make_method("bvh", mesh, topo, {.min_separation = -1.0}),
      InvalidInput,
      "min_separation");
  EXPECT_THROW_MESSAGE(
      (void)make_method("bvh", mesh, topo, {.min_separation = std::nan("")}),
      InvalidInput,
      "min_separation");
  EXPECT_THROW_MESSAGE(
      (void)make_method("kdop", mesh, topo, {.accuracy = Accuracy::exact, .min_separation = 0.1}),
      InvalidInput,
      "exact");
  EXPECT_THROW_MESSAGE(
      (void)make_method("bvh", mesh, topo, {.bvh = {.leaf_size = 0}}), InvalidInput, "leaf_size");
  auto m = make_method("kdop", mesh, topo);
  FrameResult out;
  const skinning::Positions few(3, 3);
  EXPECT_THROW_MESSAGE(
      m->detect_dcd(few, out),
      InvalidInput,
      "culling::kdop::detect_dcd: x has 3 rows, expected one per welded vertex (9)");
  const skinning::Positions x = test::welded(topo, mesh.rest_positions);
  EXPECT_THROW_MESSAGE(m->detect_ccd(x, few, out), InvalidInput, "x_t1 has 3 rows");
}

// --- hand-made cases with a known answer ---------------------------------------------------------

/// Part 0: triangle (0,0,0) (1,0,0) (0,1,0). Part 1: a thin triangle standing above (0.2, 0.2)
/// whose bottom vertex p moves from z = +0.5 to z = −0.5 straight through part 0's interior; its
/// other two vertices stay 2 above p, offset by 0.05 so its edges cross the plane z = 0 inside
/// part 0 too. Exactly one contact: VF (p, triangle 0), at t = 0.5.
struct VertexThroughTriangle {
  skinning::Mesh mesh;
  skinning::Topology topo;
  skinning::Positions x_t0, x_t1;
  VertexThroughTriangle() {
    skinning::Positions a(3, 3);
    a << 0, 0, 0, 1, 0, 0, 0, 1, 0;
    skinning::Positions b(3, 3);
    b << 0.2, 0.2, 0.5, 0.25, 0.2, 2.5, 0.2, 0.25, 2.5;
    skinning::Triangles f(1, 3);
    f << 0, 1, 2;
    mesh = test::combine(test::single_part_mesh(a, f), test::single_part_mesh(b, f));
    topo = test::simple_topology(mesh);
    x_t0 = test::welded(topo, mesh.rest_positions);
    x_t1 = x_t0;
    x_t1.bottomRows(3).col(2).array() -= 1.0;
  }
};

TEST(Method, VertexThroughOneTriangleIsExactlyOneVfContact) {
  const VertexThroughTriangle c;
  for (const auto& name : kBaselines) {
    for (const Accuracy acc : {Accuracy::exact, Accuracy::conservative}) {
      const FrameResult r = run_ccd(name, c.mesh, c.topo, c.x_t0, c.x_t1, {.accuracy = acc});
      SCOPED_TRACE(name + " " + std::string(ccd::to_string(acc)));
      ASSERT_EQ(r.contacts.size(), 1u);
      EXPECT_EQ(r.contacts[0].kind, CcdContact::Kind::vf);
      EXPECT_EQ(r.contacts[0].a, 3);  // p: the first vertex of part 1 (welded ids keep order)
      EXPECT_EQ(r.contacts[0].b, 0);
      // The time of impact is bracketed (tightly by the exact test).
      EXPECT_LE(r.contacts[0].toi_lower, 0.5);
      EXPECT_GE(r.contacts[0].toi_upper, 0.5);
      if (acc == Accuracy::exact) {
        EXPECT_NEAR(r.contacts[0].toi_lower, 0.5, 1e-9);
      }
      EXPECT_EQ(r.counters.vf_contacts, 1);
      EXPECT_EQ(r.counters.ee_contacts, 0);
      EXPECT_GE(r.counters.vf_tests, 1);
    }
  }
}

TEST(Method, VertexStoppingShortOfTheTriangleIsNoContact) {
  VertexThroughTriangle c;
  c.x_t1 = c.x_t0;
  c.x_t1.bottomRows(3).col(2).array() -= 0.4999;  // p ends 1e-4 above the plane
  for (const auto& name : kBaselines) {
    const FrameResult r = run_ccd(name, c.mesh, c.topo, c.x_t0, c.x_t1);
    EXPECT_TRUE(r.contacts.empty()) << name;
    // ...unless the contact distance reaches it.
    const FrameResult near =
        run_ccd(name, c.mesh, c.topo, c.x_t0, c.x_t1, {.min_separation = 2e-4});
    ASSERT_EQ(near.contacts.size(), 1u) << name;
    EXPECT_EQ(near.contacts[0].kind, CcdContact::Kind::vf);
  }
}

/// Part 0: triangle (−1,0,0) (1,0,0) (0,0,−1) in the plane y = 0; its edge along the x axis.
/// Part 1: triangle (0,−1,z) (0,1,z) (0,0,z+1) in the plane x = 0, moving from z = 0.5 to −0.5:
/// its bottom edge (along y) crosses part 0's top edge at the origin at t = 0.5. No vertex meets
/// a face. Exactly one contact: EE.
TEST(Method, EdgeCrossingAnEdgeIsExactlyOneEeContact) {
  skinning::Positions a(3, 3);
  a << -1, 0, 0, 1, 0, 0, 0, 0, -1;
  skinning::Positions b(3, 3);
  b << 0, -1, 0.5, 0, 1, 0.5, 0, 0, 1.5;
  skinning::Triangles f(1, 3);
  f << 0, 1, 2;
  const auto mesh = test::combine(test::single_part_mesh(a, f), test::single_part_mesh(b, f));
  const auto topo = test::simple_topology(mesh);
  const skinning::Positions x_t0 = test::welded(topo, mesh.rest_positions);
  skinning::Positions x_t1 = x_t0;
  x_t1.bottomRows(3).col(2).array() -= 1.0;
  // The two crossing edges, by their welded endpoints.
  const auto edge_id = [&](std::int32_t u, std::int32_t v) {
    for (Eigen::Index e = 0; e < topo.edges.rows(); ++e) {
      if (topo.edges(e, 0) == std::min(u, v) && topo.edges(e, 1) == std::max(u, v)) {
        return static_cast<std::int32_t>(e);
      }
    }
    return -1;
  };
  const std::int32_t ea = edge_id(0, 1);
  const std::int32_t eb = edge_id(3, 4);
  for (const auto& name : kBaselines) {
    for (const Accuracy acc : {Accuracy::exact, Accuracy::conservative}) {
      const FrameResult r = run_ccd(name, mesh, topo, x_t0, x_t1, {.accuracy = acc});
      SCOPED_TRACE(name + " " + std::string(ccd::to_string(acc)));
      ASSERT_EQ(r.contacts.size(), 1u);
      EXPECT_EQ(r.contacts[0].kind, CcdContact::Kind::ee);
      EXPECT_EQ(r.contacts[0].a, std::min(ea, eb));
      EXPECT_EQ(r.contacts[0].b, std::max(ea, eb));
      EXPECT_LE(r.contacts[0].toi_lower, 0.5);
      EXPECT_GE(r.contacts[0].toi_upper, 0.5);
      if (acc == Accuracy::exact) {
        EXPECT_NEAR(r.contacts[0].toi_lower, 0.5, 1e-9);
      }
      EXPECT_EQ(r.counters.ee_contacts, 1);
      EXPECT_EQ(r.counters.vf_contacts, 0);
    }
    // At rest apart, and at the crossing instant the triangles touch: one DCD pair then.
    EXPECT_TRUE(run_dcd(name, mesh, topo, x_t0).dcd_pairs.empty()) << name;
    const skinning::Positions x_half = 0.5 * (x_t0 + x_t1);
    EXPECT_EQ(run_dcd(name, mesh, topo, x_half).dcd_pairs, (std::vector<TrianglePair>{{0, 1}}))
        << name;
  }
}

TEST(Method, ExcludedPartPairIsNeverReported) {
  VertexThroughTriangle c;
  c.mesh.excluded_part_pairs = {{0, 1}};
  for (const auto& name : kBaselines) {
    const FrameResult r = run_ccd(name, c.mesh, c.topo, c.x_t0, c.x_t1);
    EXPECT_TRUE(r.contacts.empty()) << name;
    EXPECT_EQ(r.counters.vf_tests + r.counters.ee_tests, 0) << name;
  }
}

/// Two triangles sharing vertex 0 (a fan of two): folded so that the second passes through the
/// first away from the shared vertex. DCD must report them (the shared corner is not their only
/// common point); flat, sharing only the vertex, they do not intersect.
TEST(Method, DcdReportsTrianglesSharingAVertexOnlyWhenTheyCrossBeyondIt) {
  skinning::Positions x(5, 3);
  x << 0, 0, 0,                 // shared
      2, -1, 0, 2, 1, 0,        // triangle 0 in z = 0
      1.5, 0, -1, 1.5, 0.2, 1;  // triangle 1 stands across triangle 0
  skinning::Triangles f(2, 3);
  f << 0, 1, 2, 0, 3, 4;
  const auto mesh = test::single_part_mesh(x, f);
  const auto topo = test::simple_topology(mesh);
  skinning::Positions flat = x;
  flat.row(3) << -2, -1, 0;
  flat.row(4) << -2, 1, 0;
  for (const auto& name : kBaselines) {
    EXPECT_EQ(run_dcd(name, mesh, topo, x).dcd_pairs, (std::vector<TrianglePair>{{0, 1}})) << name;
    const FrameResult r = run_dcd(name, mesh, topo, flat);
    EXPECT_TRUE(r.dcd_pairs.empty()) << name;
    EXPECT_EQ(r.counters.tt_tests, 1) << name << ": the shared-vertex pair is tested, not skipped";
  }
}

// --- methods agree on generated meshes with known collisions -------------------------------------

struct Scene {
  std::string name;
  skinning::Mesh mesh;
  skinning::Topology topo;
  std::vector<skinning::Positions> samples;  // DCD at each, CCD between consecutive ones
  bool exact_too = true;                     // also run the (slow, GMP) exact accuracy
};

std::vector<Scene> scenes() {
  std::vector<Scene> out;
  {
    auto a = test::uv_sphere(7, 9, 1.0);
    auto b = test::uv_sphere(6, 8, 0.8);
    b.rest_positions = test::translated(b.rest_positions, Eigen::Vector3d(2.2, 0.05, 0.03));
    Scene s{"sphere moving into another", test::combine(a, b), {}, {}};
    s.topo = test::simple_topology(s.mesh);
    const auto x = test::welded(s.topo, s.mesh.rest_positions);
    for (const double shift : {0.0, 0.3, 0.6, 0.9}) {
      skinning::Positions y = x;
      for (Eigen::Index v = 0; v < y.rows(); ++v) {
        if (x(v, 0) > 1.3) y(v, 0) -= shift;
      }
      s.samples.push_back(y);
    }
    out.push_back(std::move(s));
  }
  {
    Scene s{"sheet folding through itself", test::sheet(8, 4, 2.0, 1.0), {}, {}};
    s.topo = test::simple_topology(s.mesh);
    const auto x = test::welded(s.topo, s.mesh.rest_positions);
    for (const double angle : {2.9, 3.1, 3.3}) s.samples.push_back(test::folded(x, 1.0, angle));
    out.push_back(std::move(s));
  }
  {
    Scene s{"tube squashed through itself", test::tube(14, 16, 0.4, 2.0), {}, {}, false};
    s.topo = test::simple_topology(s.mesh);
    const auto x = test::welded(s.topo, s.mesh.rest_positions);
    for (const double t : {0.0, 0.5, 1.0}) s.samples.push_back(test::squashed(x, t));
    out.push_back(std::move(s));
  }
  {
    // A tube (part 0) pushed sideways through a sheet (part 1).
    auto t = test::tube(10, 8, 0.3, 1.2);
    auto sh = test::sheet(6, 6, 2.0, 2.0);
    sh.rest_positions = test::translated(sh.rest_positions, Eigen::Vector3d(-1.0, -1.0, 1.5));
    for (Eigen::Index v = 0; v < sh.rest_positions.rows(); ++v) {  // a gentle wave
      sh.rest_positions(v, 2) += 0.05 * std::sin(3.0 * sh.rest_positions(v, 0));
    }
    Scene s{"tube through a wavy sheet", test::combine(t, sh), {}, {}, false};
    s.topo = test::simple_topology(s.mesh);
    const auto x = test::welded(s.topo, s.mesh.rest_positions);
    const auto nt = static_cast<Eigen::Index>(t.rest_positions.rows());
    for (const double rise : {0.0, 0.5, 1.0}) {
      skinning::Positions y = x;
      y.topRows(nt).col(2).array() += rise;
      s.samples.push_back(y);
    }
    out.push_back(std::move(s));
  }
  {
    // A fan of 20 triangles around one vertex, a helical ramp whose pitch reverses.
    const int n = 20;
    auto ramp = [&](double pitch) {
      skinning::Positions x(n + 2, 3);
      x.row(0) << 0, 0, 0;
      for (int i = 0; i <= n; ++i) {
        const double theta = 2.0 * std::numbers::pi * 1.6 * i / n;
        x.row(1 + i) << std::cos(theta), std::sin(theta), pitch * theta;
      }
      return x;
    };
    skinning::Triangles f(n, 3);
    for (int i = 0; i < n; ++i) f.row(i) << 0, 1 + i, 2 + i;
    Scene s{"helical fan around one vertex", test::single_part_mesh(ramp(0.05), f), {}, {}};
    s.topo = test::simple_topology(s.mesh);
    for (const double pitch : {0.05, -0.05, 0.0}) s.samples.push_back(ramp(pitch));
    out.push_back(std::move(s));
  }
  return out;
}

void expect_same_counts(const Counters& a, const Counters& b, const std::string& what) {
  EXPECT_EQ(a.vf_tests, b.vf_tests) << what;
  EXPECT_EQ(a.ee_tests, b.ee_tests) << what;
  EXPECT_EQ(a.tt_tests, b.tt_tests) << what;
  EXPECT_EQ(a.vf_contacts, b.vf_contacts) << what;
  EXPECT_EQ(a.ee_contacts, b.ee_contacts) << what;
  EXPECT_EQ(a.dcd_pairs, b.dcd_pairs) << what;
}

bool is_subset(const std::vector<CcdContact>& a, const std::vector<CcdContact>& b) {
  return std::all_of(a.begin(), a.end(), [&](const CcdContact& c) {
    return std::any_of(b.begin(), b.end(), [&](const CcdContact& d) { return c.same_pair(d); });
  });
}

TEST(Methods, AgreeOnGeneratedMeshesWithKnownCollisions) {
  for (const Scene& s : scenes()) {
    std::int64_t total_dcd = 0, total_vf = 0, total_ee = 0;
    for (const Accuracy acc : {Accuracy::exact, Accuracy::conservative}) {
      if (acc == Accuracy::exact && !s.exact_too) continue;
      const MethodOptions options{.accuracy = acc};
      auto brute = make_method("brute", s.mesh, s.topo, options);
      auto bvh = make_method("bvh", s.mesh, s.topo, options);
      auto kdop = make_method("kdop", s.mesh, s.topo, options);
      for (std::size_t i = 0; i < s.samples.size(); ++i) {
        const std::string what =
            s.name + " " + std::string(ccd::to_string(acc)) + " sample " + std::to_string(i);
        FrameResult rb, rv, rk;
        brute->detect_dcd(s.samples[i], rb);
        bvh->detect_dcd(s.samples[i], rv);
        kdop->detect_dcd(s.samples[i], rk);
        // DCD is exact in every accuracy: all three agree, and bvh tests the same pairs.
        EXPECT_EQ(rv.dcd_pairs, rb.dcd_pairs) << what;
        EXPECT_EQ(rk.dcd_pairs, rb.dcd_pairs) << what;
        expect_same_counts(rv.counters, rb.counters, what + " (DCD bvh vs brute)");
        total_dcd += static_cast<std::int64_t>(rb.dcd_pairs.size());
        if (i + 1 == s.samples.size()) continue;
        FrameResult cb, cv, ck;
        brute->detect_ccd(s.samples[i], s.samples[i + 1], cb);
        bvh->detect_ccd(s.samples[i], s.samples[i + 1], cv);
        kdop->detect_ccd(s.samples[i], s.samples[i + 1], ck);
        // bvh tests exactly brute's feature pairs (both AABB): identical in every accuracy.
        EXPECT_EQ(cv.contacts, cb.contacts) << what;
        expect_same_counts(cv.counters, cb.counters, what + " (CCD bvh vs brute)");
        total_vf += cb.counters.vf_contacts;
        total_ee += cb.counters.ee_contacts;
        if (acc == Accuracy::exact) {
          EXPECT_EQ(ck.contacts, cb.contacts) << what;
        } else {
          // 16-DOPs cull more triangle pairs (their diagonals), and the feature stage is brute
          // force's, so kdop tests a subset of its feature pairs and may lack a conservative
          // false positive — never more.
          EXPECT_TRUE(is_subset(ck.contacts, cb.contacts)) << what;
          EXPECT_LE(ck.counters.vf_tests, cb.counters.vf_tests) << what;
          EXPECT_LE(ck.counters.ee_tests, cb.counters.ee_tests) << what;
        }
        // The culling worked: fewer volume tests than brute force's (on meshes large enough
        // for a hierarchy to matter).
        if (s.topo.welded_triangles.rows() >= 150) {
          EXPECT_LT(
              cv.counters.bv_tests + cv.counters.feature_bv_tests, cb.counters.feature_bv_tests)
              << what;
        }
      }
    }
    // The scenes do collide (else agreement would prove little).
    EXPECT_GT(total_dcd + total_vf + total_ee, 0) << s.name;
    EXPECT_GT(total_vf + total_ee, 0) << s.name;
  }
}

TEST(Methods, ConeMethodsThatCannotCullHaveBvhsCandidatesAlsoFarFromTheOrigin) {
  // With a contact distance the cone methods cull nothing (docs/dual-cone.md), so their traversal
  // must find exactly `bvh`'s candidate pairs at an instant: those whose exact volumes overlap.
  // Their hierarchy keeps its node volumes as floats rounded outwards
  // (BvhOptions::float_node_volumes), which only prune: far from the origin, where floats round
  // away most of the doubles' bits, a traversal that took a leaf's float volume for its triangle's
  // would count pairs whose exact volumes are apart.
  const MethodOptions options{.min_separation = 1e-4};
  std::int64_t compared = 0;
  for (const Scene& s : scenes()) {
    for (const double offset : {0.0, 2e4}) {
      std::vector<skinning::Positions> samples;
      for (const auto& x : s.samples) {
        samples.push_back(test::translated(x, Eigen::Vector3d(offset, -offset, 0.5 * offset)));
      }
      auto bvh = make_method("bvh", s.mesh, s.topo, options);
      for (const char* name : {"normal-cone", "enhanced-dual-cone"}) {
        auto cone = make_method(name, s.mesh, s.topo, options);
        for (std::size_t i = 0; i < samples.size(); ++i) {
          const std::string what = s.name + " " + name + ", offset " + std::to_string(offset) +
                                   ", sample " + std::to_string(i);
          FrameResult rb, rc;
          bvh->detect_dcd(samples[i], rb);
          cone->detect_dcd(samples[i], rc);
          EXPECT_EQ(rc.counters.candidate_pairs, rb.counters.candidate_pairs) << what;
          EXPECT_EQ(rc.dcd_pairs, rb.dcd_pairs) << what;
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 0);
}

TEST(Methods, ExactContactsAreContainedInConservativeOnes) {
  // conservative never misses: each exact contact is a conservative one, for every method.
  for (const Scene& s : scenes()) {
    if (!s.exact_too) continue;
    for (const auto& name : kBaselines) {
      for (std::size_t i = 0; i + 1 < s.samples.size(); ++i) {
        const auto exact = run_ccd(
            name, s.mesh, s.topo, s.samples[i], s.samples[i + 1], {.accuracy = Accuracy::exact});
        const auto cons = run_ccd(name, s.mesh, s.topo, s.samples[i], s.samples[i + 1]);
        EXPECT_TRUE(is_subset(exact.contacts, cons.contacts)) << s.name << " " << name;
      }
    }
  }
}

TEST(Methods, ContactsAreCanonicallySortedAndCountersConsistent) {
  const Scene s = scenes()[0];
  for (const auto& name : kBaselines) {
    const auto r = run_ccd(name, s.mesh, s.topo, s.samples[1], s.samples[2]);
    EXPECT_TRUE(std::is_sorted(
        r.contacts.begin(), r.contacts.end(), [](const CcdContact& a, const CcdContact& b) {
          return a.before(b);
        }));
    EXPECT_EQ(
        static_cast<std::int64_t>(r.contacts.size()),
        r.counters.vf_contacts + r.counters.ee_contacts);
    EXPECT_GE(r.times.refit_us, 0.0);
    EXPECT_GT(r.times.traverse_us + r.times.elementary_us, 0.0);
    const auto d = run_dcd(name, s.mesh, s.topo, s.samples[2]);
    EXPECT_TRUE(std::is_sorted(d.dcd_pairs.begin(), d.dcd_pairs.end()));
    EXPECT_EQ(static_cast<std::int64_t>(d.dcd_pairs.size()), d.counters.dcd_pairs);
  }
}

}  // namespace
}  // namespace skelcd::culling
