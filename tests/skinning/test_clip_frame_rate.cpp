// The frame rate of a clip — the rate a check samples it at when none is asked for — on real
// files: the FBX time mode, the Collada 3ds Max <frame_rate>, keys evenly spaced at a standard
// frame rate, else 30 Hz; a rate asked for (--fps) wins. Expectations are read from the files
// here, independently of skinning/: FBX through assimp's own aiAnimation::mTicksPerSecond (its
// FBX converter sets it from the time mode), Collada from the file's text, key grids from the
// key times.

#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

namespace fs = std::filesystem;
using skelcd::test::asset;
using skelcd::test::assimp_model;

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary);
  out << bytes;
}

// What assimp itself makes of an FBX file: the time mode (GlobalSettings TimeMode, scene metadata
// "FrameRate") and the ticks per second of its first animation.
struct AssimpFbxRate {
  std::int32_t time_mode = -1;
  double ticks_per_s = 0.0;
};

AssimpFbxRate assimp_fbx_rate(const fs::path& file) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  AssimpFbxRate r;
  if (scene == nullptr || scene->mMetaData == nullptr || scene->mNumAnimations == 0) return r;
  scene->mMetaData->Get("FrameRate", r.time_mode);
  r.ticks_per_s = scene->mAnimations[0]->mTicksPerSecond;
  return r;
}

// The mean gap of sorted key times, after checking that every gap is that one (1e-6 s).
double even_gap(const std::vector<double>& keys) {
  const double gap = (keys.back() - keys.front()) / static_cast<double>(keys.size() - 1);
  for (std::size_t k = 1; k < keys.size(); ++k) {
    EXPECT_NEAR(keys[k] - keys[k - 1], gap, 1e-6) << "key " << k;
  }
  return gap;
}

void expect_sampled_at(const LoadedModel& model, const ClipSummary& clip, double rate_hz) {
  const auto motion = model.motion({.clip = clip.name});
  EXPECT_DOUBLE_EQ(motion->rate_hz(), rate_hz) << clip.name;
  EXPECT_EQ(motion->num_samples(), sample_count(clip.duration_s, rate_hz)) << clip.name;
  // A rate asked for wins over the clip's own.
  const auto chosen = model.motion({.clip = clip.name, .rate_hz = 10.0});
  EXPECT_EQ(chosen->rate_hz(), 10.0) << clip.name;
  EXPECT_EQ(chosen->num_samples(), sample_count(clip.duration_s, 10.0)) << clip.name;
}

TEST(ClipFrameRate, FbxClipsAreSampledAtTheFileFrameRate) {
  for (const char* file : {"FBX/huesitos.fbx", "FBX/animation_with_skeleton.fbx"}) {
    SCOPED_TRACE(file);
    const AssimpFbxRate expected = assimp_fbx_rate(assimp_model(file));
    ASSERT_GT(expected.time_mode, 0) << "the file declares a frame rate";
    ASSERT_GT(expected.ticks_per_s, 0.0);
    const LoadedModel model = load_model(assimp_model(file));
    ASSERT_EQ(model.clips.size(), 1U);
    const ClipSummary& clip = model.clips[0];
    EXPECT_DOUBLE_EQ(clip.rate_hz, expected.ticks_per_s);
    EXPECT_EQ(clip.rate_source, FrameRateSource::file);
    expect_sampled_at(model, clip, expected.ticks_per_s);
  }
}

