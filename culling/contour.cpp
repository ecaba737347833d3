#include "culling/contour.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "culling/contour_predicates.hpp"

namespace skelcd::culling {
namespace {

inline std::size_t sz(std::int64_t i) { return static_cast<std::size_t>(i); }

/// A contour edge while the node's loops are formed: with its edge id, which the pairing at
/// pinch vertices walks from (the stored ContourEdge does not keep it).
struct RawEdge {
  std::int32_t from = -1;
  std::int32_t to = -1;
  std::int32_t edge = -1;  ///< edge id (FeatureTopology / Topology::edges row)
  std::int8_t part = -1;
};

/// A 32-bit offset into the contours' arrays.
std::int32_t offset_of(std::size_t size) {
  if (size > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::length_error("culling::NodeContours: more than 2^31 contour rows");
  }
  return static_cast<std::int32_t>(size);
}

}  // namespace

const char* to_string(ContourStatus status) {
  switch (status) {
    case ContourStatus::loops:
      return "loops";
    case ContourStatus::not_tested:
      return "not_tested";
    case ContourStatus::no_contour:
      return "no_contour";
    case ContourStatus::degenerate_triangle:
      return "degenerate_triangle";
    case ContourStatus::non_manifold:
      return "non_manifold";
    case ContourStatus::inconsistent_orientation:
      return "inconsistent_orientation";
    case ContourStatus::unpaired_fan:
      return "unpaired_fan";
    case ContourStatus::too_many_loops:
      return "too_many_loops";
  }
  return "unknown";
}

int sub_surfaces(const AabbBvh& bvh, std::int32_t node, std::array<std::int32_t, 4>& out) {
  const auto nodes = bvh.nodes();
  const BvhNode& n = nodes[sz(node)];
  if (n.is_leaf()) return 0;
  int count = 0;
  for (const std::int32_t child : {node + 1, n.right}) {
    const BvhNode& c = nodes[sz(child)];
    if (c.is_leaf()) {
      out[static_cast<std::size_t>(count++)] = child;
    } else {
      out[static_cast<std::size_t>(count++)] = child + 1;
      out[static_cast<std::size_t>(count++)] = c.right;
    }
  }
  return count;
}

bool contour_tested(const AabbBvh& bvh, std::int32_t node) {
  const auto nodes = bvh.nodes();
  const BvhNode& n = nodes[sz(node)];
  return !n.is_leaf() && !(nodes[sz(node + 1)].is_leaf() && nodes[sz(n.right)].is_leaf());
}

NodeContours::NodeContours(const AabbBvh& bvh, const FeatureTopology& topology) {
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  const std::size_t num_nodes = nodes.size();
  status_.assign(num_nodes, ContourStatus::not_tested);
  record_.assign(num_nodes, -1);

  // Scratch indexed by edge and by vertex, reset through touched lists (§5.2.2 preprocessing).
  const auto ne = static_cast<std::size_t>(topology.num_edges());
  const auto nv = static_cast<std::size_t>(topology.num_vertices());
  std::vector<std::uint8_t> count(ne, 0);
  std::vector<std::int8_t> direction(ne, 0);
  std::vector<std::int32_t> face0(ne, -1);
  std::vector<std::int32_t> face1(ne, -1);
  std::vector<std::int32_t> contour_index(ne, -1);
  std::vector<std::int32_t> touched_edges;
  std::vector<std::int32_t> out_count(nv, 0);
  std::vector<std::int32_t> out_first(nv, -1);
  std::vector<std::int32_t> stack_pos(nv, -1);
  std::vector<std::int32_t> touched_vertices;
  std::vector<std::int32_t> slot_of(static_cast<std::size_t>(topology.num_triangles()), -1);
  for (std::size_t s = 0; s < order.size(); ++s) {
    slot_of[static_cast<std::size_t>(order[s])] = static_cast<std::int32_t>(s);
  }
  std::vector<RawEdge> raw;
  std::vector<std::int32_t> next;
  std::vector<std::uint8_t> used;
  std::vector<std::int32_t> stack;
  std::vector<std::vector<std::int32_t>> loops;
  std::vector<ContourFan> raw_fans;
  std::vector<std::int32_t> position;  // raw index → index in the node's ordered edges

  for (std::size_t i = 0; i < num_nodes; ++i) {
    std::array<std::int32_t, 4> parts{};
    const int num_parts = sub_surfaces(bvh, static_cast<std::int32_t>(i), parts);
    const BvhNode& node = nodes[i];
    if (num_parts == 0 || !contour_tested(bvh, static_cast<std::int32_t>(i))) {
      ++status_counts_[static_cast<std::size_t>(ContourStatus::not_tested)];
      continue;
    }
    ContourStatus status = ContourStatus::loops;

    // 1. The boundary chain of the node's triangles: each side adds its directed edge; an edge
    //    of two triangles traversed in opposite directions cancels (interior), an edge of one
    //    triangle is on the contour, anything else breaks the preconditions.
    touched_edges.clear();
    for (std::int32_t s = node.begin; s < node.end && status == ContourStatus::loops; ++s) {
      const std::int32_t f = order[sz(s)];
      const auto& t = topology.triangle(f);
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        status = ContourStatus::degenerate_triangle;
        break;
      }
      for (int k = 0; k < 3; ++k) {
        const std::int32_t e = topology.face_edge(f, k);
        const auto ue = static_cast<std::size_t>(e);
        const std::int8_t dir = t[static_cast<std::size_t>(k)] == topology.edge(e)[0] ? 1 : -1;
        if (count[ue] == 0) {
          touched_edges.push_back(e);
          count[ue] = 1;
          direction[ue] = dir;
          face0[ue] = f;
        } else if (count[ue] == 1) {
          if (direction[ue] == dir) status = ContourStatus::inconsistent_orientation;
          count[ue] = 2;
          face1[ue] = f;
        } else {
          status = ContourStatus::non_manifold;
        }
      }
    }
    raw.clear();
    touched_vertices.clear();
    if (status == ContourStatus::loops) {
      for (const std::int32_t e : touched_edges) {
        const auto ue = static_cast<std::size_t>(e);
        if (count[ue] != 1) continue;
        const auto& ends = topology.edge(e);
        RawEdge c;
        c.edge = e;
        c.from = direction[ue] > 0 ? ends[0] : ends[1];
        c.to = direction[ue] > 0 ? ends[1] : ends[0];
        const std::int32_t slot = slot_of[static_cast<std::size_t>(face0[ue])];
        for (int p = 0; p < num_parts; ++p) {
          const BvhNode& pn = nodes[sz(parts[static_cast<std::size_t>(p)])];
          if (slot >= pn.begin && slot < pn.end) c.part = static_cast<std::int8_t>(p);
        }
        assert(c.part >= 0);
        contour_index[ue] = static_cast<std::int32_t>(raw.size());
        const auto uf = static_cast<std::size_t>(c.from);
        if (out_count[uf]++ == 0) touched_vertices.push_back(c.from);
        out_first[uf] = static_cast<std::int32_t>(raw.size());
        raw.push_back(c);
      }
      if (raw.empty()) status = ContourStatus::no_contour;
    }

    // 2. Pair each incoming contour edge with the outgoing edge of the same fan of triangles
    //    around its end vertex (the only one, except at pinch vertices), walking around the
    //    vertex through the node's interior edges.
    next.assign(raw.size(), -1);
    used.assign(raw.size(), 0);
    raw_fans.clear();
    for (std::size_t k = 0; k < raw.size() && status == ContourStatus::loops; ++k) {
      const std::int32_t v = raw[k].to;
      std::int32_t out = -1;
      if (out_count[static_cast<std::size_t>(v)] == 1) {
        out = out_first[static_cast<std::size_t>(v)];
      } else if (out_count[static_cast<std::size_t>(v)] > 1) {
        std::int32_t f = face0[static_cast<std::size_t>(raw[k].edge)];
        for (int guard = 0; guard < 256 && out < 0 && f >= 0; ++guard) {
          const auto& t = topology.triangle(f);
          int c = 0;
          while (c < 3 && t[static_cast<std::size_t>(c)] != v) ++c;
          if (c == 3) break;
          const std::int32_t e = topology.face_edge(f, c);  // the side leaving v
          const auto ue = static_cast<std::size_t>(e);
          if (count[ue] == 1) {
            out = contour_index[ue];
          } else {
            f = face0[ue] == f ? face1[ue] : face0[ue];
          }
        }
        if (out >= 0) {
          raw_fans.push_back({v, static_cast<std::int32_t>(k), out});
        }
      }
      if (out < 0 || raw[static_cast<std::size_t>(out)].from != v ||
          used[static_cast<std::size_t>(out)] != 0) {
        status = ContourStatus::unpaired_fan;
        break;
      }
      used[static_cast<std::size_t>(out)] = 1;
      next[k] = out;
    }

    // 3. Follow the pairing; cut a cycle wherever it returns to a vertex it already holds, so
    //    that every loop visits each of its vertices once.
    loops.clear();
    if (status == ContourStatus::loops) {
      std::fill(used.begin(), used.end(), 0);
      for (std::size_t s0 = 0; s0 < raw.size(); ++s0) {
        if (used[s0] != 0) continue;
        stack.clear();
        std::size_t e = s0;
        while (used[e] == 0) {
          used[e] = 1;
          stack_pos[static_cast<std::size_t>(raw[e].from)] =
              static_cast<std::int32_t>(stack.size());
          stack.push_back(static_cast<std::int32_t>(e));
          const std::int32_t start = stack_pos[static_cast<std::size_t>(raw[e].to)];
          if (start >= 0) {
            loops.emplace_back(stack.begin() + start, stack.end());
            for (auto it = stack.begin() + start; it != stack.end(); ++it) {
              stack_pos[static_cast<std::size_t>(raw[static_cast<std::size_t>(*it)].from)] = -1;
            }
            stack.resize(static_cast<std::size_t>(start));
          }
          e = static_cast<std::size_t>(next[e]);
        }
        if (!stack.empty()) {  // cannot happen for a cycle of the pairing
          status = ContourStatus::unpaired_fan;
          for (const std::int32_t k : stack)
            stack_pos[static_cast<std::size_t>(raw[static_cast<std::size_t>(k)].from)] = -1;
          break;
        }
      }
      if (status == ContourStatus::loops &&
          loops.size() > static_cast<std::size_t>(kMaxContourLoops)) {
        status = ContourStatus::too_many_loops;
      }
    }

    // 4. Store: loops rotated to start at a change of sub-surface, chains, probes, fans.
    if (status == ContourStatus::loops) {
      record_[i] = offset_of(edge_begin_.size());
      edge_begin_.push_back(offset_of(from_.size()));
      loop_begin_.push_back(offset_of(loop_probe_.size()));
      chain_begin_.push_back(offset_of(chain_starts_.size()));
      fan_begin_.push_back(offset_of(fans_.size()));
      position.assign(raw.size(), -1);
      const auto base = static_cast<std::int32_t>(from_.size());
      for (const auto& loop : loops) {
        const std::size_t m = loop.size();
        std::size_t start = m;
        for (std::size_t k = 0; k < m; ++k) {
          if (raw[sz(loop[k])].part != raw[sz(loop[(k + m - 1) % m])].part) {
            start = k;
            break;
          }
        }
        const bool one_part = start == m;
        if (one_part) start = 0;
        const auto first = static_cast<std::int32_t>(from_.size()) - base;
        loop_starts_.push_back(first);
        std::int32_t probe = -1;
        for (std::size_t k = 0; k < m; ++k) {
          const std::int32_t r = loop[(start + k) % m];
          const RawEdge& c = raw[sz(r)];
          position[sz(r)] = static_cast<std::int32_t>(from_.size()) - base;
          if (one_part || k == 0 || c.part != part_.back()) {
            chain_starts_.push_back(position[sz(r)]);
          }
          if (probe < 0 && out_count[static_cast<std::size_t>(c.from)] == 1) probe = c.from;
          // Its `to` is the next edge's `from` (the first's for the last): not stored.
          assert(c.to == raw[sz(loop[(start + k + 1) % m])].from);
          from_.push_back(c.from);
          part_.push_back(c.part);
        }
        loop_probe_.push_back(probe);
      }
      const auto total = static_cast<std::int32_t>(from_.size()) - base;
      loop_starts_.push_back(total);
      chain_starts_.push_back(total);
      for (const ContourFan& f : raw_fans) {
        fans_.push_back({f.vertex, position[sz(f.in_edge)], position[sz(f.out_edge)]});
      }
      std::sort(
          fans_.begin() + fan_begin_.back(),
          fans_.end(),
          [](const ContourFan& a, const ContourFan& b) { return a.vertex < b.vertex; });
    }

    for (const std::int32_t e : touched_edges) {
      count[static_cast<std::size_t>(e)] = 0;
      contour_index[static_cast<std::size_t>(e)] = -1;
    }
    for (const std::int32_t v : touched_vertices) {
      out_count[static_cast<std::size_t>(v)] = 0;
      out_first[static_cast<std::size_t>(v)] = -1;
    }
    status_[i] = status;
    ++status_counts_[static_cast<std::size_t>(status)];
  }
  edge_begin_.push_back(offset_of(from_.size()));
  loop_begin_.push_back(offset_of(loop_probe_.size()));
  chain_begin_.push_back(offset_of(chain_starts_.size()));
  fan_begin_.push_back(offset_of(fans_.size()));
  // Kept for the method's lifetime: give back what push_back's doubling reserved beyond the rows.
  for (auto* v :
       {&edge_begin_,
        &loop_begin_,
        &chain_begin_,
        &fan_begin_,
        &loop_starts_,
        &loop_probe_,
        &chain_starts_}) {
    v->shrink_to_fit();
  }
  from_.shrink_to_fit();
  part_.shrink_to_fit();
  fans_.shrink_to_fit();
}

