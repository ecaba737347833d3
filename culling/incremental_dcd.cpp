#include "culling/incremental_dcd.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>

#include "culling/candidates.hpp"

namespace skelcd::culling {
namespace {

inline std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

}  // namespace

DcdUpdater::DcdUpdater(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    std::shared_ptr<const FeatureTopology> features)
    : shared_(shared_or_built(std::move(features), mesh, topology, OwnerOrder::any)),
      features_(*shared_),
      edge_face_offsets_(topology.edge_face_offsets),
      edge_faces_(topology.edge_faces) {
  const std::int32_t num_vertices = features_.num_vertices();
  const std::int32_t num_triangles = features_.num_triangles();
  vertex_face_offsets_.assign(at(num_vertices) + 1, 0);
  const auto distinct_corners = [&](std::int32_t f, auto&& visit) {
    const auto& t = features_.triangle(f);
    for (std::size_t k = 0; k < 3; ++k) {
      if ((k > 0 && t[k] == t[0]) || (k == 2 && t[2] == t[1])) continue;  // a repeated corner
      visit(t[k]);
    }
  };
  for (std::int32_t f = 0; f < num_triangles; ++f) {
    distinct_corners(f, [&](std::int32_t v) { ++vertex_face_offsets_[at(v) + 1]; });
  }
  for (std::size_t v = 0; v < at(num_vertices); ++v) {
    vertex_face_offsets_[v + 1] += vertex_face_offsets_[v];
  }
  vertex_faces_.resize(at(vertex_face_offsets_.back()));
  std::vector<std::int32_t> fill(vertex_face_offsets_.begin(), vertex_face_offsets_.end() - 1);
  for (std::int32_t f = 0; f < num_triangles; ++f) {
    distinct_corners(f, [&](std::int32_t v) { vertex_faces_[at(fill[at(v)]++)] = f; });
  }
}

void DcdUpdater::affected_pairs(
    std::span<const CcdContact> contacts, std::vector<TrianglePair>& out) const {
  out.clear();
  const auto add = [&](std::int32_t a, std::int32_t b) {
    if (a == b) return;
    const TrianglePair p{std::min(a, b), std::max(a, b)};
    if (dcd_checks_pair(features_, p)) out.push_back(p);
  };
  for (const CcdContact& c : contacts) {
    if (c.kind == CcdContact::Kind::vf) {
      for (const std::int32_t f : vertex_triangles(c.a)) add(f, c.b);
    } else {
      for (const std::int32_t f : edge_triangles(c.a)) {
        for (const std::int32_t g : edge_triangles(c.b)) add(f, g);
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void DcdUpdater::update(
    std::span<const TrianglePair> previous,
    std::span<const CcdContact> contacts,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    FrameResult& out) {
  const auto start = std::chrono::steady_clock::now();
  affected_pairs(contacts, affected_);
  tested_.clear();
  // Certifying the vertex fans costs a pass over every vertex: worth it only for many pairs.
  const ElementaryTests kernels = with_ccd_defaults(tests);
  if (affected_.size() * 4 >= static_cast<std::size_t>(features_.num_vertices())) {
    run_dcd_tests(features_, affected_, x, kernels, tested_);
  } else {
    run_dcd_tests(features_, affected_, x, kernels, std::span<const std::uint8_t>{}, tested_);
  }
  // previous \ affected, merged with the affected pairs that intersect now (both sorted).
  const std::size_t first = out.dcd_pairs.size();
  auto hit = tested_.dcd_pairs.begin();
  auto gone = affected_.begin();
  for (const TrianglePair& p : previous) {
    while (gone != affected_.end() && *gone < p) ++gone;
    if (gone != affected_.end() && *gone == p) continue;  // tested again: its new status is in hits
    while (hit != tested_.dcd_pairs.end() && *hit < p) out.dcd_pairs.push_back(*hit++);
    out.dcd_pairs.push_back(p);
  }
  out.dcd_pairs.insert(out.dcd_pairs.end(), hit, tested_.dcd_pairs.end());
  out.counters.candidate_pairs += static_cast<std::int64_t>(affected_.size());
  out.counters.tt_tests += tested_.counters.tt_tests;
  out.counters.dcd_pairs += static_cast<std::int64_t>(out.dcd_pairs.size() - first);
  out.times.elementary_us +=
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace skelcd::culling