TEST(ClipFrameRate, AnFbxClipWithSparseKeysKeepsItsFrameRate) {
  // animation_with_skeleton.fbx keys its bones on some frames only: its key rate is below its
  // frame rate, and the frame rate is what is sampled.
  const fs::path file = assimp_model("FBX/animation_with_skeleton.fbx");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  ASSERT_NE(scene, nullptr);
  ASSERT_EQ(scene->mNumAnimations, 1U);
  const aiAnimation* anim = scene->mAnimations[0];
  std::vector<double> ticks;
  for (unsigned c = 0; c < anim->mNumChannels; ++c) {
    for (unsigned k = 0; k < anim->mChannels[c]->mNumRotationKeys; ++k)
      ticks.push_back(anim->mChannels[c]->mRotationKeys[k].mTime);
    for (unsigned k = 0; k < anim->mChannels[c]->mNumPositionKeys; ++k)
      ticks.push_back(anim->mChannels[c]->mPositionKeys[k].mTime);
    for (unsigned k = 0; k < anim->mChannels[c]->mNumScalingKeys; ++k)
      ticks.push_back(anim->mChannels[c]->mScalingKeys[k].mTime);
  }
  std::sort(ticks.begin(), ticks.end());
  ticks.erase(std::unique(ticks.begin(), ticks.end()), ticks.end());
  ASSERT_GE(ticks.size(), 2U);
  const double key_rate = static_cast<double>(ticks.size() - 1) /
                          ((ticks.back() - ticks.front()) / anim->mTicksPerSecond);
  ASSERT_LT(key_rate, 0.9 * anim->mTicksPerSecond) << "the keys are sparser than the frames";

  const LoadedModel model = load_model(file);
  ASSERT_EQ(model.clips.size(), 1U);
  EXPECT_NEAR(model.clips[0].keys_per_s, key_rate, 1e-9);
  EXPECT_DOUBLE_EQ(model.clips[0].rate_hz, anim->mTicksPerSecond);
}

// huesitos.fbx with its time mode (and custom frame rate) overwritten in place: every mode gives
// the rate assimp gives it, whatever the keys (huesitos keys every frame at 25 Hz).
TEST(ClipFrameRate, EveryFbxTimeModeGivesTheRateAssimpGivesIt) {
  const std::string original = read_bytes(assimp_model("FBX/huesitos.fbx"));
  // Binary FBX properties: P "TimeMode" "enum" "" "" I <int32>, P "CustomFrameRate" … D <double>.
  static constexpr char kMode[] = "TimeModeS\x04\0\0\0enumS\0\0\0\0S\0\0\0\0I";
  static constexpr char kCustom[] = "CustomFrameRateS\x06\0\0\0doubleS\x06\0\0\0NumberS\0\0\0\0D";
  const std::string mode_tag(kMode, sizeof kMode - 1);
  const std::string custom_tag(kCustom, sizeof kCustom - 1);
  const auto mode_at = original.find(mode_tag);
  const auto custom_at = original.find(custom_tag);
  ASSERT_NE(mode_at, std::string::npos);
  ASSERT_NE(custom_at, std::string::npos);
  const fs::path dir = test::temp_dir("clip_frame_rate_fbx_modes");
  for (const std::int32_t mode : {1, 3, 6, 8, 11, 13, 14}) {
    SCOPED_TRACE("time mode " + std::to_string(mode));
    std::string bytes = original;
    std::memcpy(bytes.data() + mode_at + mode_tag.size(), &mode, sizeof mode);
    const double custom = 12.5;
    std::memcpy(bytes.data() + custom_at + custom_tag.size(), &custom, sizeof custom);
    const fs::path file = dir / ("huesitos_mode" + std::to_string(mode) + ".fbx");
    write_bytes(file, bytes);
    const AssimpFbxRate expected = assimp_fbx_rate(file);
    ASSERT_EQ(expected.time_mode, mode);
    ASSERT_GT(expected.ticks_per_s, 0.0);
    if (mode == 14) {
      ASSERT_EQ(expected.ticks_per_s, custom);
    }
    const LoadedModel model = load_model(file);
    ASSERT_EQ(model.clips.size(), 1U);
    EXPECT_NEAR(model.clips[0].rate_hz, expected.ticks_per_s, 1e-6 * expected.ticks_per_s);
    EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::file);
  }
  // The default mode (0) declares no rate (assimp then counts ticks in seconds): the keys decide.
  std::string bytes = original;
  const std::int32_t zero = 0;
  std::memcpy(bytes.data() + mode_at + mode_tag.size(), &zero, sizeof zero);
  const fs::path file = dir / "huesitos_mode0.fbx";
  write_bytes(file, bytes);
  ASSERT_EQ(assimp_fbx_rate(file).time_mode, 0);
  const LoadedModel model = load_model(file);
  ASSERT_EQ(model.clips.size(), 1U);
  const double gap = even_gap(model.rig->clips[0].key_times);
  EXPECT_NEAR(model.clips[0].rate_hz, 1.0 / gap, 1e-3);
  EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::key_grid);
}