void NodeContours::edges(std::int32_t node, std::vector<ContourEdge>& out) const {
  out.clear();
  const std::int32_t r = record_[sz(node)];
  if (r < 0) return;
  const auto base = sz(edge_begin_[sz(r)]);
  const auto starts = loop_starts(node);
  for (std::size_t l = 0; l + 1 < starts.size(); ++l) {
    const std::size_t begin = base + sz(starts[l]);
    const std::size_t end = base + sz(starts[l + 1]);
    for (std::size_t k = begin; k < end; ++k) {
      out.push_back({from_[k], from_[k + 1 < end ? k + 1 : begin], part_[k]});
    }
  }
}

std::vector<ContourEdge> NodeContours::edges(std::int32_t node) const {
  std::vector<ContourEdge> out;
  edges(node, out);
  return out;
}

std::span<const std::int32_t> NodeContours::loop_starts(std::int32_t node) const {
  const std::int32_t r = record_[sz(node)];
  if (r < 0) return {};
  // #loops + 1 entries per record before this one.
  return std::span<const std::int32_t>(loop_starts_)
      .subspan(sz(loop_begin_[sz(r)] + r), sz(loop_begin_[sz(r) + 1] - loop_begin_[sz(r)] + 1));
}

std::span<const std::int32_t> NodeContours::loop_probe(std::int32_t node) const {
  const std::int32_t r = record_[sz(node)];
  if (r < 0) return {};
  return std::span<const std::int32_t>(loop_probe_)
      .subspan(sz(loop_begin_[sz(r)]), sz(loop_begin_[sz(r) + 1] - loop_begin_[sz(r)]));
}

