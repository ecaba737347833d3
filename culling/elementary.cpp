#include "culling/elementary.hpp"

#include <algorithm>
#include <cassert>

namespace skelcd::culling {
namespace {

inline Eigen::Vector3d row(const skinning::Positions& x, std::int32_t i) {
  return x.row(static_cast<Eigen::Index>(i)).transpose();
}

}  // namespace

ccd::VertexFaceQuery vertex_face_query(
    const skinning::Positions& xv_t0,
    const skinning::Positions& xv_t1,
    std::int32_t v,
    const skinning::Positions& xf_t0,
    const skinning::Positions& xf_t1,
    const std::array<std::int32_t, 3>& f) {
  return {row(xv_t0, v),
          row(xf_t0, f[0]),
          row(xf_t0, f[1]),
          row(xf_t0, f[2]),
          row(xv_t1, v),
          row(xf_t1, f[0]),
          row(xf_t1, f[1]),
          row(xf_t1, f[2])};
}

ccd::EdgeEdgeQuery edge_edge_query(
    const skinning::Positions& xa_t0,
    const skinning::Positions& xa_t1,
    const std::array<std::int32_t, 2>& ea,
    const skinning::Positions& xb_t0,
    const skinning::Positions& xb_t1,
    const std::array<std::int32_t, 2>& eb) {
  return {row(xa_t0, ea[0]),
          row(xa_t0, ea[1]),
          row(xb_t0, eb[0]),
          row(xb_t0, eb[1]),
          row(xa_t1, ea[0]),
          row(xa_t1, ea[1]),
          row(xb_t1, eb[0]),
          row(xb_t1, eb[1])};
}

void run_ccd_tests(
    const FeatureTopology& topology,
    const FeatureCandidates& candidates,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const ElementaryTests& tests,
    ccd::Accuracy accuracy,
    const ccd::CcdOptions& options,
    FrameResult& out) {
  assert(tests.vertex_face != nullptr && tests.edge_edge != nullptr);
  const std::size_t first = out.contacts.size();
  Counters& c = out.counters;
  for (const VertexFacePair& p : candidates.vf) {
    const ccd::VertexFaceQuery q =
        vertex_face_query(x_t0, x_t1, p.vertex, x_t0, x_t1, topology.triangle(p.face));
    const ccd::CcdResult r = tests.vertex_face(q, accuracy, options);
    ++c.vf_tests;
    if (r.hit) {
      ++c.vf_contacts;
      out.contacts.push_back({CcdContact::Kind::vf, p.vertex, p.face, r.toi_lower, r.toi_upper});
    }
  }
  for (const EdgeEdgePair& p : candidates.ee) {
    const ccd::EdgeEdgeQuery q =
        edge_edge_query(x_t0, x_t1, topology.edge(p.a), x_t0, x_t1, topology.edge(p.b));
    const ccd::CcdResult r = tests.edge_edge(q, accuracy, options);
    ++c.ee_tests;
    if (r.hit) {
      ++c.ee_contacts;
      out.contacts.push_back({CcdContact::Kind::ee, p.a, p.b, r.toi_lower, r.toi_upper});
    }
  }
  // std::sort works in place: no allocation.
  std::sort(
      out.contacts.begin() + static_cast<std::ptrdiff_t>(first),
      out.contacts.end(),
      [](const CcdContact& a, const CcdContact& b) { return a.before(b); });
}

void run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    FrameResult& out) {
  assert(tests.triangles != nullptr);
  const std::size_t first = out.dcd_pairs.size();
  for (const TrianglePair& p : pairs) {
    assert(p.a < p.b);
    int count = 0;
    const ccd::SharedCorners shared = topology.shared_corners(p.a, p.b, count);
    const auto& ta = topology.triangle(p.a);
    const auto& tb = topology.triangle(p.b);
    const ccd::TriangleTriangleQuery q{
        row(x, ta[0]), row(x, ta[1]), row(x, ta[2]), row(x, tb[0]), row(x, tb[1]), row(x, tb[2])};
    ++out.counters.tt_tests;
    if (tests.triangles(q, shared)) {
      ++out.counters.dcd_pairs;
      out.dcd_pairs.push_back(p);
    }
  }
  std::sort(out.dcd_pairs.begin() + static_cast<std::ptrdiff_t>(first), out.dcd_pairs.end());
}

}  // namespace skelcd::culling
