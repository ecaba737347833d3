#include "skinning/generators.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "skinning/errors.hpp"
#include "skinning/generators_common.hpp"
#include "skinning/lbs.hpp"
#include "skinning/load.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/pose.hpp"

namespace skelcd::skinning {

// Defined in generators_tube.cpp, generators_limbs.cpp, generators_cloth.cpp, generators_panda.cpp.
namespace generators {
GeneratedRig generate_rope(std::int64_t triangles, int frames);
GeneratedRig generate_pipe(std::int64_t triangles, int frames);
GeneratedRig generate_octopus(std::int64_t triangles, int frames);
GeneratedRig generate_hand(std::int64_t triangles, int frames);
GeneratedRig generate_cloth(std::int64_t triangles, int frames);
GeneratedRig generate_panda(int frames, bool reach);
}  // namespace generators

const std::vector<GeneratorInfo>& generator_list() {
  static const std::vector<GeneratorInfo> list = {
      {"rope", "closed tube on a chain of 20 bones that coils in its plane until its end cap runs into its start cap",
       48'000, 60, true,
       "intersecting from the first frame where the end cap's leading vertex reaches the start cap's plane x = 0"},
      {"octopus", "closed body with 8 tentacles (8 bones each); neighbouring tentacles curl towards each other in pairs",
       48'000, 60, true,
       "intersecting from the first frame where a tentacle reaches the mirror plane between it and its partner"},
      {"hand", "closed palm with 4 fingers and a thumb (5 bones each); fingers bend sideways into each other in pairs",
       12'000, 60, true,
       "intersecting from the first frame where a finger reaches the mirror plane between it and its partner"},
      {"pipe", "open tube lying on the ground; a hinge of 6 bones folds one end back over the other and down into it",
       78'000, 60, false,
       "intersecting from the first frame where the folded end's lowest rim vertex reaches the other half's top ridge"},
      {"cloth", "open sheet on a row of hinge bones; its right part folds over onto its left part",
       20'000, 60, false,
       "intersecting from the first frame where the folded part's free edge reaches the plane of the part below"},
      {"panda", "the bundled Franka Panda (collision meshes, SRDF) on a generated trajectory that folds the hand onto links 0-2",
       0, 61, true,
       "intersecting (fingers, then hand, against links 1-2) for trajectory parameter tau > 0.6258, free below 0.6257"},
      {"panda-free", "the bundled Franka Panda on a generated trajectory that moves every joint far and stays collision-free",
       0, 61, true, "free at every frame"},
  };
  return list;
}

bool is_generator_spec(std::string_view model) { return model.rfind("gen:", 0) == 0; }

namespace {

constexpr std::int64_t kMinTriangles = 100;
constexpr std::int64_t kMaxTriangles = 5'000'000;
constexpr int kMaxFrames = 100'000;

const GeneratorInfo* find_generator(std::string_view name) {
  for (const GeneratorInfo& g : generator_list()) {
    if (g.name == name) return &g;
  }
  return nullptr;
}

std::string generator_names() {
  std::string names;
  for (const GeneratorInfo& g : generator_list()) names += (names.empty() ? "" : ", ") + g.name;
  return names;
}

}  // namespace

GeneratorSpec parse_generator_spec(std::string_view text) {
  const std::string where(text);
  if (!is_generator_spec(text)) throw InvalidInput(where + ": a generator spec starts with 'gen:'");
  std::string_view rest = text.substr(4);
  const std::size_t q = rest.find('?');
  GeneratorSpec spec;
  spec.name = std::string(rest.substr(0, q));
  const GeneratorInfo* info = find_generator(spec.name);
  if (info == nullptr) {
    throw InvalidInput(where + ": unknown generator '" + spec.name + "' (known: " + generator_names() + ")");
  }
  if (q != std::string_view::npos) {
    std::string_view params = rest.substr(q + 1);
    while (!params.empty()) {
      const std::size_t amp = params.find('&');
      const std::string_view item = params.substr(0, amp);
      params = amp == std::string_view::npos ? std::string_view() : params.substr(amp + 1);
      const std::size_t eq = item.find('=');
      if (eq == std::string_view::npos) throw InvalidInput(where + ": parameter '" + std::string(item) + "' has no value");
      const std::string_view key = item.substr(0, eq);
      const std::string_view value = item.substr(eq + 1);
      std::int64_t v = 0;
      const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
      if (value.empty() || ec != std::errc() || ptr != value.data() + value.size() || v <= 0) {
        throw InvalidInput(where + ": " + std::string(key) + " = '" + std::string(value) + "' is not a positive integer");
      }
      if (key == "triangles") {
        if (info->default_triangles == 0) throw InvalidInput(where + ": " + spec.name + " has a fixed size; drop 'triangles'");
        if (v < kMinTriangles || v > kMaxTriangles) {
          throw InvalidInput(where + ": triangles = " + std::to_string(v) + " is outside [" +
                             std::to_string(kMinTriangles) + ", " + std::to_string(kMaxTriangles) + "]");
        }
        spec.triangles = v;
      } else if (key == "frames") {
        if (v < 2 || v > kMaxFrames) {
          throw InvalidInput(where + ": frames = " + std::to_string(v) + " is outside [2, " + std::to_string(kMaxFrames) + "]");
        }
        spec.frames = static_cast<int>(v);
      } else {
        throw InvalidInput(where + ": unknown parameter '" + std::string(key) + "' (known: triangles, frames)");
      }
    }
  }
  return spec;
}

std::string to_string(const GeneratorSpec& spec) {
  const GeneratorInfo* info = find_generator(spec.name);
  std::string s = "gen:" + spec.name + "?";
  if (info != nullptr && info->default_triangles > 0) {
    s += "triangles=" + std::to_string(spec.triangles > 0 ? spec.triangles : info->default_triangles) + "&";
  }
  s += "frames=" + std::to_string(spec.frames > 0 ? spec.frames : (info != nullptr ? info->default_frames : 0));
  return s;
}

GeneratedRig generate(const GeneratorSpec& requested) {
  const GeneratorInfo* info = find_generator(requested.name);
  if (info == nullptr) {
    throw InvalidInput("generate: unknown generator '" + requested.name + "' (known: " + generator_names() + ")");
  }
  GeneratorSpec spec = requested;
  if (info->default_triangles == 0 && spec.triangles != 0) {
    throw InvalidInput("generate: " + spec.name + " has a fixed size; no triangle count applies");
  }
  if (info->default_triangles > 0 && spec.triangles == 0) spec.triangles = info->default_triangles;
  if (spec.frames == 0) spec.frames = info->default_frames;
  if (spec.frames < 2 || spec.frames > kMaxFrames) {
    throw InvalidInput("generate: frames = " + std::to_string(spec.frames) + " is outside [2, " + std::to_string(kMaxFrames) + "]");
  }
  if (info->default_triangles > 0 && (spec.triangles < kMinTriangles || spec.triangles > kMaxTriangles)) {
    throw InvalidInput("generate: triangles = " + std::to_string(spec.triangles) + " is outside [" +
                       std::to_string(kMinTriangles) + ", " + std::to_string(kMaxTriangles) + "]");
  }
  GeneratedRig g;
  if (spec.name == "rope") g = generators::generate_rope(spec.triangles, spec.frames);
  else if (spec.name == "pipe") g = generators::generate_pipe(spec.triangles, spec.frames);
  else if (spec.name == "octopus") g = generators::generate_octopus(spec.triangles, spec.frames);
  else if (spec.name == "hand") g = generators::generate_hand(spec.triangles, spec.frames);
  else if (spec.name == "cloth") g = generators::generate_cloth(spec.triangles, spec.frames);
  else if (spec.name == "panda") g = generators::generate_panda(spec.frames, true);
  else g = generators::generate_panda(spec.frames, false);
  g.spec = spec;
  g.rig.source = to_string(spec);
  validate_rig(g.rig);
  return g;
}

LoadedModel load_generated_model(std::string_view text, const LoadOptions& options) {
  if (!options.trajectory.empty() || !options.srdf.empty() || !options.package_path.empty()) {
    throw InvalidInput(std::string(text) + ": a trajectory, SRDF or package path applies to URDF robots only");
  }
  GeneratedRig g = generate(parse_generator_spec(text));
  const std::string source = g.rig.source;
  LoadedModel model = model_from_rig(std::move(g.rig), ModelKind::rig, {});
  model.path = source;
  return model;
}

// ---------------------------------------------------------------------------------------------
namespace generators {

std::int32_t RigBuilder::add_node(const std::string& name, std::int32_t parent, const Eigen::Affine3d& rest_local) {
  SkeletonNode node;
  node.name = name;
  node.parent = parent;
  node.rest_local = rest_local;
  const auto index = static_cast<std::int32_t>(skeleton_.nodes.size());
  skeleton_.nodes.push_back(node);
  rest_global_.push_back(parent < 0 ? rest_local : rest_global_[static_cast<std::size_t>(parent)] * rest_local);
  Bone bone;
  bone.name = name;
  bone.node = index;
  bone.parent = parent;  // every node is a bone: node index = bone index
  skeleton_.bones.push_back(bone);
  return index;
}

Rig RigBuilder::finish(MeshBuilder&& mesh, const std::string& part_name, Clip&& clip, const std::string& source) {
  Rig rig;
  // Bones: bind = rest; the segment runs to the first child, else 0.25 along the bone's x axis.
  for (std::size_t b = 0; b < skeleton_.bones.size(); ++b) {
    Bone& bone = skeleton_.bones[b];
    bone.inverse_bind = rest_global_[b].inverse();
    bone.rest_head = rest_global_[b].translation();
    bone.rest_tail = rest_global_[b] * Eigen::Vector3d(0.25, 0, 0);
    for (std::size_t c = b + 1; c < skeleton_.nodes.size(); ++c) {
      if (skeleton_.nodes[c].parent == static_cast<std::int32_t>(b) &&
          (rest_global_[c].translation() - bone.rest_head).norm() > 0) {
        bone.rest_tail = rest_global_[c].translation();
        break;
      }
    }
  }
  rig.skeleton = skeleton_;
  Mesh& m = rig.mesh;
  const auto nv = static_cast<Eigen::Index>(mesh.vertices.size());
  const auto nf = static_cast<Eigen::Index>(mesh.triangles.size());
  m.rest_positions.resize(nv, 3);
  for (Eigen::Index v = 0; v < nv; ++v) m.rest_positions.row(v) = mesh.vertices[static_cast<std::size_t>(v)].transpose();
  m.triangles.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) m.triangles(f, k) = mesh.triangles[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
  }
  label_one_part_in_file_order(m, part_name);
  rig.weights.resize(nv, static_cast<Eigen::Index>(skeleton_.bones.size()));
  rig.weights.setFromTriplets(triplets_.begin(), triplets_.end());
  rig.weights.makeCompressed();
  rig.clips.push_back(std::move(clip));
  rig.source = source;
  return rig;
}

std::vector<std::pair<std::int32_t, double>> chain_weights(const Chain& chain, double s, double blend) {
  const auto nb = static_cast<std::int32_t>(chain.joint_s.size());
  const auto bone_length = [&](std::int32_t b) {
    const double end = b + 1 < nb ? chain.joint_s[static_cast<std::size_t>(b + 1)] : chain.length;
    return end - chain.joint_s[static_cast<std::size_t>(b)];
  };
  for (std::int32_t j = 1; j < nb; ++j) {
    const double sj = chain.joint_s[static_cast<std::size_t>(j)];
    const double h = 0.5 * blend * std::min(bone_length(j - 1), bone_length(j));
    if (s > sj - h && s < sj + h) {
      const double u = (s - (sj - h)) / (2 * h);
      const double w = u * u * (3 - 2 * u);  // smoothstep
      return {{j - 1, 1 - w}, {j, w}};
    }
  }
  std::int32_t b = 0;
  while (b + 1 < nb && s >= chain.joint_s[static_cast<std::size_t>(b + 1)]) ++b;
  return {{b, 1.0}};
}

Chain add_chain(
    RigBuilder& builder,
    const std::string& prefix,
    std::int32_t parent,
    const Eigen::Affine3d& root_local,
    std::vector<double> joint_s,
    double length) {
  Chain chain;
  chain.joint_s = std::move(joint_s);
  chain.length = length;
  std::int32_t at = parent;
  for (std::size_t j = 0; j < chain.joint_s.size(); ++j) {
    const Eigen::Affine3d local =
        j == 0 ? root_local
               : Eigen::Affine3d(Eigen::Translation3d(chain.joint_s[j] - chain.joint_s[j - 1], 0, 0));
    at = builder.add_node(prefix + std::to_string(j), at, local);
    chain.nodes.push_back(at);
  }
  return chain;
}

Clip rotation_clip(
    const std::string& name,
    const RigBuilder& builder,
    const std::vector<std::int32_t>& nodes,
    const std::vector<Eigen::Vector3d>& axes,
    int frames,
    const std::function<double(std::size_t, double)>& angle) {
  Clip clip;
  clip.name = name;
  clip.duration_s = (frames - 1) / kGeneratorFrameRateHz;
  for (int i = 0; i < frames; ++i) clip.key_times.push_back(i / kGeneratorFrameRateHz);
  clip.frame_rate_hz = kGeneratorFrameRateHz;
  clip.frame_rate_source = FrameRateSource::generator;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const SkeletonNode& node = builder.skeleton().nodes[static_cast<std::size_t>(nodes[k])];
    Channel c;
    c.node = nodes[k];
    c.translation_times = {0.0};
    c.translations = {node.rest_local.translation()};
    const Eigen::Quaterniond rest(node.rest_local.rotation());
    for (int i = 0; i < frames; ++i) {
      const double tau = static_cast<double>(i) / (frames - 1);
      c.rotation_times.push_back(clip.key_times[static_cast<std::size_t>(i)]);
      c.rotations.push_back(rest * Eigen::Quaterniond(Eigen::AngleAxisd(angle(k, tau), axes[k])));
    }
    clip.channels.push_back(std::move(c));
  }
  return clip;
}

void posed_frames(const Rig& rig, int frames, const std::function<void(int, const Positions&)>& visit) {
  const PoseEvaluator evaluator(rig);
  const LinearBlendSkinning skinning(rig);
  Pose pose;
  Positions positions;
  for (int i = 0; i < frames; ++i) {
    evaluator.clip_pose(0, rig.clips[0].key_times[static_cast<std::size_t>(i)], pose);
    skinning.apply(pose, positions);
    visit(i, positions);
  }
}

void decide(KnownAnswer& answer, double tolerance) {
  const auto n = static_cast<int>(answer.margin.size());
  answer.last_free_frame = -1;
  while (answer.last_free_frame + 1 < n && answer.margin[static_cast<std::size_t>(answer.last_free_frame + 1)] < -tolerance) {
    ++answer.last_free_frame;
  }
  int first = n;
  while (first > 0 && answer.margin[static_cast<std::size_t>(first - 1)] > tolerance) --first;
  answer.first_intersecting_frame = first < n ? first : -1;
}

std::int64_t round_at_least(double x, std::int64_t lo) {
  return std::max(lo, static_cast<std::int64_t>(std::llround(x)));
}

}  // namespace generators
}  // namespace skelcd::skinning
