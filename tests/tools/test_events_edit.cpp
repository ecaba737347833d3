// Collision events on real characters whose clips are edited in the test (issue 13's acceptance
// test): one bone's rotation keys are turned, over a known window of samples, so that the limb
// swings into the body; the rest of the clip is untouched. The edited clip must report a new event
// in that window driven by that limb, the unedited clip none there, and the samples before the edit
// must be labelled exactly as in the unedited clip. One character per file format: glTF
// (CesiumMan), Collada (the stormtrooper) and Ogre (the ninja).
//
// The edit. Let G be the limb node's posed global transform and E a rotation about an axis through
// the joint. Replacing the node's rotation key R by R·E (L = T·R·S with a uniform S) turns the
// whole limb, children included, by G·E·G⁻¹ about its joint. E's axis is chosen in object space, at
// the middle of the window, as d × (c − h): d the posed bone direction (head h → tail), c the
// centroid of the posed vertices the limb does not drive. So E swings the limb towards the body's
// centre; the angle is fixed per case (60–90°). The axis is carried into the node's frame through G
// at that sample. The weight of E ramps 0 → 1 → 0 (smoothstep) over the window, and the edited keys
// sit strictly between two of the channel's own keys, so every sample before the first of those
// keys is posed by the very same keys as before (bit for bit).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "skinning/load.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"
#include "tests/support/test_support.hpp"
#include "tools/engine/check_engine.hpp"
#include "tools/engine/events.hpp"

