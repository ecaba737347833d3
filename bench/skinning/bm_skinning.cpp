// Skinned vertices per second, and topology build time, on a generated tube rig: a tube of
// `rings` rings × 64 vertices around a chain of 32 bones along x, each vertex weighted to the
// 2–4 bones whose segment centres lie within 1.5 segment lengths (a linear falloff). The clip
// bends every joint about z by a sine. Built once per size; each iteration poses one sample.
//
//   build/bench/skinning/bm_skinning --benchmark_counters_tabular=true

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include <benchmark/benchmark.h>

#include "skinning/lbs.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"

namespace {

using namespace skelcd::skinning;

constexpr int kRingVertices = 64;
constexpr int kBones = 32;
constexpr double kLength = 32.0;  // tube length along x; one bone per unit
constexpr double kRadius = 1.0;

std::shared_ptr<const Rig> tube_rig(int rings) {
  Rig rig;
  rig.source = "tube(" + std::to_string(rings) + " rings)";
  const int nv = rings * kRingVertices;
  rig.mesh.rest_positions.resize(nv, 3);
  for (int r = 0; r < rings; ++r) {
    const double x = kLength * r / (rings - 1);
    for (int k = 0; k < kRingVertices; ++k) {
      const double a = 2 * std::numbers::pi * k / kRingVertices;
      rig.mesh.rest_positions.row(r * kRingVertices + k) << x, kRadius * std::cos(a), kRadius * std::sin(a);
    }
  }
  const int nf = 2 * kRingVertices * (rings - 1);
  rig.mesh.triangles.resize(nf, 3);
  int f = 0;
  for (int r = 0; r + 1 < rings; ++r) {
    for (int k = 0; k < kRingVertices; ++k) {
      const int a = r * kRingVertices + k;
      const int b = r * kRingVertices + (k + 1) % kRingVertices;
      rig.mesh.triangles.row(f++) << a, b + kRingVertices, b;
      rig.mesh.triangles.row(f++) << a, a + kRingVertices, b + kRingVertices;
    }
  }
  rig.mesh.face_part.assign(static_cast<std::size_t>(nf), 0);
  rig.mesh.face_index_in_part.resize(static_cast<std::size_t>(nf));
  for (int i = 0; i < nf; ++i) rig.mesh.face_index_in_part[static_cast<std::size_t>(i)] = i;
  rig.mesh.vertex_part.assign(static_cast<std::size_t>(nv), 0);
  rig.mesh.vertex_index_in_part.resize(static_cast<std::size_t>(nv));
  for (int i = 0; i < nv; ++i) rig.mesh.vertex_index_in_part[static_cast<std::size_t>(i)] = i;
  rig.mesh.part_names = {"tube"};

  // Chain of bones, node b at x = b, each child one unit along x from its parent.
  for (int b = 0; b < kBones; ++b) {
    SkeletonNode node;
    node.name = "joint" + std::to_string(b);
    node.parent = b - 1;
    node.rest_local = Eigen::Translation3d(b == 0 ? 0.0 : 1.0, 0, 0);
    rig.skeleton.nodes.push_back(node);
    Bone bone;
    bone.name = node.name;
    bone.node = b;
    bone.parent = b - 1;
    bone.inverse_bind = Eigen::Translation3d(-b, 0, 0);
    bone.rest_head = {double(b), 0, 0};
    bone.rest_tail = {double(b + 1), 0, 0};
    rig.skeleton.bones.push_back(bone);
  }
  // Weights: linear falloff from each bone's segment centre, normalised.
  std::vector<Eigen::Triplet<double>> w;
  for (int v = 0; v < nv; ++v) {
    const double x = rig.mesh.rest_positions(v, 0);
    double sum = 0;
    const std::size_t first = w.size();
    for (int b = 0; b < kBones; ++b) {
      const double d = std::abs(x - (b + 0.5));
      if (d < 1.5) {
        w.emplace_back(v, b, 1.5 - d);
        sum += 1.5 - d;
      }
    }
    for (std::size_t i = first; i < w.size(); ++i) w[i] = Eigen::Triplet<double>(w[i].row(), w[i].col(), w[i].value() / sum);
  }
  rig.weights.resize(nv, kBones);
  rig.weights.setFromTriplets(w.begin(), w.end());
  rig.weights.makeCompressed();

  // Clip: 2 s, 60 keys per joint, joint j bends by 0.3 sin(2π t + j/4) rad about z.
  Clip clip;
  clip.name = "wave";
  clip.duration_s = 2.0;
  for (int k = 0; k <= 60; ++k) clip.key_times.push_back(2.0 * k / 60);
  for (int b = 1; b < kBones; ++b) {
    Channel ch;
    ch.node = b;
    ch.rotation_times = clip.key_times;
    for (double t : clip.key_times) {
      const double angle = 0.3 * std::sin(2 * std::numbers::pi * t + b / 4.0);
      ch.rotations.emplace_back(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
    }
    clip.channels.push_back(std::move(ch));
  }
  rig.clips.push_back(std::move(clip));
  return std::make_shared<const Rig>(std::move(rig));
}

void add_context(benchmark::State& state, const Rig& rig) {
  state.counters["vertices"] = static_cast<double>(rig.mesh.num_vertices());
  state.counters["influences/vertex"] = static_cast<double>(rig.weights.nonZeros()) / static_cast<double>(rig.mesh.num_vertices());
}

// The LBS kernel alone, transforms given.
void BM_LinearBlendSkinning(benchmark::State& state) {
  const auto rig = tube_rig(static_cast<int>(state.range(0)));
  const PoseEvaluator evaluator(*rig);
  const LinearBlendSkinning lbs(*rig);
  Pose pose;
  evaluator.clip_pose(0, 0.7, pose);
  Positions out;
  lbs.apply(pose, out);
  for (auto _ : state) {
    lbs.apply(pose, out);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * rig->mesh.num_vertices());
  add_context(state, *rig);
}

// One sample of the clip: interpolate the keys, evaluate the hierarchy, skin.
void BM_RigMotionSample(benchmark::State& state) {
  const auto rig = tube_rig(static_cast<int>(state.range(0)));
  const RigMotion motion(rig, RigMotionOptions{.clip = 0, .rate_hz = 30});
  Positions out;
  motion.positions(0, out);
  int i = 0;
  for (auto _ : state) {
    motion.positions(i, out);
    i = (i + 1) % motion.num_samples();
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * rig->mesh.num_vertices());
  add_context(state, *rig);
}

// Welding, edges, adjacency, boundary loops, components, degenerate test, on the same tube.
void BM_BuildTopology(benchmark::State& state) {
  const auto rig = tube_rig(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    auto topology = build_topology(rig->mesh);
    benchmark::DoNotOptimize(topology.edges.data());
  }
  state.SetItemsProcessed(state.iterations() * rig->mesh.num_triangles());
  state.counters["triangles"] = static_cast<double>(rig->mesh.num_triangles());
}

// 1,600 rings × 64 = 102,400 vertices (204,672 triangles); 160 rings = 10,240 vertices.
BENCHMARK(BM_LinearBlendSkinning)->Arg(160)->Arg(1600)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RigMotionSample)->Arg(160)->Arg(1600)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildTopology)->Arg(160)->Arg(1600)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
#ifdef NDEBUG
  benchmark::AddCustomContext("build_type", "release (NDEBUG)");
#else
  benchmark::AddCustomContext("build_type", "debug (asserts on)");
#endif
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