// The <frame_rate> of the file's <visual_scene><extra><technique profile="MAX3D">, read here
// from the text.
double max3d_frame_rate(const fs::path& file) {
  const std::string text = read_bytes(file);
  std::smatch m;
  const std::regex tag(R"(<technique profile="MAX3D">\s*<frame_rate>([^<]*)</frame_rate>)");
  return std::regex_search(text, m, tag) ? std::stod(m[1].str()) : 0.0;
}

TEST(ClipFrameRate, ColladaFrameRateComesFromThe3dsMaxExtra) {
  // 64 boxes turned by keys about 3 s apart, exported from 3ds Max at a frame rate it writes.
  const fs::path file = assimp_model("Collada/anims_with_full_rotations_between_keys.DAE");
  const double expected = max3d_frame_rate(file);
  ASSERT_GT(expected, 0.0);
  const LoadedModel model = load_model(file);
  ASSERT_FALSE(model.clips.empty());
  for (const ClipSummary& clip : model.clips) {
    EXPECT_LT(clip.keys_per_s, 0.5 * expected) << clip.name;  // the keys are not the frames
    EXPECT_EQ(clip.rate_hz, expected) << clip.name;
    EXPECT_EQ(clip.rate_source, FrameRateSource::file) << clip.name;
    expect_sampled_at(model, clip, expected);
  }

  // A <frame_rate> that is no rate is reported and ignored.
  std::string text = read_bytes(file);
  const std::string open = "<technique profile=\"MAX3D\"><frame_rate>";
  const auto from = text.find(open);
  ASSERT_NE(from, std::string::npos);
  const auto to = text.find("</frame_rate>", from);
  ASSERT_NE(to, std::string::npos);
  text.replace(from + open.size(), to - from - open.size(), "-5");
  const fs::path bad = test::temp_dir("clip_frame_rate_collada") / "bad_rate.dae";
  write_bytes(bad, text);
  const LoadedModel refused = load_model(bad);
  ASSERT_FALSE(refused.clips.empty());
  EXPECT_NE(refused.clips[0].rate_source, FrameRateSource::file);
  EXPECT_TRUE(
      std::any_of(refused.problems.begin(), refused.problems.end(), [](const std::string& p) {
        return p.find("Collada <frame_rate> '-5' is not a positive number; ignored") !=
               std::string::npos;
      }));
}

// The <frame_rate> as XML writes it: blanks around the number, an entity, CDATA; a rate that is
// two numbers is named as one line, its blanks folded (the problem line has no line breaks).
TEST(ClipFrameRate, ColladaFrameRateIsReadAsXmlWritesIt) {
  const fs::path file = assimp_model("Collada/anims_with_full_rotations_between_keys.DAE");
  const std::string text = read_bytes(file);
  const std::string open = "<technique profile=\"MAX3D\"><frame_rate>";
  const auto from = text.find(open);
  ASSERT_NE(from, std::string::npos);
  const auto to = text.find("</frame_rate>", from);
  ASSERT_NE(to, std::string::npos);
  const auto with_rate = [&](const std::string& rate, const std::string& name) {
    std::string changed = text;
    changed.replace(from + open.size(), to - from - open.size(), rate);
    const fs::path out = test::temp_dir("clip_frame_rate_collada_text") / (name + ".dae");
    write_bytes(out, changed);
    return load_model(out);
  };
  for (const auto& [rate, name] : std::vector<std::pair<std::string, std::string>>{
           {"\n      24  \n    ", "blanks"}, {"&#50;4", "entity"}, {"<![CDATA[24]]>", "cdata"}}) {
    const LoadedModel model = with_rate(rate, name);
    ASSERT_FALSE(model.clips.empty()) << name;
    EXPECT_EQ(model.clips[0].rate_hz, 24.0) << name;
    EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::file) << name;
  }
  const LoadedModel two = with_rate("\n  24\n\t 25 ", "two_numbers");
  ASSERT_FALSE(two.clips.empty());
  EXPECT_NE(two.clips[0].rate_source, FrameRateSource::file);
  EXPECT_TRUE(std::any_of(two.problems.begin(), two.problems.end(), [](const std::string& p) {
    return p.find("Collada <frame_rate> '24 25' is not a positive number; ignored") !=
           std::string::npos;
  }));
}

