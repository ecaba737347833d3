#include "skinning/topology.hpp"

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <numeric>
#include <string>

#include "skinning/detail/exact_collinear.hpp"
#include "skinning/errors.hpp"

namespace skelcd::skinning {
namespace {

// Welding: sort the file vertices by position (ties by index), so that equal positions form runs
// whose first element is the smallest file index. Welded ids are then handed out in file order of
// those representatives: the welded numbering follows the file's.
void weld(const Mesh& mesh, bool enabled, Topology& topo) {
  const auto nv = static_cast<std::int32_t>(mesh.num_vertices());
  topo.welded_of_vertex.assign(static_cast<std::size_t>(nv), -1);
  topo.representative_vertex.clear();
  if (!enabled) {
    topo.representative_vertex.resize(static_cast<std::size_t>(nv));
    std::iota(topo.representative_vertex.begin(), topo.representative_vertex.end(), 0);
    std::iota(topo.welded_of_vertex.begin(), topo.welded_of_vertex.end(), 0);
    return;
  }
  const Positions& p = mesh.rest_positions;
  std::vector<std::int32_t> order(static_cast<std::size_t>(nv));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&p](std::int32_t a, std::int32_t b) {
    for (int k = 0; k < 3; ++k) {
      if (p(a, k) < p(b, k)) return true;
      if (p(b, k) < p(a, k)) return false;
    }
    return a < b;
  });
  // rep[v] = smallest file index with v's position (compared as values: -0.0 equals 0.0).
  std::vector<std::int32_t> rep(static_cast<std::size_t>(nv));
  for (std::size_t s = 0; s < order.size();) {
    std::size_t e = s + 1;
    while (e < order.size() && p.row(order[e]) == p.row(order[s])) ++e;
    for (std::size_t k = s; k < e; ++k) rep[static_cast<std::size_t>(order[k])] = order[s];
    s = e;
  }
  for (std::int32_t v = 0; v < nv; ++v) {
    const auto r = static_cast<std::size_t>(rep[static_cast<std::size_t>(v)]);
    if (r == static_cast<std::size_t>(v)) {
      topo.welded_of_vertex[r] = static_cast<std::int32_t>(topo.representative_vertex.size());
      topo.representative_vertex.push_back(v);
    } else {
      topo.welded_of_vertex[static_cast<std::size_t>(v)] = topo.welded_of_vertex[r];
    }
  }
}

struct HalfEdge {
  std::uint64_t key;  // (smaller welded id << 32) | larger welded id
  std::int32_t face;
  std::int32_t side;
};

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b)));
  const auto hi = static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::max(a, b)));
  return (lo << 32) | hi;
}