namespace skelcd::tools {
namespace {

using skinning::Rig;

/// One edit: the clip, the bone whose node is turned, the samples of the window (the weight of the
/// extra rotation ramps up over [ramp_start, hold_start], holds until hold_end, ramps down until
/// ramp_end) and the angle.
struct EditCase {
  const char* name;
  const char* file;  ///< under assets/
  const char* clip;
  const char* bone;
  std::int32_t ramp_start;
  std::int32_t hold_start;
  std::int32_t hold_end;
  std::int32_t ramp_end;
  double degrees;
};

std::ostream& operator<<(std::ostream& out, const EditCase& c) { return out << c.name; }

/// Samples checked on either side of the window.
constexpr std::int32_t kMargin = 3;
/// Sample times closer than this to a key of the clip reuse that key's time (no near-duplicates).
constexpr double kSnapS = 1e-4;

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

/// The bone and every bone below it.
std::set<std::string> subtree_bones(const Rig& rig, std::int32_t bone) {
  std::set<std::string> names;
  const auto& bones = rig.skeleton.bones;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    for (auto a = static_cast<std::int32_t>(b); a >= 0; a = bones[at(a)].parent) {
      if (a == bone) {
        names.insert(bones[b].name);
        break;
      }
    }
  }
  return names;
}

std::int32_t find_bone(const Rig& rig, const std::string& name) {
  for (std::size_t b = 0; b < rig.skeleton.bones.size(); ++b) {
    if (rig.skeleton.bones[b].name == name) return static_cast<std::int32_t>(b);
  }
  return -1;
}

/// Object space → the limb's node frame: the axis of the extra rotation, a unit vector in the
/// node's frame, from the pose at `sample`.
Eigen::Vector3d swing_axis(
    const skinning::LoadedModel& model,
    std::int32_t clip,
    std::int32_t bone,
    const std::set<std::string>& limb,
    const skinning::Motion& motion,
    std::int32_t sample,
    std::string& note) {
  const Rig& rig = *model.rig;
  skinning::PoseEvaluator evaluator(rig);
  skinning::Pose pose;
  evaluator.clip_pose(clip, motion.sample_time(sample), pose);
  const auto& b = rig.skeleton.bones[at(bone)];
  const skinning::BoneTransform& skin = pose.transforms[at(bone)];
  const Eigen::Vector3d head = skin.leftCols<3>() * b.rest_head + skin.col(3);
  const Eigen::Vector3d tail = skin.leftCols<3>() * b.rest_tail + skin.col(3);
  // The centroid of the posed vertices driven (most) by bones outside the limb.
  skinning::Positions x;
  motion.positions(sample, x);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::int64_t count = 0;
  for (Eigen::Index v = 0; v < rig.weights.rows(); ++v) {
    double best = 0;
    Eigen::Index driver = -1;
    for (skinning::SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
      if (it.value() > best) {
        best = it.value();
        driver = it.col();
      }
    }
    if (driver >= 0 && limb.count(rig.skeleton.bones[static_cast<std::size_t>(driver)].name) == 0) {
      centre += x.row(v).transpose();
      ++count;
    }
  }
  centre /= static_cast<double>(std::max<std::int64_t>(count, 1));
  const Eigen::Vector3d d = tail - head;
  const Eigen::Vector3d to_centre = centre - head;
  const Eigen::Vector3d axis = d.cross(to_centre).normalized();
  std::ostringstream s;
  s << "bone direction to body centre: "
    << std::acos(std::clamp(d.normalized().dot(to_centre.normalized()), -1.0, 1.0)) * 180 /
           std::numbers::pi
    << "°";
  note = s.str();
  const Eigen::Matrix3d node_linear = pose.node_global[at(b.node)].linear();
  return (node_linear.inverse() * axis).normalized();
}

/// What the edit changed: the first and last key time it wrote (the channel's keys before `first`
/// and after `last` are the file's).
struct EditSpan {
  double first = 0;  ///< a key of the channel kept as it was (weight 0), or the first new key
  double last = 0;
};

/// Turns `bone`'s node in clip `clip` by `degrees` about `axis` (node frame), weighted by the
/// case's ramp at the sample times of `motion` (and at the channel's own keys in the window).
EditSpan edit_clip(
    Rig& rig,
    std::int32_t clip,
    std::int32_t bone,
    const Eigen::Vector3d& axis,
    const EditCase& edit,
    const skinning::Motion& motion) {
  auto& c = rig.clips[at(clip)];
  const std::int32_t node = rig.skeleton.bones[at(bone)].node;
  const auto channel =
      std::find_if(c.channels.begin(), c.channels.end(), [&](const skinning::Channel& ch) {
        return ch.node == node;
      });
  if (channel == c.channels.end() || channel->rotation_times.empty()) {
    throw std::logic_error(std::string("no rotation keys move ") + edit.bone);
  }
  const auto& times = channel->rotation_times;
  const auto& rotations = channel->rotations;

  const double t_ramp_start = motion.sample_time(edit.ramp_start);
  const double t_hold_start = motion.sample_time(edit.hold_start);
  const double t_hold_end = motion.sample_time(edit.hold_end);
  const double t_ramp_end = motion.sample_time(edit.ramp_end);
  const auto weight = [&](double t) {
    if (t <= t_ramp_start || t >= t_ramp_end) return 0.0;
    if (t < t_hold_start) return smoothstep((t - t_ramp_start) / (t_hold_start - t_ramp_start));
    if (t > t_hold_end) return smoothstep((t_ramp_end - t) / (t_ramp_end - t_hold_end));
    return 1.0;
  };
  // The channel's keys around the window, kept: the last at or before its start, the first at or
  // after its end (none when the window reaches past the last key: the last value holds there).
  const auto lo = std::upper_bound(times.begin(), times.end(), t_ramp_start + kSnapS);
  const std::size_t keep_before =
      static_cast<std::size_t>(lo - times.begin());  // keys [0, keep_before)
  const auto hi = std::lower_bound(times.begin(), times.end(), t_ramp_end - kSnapS);
  const std::size_t keep_after =
      static_cast<std::size_t>(hi - times.begin());  // keys [keep_after, n)
  const double open_lo = keep_before > 0 ? times[keep_before - 1] : -1.0;
  const double open_hi = keep_after < times.size() ? times[keep_after] : 1e300;

  // New key times strictly inside (open_lo, open_hi): the channel's own keys there and the sample
  // times of the window, a sample time snapped to a key of the clip within kSnapS.
  std::vector<double> inside(
      times.begin() + static_cast<std::ptrdiff_t>(keep_before),
      times.begin() + static_cast<std::ptrdiff_t>(keep_after));
  for (std::int32_t s = edit.ramp_start; s <= edit.ramp_end; ++s) {
    double t = motion.sample_time(s);
    const auto near = std::lower_bound(c.key_times.begin(), c.key_times.end(), t - kSnapS);
    if (near != c.key_times.end() && std::abs(*near - t) <= kSnapS) t = *near;
    if (t > open_lo && t < open_hi) inside.push_back(t);
  }
  std::sort(inside.begin(), inside.end());
  inside.erase(std::unique(inside.begin(), inside.end()), inside.end());

  std::vector<double> new_times(times.begin(), lo);
  std::vector<Eigen::Quaterniond> new_rotations(
      rotations.begin(), rotations.begin() + static_cast<std::ptrdiff_t>(keep_before));
  const double radians = edit.degrees * std::numbers::pi / 180;
  for (const double t : inside) {
    const Eigen::Quaterniond original = skinning::interpolate_rotation(times, rotations, t);
    const Eigen::Quaterniond extra(Eigen::AngleAxisd(weight(t) * radians, axis));
    new_times.push_back(t);
    new_rotations.push_back((original * extra).normalized());
  }
  new_times.insert(new_times.end(), hi, times.end());
  new_rotations.insert(
      new_rotations.end(),
      rotations.begin() + static_cast<std::ptrdiff_t>(keep_after),
      rotations.end());
  channel->rotation_times = std::move(new_times);
  channel->rotations = std::move(new_rotations);
  // The clip's key times: the sorted union gains the new ones (the rest are unchanged).
  std::vector<double> keys = c.key_times;
  keys.insert(keys.end(), inside.begin(), inside.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  c.key_times = std::move(keys);
  return {open_lo >= 0 ? open_lo : inside.front(), open_hi < 1e300 ? open_hi : inside.back()};
}

struct CheckRun {
  CheckOutcome outcome;
  std::vector<FrameReport> reports;
};

CheckRun run_check(const skinning::LoadedModel& model, const CheckRequest& request) {
  CheckRun run;
  run.outcome = check_model(
      model, request, [&](const FrameReport& report) { run.reports.push_back(report); });
  return run;
}

bool touches(const EventRecord& e, const std::set<std::string>& bones) {
  return std::any_of(
      e.bones.begin(), e.bones.end(), [&](const std::string& b) { return bones.count(b) > 0; });
}

bool overlaps(const EventRecord& e, std::int32_t first, std::int32_t last) {
  return e.first_sample <= last && e.last_sample >= first;
}

std::string describe_events(const std::vector<EventRecord>& events) {
  std::ostringstream out;
  for (const auto& e : events) {
    out << "  event " << e.id << " samples " << e.first_sample << "-" << e.last_sample << " peak "
        << e.peak_pairs << "@" << e.peak_sample << " depth " << e.depth << " merged_into "
        << e.merged_into << " bones";
    for (const auto& b : e.bones) out << " " << b;
    out << "\n";
  }
  return out.str();
}

class EditedClip : public ::testing::TestWithParam<EditCase> {};

TEST_P(EditedClip, ReportsANewEventOfTheLimbInTheWindowAndNothingElseChanges) {
  const EditCase& edit = GetParam();
  const auto started = std::chrono::steady_clock::now();
  const auto model = skinning::load_model(skelcd::test::asset(edit.file));
  const Rig& rig = *model.rig;
  const std::int32_t clip = rig.find_clip(edit.clip);
  ASSERT_GE(clip, 0) << edit.clip;
  const std::int32_t bone = find_bone(rig, edit.bone);
  ASSERT_GE(bone, 0) << edit.bone;
  const double fps = model.clips[at(clip)].rate_hz;
  const auto motion = model.motion({edit.clip, fps});
  ASSERT_LE(edit.ramp_end, motion->num_samples() - 1);
  const std::set<std::string> limb = subtree_bones(rig, bone);

  std::string note;
  const Eigen::Vector3d axis =
      swing_axis(model, clip, bone, limb, *motion, (edit.hold_start + edit.hold_end) / 2, note);
  Rig edited = rig;
  const EditSpan span = edit_clip(edited, clip, bone, axis, edit, *motion);
  ASSERT_NO_THROW(skinning::validate_rig(edited));
  const auto edited_model = skinning::model_from_rig(std::move(edited), model.kind, {});

  CheckRequest request;
  request.clip = edit.clip;
  request.fps = fps;  // the edit must not change the sampling (new keys break a key grid)
  request.frames.first = std::max(edit.ramp_start - kMargin, 0);
  request.frames.last = std::min(edit.ramp_end + kMargin, motion->num_samples() - 1);
  request.method = "bvh";
  request.query = QuerySet::both;
  request.threads = 1;
  request.baseline.kind = BaselineSpec::Kind::rest;
  const CheckRun before = run_check(model, request);
  const CheckRun after = run_check(edited_model, request);

  // The samples the edit cannot have changed: those at or before the last kept key.
  std::int32_t untouched = request.frames.first - 1;
  while (untouched + 1 <= *request.frames.last &&
         motion->sample_time(untouched + 1) <= span.first) {
    ++untouched;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::cout << edit.name << ": " << edit.bone << " turned " << edit.degrees << "° (" << note
            << "), window samples " << edit.ramp_start << "-" << edit.ramp_end << " at " << fps
            << " Hz, checked " << request.frames.first << "-" << *request.frames.last
            << ", untouched through sample " << untouched << " (kept key " << span.first << " s); "
            << seconds << " s\n unedited:\n"
            << describe_events(before.outcome.events) << " edited:\n"
            << describe_events(after.outcome.events);

  // The edited clip: a new event in the window driven by the limb — by the turned bone itself (its
  // triangles, next to the joint, are the first to enter the body) — and no event of the limb
  // outside the window. An event is "of the limb" when a bone of the limb (the turned bone or one
  // below it, which the edit turns with it) drives some of its triangles.
  const auto found = std::find_if(
      after.outcome.events.begin(), after.outcome.events.end(), [&](const EventRecord& e) {
        return touches(e, limb) && overlaps(e, edit.ramp_start, edit.ramp_end);
      });
  ASSERT_NE(found, after.outcome.events.end()) << "no event of " << edit.bone << " in the window";
  EXPECT_NE(std::find(found->bones.begin(), found->bones.end(), edit.bone), found->bones.end())
      << "the limb's event is not driven by " << edit.bone << " itself";
  EXPECT_LE(found->first_sample, edit.hold_start);
  EXPECT_GT(found->peak_pairs, 0);
  EXPECT_GE(found->peak_sample, edit.ramp_start);
  EXPECT_LE(found->peak_sample, edit.ramp_end);
  EXPECT_GT(found->depth, 0);
  for (const auto& e : after.outcome.events) {
    if (!touches(e, limb)) continue;
    EXPECT_GE(e.first_sample, edit.ramp_start) << "event " << e.id << " of the limb";
    EXPECT_LE(e.last_sample, edit.ramp_end) << "event " << e.id << " of the limb";
  }
  EXPECT_GT(after.outcome.summary.new_dcd_pairs, before.outcome.summary.new_dcd_pairs);

  // The unedited clip: no event of the limb there.
  for (const auto& e : before.outcome.events) {
    EXPECT_FALSE(touches(e, limb) && overlaps(e, edit.ramp_start, edit.ramp_end))
        << "the unedited clip has event " << e.id << " of the limb in the window";
  }

  // Before the edit: the same rows, findings and labels, and the same events ended there.
  ASSERT_GE(untouched, request.frames.first) << "no sample before the edit was checked";
  std::size_t compared = 0;
  for (std::size_t r = 0; r < before.reports.size() && r < after.reports.size(); ++r) {
    const auto& a = before.reports[r];
    const auto& b = after.reports[r];
    const std::int32_t end = a.row.kind == QueryKind::ccd ? a.row.sample + 1 : a.row.sample;
    if (end > untouched) break;
    ASSERT_EQ(a.row.sample, b.row.sample);
    ASSERT_EQ(a.row.kind, b.row.kind);
    EXPECT_EQ(a.dcd_pairs, b.dcd_pairs) << "row " << r;
    EXPECT_EQ(a.contacts, b.contacts) << "row " << r;
    ++compared;
  }
  EXPECT_GT(compared, 0U);
  for (const auto& e : before.outcome.events) {
    if (e.last_sample >= untouched) continue;
    ASSERT_LT(at(e.id), after.outcome.events.size());
    EXPECT_EQ(e, after.outcome.events[at(e.id)]) << "event " << e.id << " ended before the edit";
  }
  for (const auto& e : before.outcome.events) {
    if (e.first_sample > untouched) continue;
    ASSERT_LT(at(e.id), after.outcome.events.size());
    EXPECT_EQ(e.first_sample, after.outcome.events[at(e.id)].first_sample) << "event " << e.id;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Characters,
    EditedClip,
    ::testing::Values(
        // glTF, 24 Hz, a key per sample. The left leg's own events of the walk end by sample 15;
        // the thigh swings forward into the pelvis.
        EditCase{
            "CesiumMan_glTF",
            "characters/CesiumMan.glb",
            "clip_0",
            "leg_joint_L_1",
            18,
            21,
            27,
            30,
            80},
        // Collada, 30 Hz, a key per sample. The left thigh has events of its own at 82–89 and
        // 112–116; here it crosses the right thigh.
        EditCase{
            "Stormtrooper_Collada",
            "characters/stormtrooper/stormtrooper.dae",
            "animation",
            "mixamorig_LeftUpLeg",
            93,
            96,
            104,
            107,
            80},
        // Ogre, sampled at 30 Hz (no frame rate in the file); the walk has no new finding at all.
        // Joint15 is the upper arm without the sword; its channel has keys at 0, 0.5 s (sample
        // 15) and 1.083 s only, so the edit starts at the middle one.
        EditCase{
            "Ninja_Ogre", "characters/ninja/ninja.mesh", "Walk", "Joint15", 15, 18, 24, 28, 60}),
    [](const ::testing::TestParamInfo<EditCase>& param) { return std::string(param.param.name); });

}  // namespace
}  // namespace skelcd::tools
