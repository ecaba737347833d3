// Baselines and collision events (tools/engine/events.hpp, docs/events.md): the depth measure
// against hand-computed segments, labels and events on generated rigs with known answers and on
// real characters whose clips are edited in the test.

#include <gtest/gtest.h>

#include <cmath>

#include "tools/engine/events.hpp"

namespace skelcd::tools {
namespace {

TEST(IntersectionLength, CrossingTrianglesGiveTheSegmentInsideBoth) {
  // P lies in z = 0 and covers x in [-1, 1] along y = 0; Q lies in y = 0 and crosses z = 0 for
  // x in [-0.5, 0.25]: the common segment is [-0.5, 0.25] on the x axis.
  const Eigen::Vector3d p0(-1, -1, 0), p1(1, -1, 0), p2(0, 2, 0);
  const Eigen::Vector3d q0(-0.5, 0, -1), q1(0.25, 0, -1), q2(-0.125, 0, 1);
  // Q at z = 0: between (-0.5,-1)-(-0.125,1) at x = -0.3125 and (0.25,-1)-(-0.125,1) at 0.0625.
  // P at y = 0: x from -2/3 to 2/3. Overlap: [-0.3125, 0.0625].
  EXPECT_NEAR(intersection_length(p0, p1, p2, q0, q1, q2), 0.375, 1e-12);
  EXPECT_NEAR(intersection_length(q0, q1, q2, p0, p1, p2), 0.375, 1e-12);
}

TEST(IntersectionLength, SeparateOrCoplanarTrianglesGiveZero) {
  const Eigen::Vector3d p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0);
  EXPECT_EQ(intersection_length(p0, p1, p2, {0, 0, 1}, {1, 0, 1}, {0, 1, 2}), 0.0);
  EXPECT_EQ(intersection_length(p0, p1, p2, {0.1, 0.1, 0}, {2, 0, 0}, {0, 2, 0}), 0.0);
}

}  // namespace
}  // namespace skelcd::tools

// --- the engine on rigs with known answers -------------------------------------------------------

#include <filesystem>
#include <set>

#include "skinning/errors.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tools/engine/check_engine.hpp"
#include "tools/engine/run_summary.hpp"

