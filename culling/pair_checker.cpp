// Inter-object checks: two AABB hierarchies refit per query and traversed against each other,
// then the shared feature rules and elementary tests (docs/scenes.md, "Pair checks").
#include "culling/pair_checker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "culling/pair_sort.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace {

using Clock = std::chrono::steady_clock;

double micros(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

Eigen::Vector3d row(const skinning::Positions& x, std::int32_t i) { return x.row(i).transpose(); }

/// Welded rest positions: row w is the rest position of representative_vertex[w].
skinning::Positions welded_rest(const skinning::Mesh& mesh, const skinning::Topology& topology) {
  skinning::Positions rest(topology.num_welded_vertices(), 3);
  for (std::int32_t w = 0; w < topology.num_welded_vertices(); ++w) {
    const std::int32_t v = topology.representative_vertex[at(w)];
    if (v < 0 || v >= mesh.rest_positions.rows()) {
      throw InvalidInput(
          "culling::PairChecker: representative_vertex[" + std::to_string(w) +
          "] = " + std::to_string(v) + " is not a mesh vertex");
    }
    rest.row(w) = mesh.rest_positions.row(v);
  }
  return rest;
}

}  // namespace

PairChecker::PairChecker(
    const skinning::Mesh& mesh_a,
    const skinning::Topology& topology_a,
    const skinning::Mesh& mesh_b,
    const skinning::Topology& topology_b,
    const PairOptions& options)
    : options_(options),
      tests_(with_ccd_defaults(options.elementary)),
      topology_a_(mesh_a, topology_a),
      topology_b_(mesh_b, topology_b) {
  if (!(std::isfinite(options.min_separation) && options.min_separation >= 0.0)) {
    throw InvalidInput("culling::PairChecker: min_separation must be finite and >= 0");
  }
  if (options.min_separation > 0.0 && options.accuracy == ccd::Accuracy::exact) {
    throw InvalidInput("culling::PairChecker: the exact accuracy supports only min_separation 0");
  }
  ccd_options_.min_separation = options.min_separation;
  ccd_options_.relative_boxes = true;  // docs/ccd.md, "Relative boxes"
  // Traversed on their wide copies only (pair_traverse): no binary node volumes to refit.
  BvhOptions bvh = options.bvh;
  bvh.node_volumes = false;
  bvh_a_ = AabbBvh(topology_a_.welded_triangles(), welded_rest(mesh_a, topology_a), bvh);
  bvh_b_ = AabbBvh(topology_b_.welded_triangles(), welded_rest(mesh_b, topology_b), bvh);
  scratch_.reserve_pair(bvh_a_, bvh_b_);
  const auto faces =
      static_cast<std::size_t>(topology_a_.num_triangles() + topology_b_.num_triangles());
  pairs_.reserve(4 * faces);
  vf_.reserve(4 * faces);
  ee_.reserve(4 * faces);
}

void PairChecker::check_rows(
    const skinning::Positions& x, std::int32_t rows, const char* what) const {
  if (x.rows() != rows) {
    throw InvalidInput(
        "culling::PairChecker: " + std::string(what) + " has " + std::to_string(x.rows()) +
        " rows, expected " + std::to_string(rows));
  }
}

void PairChecker::detect_dcd(
    const skinning::Positions& x_a, const skinning::Positions& x_b, PairFrameResult& out) {
  check_rows(x_a, topology_a_.num_vertices(), "x_a");
  check_rows(x_b, topology_b_.num_vertices(), "x_b");
  const auto t0 = Clock::now();
  // Refit both hierarchies over the static volumes of the instant.
  static_vertex_bounds<3>(x_a, bounds_a_.vertices);
  bounds_a_.derive(topology_a_, /*with_edges=*/false);
  bvh_a_.refit(bounds_a_.triangles);
  static_vertex_bounds<3>(x_b, bounds_b_.vertices);
  bounds_b_.derive(topology_b_, /*with_edges=*/false);
  bvh_b_.refit(bounds_b_.triangles);
  const auto t1 = Clock::now();
  // A against B: every cross pair whose volumes overlap is a candidate (no adjacency between
  // objects, no part exclusion across them).
  pairs_.clear();
  pair_traverse<3>(
      bvh_a_,
      bounds_a_.triangles,
      bvh_b_,
      bounds_b_.triangles,
      scratch_,
      pairs_,
      out.counters.bv_tests);
  out.counters.candidate_pairs += static_cast<std::int64_t>(pairs_.size());
  const auto t2 = Clock::now();
  // Exact triangle-triangle tests (the objects share no corner).
  const std::size_t first = out.dcd_pairs.size();
  for (const TrianglePair& p : pairs_) {
    const auto& ta = topology_a_.triangle(p.a);
    const auto& tb = topology_b_.triangle(p.b);
    const ccd::TriangleTriangleQuery q{
        row(x_a, ta[0]),
        row(x_a, ta[1]),
        row(x_a, ta[2]),
        row(x_b, tb[0]),
        row(x_b, tb[1]),
        row(x_b, tb[2])};
    ++out.counters.tt_tests;
    if (tests_.triangles(q, ccd::kNoSharedCorners)) {
      ++out.counters.dcd_pairs;
      out.dcd_pairs.push_back(p);
    }
  }
  sort_pairs(std::span(out.dcd_pairs).subspan(first));
  const auto t3 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2);
  out.times.elementary_us += micros(t2, t3);
}