// Unique edges: every side of every triangle is a half-edge keyed by its (sorted) welded ends;
// sorting the keys groups the sides of one edge together, faces ascending. Sides whose two
// corners are the same welded vertex (a collapsed triangle) are not edges.
void build_edges(Topology& topo) {
  const auto nf = static_cast<std::int32_t>(topo.welded_triangles.rows());
  const auto nw = static_cast<std::size_t>(topo.num_welded_vertices());
  const auto at = [](std::int32_t i) { return static_cast<std::size_t>(i); };
  topo.face_edges.setConstant(nf, 3, -1);
  // The half-edges in (key, face, side) order. A counting sort by the smaller end puts each in its
  // vertex's bucket in (face, side) order; a stable sort of a bucket by key finishes it (buckets
  // are a vertex's valence long). A std::sort of them all made the cloth-ball step's first
  // build_topology ~30 % slower (92k triangles: 49.4 against 37.8 ms, docs/benchmarks.md).
  std::vector<std::int32_t> start(nw + 1, 0);
  for (std::int32_t f = 0; f < nf; ++f) {
    for (std::int32_t k = 0; k < 3; ++k) {
      const auto a = topo.welded_triangles(f, k);
      const auto b = topo.welded_triangles(f, (k + 1) % 3);
      if (a != b) ++start[at(std::min(a, b)) + 1];
    }
  }
  for (std::size_t v = 0; v < nw; ++v) start[v + 1] += start[v];
  std::vector<HalfEdge> sides(at(start[nw]));
  {
    std::vector<std::int32_t> next(start.begin(), start.end() - 1);
    for (std::int32_t f = 0; f < nf; ++f) {
      for (std::int32_t k = 0; k < 3; ++k) {
        const auto a = topo.welded_triangles(f, k);
        const auto b = topo.welded_triangles(f, (k + 1) % 3);
        if (a != b) sides[at(next[at(std::min(a, b))]++)] = {edge_key(a, b), f, k};
      }
    }
  }
  const auto by_key = [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; };
  for (std::size_t v = 0; v < nw; ++v) {
    const auto first = sides.begin() + start[v];
    const auto last = sides.begin() + start[v + 1];
    if (last - first > 16) {
      std::stable_sort(first, last, by_key);
      continue;
    }
    for (auto i = first; i != last; ++i) {  // insertion sort: stable, and short here
      const HalfEdge x = *i;
      auto j = i;
      for (; j != first && by_key(x, *(j - 1)); --j) *j = *(j - 1);
      *j = x;
    }
  }

  std::vector<std::uint64_t> keys;
  keys.reserve(sides.size() / 2 + 1);
  topo.edge_face_offsets.clear();
  topo.edge_faces.clear();
  topo.edge_faces.reserve(sides.size());
  for (std::size_t s = 0; s < sides.size();) {
    const auto e = static_cast<std::int32_t>(keys.size());
    keys.push_back(sides[s].key);
    topo.edge_face_offsets.push_back(static_cast<std::int32_t>(topo.edge_faces.size()));
    std::size_t t = s;
    for (; t < sides.size() && sides[t].key == sides[s].key; ++t) {
      topo.face_edges(sides[t].face, sides[t].side) = e;
      // A degenerate triangle (a, a, b) has two sides on edge (a, b): list the face once.
      if (topo.edge_faces.size() == static_cast<std::size_t>(topo.edge_face_offsets.back()) ||
          topo.edge_faces.back() != sides[t].face) {
        topo.edge_faces.push_back(sides[t].face);
      }
    }
    s = t;
  }
  topo.edge_face_offsets.push_back(static_cast<std::int32_t>(topo.edge_faces.size()));

  topo.edges.resize(static_cast<Eigen::Index>(keys.size()), 2);
  for (std::size_t e = 0; e < keys.size(); ++e) {
    topo.edges(static_cast<Eigen::Index>(e), 0) = static_cast<std::int32_t>(keys[e] >> 32);
    topo.edges(static_cast<Eigen::Index>(e), 1) = static_cast<std::int32_t>(keys[e] & 0xffffffffU);
  }
}

std::int32_t edge_face_count(const Topology& topo, std::int32_t e) {
  return topo.edge_face_offsets[static_cast<std::size_t>(e) + 1] -
         topo.edge_face_offsets[static_cast<std::size_t>(e)];
}

void build_adjacency(Topology& topo) {
  const auto nf = static_cast<std::int32_t>(topo.welded_triangles.rows());
  topo.face_adjacency.setConstant(nf, 3, -1);
  for (std::int32_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto e = topo.face_edges(f, k);
      if (e < 0) continue;
      const auto begin = topo.edge_face_offsets[static_cast<std::size_t>(e)];
      const auto end = topo.edge_face_offsets[static_cast<std::size_t>(e) + 1];
      for (auto i = begin; i < end; ++i) {
        const auto g = topo.edge_faces[static_cast<std::size_t>(i)];
        if (g != f) {
          topo.face_adjacency(f, k) = g;
          break;
        }
      }
    }
  }
  topo.boundary_edges.clear();
  topo.non_manifold_edges.clear();
  for (std::int32_t e = 0; e < topo.num_edges(); ++e) {
    const auto n = edge_face_count(topo, e);
    if (n == 1) topo.boundary_edges.push_back(e);
    if (n >= 3) topo.non_manifold_edges.push_back(e);
  }
}

// Boundary loops: walk the boundary edges vertex to vertex. Each boundary edge is oriented as its
// face's side (a → b); at every step the walk prefers an unvisited boundary edge leaving the
// current vertex in that orientation, so that loops around pinch vertices close where they should.
// A walk that cannot return to its start (inconsistently oriented faces) is kept as an open chain.
/// Each boundary edge as its one face runs it (from → to), in boundary_edges order.
std::vector<BoundarySide> boundary_sides(const Topology& topo) {
  std::vector<BoundarySide> sides;
  sides.reserve(topo.boundary_edges.size());
  for (const std::int32_t e : topo.boundary_edges) {
    const auto f = topo.edge_faces[static_cast<std::size_t>(
        topo.edge_face_offsets[static_cast<std::size_t>(e)])];
    for (int k = 0; k < 3; ++k) {
      if (topo.face_edges(f, k) == e) {
        sides.push_back({topo.welded_triangles(f, k), topo.welded_triangles(f, (k + 1) % 3), f});
        break;
      }
    }
  }
  return sides;
}

