// Generated rigs: sizes, closed/open parts, determinism, spec strings, and every known answer
// checked against the exact brute-force reference of test_generators_exact.cpp on the positions
// the rig's Motion produces.

#include "skinning/generators.hpp"

#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "skinning/errors.hpp"
#include "skinning/generators_panda.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "skinning/urdf_trajectory.hpp"
#include "tests/skinning/test_generators_exact.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

const std::vector<std::string> kSized = {"rope", "octopus", "hand", "pipe", "cloth"};

GeneratedRig make(const std::string& name, std::int64_t triangles, int frames) {
  GeneratorSpec spec;
  spec.name = name;
  spec.triangles = triangles;
  spec.frames = frames;
  return generate(spec);
}

// Intersecting pairs at every listed frame, positions from RigMotion (what every command reads).
std::vector<bool> frames_intersect(const GeneratedRig& g, const std::vector<int>& frames) {
  auto rig = std::make_shared<Rig>(g.rig);
  RigMotionOptions options;
  options.clip = 0;
  const RigMotion motion(rig, options);
  EXPECT_EQ(motion.num_samples(), g.spec.frames);
  const Mesh& mesh = g.rig.mesh;
  std::set<std::pair<std::int32_t, std::int32_t>> excluded(mesh.excluded_part_pairs.begin(), mesh.excluded_part_pairs.end());
  const auto skip = [&](std::int32_t a, std::int32_t b) {
    const std::int32_t pa = mesh.face_part[static_cast<std::size_t>(a)];
    const std::int32_t pb = mesh.face_part[static_cast<std::size_t>(b)];
    return excluded.count({std::min(pa, pb), std::max(pa, pb)}) > 0;
  };
  std::vector<bool> out;
  Positions p;
  for (const int i : frames) {
    motion.positions(i, p);
    out.push_back(!test::exact::self_intersections(p, mesh.triangles, true, skip).pairs.empty());
  }
  return out;
}

// Checks the known answer at `frames` (all frames when empty).
void expect_known_answer(const GeneratedRig& g, std::vector<int> frames = {}) {
  const KnownAnswer& a = g.answer;
  ASSERT_GE(a.last_free_frame, 0) << g.rig.source;
  ASSERT_GT(a.first_intersecting_frame, a.last_free_frame) << g.rig.source;
  if (frames.empty()) {
    for (int i = 0; i < g.spec.frames; ++i) frames.push_back(i);
  }
  const std::vector<bool> hit = frames_intersect(g, frames);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const int i = frames[k];
    if (i <= a.last_free_frame) {
      EXPECT_FALSE(hit[k]) << g.rig.source << ": frame " << i << " should be free";
    }
    if (i >= a.first_intersecting_frame) {
      EXPECT_TRUE(hit[k]) << g.rig.source << ": frame " << i << " should intersect";
    }
  }
}

TEST(Generators, SizesWithinTenPercentOfTheRequest) {
  for (const std::string& name : kSized) {
    for (const std::int64_t t : {1'000LL, 7'500LL, 48'000LL, 200'000LL}) {
      const GeneratedRig g = make(name, t, 2);
      const auto n = static_cast<double>(g.rig.mesh.num_triangles());
      EXPECT_NEAR(n / static_cast<double>(t), 1.0, 0.1) << name << " asked " << t << " got " << n;
    }
  }
}