std::span<const std::int32_t> NodeContours::chain_starts(std::int32_t node) const {
  const std::int32_t r = record_[sz(node)];
  if (r < 0) return {};
  return std::span<const std::int32_t>(chain_starts_)
      .subspan(sz(chain_begin_[sz(r)]), sz(chain_begin_[sz(r) + 1] - chain_begin_[sz(r)]));
}

std::span<const ContourFan> NodeContours::fans(std::int32_t node) const {
  const std::int32_t r = record_[sz(node)];
  if (r < 0) return {};
  return std::span<const ContourFan>(fans_).subspan(
      sz(fan_begin_[sz(r)]), sz(fan_begin_[sz(r) + 1] - fan_begin_[sz(r)]));
}

namespace {

/// Positions at the two ends of the interval (the same matrix twice for an instant).
struct Frames {
  const skinning::Positions& x0;
  const skinning::Positions& x1;
  [[nodiscard]] Eigen::Vector3d at0(std::int32_t w) const { return x0.row(w).transpose(); }
  [[nodiscard]] Eigen::Vector3d at1(std::int32_t w) const { return x1.row(w).transpose(); }
};

/// Sign of form(x[b] − x[a], x[d] − x[c]) at the instant, or over all t in [0,1].
template <bool kContinuous, class Form>
ProvenSign form_sign(
    Form form, const Frames& x, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
  const Eigen::Vector3d p0 = x.at0(b) - x.at0(a);
  const Eigen::Vector3d q0 = x.at0(d) - x.at0(c);
  if constexpr (!kContinuous) {
    return sign_of(form(p0, q0));
  } else {
    const Eigen::Vector3d p1 = x.at1(b) - x.at1(a);
    const Eigen::Vector3d q1 = x.at1(d) - x.at1(c);
    const auto cs = bernstein_bilinear(form, p0, p1, q0, q1);
    return bernstein_quadratic_sign(cs[0], cs[1], cs[2]);
  }
}

/// True when the projected edges (v0 → a) and (v0 → b), sharing v0, provably meet only at v0
/// (at the instant / for all t): they are never collinear, or always point apart.
template <bool kContinuous, class Det, class Dot>
bool adjacent_separated(
    Det det, Dot dot, const Frames& x, std::int32_t v0, std::int32_t a, std::int32_t b) {
  if (form_sign<kContinuous>(det, x, v0, a, v0, b) != ProvenSign::uncertain) return true;
  return form_sign<kContinuous>(dot, x, v0, a, v0, b) == ProvenSign::negative;
}

/// True when projected segments p1p2 and q1q2 (no shared vertex) provably do not meet: some
/// line separates them — the supporting line of one segment, or a line through an endpoint
/// perpendicular to it (the last covers collinear, disjoint segments).
template <bool kContinuous, class Det, class Dot>
bool segments_separated(
    Det det,
    Dot dot,
    const Frames& x,
    std::int32_t p1,
    std::int32_t p2,
    std::int32_t q1,
    std::int32_t q2) {
  // Both q's strictly on one side of line(p), or both p's of line(q).
  const ProvenSign a = form_sign<kContinuous>(det, x, p1, p2, p1, q1);
  if (a != ProvenSign::uncertain && a == form_sign<kContinuous>(det, x, p1, p2, p1, q2)) {
    return true;
  }
  const ProvenSign b = form_sign<kContinuous>(det, x, q1, q2, q1, p1);
  if (b != ProvenSign::uncertain && b == form_sign<kContinuous>(det, x, q1, q2, q1, p2)) {
    return true;
  }
  // Both q's beyond p2 along p1 → p2, or before p1; and the same for the p's along q.
  auto beyond = [&](std::int32_t s1, std::int32_t s2, std::int32_t o1, std::int32_t o2) {
    // dot(o − s2, s2 − s1) > 0 for both o's: past the end s2.
    if (form_sign<kContinuous>(dot, x, s2, o1, s1, s2) == ProvenSign::positive &&
        form_sign<kContinuous>(dot, x, s2, o2, s1, s2) == ProvenSign::positive) {
      return true;
    }
    // dot(o − s1, s2 − s1) < 0 for both o's: before the start s1.
    return form_sign<kContinuous>(dot, x, s1, o1, s1, s2) == ProvenSign::negative &&
           form_sign<kContinuous>(dot, x, s1, o2, s1, s2) == ProvenSign::negative;
  };
  return beyond(p1, p2, q1, q2) || beyond(q1, q2, p1, p2);
}

/// Sign of det_V(x[a] − x[v], x[b] − x[v]): the turn from direction v→a to v→b.
template <bool kContinuous, class Det>
ProvenSign turn(Det det, const Frames& x, std::int32_t v, std::int32_t a, std::int32_t b) {
  return form_sign<kContinuous>(det, x, v, a, v, b);
}

/// True when the fans at one pinch vertex provably cover disjoint wedges in the projection
/// (at the instant / for all t): no fan's edge direction lies in another fan's closed wedge,
/// the wedge of a fan being swept counter-clockwise from its out-edge to its in-edge.
template <bool kContinuous, class Det, class Dot>
bool fans_disjoint(
    Det det,
    Dot dot,
    const Frames& x,
    std::span<const ContourFan> group,
    std::span<const ContourEdge> edges,
    ContourTestCounters& counters) {
  const std::int32_t v = group.front().vertex;
  for (const ContourFan& a : group) {
    const std::int32_t wa = edges[sz(a.out_edge)].to;   // wedge start direction
    const std::int32_t wb = edges[sz(a.in_edge)].from;  // wedge end direction
    ProvenSign sab = turn<kContinuous>(det, x, v, wa, wb);
    if (sab == ProvenSign::uncertain) {
      // A wedge of about π (a straight boundary through v): only directions strictly on the
      // far side of both edges are certainly outside it, as for a reflex wedge.
      if (form_sign<kContinuous>(dot, x, v, wa, v, wb) != ProvenSign::negative) return false;
      sab = ProvenSign::negative;
    }
    for (const ContourFan& b : group) {
      if (&a == &b) continue;
      ++counters.pinch_tests;
      for (const std::int32_t d : {edges[sz(b.out_edge)].to, edges[sz(b.in_edge)].from}) {
        // d is outside the closed wedge from wa counter-clockwise to wb when it is strictly
        // clockwise of wa or strictly counter-clockwise of wb (a wedge below π), or both (above).
        const bool cw_of_start = turn<kContinuous>(det, x, v, wa, d) == ProvenSign::negative;
        const bool ccw_of_end = turn<kContinuous>(det, x, v, d, wb) == ProvenSign::negative;
        const bool outside =
            sab == ProvenSign::positive ? (cw_of_start || ccw_of_end) : (cw_of_start && ccw_of_end);
        if (!outside) return false;
      }
    }
  }
  return true;
}

/// Orientation of one loop (at positions x): the sign of its signed area in the projection,
/// proven with the rounding bounds of its fan of det_V terms.
ProvenSign loop_orientation(
    const Eigen::Vector3d& v, const skinning::Positions& x, std::span<const ContourEdge> loop) {
  const Eigen::Vector3d p0 = x.row(loop[0].from).transpose();
  double sum = 0.0;
  double err = 0.0;
  double mag = 0.0;
  for (std::size_t k = 1; k + 1 < loop.size(); ++k) {
    const BoundedValue t = det_v(
        v,
        Eigen::Vector3d(x.row(loop[k].from).transpose()) - p0,
        Eigen::Vector3d(x.row(loop[k + 1].from).transpose()) - p0);
    sum += t.value;
    err += t.error;
    mag += std::abs(t.value);
  }
  // Recursive summation of n terms: at most n·u of the sum of magnitudes, plus the term errors.
  const double n = static_cast<double>(loop.size());
  return sign_of({sum, err * (1.0 + n * kUnitRoundoff) + 2.0 * n * kUnitRoundoff * mag});
}

/// Winding number of the projected loop around the projection of point p (at positions x);
/// `ok` becomes false when a predicate is undecided (p on or very near the loop, or a loop vertex
/// on the ray) — the caller then gives up, the safe side.
int winding_number(
    const Eigen::Vector3d& v,
    const ProjectionFrame& frame,
    const skinning::Positions& x,
    std::span<const ContourEdge> loop,
    const Eigen::Vector3d& p,
    bool& ok) {
  // Sunday's crossing rule with sign primitives: the "height" of a point is det_V(w, a − p), a
  // coordinate of the projection across the ray direction; w mixes the frame's two axes with
  // irrational-looking weights so that grid-aligned meshes do not put vertices on the ray.
  // "Left of" is det_V as everywhere else, so the count has the orientation of the loop signs.
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  w(frame.i) = 0.7548776662466927;
  w(frame.j) = 0.5698402909980532;
  auto height = [&](const Eigen::Vector3d& a) { return sign_of(det_v(v, w, a - p)); };
  int count = 0;
  for (const ContourEdge& e : loop) {
    const Eigen::Vector3d a = x.row(e.from).transpose();
    const Eigen::Vector3d b = x.row(e.to).transpose();
    const ProvenSign ha = height(a);
    const ProvenSign hb = height(b);
    if (ha == ProvenSign::uncertain || hb == ProvenSign::uncertain) {
      ok = false;
      return 0;
    }
    if (ha == hb) continue;
    const ProvenSign left = sign_of(det_v(v, b - a, p - a));
    if (left == ProvenSign::uncertain) {
      ok = false;
      return 0;
    }
    if (ha == ProvenSign::negative && left == ProvenSign::positive) ++count;
    if (ha == ProvenSign::positive && left == ProvenSign::negative) --count;
  }
  return count;
}

/// True when the loops (already proven simple and mutually non-crossing) cover every point at
/// most once: just inside each counter-clockwise loop the other loops' winding numbers add up to
/// at most 0. Evaluated at x; a continuous motion that keeps the loops simple and apart keeps
/// every orientation and winding number, so this holds over the interval too.
bool loops_cover_once(
    const Eigen::Vector3d& v,
    const ProjectionFrame& frame,
    const skinning::Positions& x,
    std::span<const ContourEdge> edges,
    std::span<const std::int32_t> loop_starts,
    std::span<const std::int32_t> probes,
    ContourTestCounters& counters) {
  const std::size_t m = probes.size();
  for (std::size_t j = 0; j < m; ++j) {
    const auto loop_j = edges.subspan(sz(loop_starts[j]), sz(loop_starts[j + 1] - loop_starts[j]));
    const ProvenSign o = loop_orientation(v, x, loop_j);
    if (o == ProvenSign::uncertain) return false;
    if (o == ProvenSign::negative) continue;
    if (probes[j] < 0) return false;
    const Eigen::Vector3d p = x.row(probes[j]).transpose();
    int w = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (i == j) continue;
      ++counters.nesting_tests;
      bool ok = true;
      w += winding_number(
          v,
          frame,
          x,
          edges.subspan(sz(loop_starts[i]), sz(loop_starts[i + 1] - loop_starts[i])),
          p,
          ok);
      if (!ok) return false;
    }
    if (w > 0) return false;
  }
  return true;
}

}  // namespace