namespace skelcd::tools {
namespace {

struct Run {
  CheckOutcome outcome;
  std::vector<FrameReport> reports;
};

Run check(
    const skinning::LoadedModel& model,
    const BaselineSpec& baseline,
    QuerySet query = QuerySet::both,
    FrameRange frames = {},
    Allowances allow = {},
    const std::string& log = {}) {
  CheckRequest request;
  request.baseline = baseline;
  request.query = query;
  request.frames = frames;
  request.allow = std::move(allow);
  request.log_path = log;
  Run run;
  run.outcome =
      check_model(model, request, [&](const FrameReport& r) { run.reports.push_back(r); });
  return run;
}

BaselineSpec at_sample(std::int32_t k) {
  return BaselineSpec{.kind = BaselineSpec::Kind::sample, .sample = k, .log_path = {}};
}

std::vector<const EventRecord*> roots(const CheckOutcome& o) {
  std::vector<const EventRecord*> out;
  for (const auto& e : o.events) {
    if (e.merged_into < 0) out.push_back(&e);
  }
  return out;
}

/// Limb of a generated body's bone ("octopus_limb3_5" → 3), -1 for the body.
int limb_of(const std::string& bone) {
  const auto at = bone.find("_limb");
  if (at == std::string::npos) return -1;
  return std::stoi(bone.substr(at + 5));
}

/// Every labelled finding is counted once: new + baseline + allowed = all, per row.
void expect_rows_account_for_every_finding(const Run& run) {
  for (const auto& r : run.reports) {
    const auto& c = r.row.counters;
    EXPECT_EQ(
        c.new_dcd_pairs + c.baseline_dcd_pairs + c.allowed_dcd_pairs,
        static_cast<std::int64_t>(r.dcd_pairs.size()));
    EXPECT_EQ(
        c.new_ccd_contacts + c.baseline_ccd_contacts + c.allowed_ccd_contacts,
        static_cast<std::int64_t>(r.contacts.size()));
    for (const auto& p : r.dcd_pairs) EXPECT_NE(p.label, kLabelNone);
    for (const auto& p : r.contacts) EXPECT_NE(p.label, kLabelNone);
  }
}

struct LimbCase {
  std::string spec;
  std::size_t events;  ///< touching limb pairs of the generator (docs: generate --list)
};

class KnownAnswerEvents : public ::testing::TestWithParam<LimbCase> {};

// Against a baseline where the limbs are apart, exactly the known contacts appear: one event per
// touching pair of limbs, starting at the known first intersecting frame (or in the interval
// before it, found by CCD), driven by the two partner limbs' bones.
TEST_P(KnownAnswerEvents, OneEventPerTouchingPairFromTheKnownFrame) {
  const auto& param = GetParam();
  const auto generated = skinning::generate(skinning::parse_generator_spec(param.spec));
  const int first = generated.answer.first_intersecting_frame;
  ASSERT_GT(first, 3);
  const auto model = skinning::load_model(param.spec);
  // The samples around the first contact (the rest of the clip only deepens it, at a cost).
  const FrameRange window{.first = first - 3, .last = first + 3};
  const auto run = check(model, at_sample(0), QuerySet::both, window);
  expect_rows_account_for_every_finding(run);
  for (const auto& r : run.reports) {
    if (r.row.kind != QueryKind::dcd) continue;
    EXPECT_EQ(r.row.counters.new_dcd_pairs > 0, r.row.sample >= first) << "sample " << r.row.sample;
  }
  const auto events = roots(run.outcome);
  ASSERT_EQ(events.size(), param.events);
  const double dt = 1.0 / skinning::kGeneratorFrameRateHz;
  for (const auto* e : events) {
    EXPECT_TRUE(e->first_sample == first || e->first_sample == first - 1) << e->first_sample;
    if (e->first_sample == first - 1) {
      ASSERT_TRUE(e->t_first_contact.has_value());
      EXPECT_GT(*e->t_first_contact, (first - 1) * dt - 1e-12);
      EXPECT_LE(*e->t_first_contact, first * dt + 1e-12);
    }
    EXPECT_EQ(e->last_sample, *window.last);
    EXPECT_GT(e->peak_pairs, 0);
    EXPECT_GT(e->depth, 0.0);
    std::set<int> limbs;
    for (const auto& bone : e->bones) limbs.insert(limb_of(bone));
    limbs.erase(-1);
    ASSERT_EQ(limbs.size(), 2u) << "event " << e->id << " bones " << e->bones.front();
    // Partners curl towards each other: limbs 2k and 2k + 1.
    EXPECT_EQ(*limbs.begin() / 2, *limbs.rbegin() / 2);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Generators,
    KnownAnswerEvents,
    ::testing::Values(
        LimbCase{"gen:octopus?triangles=4000", 4}, LimbCase{"gen:hand?triangles=2000", 2}),
    [](const auto& test) { return test.param.spec.substr(4, test.param.spec.find('?') - 4); });

TEST(KnownAnswerEvents, RopeEndCapRunsIntoItsStartCapAsOneEvent) {
  const std::string spec = "gen:rope?triangles=6000";
  const auto generated = skinning::generate(skinning::parse_generator_spec(spec));
  const int first = generated.answer.first_intersecting_frame;
  const auto run = check(
      skinning::load_model(spec),
      at_sample(0),
      QuerySet::both,
      FrameRange{.first = first - 3, .last = first + 3});
  expect_rows_account_for_every_finding(run);
  const auto events = roots(run.outcome);
  ASSERT_EQ(events.size(), 1u);
  const auto& e = *events.front();
  EXPECT_TRUE(e.first_sample == first || e.first_sample == first - 1);
  // The chain's first and last bones drive the two caps.
  const auto& bones = generated.rig.skeleton.bones;
  EXPECT_NE(std::find(e.bones.begin(), e.bones.end(), bones.front().name), e.bones.end());
  EXPECT_NE(std::find(e.bones.begin(), e.bones.end(), bones.back().name), e.bones.end());
}

TEST(KnownAnswerEvents, PandaFoldsOntoItsLinksFromTheKnownFrame) {
  const std::string spec = "gen:panda";
  const auto generated = skinning::generate(skinning::parse_generator_spec(spec));
  const int first = generated.answer.first_intersecting_frame;
  const auto model = skinning::load_model(spec);
  const auto run = check(model, at_sample(0));
  expect_rows_account_for_every_finding(run);
  const auto events = roots(run.outcome);
  ASSERT_FALSE(events.empty());
  std::set<std::string> parts;
  for (const auto* e : events) {
    EXPECT_TRUE(e->first_sample == first || e->first_sample == first - 1) << e->first_sample;
    for (const auto p : e->parts) parts.insert(model.mesh->part_names[static_cast<std::size_t>(p)]);
  }
  // Fingers, then the hand, against links 1-2 (generate --list).
  EXPECT_TRUE(parts.contains("panda_link1") || parts.contains("panda_link2"));
  EXPECT_TRUE(
      parts.contains("panda_hand") || parts.contains("panda_leftfinger") ||
      parts.contains("panda_rightfinger"));
}

// With the baseline at a sample where the limbs already touch, that contact is the baseline's:
// nothing new at that sample, and every pair there labelled baseline.
TEST(BaselineEvents, ASampleWhereLimbsTouchIsTheBaseline) {
  const std::string spec = "gen:octopus?triangles=4000";
  const auto generated = skinning::generate(skinning::parse_generator_spec(spec));
  const int k = generated.answer.first_intersecting_frame + 2;
  const auto run = check(
      skinning::load_model(spec),
      at_sample(k),
      QuerySet::both,
      FrameRange{.first = k - 4, .last = k + 1});
  expect_rows_account_for_every_finding(run);
  bool seen = false;
  for (const auto& r : run.reports) {
    if (r.row.kind != QueryKind::dcd || r.row.sample != k) continue;
    seen = true;
    EXPECT_GT(r.row.counters.dcd_pairs, 0);
    EXPECT_EQ(r.row.counters.new_dcd_pairs, 0);
    EXPECT_EQ(r.row.counters.baseline_dcd_pairs, r.row.counters.dcd_pairs);
    for (const auto& p : r.dcd_pairs) EXPECT_EQ(p.label, kLabelBaseline);
  }
  EXPECT_TRUE(seen);
  for (const auto* e : roots(run.outcome)) {
    EXPECT_FALSE(e->first_sample <= k && k <= e->last_sample && e->peak_sample == k);
  }
}

// A clip checked against a log of itself has nothing new.
TEST(BaselineEvents, AClipCheckedAgainstALogOfItselfHasNoNewEvent) {
  const std::string spec = "gen:octopus?triangles=4000";
  const auto model = skinning::load_model(spec);
  const auto generated = skinning::generate(skinning::parse_generator_spec(spec));
  const int k = generated.answer.first_intersecting_frame;
  const FrameRange window{.first = k - 2, .last = k + 3};
  const auto dir = std::filesystem::temp_directory_path() / "skelcd_test_events";
  std::filesystem::create_directories(dir);
  const auto log = (dir / "octopus.h5").string();
  const auto first = check(model, at_sample(0), QuerySet::both, window, {}, log);
  ASSERT_GT(roots(first.outcome).size(), 0u);
  const auto again = check(
      model,
      BaselineSpec{.kind = BaselineSpec::Kind::log, .sample = 0, .log_path = log},
      QuerySet::both,
      window);
  EXPECT_TRUE(again.outcome.events.empty());
  EXPECT_EQ(again.outcome.summary.new_dcd_pairs, 0);
  EXPECT_EQ(again.outcome.summary.new_ccd_contacts, 0);
  EXPECT_EQ(again.outcome.summary.baseline_dcd_pairs, first.outcome.summary.dcd_pairs);
  // A log of another model is refused, naming the log.
  try {
    (void)check(
        skinning::load_model("gen:rope?triangles=6000"),
        BaselineSpec{.kind = BaselineSpec::Kind::log, .sample = 0, .log_path = log});
    ADD_FAILURE() << "a log of another model was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(log), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// Allowing the parts an event touches turns its findings into allowed ones, counted apart.
TEST(AllowedEvents, AllowingThePartsOfEveryEventLeavesNothingNew) {
  const auto model = skinning::load_model("gen:panda");
  const auto run = check(model, at_sample(0), QuerySet::dcd);
  ASSERT_GT(run.outcome.summary.new_dcd_pairs, 0);
  std::set<std::string> rules;
  const auto& m = *model.mesh;
  for (const auto& r : run.reports) {
    for (const auto& p : r.dcd_pairs) {
      if (p.label < 0) continue;
      rules.insert(
          m.part_names[static_cast<std::size_t>(p.a.part)] + ":" +
          m.part_names[static_cast<std::size_t>(p.b.part)]);
    }
  }
  Allowances allow;
  allow.rules.assign(rules.begin(), rules.end());
  const auto allowed = check(model, at_sample(0), QuerySet::dcd, {}, allow);
  expect_rows_account_for_every_finding(allowed);
  EXPECT_TRUE(allowed.outcome.events.empty());
  EXPECT_EQ(allowed.outcome.summary.new_dcd_pairs, 0);
  EXPECT_EQ(allowed.outcome.summary.allowed_dcd_pairs, run.outcome.summary.new_dcd_pairs);
  // A name that is neither a part nor a bone is refused.
  allow.rules = {"panda_link1:no_such_part"};
  EXPECT_THROW((void)check(model, at_sample(0), QuerySet::dcd, {}, allow), InvalidInput);
}

TEST(BaselineSpecs, ParseAndDescribe) {
  EXPECT_EQ(parse_baseline("rest").kind, BaselineSpec::Kind::rest);
  EXPECT_EQ(parse_baseline("none").kind, BaselineSpec::Kind::none);
  EXPECT_EQ(parse_baseline("sample:12").sample, 12);
  EXPECT_EQ(parse_baseline("runs/a.h5").log_path, "runs/a.h5");
  EXPECT_EQ(describe(parse_baseline("sample:3")), "sample 3");
  for (const char* bad : {"", "sample:", "sample:-1", "sample:x", "rest2", "log.txt"}) {
    EXPECT_THROW((void)parse_baseline(bad), InvalidInput) << bad;
  }
}

}  // namespace
}  // namespace skelcd::tools

// --- a pass-through, and real characters -------------------------------------------------------

#include "tests/support/test_support.hpp"

namespace skelcd::tools {
namespace {

/// A unit cube centred at `c` into `mesh` as part `part` (12 triangles, outward).
void add_cube(skinning::Mesh& mesh, const Eigen::Vector3d& c, std::int32_t part) {
  const auto v0 = static_cast<std::int32_t>(mesh.rest_positions.rows());
  mesh.rest_positions.conservativeResize(v0 + 8, 3);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p =
        c + 0.5 * Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    mesh.rest_positions.row(v0 + i) = p.transpose();
    mesh.vertex_part.push_back(part);
    mesh.vertex_index_in_part.push_back(i);
  }
  const int faces[12][3] = {
      {0, 2, 1},
      {1, 2, 3},
      {4, 5, 6},
      {5, 7, 6},
      {0, 1, 4},
      {1, 5, 4},
      {2, 6, 3},
      {3, 6, 7},
      {0, 4, 2},
      {2, 4, 6},
      {1, 3, 5},
      {3, 7, 5}};
  const auto f0 = static_cast<std::int32_t>(mesh.triangles.rows());
  mesh.triangles.conservativeResize(f0 + 12, 3);
  for (int f = 0; f < 12; ++f) {
    for (int k = 0; k < 3; ++k) mesh.triangles(f0 + f, k) = v0 + faces[f][k];
    mesh.face_part.push_back(part);
    mesh.face_index_in_part.push_back(f);
  }
}

// A cube shot through a wall between two samples: no DCD finding at any sample, one event found by
// CCD alone, spanning that interval, driven by the moving bone.
TEST(PassThroughEvents, AMotionThroughAndOutBetweenSamplesIsAnEvent) {
  skinning::Rig rig;
  rig.source = "pass-through";
  add_cube(rig.mesh, {0, 0, 0}, 0);
  add_cube(rig.mesh, {-3, 0, 0}, 1);
  rig.mesh.part_names = {"wall", "bullet"};
  rig.skeleton.nodes = {
      {.name = "root", .parent = -1, .rest_local = Eigen::Affine3d::Identity()},
      {.name = "mover", .parent = 0, .rest_local = Eigen::Affine3d::Identity()}};
  rig.skeleton.bones.resize(2);
  rig.skeleton.bones[0].name = "root";
  rig.skeleton.bones[0].node = 0;
  rig.skeleton.bones[1].name = "mover";
  rig.skeleton.bones[1].node = 1;
  rig.skeleton.bones[1].parent = 0;
  rig.weights.resize(16, 2);
  for (int v = 0; v < 16; ++v) rig.weights.insert(v, v < 8 ? 0 : 1) = 1.0;
  rig.weights.makeCompressed();
  skinning::Clip clip;
  clip.name = "shot";
  const double dt = 1.0 / 30;
  skinning::Channel channel;
  channel.node = 1;
  channel.translation_times = {0, dt, 2 * dt, 3 * dt};
  channel.translations = {{0, 0, 0}, {0, 0, 0}, {6, 0, 0}, {6, 0, 0}};
  clip.channels.push_back(channel);
  clip.key_times = channel.translation_times;
  clip.duration_s = 3 * dt;
  rig.clips.push_back(clip);
  const auto model = skinning::model_from_rig(std::move(rig), skinning::ModelKind::rig, {});

  CheckRequest request;
  request.fps = 30;
  request.baseline = BaselineSpec{.kind = BaselineSpec::Kind::none, .sample = 0, .log_path = {}};
  const auto outcome = check_model(model, request);
  EXPECT_EQ(outcome.summary.dcd_pairs, 0);
  ASSERT_EQ(outcome.events.size(), 1u);
  const auto& e = outcome.events.front();
  EXPECT_EQ(e.first_sample, 1);
  EXPECT_EQ(e.last_sample, 2);
  EXPECT_EQ(e.peak_pairs, 0);
  EXPECT_GT(e.ccd_contacts, 0);
  ASSERT_TRUE(e.t_first_contact.has_value());
  // The near face (x = -2.5 + 6 τ) reaches the wall (x = -0.5) at τ = 1/3 of the interval.
  EXPECT_NEAR(*e.t_first_contact, dt + dt / 3, 1e-6);
  EXPECT_EQ(e.parts, (std::vector<std::int32_t>{0, 1}));
  ASSERT_FALSE(e.bones.empty());
  EXPECT_NE(std::find(e.bones.begin(), e.bones.end(), "mover"), e.bones.end());
}

// On real characters, a baseline taken at sample K leaves nothing new at sample K, whatever their
// shells do at rest.
TEST(RealCharacterBaselines, ABaselineAtSampleKLeavesNothingNewAtK) {
  for (const char* file :
       {"characters/CesiumMan.glb",
        "characters/RobotExpressive.glb",
        "characters/stormtrooper/stormtrooper.dae",
        "characters/ninja/ninja.mesh"}) {
    const auto model = skinning::load_model(test::asset(file));
    const std::int32_t k = 7;
    const auto run = check(model, at_sample(k), QuerySet::dcd, FrameRange{.first = k, .last = k});
    ASSERT_EQ(run.reports.size(), 1u) << file;
    const auto& c = run.reports.front().row.counters;
    EXPECT_EQ(c.new_dcd_pairs, 0) << file;
    EXPECT_EQ(c.baseline_dcd_pairs + c.allowed_dcd_pairs, c.dcd_pairs) << file;
    EXPECT_TRUE(run.outcome.events.empty()) << file;
    // Against the rest pose, the same sample has findings of its own on these characters.
    const auto rest =
        check(model, BaselineSpec{}, QuerySet::dcd, FrameRange{.first = k, .last = k});
    EXPECT_EQ(rest.reports.front().row.counters.dcd_pairs, c.dcd_pairs) << file;
  }
}

}  // namespace
}  // namespace skelcd::tools

namespace skelcd::tools {
namespace {

// A real character's clip checked against a log of itself has nothing new: CesiumMan's walk has
// events against its rest pose, none against its own log (DCD pairs and CCD contacts both).
TEST(RealCharacterBaselines, AClipAgainstALogOfItselfHasNoNewEvent) {
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  const auto dir = test::temp_dir("events-self-log");
  const auto log = (dir / "walk.h5").string();
  const FrameRange frames{.first = 8, .last = 16};
  const auto first = check(model, BaselineSpec{}, QuerySet::both, frames, {}, log);
  ASSERT_FALSE(roots(first.outcome).empty());
  const auto again = check(
      model,
      BaselineSpec{.kind = BaselineSpec::Kind::log, .sample = 0, .log_path = log},
      QuerySet::both,
      frames);
  expect_rows_account_for_every_finding(again);
  EXPECT_TRUE(again.outcome.events.empty());
  EXPECT_EQ(again.outcome.summary.new_dcd_pairs, 0);
  EXPECT_EQ(again.outcome.summary.new_ccd_contacts, 0);
  EXPECT_EQ(again.outcome.summary.dcd_pairs, first.outcome.summary.dcd_pairs);
}

// RobotExpressive's rigid arm meshes hang from nodes beside the lower-arm bones (both under the
// upper arm): with --allow-adjacent-bones their contact with the hands is allowed, not an event.
TEST(RealCharacterAllowances, AdjacentBonesIncludeRigidPartsHangingFromABone) {
  const auto model = skinning::load_model(test::asset("characters/RobotExpressive.glb"));
  const auto arm_and_hand = [](const CheckOutcome& o) {
    for (const auto* e : roots(o)) {
      const auto has = [&](const char* bone) {
        return std::find(e->bones.begin(), e->bones.end(), bone) != e->bones.end();
      };
      if (has("Arm.L") && has("LowerArm.L") && e->bones.size() == 2) return true;
    }
    return false;
  };
  const FrameRange frames{.first = 0, .last = 2};
  const auto plain = check(model, BaselineSpec{}, QuerySet::dcd, frames);
  ASSERT_TRUE(arm_and_hand(plain.outcome));
  const auto allowed = check(
      model,
      BaselineSpec{},
      QuerySet::dcd,
      frames,
      Allowances{.rules = {}, .adjacent_bones = true});
  expect_rows_account_for_every_finding(allowed);
  EXPECT_FALSE(arm_and_hand(allowed.outcome));
  EXPECT_GT(allowed.outcome.summary.allowed_dcd_pairs, 0);
  // Allowing is decided first: it takes from the new pairs and from the baseline's.
  const auto& a = allowed.outcome.summary;
  const auto& p = plain.outcome.summary;
  EXPECT_LT(a.new_dcd_pairs, p.new_dcd_pairs);
  EXPECT_LE(a.baseline_dcd_pairs, p.baseline_dcd_pairs);
  EXPECT_EQ(
      a.new_dcd_pairs + a.baseline_dcd_pairs + a.allowed_dcd_pairs,
      p.new_dcd_pairs + p.baseline_dcd_pairs);
}

// The tracker alone, on rows made by hand: two events, a region joining both (the older takes the
// younger), a gap long enough to end them, then the same place again (a new event) beside a
// third pair. Steps reuse their scratch arrays; nothing of an earlier step may leak into a later.
TEST(EventTracking, EventsMergeEndAfterAGapAndStartAgain) {
  skinning::Mesh mesh;
  for (int k = 0; k < 5; ++k) add_cube(mesh, {3.0 * k, 0, 0}, k);
  mesh.part_names = {"A", "B", "C", "D", "E"};
  const auto topology = skinning::build_topology(mesh);
  EventTracker tracker(mesh, topology, nullptr, BaselineFindings{}, Allowances{}, 2, {});
  const auto tri = [](std::int32_t part, std::int32_t index) {
    return FeatureId{.part = part, .index = index, .side = -1};
  };
  const double dt = 1.0 / 30;
  std::vector<FrameReport> out;
  const auto push = [&](std::int32_t sample, std::vector<std::pair<FeatureId, FeatureId>> pairs) {
    FrameReport r;
    r.row.kind = QueryKind::dcd;
    r.row.sample = sample;
    r.row.t0 = r.row.t1 = sample * dt;
    for (const auto& [a, b] : pairs) {
      r.dcd_pairs.push_back(DcdPairRow{.frame = sample, .a = a, .b = b, .label = kLabelNone});
    }
    for (auto& labelled : tracker.push(std::move(r))) out.push_back(std::move(labelled));
  };
  push(0, {{tri(0, 0), tri(1, 0)}, {tri(2, 0), tri(3, 0)}});
  push(1, {{tri(1, 1), tri(2, 1)}});  // B's and C's neighbours of sample 0's triangles
  for (std::int32_t s = 2; s < 10; ++s) push(s, {});
  push(10, {{tri(0, 0), tri(1, 0)}});
  push(11, {{tri(0, 0), tri(1, 0)}, {tri(3, 5), tri(4, 5)}});
  for (auto& labelled : tracker.flush()) out.push_back(std::move(labelled));

  ASSERT_EQ(out.size(), 12u);
  const auto labels = [&](std::size_t row) {
    std::vector<std::int32_t> l;
    for (const auto& p : out[row].dcd_pairs) l.push_back(p.label);
    return l;
  };
  EXPECT_EQ(labels(0), (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(labels(1), (std::vector<std::int32_t>{0}));
  EXPECT_EQ(labels(10), (std::vector<std::int32_t>{2}));
  EXPECT_EQ(labels(11), (std::vector<std::int32_t>{2, 3}));
  for (const auto& r : out) EXPECT_EQ(r.row.counters.new_dcd_pairs, std::ssize(r.dcd_pairs));

  const auto& events = tracker.events();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[1].merged_into, 0);
  for (const std::size_t e : {0u, 2u, 3u}) EXPECT_EQ(events[e].merged_into, -1);
  EXPECT_EQ(events[0].first_sample, 0);
  EXPECT_EQ(events[0].last_sample, 1);
  EXPECT_EQ(events[0].dcd_pairs, 3);
  EXPECT_EQ(events[0].peak_pairs, 1);  // one pair at each of its two samples
  EXPECT_EQ(events[0].peak_sample, 0);
  EXPECT_EQ(events[0].parts, (std::vector<std::int32_t>{0, 1, 2, 3}));
  EXPECT_EQ(events[2].first_sample, 10);
  EXPECT_EQ(events[2].last_sample, 11);
  EXPECT_EQ(events[2].dcd_pairs, 2);
  EXPECT_EQ(events[2].parts, (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(events[3].first_sample, 11);
  EXPECT_EQ(events[3].dcd_pairs, 1);
  EXPECT_EQ(events[3].parts, (std::vector<std::int32_t>{3, 4}));
}

// A run without DCD rows (`--query ccd`): the tracker labels each CCD row at the push that brings
// it, instead of holding it until the next, and the labels, counters and events are those of a
// tracker that held it. CesiumMan's whole clip, every contact new (no baseline): its events.
TEST(EventTracking, ACcdOnlyRunLabelsEachRowAtOnceAsWhenItWasHeld) {
  const auto model = skinning::load_model(test::asset("characters/CesiumMan.glb"));
  const BaselineSpec none{.kind = BaselineSpec::Kind::none, .sample = 0, .log_path = {}};
  const auto run = check(model, none, QuerySet::ccd);
  ASSERT_GT(run.reports.size(), 10u);
  ASSERT_GT(run.outcome.events.size(), 1u) << "no events: the clip proves nothing";
  const auto motion = model.motion();
  const auto topology = skinning::build_topology(motion->mesh());
  const auto positions_at = [&](std::int32_t sample, skinning::Positions& out) {
    motion->positions(sample, out);
  };
  std::vector<FrameReport> labelled[2];
  std::vector<EventRecord> events[2];
  for (const auto rows : {EventTracker::DcdRows::expected, EventTracker::DcdRows::none}) {
    const auto k = static_cast<std::size_t>(rows == EventTracker::DcdRows::none);
    EventTracker tracker(
        motion->mesh(),
        topology,
        model.rig.get(),
        BaselineFindings{},
        Allowances{},
        2,
        positions_at,
        rows);
    for (const auto& report : run.reports) {
      FrameReport unlabelled = report;
      unlabelled.row.counters.new_ccd_contacts = 0;
      for (auto& c : unlabelled.contacts) c.label = kLabelNone;
      auto out = tracker.push(std::move(unlabelled));
      // Held, a row comes out at the next push; without DCD rows, at its own.
      EXPECT_EQ(out.size(), k == 1 || &report != &run.reports.front() ? 1u : 0u);
      if (k == 1 && out.size() == 1) {
        EXPECT_EQ(out.front().row.sample, report.row.sample);
      }
      for (auto& r : out) labelled[k].push_back(std::move(r));
    }
    auto rest = tracker.flush();
    EXPECT_EQ(rest.size(), 1 - k);
    for (auto& r : rest) labelled[k].push_back(std::move(r));
    events[k] = tracker.events();
  }
  ASSERT_EQ(labelled[0].size(), run.reports.size());
  ASSERT_EQ(labelled[1].size(), run.reports.size());
  std::int64_t new_contacts = 0;
  for (std::size_t i = 0; i < run.reports.size(); ++i) {
    EXPECT_EQ(labelled[1][i].contacts, labelled[0][i].contacts) << i;  // the labels with them
    EXPECT_EQ(labelled[1][i].contacts, run.reports[i].contacts) << i;  // the check's own run
    EXPECT_EQ(
        labelled[1][i].row.counters.new_ccd_contacts, labelled[0][i].row.counters.new_ccd_contacts);
    new_contacts += labelled[1][i].row.counters.new_ccd_contacts;
  }
  EXPECT_GT(new_contacts, 0);
  EXPECT_EQ(events[1], events[0]);
  EXPECT_EQ(events[1], run.outcome.events);
}

}  // namespace
}  // namespace skelcd::tools