TEST(ClipFrameRate, ColladaWithoutFrameRateFollowsItsEvenlySpacedKeys) {
  const fs::path file = asset("characters/stormtrooper/stormtrooper.dae");
  ASSERT_EQ(max3d_frame_rate(file), 0.0);
  const LoadedModel model = load_model(file);
  ASSERT_EQ(model.clips.size(), 1U);
  const double gap = even_gap(model.rig->clips[0].key_times);
  const double frames_per_s = std::round(1.0 / gap);
  ASSERT_NEAR(1.0 / gap, frames_per_s, 1e-3);
  EXPECT_EQ(model.clips[0].rate_hz, frames_per_s);
  EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::key_grid);
  expect_sampled_at(model, model.clips[0], frames_per_s);
}

TEST(ClipFrameRate, GltfDeclaresNoFrameRate) {
  // CesiumMan keys every frame of a 24 fps export: its keys are its frames.
  {
    const LoadedModel model = load_model(asset("characters/CesiumMan.glb"));
    ASSERT_EQ(model.clips.size(), 1U);
    const double gap = even_gap(model.rig->clips[0].key_times);
    const double frames_per_s = std::round(1.0 / gap);
    ASSERT_NEAR(1.0 / gap, frames_per_s, 1e-3);
    EXPECT_EQ(model.clips[0].rate_hz, frames_per_s);
    EXPECT_EQ(model.clips[0].rate_source, FrameRateSource::key_grid);
  }
  // Two keys 1.25 s apart (RiggedFigure), keys every 0.5 s (simple_skin), keys on a grid with a
  // hole (Fox's Run): no frame rate, 30 Hz — not 2 samples for RiggedFigure's 1.25 s.
  struct Case {
    fs::path file;
    std::string clip;
  };
  for (const Case& c :
       {Case{asset("characters/RiggedFigure.glb"), ""},
        Case{assimp_model("glTF2/simple_skin/simple_skin.gltf"), ""},
        Case{asset("characters/Fox.glb"), "Run"}}) {
    SCOPED_TRACE(c.file.string() + " " + c.clip);
    const LoadedModel model = load_model(c.file);
    const auto it =
        c.clip.empty()
            ? model.clips.begin()
            : std::find_if(model.clips.begin(), model.clips.end(), [&](const ClipSummary& s) {
                return s.name == c.clip;
              });
    ASSERT_NE(it, model.clips.end());
    const auto& keys =
        model.rig->clips[static_cast<std::size_t>(model.rig->find_clip(it->name))].key_times;
    std::vector<double> gaps;
    for (std::size_t k = 1; k < keys.size(); ++k) gaps.push_back(keys[k] - keys[k - 1]);
    ASSERT_FALSE(gaps.empty());
    const bool uneven = *std::max_element(gaps.begin(), gaps.end()) >
                        1.5 * *std::min_element(gaps.begin(), gaps.end());
    EXPECT_TRUE(keys.size() < 3 || uneven || gaps[0] >= 0.25) << "no frame grid in these keys";
    EXPECT_EQ(it->rate_hz, kDefaultSampleRateHz);
    EXPECT_EQ(it->rate_source, FrameRateSource::none);
    expect_sampled_at(model, *it, kDefaultSampleRateHz);
  }
}

}  // namespace
}  // namespace skelcd::skinning