void build_boundary_loops(Topology& topo) {
  topo.boundary_loops.clear();
  const auto nb = topo.boundary_edges.size();
  if (nb == 0) return;
  const auto nw = static_cast<std::size_t>(topo.num_welded_vertices());
  // Oriented ends of each boundary edge.
  std::vector<std::int32_t> from(nb), to(nb);
  const std::vector<BoundarySide> sides = boundary_sides(topo);
  for (std::size_t i = 0; i < nb; ++i) {
    from[i] = sides[i].from;
    to[i] = sides[i].to;
  }
  // CSR: boundary edges incident to each welded vertex.
  std::vector<std::int32_t> offsets(nw + 1, 0);
  for (std::size_t i = 0; i < nb; ++i) {
    ++offsets[static_cast<std::size_t>(from[i]) + 1];
    ++offsets[static_cast<std::size_t>(to[i]) + 1];
  }
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<std::int32_t> incident(static_cast<std::size_t>(offsets.back()));
  {
    std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < nb; ++i) {
      incident[static_cast<std::size_t>(fill[static_cast<std::size_t>(from[i])]++)] = static_cast<std::int32_t>(i);
      incident[static_cast<std::size_t>(fill[static_cast<std::size_t>(to[i])]++)] = static_cast<std::int32_t>(i);
    }
  }
  std::vector<bool> used(nb, false);
  for (std::size_t start = 0; start < nb; ++start) {
    if (used[start]) continue;
    used[start] = true;
    std::vector<std::int32_t> loop{from[start]};
    const auto first = from[start];
    auto current = to[start];
    while (current != first) {
      std::int32_t next = -1;
      bool next_forward = false;
      for (auto k = offsets[static_cast<std::size_t>(current)]; k < offsets[static_cast<std::size_t>(current) + 1]; ++k) {
        const auto i = static_cast<std::size_t>(incident[static_cast<std::size_t>(k)]);
        if (used[i]) continue;
        const bool forward = from[i] == current;
        if (next < 0 || (forward && !next_forward)) {
          next = static_cast<std::int32_t>(i);
          next_forward = forward;
        }
      }
      if (next < 0) break;  // open chain
      loop.push_back(current);
      used[static_cast<std::size_t>(next)] = true;
      const auto n = static_cast<std::size_t>(next);
      current = (from[n] == current) ? to[n] : from[n];
    }
    if (current != first) loop.push_back(current);  // keep the chain's last vertex
    topo.boundary_loops.push_back(std::move(loop));
  }
}

// Components: union-find over faces joined through shared edges; numbered by smallest face.
std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t x) {
  while (parent[static_cast<std::size_t>(x)] != x) {
    auto& px = parent[static_cast<std::size_t>(x)];
    px = parent[static_cast<std::size_t>(px)];
    x = px;
  }
  return x;
}