void PairChecker::detect_ccd(
    const skinning::Positions& x_a_t0,
    const skinning::Positions& x_a_t1,
    const skinning::Positions& x_b_t0,
    const skinning::Positions& x_b_t1,
    PairFrameResult& out) {
  check_rows(x_a_t0, topology_a_.num_vertices(), "x_a_t0");
  check_rows(x_a_t1, topology_a_.num_vertices(), "x_a_t1");
  check_rows(x_b_t0, topology_b_.num_vertices(), "x_b_t0");
  check_rows(x_b_t1, topology_b_.num_vertices(), "x_b_t1");
  const auto t0 = Clock::now();
  // Swept volumes of the interval, each grown by half the contact distance.
  const double half_width = 0.5 * options_.min_separation;
  swept_vertex_bounds<3>(x_a_t0, x_a_t1, half_width, bounds_a_.vertices);
  bounds_a_.derive(topology_a_);
  bvh_a_.refit(bounds_a_.triangles);
  swept_vertex_bounds<3>(x_b_t0, x_b_t1, half_width, bounds_b_.vertices);
  bounds_b_.derive(topology_b_);
  bvh_b_.refit(bounds_b_.triangles);
  const auto t1 = Clock::now();
  pairs_.clear();
  pair_traverse<3>(
      bvh_a_,
      bounds_a_.triangles,
      bvh_b_,
      bounds_b_.triangles,
      scratch_,
      pairs_,
      out.counters.bv_tests);
  out.counters.candidate_pairs += static_cast<std::int64_t>(pairs_.size());
  // Feature stage. Each vertex and edge is owned by exactly one of its triangles
  // (FeatureTopology), so the triangle pair (A_i, B_j) produces (vertex owned by A_i, face B_j),
  // (vertex owned by B_j, face A_i) and (edge owned by A_i, edge owned by B_j): every cross
  // feature pair whose volumes overlap comes from exactly one overlapping triangle pair, because
  // a feature's volume lies inside its owner's (docs/culling.md, de-duplication).
  vf_.clear();
  ee_.clear();
  std::int64_t feature_bv_tests = 0;
  for (const TrianglePair& p : pairs_) {
    const auto& ta = topology_a_.triangle(p.a);
    const auto& tb = topology_b_.triangle(p.b);
    const std::uint8_t own_a = topology_a_.owned(p.a);
    const std::uint8_t own_b = topology_b_.owned(p.b);
    const Dop<3>& face_a = bounds_a_.triangles[at(p.a)];
    const Dop<3>& face_b = bounds_b_.triangles[at(p.b)];
    for (int k = 0; k < 3; ++k) {
      if ((own_a & (1u << k)) != 0) {
        const std::int32_t v = ta[static_cast<std::size_t>(k)];
        ++feature_bv_tests;
        if (bounds_a_.vertices[at(v)].overlaps(face_b)) vf_.push_back({false, v, p.b});
      }
      if ((own_b & (1u << k)) != 0) {
        const std::int32_t v = tb[static_cast<std::size_t>(k)];
        ++feature_bv_tests;
        if (bounds_b_.vertices[at(v)].overlaps(face_a)) vf_.push_back({true, v, p.a});
      }
    }
    for (int ka = 0; ka < 3; ++ka) {
      if ((own_a & (1u << (3 + ka))) == 0) continue;
      const std::int32_t ea = topology_a_.face_edge(p.a, ka);
      if (ea < 0) continue;
      for (int kb = 0; kb < 3; ++kb) {
        if ((own_b & (1u << (3 + kb))) == 0) continue;
        const std::int32_t eb = topology_b_.face_edge(p.b, kb);
        if (eb < 0) continue;
        ++feature_bv_tests;
        if (bounds_a_.edges[at(ea)].overlaps(bounds_b_.edges[at(eb)])) ee_.push_back({ea, eb});
      }
    }
  }
  out.counters.feature_bv_tests += feature_bv_tests;
  const auto t2 = Clock::now();
  // Elementary tests at the requested accuracy.
  const std::size_t first = out.contacts.size();
  for (const VertexFace& p : vf_) {
    const auto& xv0 = p.vertex_of_b ? x_b_t0 : x_a_t0;
    const auto& xv1 = p.vertex_of_b ? x_b_t1 : x_a_t1;
    const auto& xf0 = p.vertex_of_b ? x_a_t0 : x_b_t0;
    const auto& xf1 = p.vertex_of_b ? x_a_t1 : x_b_t1;
    const auto& f = p.vertex_of_b ? topology_a_.triangle(p.face) : topology_b_.triangle(p.face);
    const ccd::VertexFaceQuery q = vertex_face_query(xv0, xv1, p.vertex, xf0, xf1, f);
    const ccd::CcdResult r = tests_.vertex_face(q, options_.accuracy, ccd_options_);
    ++out.counters.vf_tests;
    if (r.hit) {
      ++out.counters.vf_contacts;
      out.contacts.push_back(
          {CcdContact::Kind::vf, p.vertex_of_b, p.vertex, p.face, r.toi_lower, r.toi_upper});
    }
  }
  for (const EdgeEdgePair& p : ee_) {
    const ccd::EdgeEdgeQuery q = edge_edge_query(
        x_a_t0, x_a_t1, topology_a_.edge(p.a), x_b_t0, x_b_t1, topology_b_.edge(p.b));
    const ccd::CcdResult r = tests_.edge_edge(q, options_.accuracy, ccd_options_);
    ++out.counters.ee_tests;
    if (r.hit) {
      ++out.counters.ee_contacts;
      out.contacts.push_back({CcdContact::Kind::ee, false, p.a, p.b, r.toi_lower, r.toi_upper});
    }
  }
  std::sort(
      out.contacts.begin() + static_cast<std::ptrdiff_t>(first),
      out.contacts.end(),
      [](const PairContact& x, const PairContact& y) { return x.before(y); });
  const auto t3 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2);
  out.times.elementary_us += micros(t2, t3);
}

}  // namespace skelcd::culling