ContourVerdict ContourTester::test(
    const NodeContours& nodes,
    std::int32_t node,
    const Eigen::Vector3d& v,
    const skinning::Positions& x,
    ContourMode mode,
    ContourTestCounters& counters) {
  return run<false>(nodes, node, v, x, x, mode, counters);
}

ContourVerdict ContourTester::test(
    const NodeContours& nodes,
    std::int32_t node,
    const Eigen::Vector3d& v,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    ContourMode mode,
    ContourTestCounters& counters) {
  return run<true>(nodes, node, v, x_t0, x_t1, mode, counters);
}

template <bool kContinuous>
ContourVerdict ContourTester::run(
    const NodeContours& nodes,
    std::int32_t node,
    const Eigen::Vector3d& v,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    ContourMode mode,
    ContourTestCounters& counters) {
  assert(nodes.status(node) == ContourStatus::loops);
  nodes.edges(node, edges_);
  const std::span<const ContourEdge> edges(edges_);
  const auto chains = nodes.chain_starts(node);
  const std::size_t m = edges.size();
  const Frames x{x_t0, x_t1};
  const auto det = [&v](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return det_v(v, a, b);
  };
  const auto dot = [&v](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return dot_v(v, a, b);
  };
  const ProjectionFrame frame(v);
  ContourVerdict verdict;

  // Condition 2 (§5.1, Algorithm 2), chains mode: each chain's projected binormals lie in an open
  // half-plane — equivalently its projected edge directions do — so the chain is strictly
  // monotone along a direction of the projection plane, hence simple (Turning Tangent argument of
  // §5.1.1). The half-plane is found from the edges' angles in the frame's coordinates, then
  // proven edge by edge: det_V(w, e) > 0 with w = cos φ e_i + sin φ e_j is the coordinate of the
  // projected e along the witness direction.
  chain_of_.resize(m);
  const std::size_t num_chains = chains.empty() ? 0 : chains.size() - 1;
  std::int32_t next_id = 0;
  auto angle2 = [&frame](const Eigen::Vector3d& e) {
    return std::atan2(frame.g2.dot(e), frame.g1.dot(e));
  };
  auto wrap = [](double a) {
    constexpr double kPi = std::numbers::pi;
    while (a > kPi) a -= 2.0 * kPi;
    while (a < -kPi) a += 2.0 * kPi;
    return a;
  };
  auto edge0 = [&](std::size_t k) -> Eigen::Vector3d {
    return x.at0(edges[k].to) - x.at0(edges[k].from);
  };
  auto edge1 = [&](std::size_t k) -> Eigen::Vector3d {
    return x.at1(edges[k].to) - x.at1(edges[k].from);
  };
  for (std::size_t c = 0; c < num_chains; ++c) {
    const auto begin = static_cast<std::size_t>(chains[c]);
    const auto end = static_cast<std::size_t>(chains[c + 1]);
    if (mode != ContourMode::chains) {
      for (std::size_t k = begin; k < end; ++k) chain_of_[k] = next_id++;
      continue;
    }
    if (end - begin >= 2) ++counters.chain_tests;
    // Cut the chain greedily into runs whose projected edge directions (at t0 and t1 for CCD)
    // span less than π: each such run has a binormal cone of half-angle < π/2 in the projection
    // plane, which is proven edge by edge below (det_V(w, e) > 0 for the witness direction w,
    // w = cos φ e_i + sin φ e_j, φ mid-range) and makes the run strictly monotone, hence simple.
    // A chain that needs no cut passes the dual-cone test of Algorithm 2 as is; one that needs
    // cuts (or whose proof fails, leaving one-edge runs) is counted, and its runs are then
    // tested against each other like any two chains.
    bool cut = false;
    std::size_t run = begin;
    while (run < end) {
      double prev = angle2(edge0(run));
      double lo = prev;
      double hi = prev;
      if (kContinuous) {
        const double a1 = prev + wrap(angle2(edge1(run)) - prev);
        lo = std::min(lo, a1);
        hi = std::max(hi, a1);
      }
      std::size_t k = run + 1;
      for (; k < end; ++k) {
        const double a0 = prev + wrap(angle2(edge0(k)) - prev);
        double nlo = std::min(lo, a0);
        double nhi = std::max(hi, a0);
        if (kContinuous) {
          const double a1 = a0 + wrap(angle2(edge1(k)) - angle2(edge0(k)));
          nlo = std::min(nlo, a1);
          nhi = std::max(nhi, a1);
        }
        if (nhi - nlo >= std::numbers::pi * (1.0 - 1e-9)) break;
        lo = nlo;
        hi = nhi;
        prev = a0;
      }
      bool monotone = k - run >= 2;
      if (monotone) {
        const double mid = 0.5 * (lo + hi);
        Eigen::Vector3d w = Eigen::Vector3d::Zero();
        w(frame.i) = std::cos(mid);
        w(frame.j) = std::sin(mid);
        for (std::size_t q = run; q < k && monotone; ++q) {
          monotone = sign_of(det_v(v, w, edge0(q))) == ProvenSign::positive;
          // det_V(w, e(t)) is linear in t: positive at both ends means positive throughout.
          if (kContinuous && monotone)
            monotone = sign_of(det_v(v, w, edge1(q))) == ProvenSign::positive;
        }
      }
      if (monotone) {
        for (std::size_t q = run; q < k; ++q) chain_of_[q] = next_id;
        ++next_id;
      } else {
        for (std::size_t q = run; q < k; ++q) chain_of_[q] = next_id++;
      }
      cut = cut || k < end || !monotone;
      run = k;
    }
    if (cut && end - begin >= 2) {
      ++counters.chain_cuts;
      verdict.cut_parts = static_cast<std::uint8_t>(verdict.cut_parts | (1u << edges[begin].part));
    }
  }

  // Condition 3 (the contour overlap test): 2D boxes of the projected edges (over the interval
  // for CCD), in the frame's exact-on-V coordinates with rounding margins; a sweep along the
  // first coordinate finds the overlapping pairs, which get the conservative segment tests.
  boxes_.resize(m);
  sorted_.resize(m);
  counters.projected_edges += static_cast<std::int64_t>(m);
  auto widen = [&frame](Box2& box, const Eigen::Vector3d& p) {
    const BoundedValue c1 = ProjectionFrame::coordinate(frame.g1, p);
    const BoundedValue c2 = ProjectionFrame::coordinate(frame.g2, p);
    box.lo1 = std::min(box.lo1, c1.value - c1.error);
    box.hi1 = std::max(box.hi1, c1.value + c1.error);
    box.lo2 = std::min(box.lo2, c2.value - c2.error);
    box.hi2 = std::max(box.hi2, c2.value + c2.error);
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < m; ++k) {
    Box2 box{kInf, -kInf, kInf, -kInf};
    widen(box, x.at0(edges[k].from));
    widen(box, x.at0(edges[k].to));
    if constexpr (kContinuous) {
      widen(box, x.at1(edges[k].from));
      widen(box, x.at1(edges[k].to));
    }
    boxes_[k] = box;
    sorted_[k] = {box.lo1, static_cast<std::int32_t>(k)};
  }
  std::sort(sorted_.begin(), sorted_.end());
  for (std::size_t s = 0; s < m; ++s) {
    const auto a = static_cast<std::size_t>(sorted_[s].second);
    const Box2& ba = boxes_[a];
    for (std::size_t r = s + 1; r < m && sorted_[r].first <= ba.hi1; ++r) {
      const auto b = static_cast<std::size_t>(sorted_[r].second);
      if (chain_of_[a] == chain_of_[b]) continue;  // one monotone chain is simple by itself
      ++counters.edge_box_tests;
      const Box2& bb = boxes_[b];
      if (bb.lo2 > ba.hi2 || ba.lo2 > bb.hi2) continue;
      ++counters.edge_pair_tests;
      const ContourEdge& ea = edges[a];
      const ContourEdge& eb = edges[b];
      bool separated;
      // Edges sharing a vertex (consecutive along a loop, or meeting at a pinch vertex) may
      // only meet there; any other pair must be apart.
      if (ea.to == eb.from) {
        separated = adjacent_separated<kContinuous>(det, dot, x, ea.to, ea.from, eb.to);
      } else if (eb.to == ea.from) {
        separated = adjacent_separated<kContinuous>(det, dot, x, eb.to, eb.from, ea.to);
      } else if (ea.from == eb.from) {
        separated = adjacent_separated<kContinuous>(det, dot, x, ea.from, ea.to, eb.to);
      } else if (ea.to == eb.to) {
        separated = adjacent_separated<kContinuous>(det, dot, x, ea.to, ea.from, eb.from);
      } else {
        separated = segments_separated<kContinuous>(det, dot, x, ea.from, ea.to, eb.from, eb.to);
      }
      if (!separated) {
        verdict.part_a = static_cast<std::int8_t>(ea.part);
        verdict.part_b = static_cast<std::int8_t>(eb.part);
        return verdict;
      }
    }
  }
  // Pinch vertices: the fans meeting there must not overlap, or two sheets would cover the
  // wedge they share (the loops through the vertex would cross there).
  const auto fans = nodes.fans(node);
  for (std::size_t g = 0; g < fans.size();) {
    std::size_t h = g + 1;
    while (h < fans.size() && fans[h].vertex == fans[g].vertex) ++h;
    if (!fans_disjoint<kContinuous>(det, dot, x, fans.subspan(g, h - g), edges, counters)) {
      verdict.failed_pinch = true;
      return verdict;
    }
    g = h;
  }
  // Several loops: simple and apart, they still must not nest so that two sheets overlap.
  const auto loop_starts = nodes.loop_starts(node);
  if (loop_starts.size() > 2 &&
      !loops_cover_once(v, frame, x_t0, edges, loop_starts, nodes.loop_probe(node), counters)) {
    verdict.failed_nesting = true;
    return verdict;
  }
  verdict.simple = true;
  return verdict;
}

template ContourVerdict ContourTester::run<false>(
    const NodeContours&,
    std::int32_t,
    const Eigen::Vector3d&,
    const skinning::Positions&,
    const skinning::Positions&,
    ContourMode,
    ContourTestCounters&);
template ContourVerdict ContourTester::run<true>(
    const NodeContours&,
    std::int32_t,
    const Eigen::Vector3d&,
    const skinning::Positions&,
    const skinning::Positions&,
    ContourMode,
    ContourTestCounters&);

}  // namespace skelcd::culling