void build_components(const Mesh& mesh, Topology& topo) {
  const auto nf = static_cast<std::int32_t>(topo.welded_triangles.rows());
  std::vector<std::int32_t> parent(static_cast<std::size_t>(nf));
  std::iota(parent.begin(), parent.end(), 0);
  for (std::int32_t e = 0; e < topo.num_edges(); ++e) {
    const auto begin = topo.edge_face_offsets[static_cast<std::size_t>(e)];
    const auto end = topo.edge_face_offsets[static_cast<std::size_t>(e) + 1];
    const auto a = find_root(parent, topo.edge_faces[static_cast<std::size_t>(begin)]);
    for (auto i = begin + 1; i < end; ++i) {
      const auto b = find_root(parent, topo.edge_faces[static_cast<std::size_t>(i)]);
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
  }
  topo.face_component.assign(static_cast<std::size_t>(nf), -1);
  topo.components.clear();
  for (std::int32_t f = 0; f < nf; ++f) {
    const auto r = find_root(parent, f);
    auto& c = topo.face_component[static_cast<std::size_t>(r)];
    if (r == f) {
      c = static_cast<std::int32_t>(topo.components.size());
      Component comp;
      comp.part = mesh.face_part.empty() ? 0 : mesh.face_part[static_cast<std::size_t>(f)];
      comp.closed = true;
      topo.components.push_back(std::move(comp));
    }
    topo.face_component[static_cast<std::size_t>(f)] = c;
    topo.components[static_cast<std::size_t>(c)].faces.push_back(f);
  }
  // Open: a boundary or non-manifold edge on any of its faces, or no edge at all (only
  // triangles collapsed to a point).
  for (auto& comp : topo.components) {
    comp.closed = std::any_of(comp.faces.begin(), comp.faces.end(), [&topo](std::int32_t f) {
      return (topo.face_edges.row(f).array() >= 0).any();
    });
  }
  for (const auto edges : {&topo.boundary_edges, &topo.non_manifold_edges}) {
    for (const auto e : *edges) {
      const auto f = topo.edge_faces[static_cast<std::size_t>(topo.edge_face_offsets[static_cast<std::size_t>(e)])];
      topo.components[static_cast<std::size_t>(topo.face_component[static_cast<std::size_t>(f)])].closed = false;
    }
  }
}

void find_degenerate_triangles(const Mesh& mesh, Topology& topo) {
  topo.degenerate_triangles.clear();
  const auto nf = static_cast<std::int32_t>(topo.welded_triangles.rows());
  for (std::int32_t f = 0; f < nf; ++f) {
    const auto a = topo.welded_triangles(f, 0);
    const auto b = topo.welded_triangles(f, 1);
    const auto c = topo.welded_triangles(f, 2);
    if (a == b || b == c || c == a) {
      topo.degenerate_triangles.push_back(f);
      continue;
    }
    const Eigen::Vector3d pa = mesh.rest_positions.row(mesh.triangles(f, 0)).transpose();
    const Eigen::Vector3d pb = mesh.rest_positions.row(mesh.triangles(f, 1)).transpose();
    const Eigen::Vector3d pc = mesh.rest_positions.row(mesh.triangles(f, 2)).transpose();
    if (detail::exactly_collinear(pa, pb, pc)) topo.degenerate_triangles.push_back(f);
  }
}

}  // namespace

Topology build_topology(const Mesh& mesh, const WeldOptions& options) {
  validate_mesh(mesh, "build_topology");
  if (mesh.num_vertices() > INT32_MAX || mesh.num_triangles() > INT32_MAX / 3) {
    throw InvalidInput("build_topology: mesh too large for 32-bit indices");
  }
  Topology topo;
  weld(mesh, options.weld, topo);
  const auto nf = mesh.num_triangles();
  topo.welded_triangles.resize(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      topo.welded_triangles(f, k) = topo.welded_of_vertex[static_cast<std::size_t>(mesh.triangles(f, k))];
    }
  }
  build_edges(topo);
  build_adjacency(topo);
  build_boundary_loops(topo);
  build_components(mesh, topo);
  find_degenerate_triangles(mesh, topo);
  return topo;
}

void gather_welded(const Topology& topology, const Positions& positions, Positions& welded) {
  const auto nw = static_cast<Eigen::Index>(topology.representative_vertex.size());
  assert(positions.rows() == static_cast<Eigen::Index>(topology.welded_of_vertex.size()));
  welded.resize(nw, 3);
  for (Eigen::Index w = 0; w < nw; ++w) {
    welded.row(w) = positions.row(topology.representative_vertex[static_cast<std::size_t>(w)]);
  }
}

