#include "tests/culling/real_triangle_queries.hpp"

#include <array>
#include <bit>
#include <cassert>
#include <cstring>
#include <map>

#include "culling/frame_result.hpp"
#include "culling/method.hpp"
#include "culling/vertex_fans.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling::test {
namespace {

// Where the stand-in test writes (the DCD runs on the calling thread: ElementaryTests::threads 1).
std::vector<RecordedTriangleQuery>* g_sink = nullptr;

bool record(const ccd::TriangleTriangleQuery& q, const ccd::SharedCorners& shared) {
  assert(g_sink != nullptr);
  g_sink->push_back({q, shared, false});
  return ccd::triangles_intersect(q, shared);
}

using PositionKey = std::array<std::uint64_t, 3>;

PositionKey key_of(const Eigen::Vector3d& p) {
  return {
      std::bit_cast<std::uint64_t>(p.x()),
      std::bit_cast<std::uint64_t>(p.y()),
      std::bit_cast<std::uint64_t>(p.z())};
}

}  // namespace

RealTriangleQueries record_dcd_queries(const std::filesystem::path& model_path, int samples) {
  assert(samples >= 1);
  const skinning::LoadedModel model = skinning::load_model(model_path);
  const auto motion = model.motion();
  const skinning::Mesh& mesh = motion->mesh();
  const skinning::Topology topology = skinning::build_topology(mesh);
  auto recording = make_method("bvh", mesh, topology, {.elementary = {.triangles = &record}});
  auto production = make_method("bvh", mesh, topology);

  // The fans the production DCD certifies, rebuilt here to mark the pairs it settles without a
  // test: a pair sharing a corner whose welded vertex has a certified fan.
  std::vector<std::array<std::int32_t, 3>> triangles(
      static_cast<std::size_t>(topology.welded_triangles.rows()));
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    for (std::size_t k = 0; k < 3; ++k) {
      triangles[f][k] =
          topology.welded_triangles(static_cast<Eigen::Index>(f), static_cast<Eigen::Index>(k));
    }
  }
  const VertexFans fans(triangles, topology.num_welded_vertices());

  RealTriangleQueries out;
  const int n = motion->num_samples();
  skinning::Positions posed, welded;
  std::vector<std::uint8_t> certified;
  for (int s = 0; s < samples; ++s) {
    const int k = samples == 1
                      ? 0
                      : static_cast<int>((static_cast<std::int64_t>(s) * (n - 1)) / (samples - 1));
    motion->positions(k, posed);
    skinning::gather_welded(topology, posed, welded);

    const std::size_t first = out.queries.size();
    g_sink = &out.queries;
    FrameResult recorded;
    recording->detect_dcd(welded, recorded);
    g_sink = nullptr;
    FrameResult result;
    production->detect_dcd(welded, result);
    out.production_tests += result.counters.tt_tests;
    out.intersecting_pairs += static_cast<std::int64_t>(result.dcd_pairs.size());

    // Welded vertex of each position (-1 where two welded vertices coincide: left untested).
    std::map<PositionKey, std::int32_t> vertex_at;
    for (Eigen::Index v = 0; v < welded.rows(); ++v) {
      const auto [it, inserted] =
          vertex_at.emplace(key_of(welded.row(v).transpose()), static_cast<std::int32_t>(v));
      if (!inserted) it->second = -1;
    }
    fans.certify(welded, certified);
    for (std::size_t i = first; i < out.queries.size(); ++i) {
      RecordedTriangleQuery& r = out.queries[i];
      const Eigen::Vector3d* a[3] = {&r.query.a0, &r.query.a1, &r.query.a2};
      for (std::size_t c = 0; c < 3; ++c) {
        if (r.shared[c] < 0) continue;
        const auto it = vertex_at.find(key_of(*a[c]));
        if (it != vertex_at.end() && it->second >= 0 &&
            certified[static_cast<std::size_t>(it->second)] != 0) {
          r.fan_settled = true;
        }
      }
    }
  }
  return out;
}

}  // namespace skelcd::culling::test