TEST(Generators, ClosedAndOpenAsDocumented) {
  for (const GeneratorInfo& info : generator_list()) {
    if (info.name == "panda" || info.name == "panda-free") continue;  // checked in PandaReach
    const GeneratedRig g = make(info.name, 3'000, 3);
    const Topology topo = build_topology(g.rig.mesh);
    EXPECT_EQ(topo.components.size(), 1U) << info.name;
    EXPECT_TRUE(topo.non_manifold_edges.empty()) << info.name;
    EXPECT_TRUE(topo.degenerate_triangles.empty()) << info.name;
    for (const Component& c : topo.components) EXPECT_EQ(c.closed, info.closed) << info.name;
    // No duplicated positions: the mesh is already welded.
    EXPECT_EQ(topo.num_welded_vertices(), g.rig.mesh.num_vertices()) << info.name;
    if (info.closed) {
      EXPECT_TRUE(topo.boundary_edges.empty()) << info.name;
      // Outward orientation: positive enclosed volume.
      double volume = 0;
      const Mesh& m = g.rig.mesh;
      for (Eigen::Index f = 0; f < m.num_triangles(); ++f) {
        const Eigen::Vector3d a = m.rest_positions.row(m.triangles(f, 0)).transpose();
        const Eigen::Vector3d b = m.rest_positions.row(m.triangles(f, 1)).transpose();
        const Eigen::Vector3d c = m.rest_positions.row(m.triangles(f, 2)).transpose();
        volume += a.dot(b.cross(c)) / 6;
      }
      EXPECT_GT(volume, 0.0) << info.name;
    }
  }
  // Open ones: the pipe has two rim loops, the cloth one border loop.
  EXPECT_EQ(build_topology(make("pipe", 3'000, 2).rig.mesh).boundary_loops.size(), 2U);
  EXPECT_EQ(build_topology(make("cloth", 3'000, 2).rig.mesh).boundary_loops.size(), 1U);
}

TEST(Generators, DeterministicBitForBit) {
  for (const std::string& name : kSized) {
    const GeneratedRig a = make(name, 2'000, 5);
    const GeneratedRig b = make(name, 2'000, 5);
    EXPECT_EQ(a.rig.mesh.rest_positions, b.rig.mesh.rest_positions) << name;
    EXPECT_EQ(a.rig.mesh.triangles, b.rig.mesh.triangles) << name;
    EXPECT_TRUE(a.rig.weights.isApprox(b.rig.weights, 0.0)) << name;
    ASSERT_EQ(a.rig.clips.size(), 1U);
    ASSERT_EQ(a.rig.clips[0].channels.size(), b.rig.clips[0].channels.size());
    for (std::size_t c = 0; c < a.rig.clips[0].channels.size(); ++c) {
      for (std::size_t k = 0; k < a.rig.clips[0].channels[c].rotations.size(); ++k) {
        EXPECT_EQ(a.rig.clips[0].channels[c].rotations[k].coeffs(), b.rig.clips[0].channels[c].rotations[k].coeffs());
      }
    }
    EXPECT_EQ(a.answer.margin, b.answer.margin) << name;
  }
}

TEST(Generators, RigsAreValidAndStartAtRest) {
  for (const std::string& name : kSized) {
    const GeneratedRig g = make(name, 1'000, 4);
    EXPECT_NO_THROW(validate_rig(g.rig)) << name;
    EXPECT_EQ(g.rig.source, "gen:" + name + "?triangles=1000&frames=4");
    ASSERT_EQ(g.rig.clips.size(), 1U);
    EXPECT_DOUBLE_EQ(g.rig.clips[0].keys_per_s(), kGeneratorFrameRateHz);
    EXPECT_EQ(g.rig.clips[0].frame_rate_hz, kGeneratorFrameRateHz);
    EXPECT_EQ(g.rig.clips[0].frame_rate_source, FrameRateSource::generator);
    EXPECT_NEAR(g.rig.clips[0].duration_s, 3.0 / 30.0, 1e-15);
    // Frame 0 is the rest pose: every joint angle is 0 at tau = 0.
    auto rig = std::make_shared<Rig>(g.rig);
    RigMotionOptions options;
    options.clip = 0;
    Positions p;
    RigMotion(rig, options).positions(0, p);
    EXPECT_TRUE(test::expect_matrix_near(p, g.rig.mesh.rest_positions, 1e-12)) << name;
  }
}

// The known answers, exactly, at every frame of a short clip and around the change at the
// default frame count, at two sizes.
TEST(Generators, KnownAnswersHoldExactly) {
  for (const std::string& name : kSized) {
    SCOPED_TRACE(name);
    const GeneratedRig small = make(name, 1'000, 16);
    expect_known_answer(small);
    const GeneratedRig standard = make(name, 1'000, 60);
    EXPECT_EQ(standard.answer.first_intersecting_frame, standard.answer.last_free_frame + 1);
    const int k = standard.answer.last_free_frame;
    expect_known_answer(standard, {0, k - 1, k, k + 1, k + 2, 59});
    const GeneratedRig larger = make(name, 4'000, 60);
    EXPECT_EQ(larger.answer.last_free_frame, k);  // the answer does not depend on the size
    EXPECT_EQ(larger.answer.first_intersecting_frame, k + 1);
    expect_known_answer(larger, {k, k + 1});
  }
}

// The documented default answers (docs/generators.md): frames 0 … k free, k + 1 … 59 intersecting.
TEST(Generators, DocumentedDefaults) {
  const std::vector<std::pair<std::string, int>> documented = {
      {"rope", 44}, {"octopus", 37}, {"hand", 42}, {"pipe", 45}, {"cloth", 43}};
  for (const auto& [name, last_free] : documented) {
    const GeneratedRig g = make(name, 1'000, 60);
    EXPECT_EQ(g.answer.last_free_frame, last_free) << name;
    EXPECT_EQ(g.answer.first_intersecting_frame, last_free + 1) << name;
  }
}

TEST(Generators, PandaReachAndFree) {
  const GeneratedRig reach = make("panda", 0, 61);
  EXPECT_EQ(reach.rig.mesh.num_parts(), 11);
  EXPECT_EQ(reach.answer.last_free_frame, 37);  // tau = 37/60 < 0.6257 < 0.6258 < 38/60
  EXPECT_EQ(reach.answer.first_intersecting_frame, 38);
  expect_known_answer(reach);
  // Which parts touch at the last row: the hand and fingers against links 1 and 2 only.
  {
    auto rig = std::make_shared<Rig>(reach.rig);
    RigMotionOptions options;
    options.clip = 0;
    Positions p;
    RigMotion(rig, options).positions(60, p);
    const Mesh& m = reach.rig.mesh;
    std::set<std::pair<std::int32_t, std::int32_t>> excluded(m.excluded_part_pairs.begin(), m.excluded_part_pairs.end());
    const auto part = [&](std::int32_t f) { return m.face_part[static_cast<std::size_t>(f)]; };
    const auto r = test::exact::self_intersections(p, m.triangles, false, [&](std::int32_t a, std::int32_t b) {
      return excluded.count({std::min(part(a), part(b)), std::max(part(a), part(b))}) > 0;
    });
    std::set<std::string> touching;
    for (const auto& [a, b] : r.pairs) {
      touching.insert(m.part_names[static_cast<std::size_t>(part(a))] + "-" + m.part_names[static_cast<std::size_t>(part(b))]);
    }
    EXPECT_EQ(touching, (std::set<std::string>{"panda_link1-panda_hand", "panda_link1-panda_leftfinger",
                                                "panda_link2-panda_hand", "panda_link2-panda_rightfinger"}));
  }
  const GeneratedRig free = make("panda-free", 0, 61);
  EXPECT_EQ(free.answer.last_free_frame, 60);
  EXPECT_EQ(free.answer.first_intersecting_frame, -1);
  const std::vector<bool> hit = frames_intersect(free, [] {
    std::vector<int> all;
    for (int i = 0; i < 61; ++i) all.push_back(i);
    return all;
  }());
  for (std::size_t i = 0; i < hit.size(); ++i) EXPECT_FALSE(hit[i]) << "panda-free row " << i;
  // Every link part is closed.
  const Topology topo = build_topology(reach.rig.mesh);
  for (const Component& c : topo.components) EXPECT_TRUE(c.closed);
}

// The bundled CSVs are the generator's output: regenerate and compare value for value.
TEST(Generators, BundledTrajectoriesAreReproducible) {
  const Robot panda = load_bundled_panda();
  for (const bool reach : {true, false}) {
    const auto file = test::asset(reach ? "trajectories/panda_reach.csv" : "trajectories/panda_free.csv");
    const JointTrajectory bundled = read_joint_trajectory(file, panda);
    const JointTrajectory made = panda_trajectory(panda, 61, reach);
    EXPECT_EQ(bundled.joints, made.joints) << file;
    EXPECT_EQ(bundled.times, made.times) << file;
    EXPECT_EQ(bundled.positions, made.positions) << file;
  }
}

TEST(Generators, SpecStrings) {
  const GeneratorSpec s = parse_generator_spec("gen:rope?triangles=48000&frames=60");
  EXPECT_EQ(s.name, "rope");
  EXPECT_EQ(s.triangles, 48000);
  EXPECT_EQ(s.frames, 60);
  EXPECT_EQ(to_string(parse_generator_spec("gen:octopus")), "gen:octopus?triangles=48000&frames=60");
  EXPECT_EQ(to_string(parse_generator_spec("gen:panda?frames=10")), "gen:panda?frames=10");
  EXPECT_TRUE(is_generator_spec("gen:cloth"));
  EXPECT_FALSE(is_generator_spec("cloth.obj"));
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:squid"), InvalidInput, "gen:squid: unknown generator 'squid'");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?size=3"), InvalidInput, "unknown parameter 'size'");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?triangles=abc"), InvalidInput, "triangles = 'abc' is not a positive integer");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?triangles=-5"), InvalidInput, "is not a positive integer");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?triangles=10"), InvalidInput, "outside [100, 5000000]");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?frames=1"), InvalidInput, "frames = 1 is outside [2, 100000]");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:rope?frames"), InvalidInput, "has no value");
  EXPECT_THROW_MESSAGE((void)parse_generator_spec("gen:panda?triangles=5000"), InvalidInput, "fixed size");
}

TEST(Generators, LoadModelTakesSpecs) {
  const LoadedModel model = load_model("gen:cloth?triangles=2000&frames=12");
  EXPECT_EQ(model.kind, ModelKind::rig);
  EXPECT_EQ(model.path.string(), "gen:cloth?triangles=2000&frames=12");
  ASSERT_EQ(model.clips.size(), 1U);
  EXPECT_EQ(model.clips[0].name, "fold");
  EXPECT_NEAR(model.clips[0].duration_s, 11.0 / 30.0, 1e-15);
  const auto motion = model.motion({});
  EXPECT_EQ(motion->num_samples(), 12);
  EXPECT_THROW_MESSAGE((void)load_model("gen:nothing"), InvalidInput, "unknown generator");
  LoadOptions robot_only;
  robot_only.trajectory = "t.csv";
  EXPECT_THROW_MESSAGE((void)load_model("gen:rope", robot_only), InvalidInput, "URDF robots only");
}

// The reference itself, on hand-made cases whose answers are known.
TEST(GeneratorsExactReference, HandMadeCases) {
  using V = Eigen::Vector3d;
  using test::exact::triangles_intersect;
  const std::array<V, 3> t{V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  // Piercing, touching at a vertex, just missing, coplanar overlap, coplanar disjoint.
  EXPECT_TRUE(triangles_intersect(t, {V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(3, 3, 0.5)}, {}));
  EXPECT_TRUE(triangles_intersect(t, {V(0.5, 0.5, 0), V(2, 2, 1), V(2, 0, 1)}, {}));  // vertex on the hypotenuse
  EXPECT_FALSE(triangles_intersect(t, {V(0.5, std::nextafter(0.5, 1.0), 0), V(2, 2, 1), V(2, 0.6, 1)}, {}));
  EXPECT_TRUE(triangles_intersect(t, {V(0.1, 0.1, 0), V(2, 0.1, 0), V(0.1, 2, 0)}, {}));
  EXPECT_FALSE(triangles_intersect(t, {V(1, 1, 0), V(2, 1, 0), V(1, 2, 0)}, {}));
  // Shared edge: folded flat onto itself intersects, a hinge does not.
  EXPECT_TRUE(triangles_intersect(t, {V(0, 0, 0), V(1, 0, 0), V(0.5, 0.5, 0)}, {{0, 0}, {1, 1}}));
  EXPECT_FALSE(triangles_intersect(t, {V(0, 0, 0), V(1, 0, 0), V(0.5, -0.5, 0)}, {{0, 0}, {1, 1}}));
  EXPECT_FALSE(triangles_intersect(t, {V(0, 0, 0), V(1, 0, 0), V(0.5, 0.5, 1)}, {{0, 0}, {1, 1}}));
  // Shared vertex: a fan neighbour does not; one folded into the other's angle does.
  EXPECT_FALSE(triangles_intersect(t, {V(0, 0, 0), V(-1, 0, 0), V(0, -1, 0)}, {{0, 0}}));
  EXPECT_TRUE(triangles_intersect(t, {V(0, 0, 0), V(1, 1, 0), V(1, 2, 1)}, {{0, 0}}));
  EXPECT_FALSE(triangles_intersect(t, {V(0, 0, 0), V(1, 1, 0.001), V(-1, 1, 1)}, {{0, 0}}));
  EXPECT_TRUE(triangles_intersect(t, {V(0, 0, 0), V(0.3, 0.3, -1), V(0.3, 0.3, 1)}, {{0, 0}}));
  EXPECT_EQ(test::exact::orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1e-300)), 1);
  EXPECT_EQ(test::exact::orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(5, 7, 0)), 0);
  EXPECT_EQ(test::exact::orient3d(V(0.1, 0.2, 0.3), V(0.2, 0.4, 0.6), V(0.4, 0.8, 1.2), V(1.0, -1.1, 1.2)), 0) << "collinear";
  EXPECT_EQ(test::exact::orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.3, 0.7, -1e-200)), -1);
}

}  // namespace
}  // namespace skelcd::skinning