std::vector<std::vector<BoundarySide>> small_simple_loops(
    const Topology& topology, std::int32_t max_edges) {
  const auto at = [](std::int32_t i) { return static_cast<std::size_t>(i); };
  std::vector<std::vector<BoundarySide>> loops;
  if (topology.boundary_edges.empty()) return loops;
  std::vector<std::uint8_t> bad_component(topology.components.size(), 0);
  for (const std::int32_t e : topology.non_manifold_edges) {
    const auto f = topology.edge_faces[at(topology.edge_face_offsets[at(e)])];
    bad_component[at(topology.face_component[at(f)])] = 1;
  }
  const auto nw = at(topology.num_welded_vertices());
  const std::vector<BoundarySide> sides = boundary_sides(topology);
  std::vector<std::int32_t> out_count(nw, 0), in_count(nw, 0);
  for (const auto& s : sides) {
    ++out_count[at(s.from)];
    ++in_count[at(s.to)];
  }
  // CSR: the sides leaving each vertex. A vertex with as many sides in as out lies on cycles; a
  // pinch vertex (two or more of each) is where the walk below splits a loop into simple cycles.
  std::vector<std::int32_t> offsets(nw + 1, 0);
  for (const auto& s : sides) ++offsets[at(s.from) + 1];
  for (std::size_t v = 0; v < nw; ++v) offsets[v + 1] += offsets[v];
  std::vector<std::int32_t> leaving_sides(sides.size());
  {
    std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < sides.size(); ++i) {
      leaving_sides[at(fill[at(sides[i].from)]++)] = static_cast<std::int32_t>(i);
    }
  }
  std::vector<std::int32_t> next_leaving(offsets.begin(), offsets.end() - 1);
  std::vector<std::uint8_t> used(sides.size(), 0);
  std::vector<std::int32_t> position(nw, -1);  // index in `path` of the side leaving a vertex
  std::vector<std::int32_t> path;
  const auto unused_leaving = [&](std::int32_t v) -> std::int32_t {
    for (auto& k = next_leaving[at(v)]; k < offsets[at(v) + 1]; ++k) {
      const std::int32_t i = leaving_sides[at(k)];
      if (used[at(i)] == 0) return i;
    }
    return -1;
  };
  for (std::size_t s0 = 0; s0 < sides.size(); ++s0) {
    if (used[s0] != 0) continue;
    // Walk head to tail; whenever the walk comes back to a vertex of its path, the sides since
    // then are a simple cycle: cut it off and go on from there.
    path.assign(1, static_cast<std::int32_t>(s0));
    used[s0] = 1;
    position[at(sides[s0].from)] = 0;
    std::int32_t v = sides[s0].to;
    while (!path.empty()) {
      if (position[at(v)] >= 0) {
        const auto first = static_cast<std::size_t>(position[at(v)]);
        std::vector<BoundarySide> cycle;
        for (std::size_t i = first; i < path.size(); ++i) {
          cycle.push_back(sides[at(path[i])]);
          position[at(sides[at(path[i])].from)] = -1;
        }
        path.resize(first);
        const auto component = topology.face_component[at(cycle.front().face)];
        const bool balanced = std::all_of(cycle.begin(), cycle.end(), [&](const BoundarySide& c) {
          return out_count[at(c.from)] == in_count[at(c.from)];
        });
        if (balanced && cycle.size() >= 3 && static_cast<std::int32_t>(cycle.size()) <= max_edges &&
            bad_component[at(component)] == 0) {
          loops.push_back(std::move(cycle));
        }
        if (path.empty()) break;
      }
      const std::int32_t t = unused_leaving(v);
      if (t < 0) {  // an open chain (inconsistent orientation): not capped
        for (const std::int32_t i : path) position[at(sides[at(i)].from)] = -1;
        path.clear();
        break;
      }
      position[at(v)] = static_cast<std::int32_t>(path.size());
      path.push_back(t);
      used[at(t)] = 1;
      v = sides[at(t)].to;
    }
  }
  return loops;
}

std::vector<std::vector<BoundarySide>> closing_loops(
    const Topology& topology, std::int32_t max_edges, std::int32_t triangles_per_side) {
  const auto at = [](std::int32_t i) { return static_cast<std::size_t>(i); };
  auto loops = small_simple_loops(topology, max_edges);
  if (loops.empty()) return loops;
  // Per component: its boundary edges, and the sides of its closable loops.
  std::vector<std::int64_t> holes(topology.components.size(), 0), sides(holes.size(), 0);
  for (const std::int32_t e : topology.boundary_edges) {
    const auto f = topology.edge_faces[at(topology.edge_face_offsets[at(e)])];
    ++holes[at(topology.face_component[at(f)])];
  }
  for (const auto& loop : loops) {
    sides[at(topology.face_component[at(loop.front().face)])] +=
        static_cast<std::int64_t>(loop.size());
  }
  std::erase_if(loops, [&](const std::vector<BoundarySide>& loop) {
    const auto c = at(topology.face_component[at(loop.front().face)]);
    const auto triangles = static_cast<std::int64_t>(topology.components[c].faces.size());
    return holes[c] != sides[c] || triangles < triangles_per_side * sides[c];
  });
  return loops;
}

}  // namespace skelcd::skinning
