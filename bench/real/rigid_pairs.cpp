// How many of a rig's near triangle pairs move as one by linear blend skinning (docs/benchmarks.md,
// "Pairs that skinning moves as one"): two triangles whose six corners have the same weight row
// get the same blended matrix M_s at every sample, so between two samples they move by one
// matrix blend (1 − t) M_s + t M_s+1 and keep their rest relation up to rounding. Counts, over
// every interval of the model's first clip, the triangle pairs (welded, as skelcd's methods see
// them; triangles with a repeated welded vertex left out) whose swept boxes overlap, those that
// share a vertex, and those whose corners all have one weight row (and, of those, the ones whose
// row is a single bone: a rigid motion). A measurement, not a culling. With --ccd it also runs the
// CCD tests of every vertex-face and edge-edge pair of those triangle pairs that shares no vertex
// (conservative, as the engine's default; the one-row ones also exact), times the two kinds of pair
// apart, and checks the invariance on the one-row pairs: each exact contact among them must also be
// a contact of the same features held still at rest.
//   rigid_pairs MODEL [STRIDE] [--ccd]   (STRIDE: every STRIDE-th interval, default 1)
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"
#include "culling/elementary.hpp"
#include "skinning/lbs.hpp"
#include "skinning/load.hpp"
#include "skinning/motion.hpp"
#include "skinning/rig.hpp"
#include "skinning/topology.hpp"

namespace {

using skelcd::skinning::Positions;
using Box = std::array<double, 6>;  // lo x, y, z, hi x, y, z

struct Counts {
  std::int64_t pairs = 0;
  std::int64_t sharing = 0;
  std::int64_t one_row = 0;
  std::int64_t one_row_apart = 0;  ///< one weight row, no shared vertex
  std::int64_t one_bone = 0;       ///< one weight row of a single bone
};

/// The CCD tests of the feature pairs of swept-box triangle pairs (--ccd), by kind of pair.
struct Tests {
  std::int64_t vf = 0;  ///< queries, one row / other
  std::int64_t ee = 0;
  std::int64_t hits = 0;  ///< conservative hits
  double seconds = 0.0;   ///< conservative tests' time
};

/// Feature pairs (no shared vertex) of triangles a and b, both ways: VF (vertex, face) and EE.
template <typename Vf, typename Ee>
void for_each_feature_pair(
    const std::array<int, 3>& a, const std::array<int, 3>& b, const Vf& vf, const Ee& ee) {
  const auto in = [](int v, const std::array<int, 3>& t) {
    return v == t[0] || v == t[1] || v == t[2];
  };
  for (const int v : a) {
    if (!in(v, b)) vf(v, b);
  }
  for (const int v : b) {
    if (!in(v, a)) vf(v, a);
  }
  for (int i = 0; i < 3; ++i) {
    const std::array<int, 2> ea{
        a[static_cast<std::size_t>(i)], a[static_cast<std::size_t>((i + 1) % 3)]};
    for (int j = 0; j < 3; ++j) {
      const std::array<int, 2> eb{
          b[static_cast<std::size_t>(j)], b[static_cast<std::size_t>((j + 1) % 3)]};
      if (ea[0] == eb[0] || ea[0] == eb[1] || ea[1] == eb[0] || ea[1] == eb[1]) continue;
      ee(ea, eb);
    }
  }
}

skelcd::ccd::VertexFaceQuery vf_query(
    const Positions& x0, const Positions& x1, int v, const std::array<int, 3>& f) {
  return skelcd::culling::vertex_face_query(x0, x1, v, x0, x1, f);
}

skelcd::ccd::EdgeEdgeQuery ee_query(
    const Positions& x0,
    const Positions& x1,
    const std::array<int, 2>& a,
    const std::array<int, 2>& b) {
  return skelcd::culling::edge_edge_query(x0, x1, a, x0, x1, b);
}

int run(const std::string& path, int stride, bool ccd) {
  const skelcd::skinning::LoadedModel model = skelcd::skinning::load_model(path);
  if (!model.rig) {
    std::fprintf(stderr, "rigid_pairs: %s: not a rig (no skin weights)\n", path.c_str());
    return 1;
  }
  const skelcd::skinning::LinearBlendSkinning lbs(*model.rig);
  const skelcd::skinning::SkinWeights& w = lbs.weights();
  // Weight rows, exactly as stored: vertices of one row get the same blended matrix.
  std::map<std::vector<std::pair<int, double>>, int> rows;
  std::vector<int> row_of(static_cast<std::size_t>(w.rows()));
  std::vector<bool> single_bone_row;
  for (int v = 0; v < w.rows(); ++v) {
    std::vector<std::pair<int, double>> row;
    for (skelcd::skinning::SkinWeights::InnerIterator it(w, v); it; ++it) {
      if (it.value() != 0.0) row.emplace_back(static_cast<int>(it.col()), it.value());
    }
    const auto [at, added] = rows.emplace(row, static_cast<int>(rows.size()));
    if (added) single_bone_row.push_back(row.size() == 1);
    row_of[static_cast<std::size_t>(v)] = at->second;
  }
  // Welded, as skelcd's methods see the mesh (seams' duplicate vertices are one vertex): a welded
  // vertex moves as its representative file vertex.
  const skelcd::skinning::Topology topology = skelcd::skinning::build_topology(*model.mesh);
  {
    std::vector<int> welded_row(topology.representative_vertex.size());
    for (std::size_t i = 0; i < welded_row.size(); ++i) {
      welded_row[i] = row_of[static_cast<std::size_t>(topology.representative_vertex[i])];
    }
    row_of = std::move(welded_row);
  }
  const auto& tris = topology.welded_triangles;
  const auto nf = static_cast<int>(tris.rows());
  std::vector<int> tri_row(static_cast<std::size_t>(nf), -1);
  int one_row_tris = 0;
  std::vector<bool> collapsed(static_cast<std::size_t>(nf));  // a repeated welded vertex
  for (int f = 0; f < nf; ++f) {
    collapsed[static_cast<std::size_t>(f)] =
        tris(f, 0) == tris(f, 1) || tris(f, 1) == tris(f, 2) || tris(f, 0) == tris(f, 2);
  }
  for (int f = 0; f < nf; ++f) {
    const int a = row_of[static_cast<std::size_t>(tris(f, 0))];
    if (a == row_of[static_cast<std::size_t>(tris(f, 1))] &&
        a == row_of[static_cast<std::size_t>(tris(f, 2))]) {
      tri_row[static_cast<std::size_t>(f)] = a;
      ++one_row_tris;
    }
  }
  const auto motion = model.motion();
  const int n = motion->num_samples();
  Positions file_x;
  Positions x0;
  Positions x1;
  std::vector<Box> box(static_cast<std::size_t>(nf));
  std::vector<int> by_lo(static_cast<std::size_t>(nf));
  Counts c;
  // --ccd: the interval's triangle pairs by kind (0: one row, 1: other), then their tests.
  std::array<std::vector<std::pair<int, int>>, 2> kind_pairs;
  std::array<Tests, 2> tests;
  std::set<std::tuple<int, int, int, int, int>> row_contacts;  // kind, features: exact, one row
  std::int64_t row_contacts_at_rest = 0;
  Positions rest;
  skelcd::skinning::gather_welded(topology, model.mesh->rest_positions, rest);
  const auto tri = [&](int f) { return std::array<int, 3>{tris(f, 0), tris(f, 1), tris(f, 2)}; };
  int intervals = 0;
  for (int s = 0; s + 1 < n; s += stride) {
    ++intervals;
    motion->positions(s, file_x);
    skelcd::skinning::gather_welded(topology, file_x, x0);
    motion->positions(s + 1, file_x);
    skelcd::skinning::gather_welded(topology, file_x, x1);
    for (int f = 0; f < nf; ++f) {
      Box b{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
      for (int k = 0; k < 3; ++k) {
        for (const Positions* x : {&x0, &x1}) {
          for (int d = 0; d < 3; ++d) {
            const double p = (*x)(tris(f, k), d);
            b[static_cast<std::size_t>(d)] = std::min(b[static_cast<std::size_t>(d)], p);
            b[static_cast<std::size_t>(3 + d)] = std::max(b[static_cast<std::size_t>(3 + d)], p);
          }
        }
      }
      box[static_cast<std::size_t>(f)] = b;
      by_lo[static_cast<std::size_t>(f)] = f;
    }
    kind_pairs[0].clear();
    kind_pairs[1].clear();
    // Sweep on x: each triangle against those whose x range starts within its own.
    std::sort(by_lo.begin(), by_lo.end(), [&](int a, int b) {
      return box[static_cast<std::size_t>(a)][0] < box[static_cast<std::size_t>(b)][0];
    });
    for (std::size_t i = 0; i < by_lo.size(); ++i) {
      const int fi = by_lo[i];
      if (collapsed[static_cast<std::size_t>(fi)]) continue;
      const Box& bi = box[static_cast<std::size_t>(fi)];
      for (std::size_t j = i + 1; j < by_lo.size(); ++j) {
        const int fj = by_lo[j];
        const Box& bj = box[static_cast<std::size_t>(fj)];
        if (bj[0] > bi[3]) break;
        if (collapsed[static_cast<std::size_t>(fj)]) continue;
        if (bj[1] > bi[4] || bi[1] > bj[4] || bj[2] > bi[5] || bi[2] > bj[5]) continue;
        ++c.pairs;
        bool share = false;
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) share = share || tris(fi, a) == tris(fj, b);
        }
        c.sharing += share ? 1 : 0;
        const int r = tri_row[static_cast<std::size_t>(fi)];
        const bool one_row = r >= 0 && r == tri_row[static_cast<std::size_t>(fj)];
        if (one_row) {
          ++c.one_row;
          c.one_row_apart += share ? 0 : 1;
          c.one_bone += single_bone_row[static_cast<std::size_t>(r)] ? 1 : 0;
        }
        if (ccd) kind_pairs[one_row ? 0 : 1].emplace_back(fi, fj);
      }
    }
    for (int k = 0; k < 2 && ccd; ++k) {
      Tests& t = tests[static_cast<std::size_t>(k)];
      const auto start = std::chrono::steady_clock::now();
      for (const auto& [fi, fj] : kind_pairs[static_cast<std::size_t>(k)]) {
        for_each_feature_pair(
            tri(fi),
            tri(fj),
            [&](int v, const std::array<int, 3>& f) {
              ++t.vf;
              t.hits += skelcd::ccd::vertex_face_ccd(vf_query(x0, x1, v, f)).hit ? 1 : 0;
            },
            [&](const std::array<int, 2>& a, const std::array<int, 2>& b) {
              ++t.ee;
              t.hits += skelcd::ccd::edge_edge_ccd(ee_query(x0, x1, a, b)).hit ? 1 : 0;
            });
      }
      t.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    // The invariance, exactly: a one-row feature pair touches over the interval only if it
    // touches at rest (held still: the same positions at both ends).
    constexpr auto kExact = skelcd::ccd::Accuracy::exact;
    for (const auto& [fi, fj] : ccd ? kind_pairs[0] : std::vector<std::pair<int, int>>{}) {
      for_each_feature_pair(
          tri(fi),
          tri(fj),
          [&](int v, const std::array<int, 3>& f) {
            const skelcd::ccd::VertexFaceQuery q = vf_query(x0, x1, v, f);
            if (!skelcd::ccd::vertex_face_ccd(q).hit ||
                !skelcd::ccd::vertex_face_ccd(q, kExact).hit) {
              return;  // conservative first: it never misses, and is cheaper
            }
            std::array<int, 3> g = f;
            std::sort(g.begin(), g.end());
            if (row_contacts.emplace(0, v, g[0], g[1], g[2]).second &&
                skelcd::ccd::vertex_face_ccd(vf_query(rest, rest, v, f), kExact).hit) {
              ++row_contacts_at_rest;
            }
          },
          [&](const std::array<int, 2>& a, const std::array<int, 2>& b) {
            const skelcd::ccd::EdgeEdgeQuery query = ee_query(x0, x1, a, b);
            if (!skelcd::ccd::edge_edge_ccd(query).hit ||
                !skelcd::ccd::edge_edge_ccd(query, kExact).hit) {
              return;
            }
            const auto lo = [](const std::array<int, 2>& e) { return std::min(e[0], e[1]); };
            const auto hi = [](const std::array<int, 2>& e) { return std::max(e[0], e[1]); };
            const bool a_first = std::pair(lo(a), hi(a)) < std::pair(lo(b), hi(b));
            const auto& p = a_first ? a : b;
            const auto& q = a_first ? b : a;
            if (row_contacts.emplace(1, lo(p), hi(p), lo(q), hi(q)).second &&
                skelcd::ccd::edge_edge_ccd(ee_query(rest, rest, a, b), kExact).hit) {
              ++row_contacts_at_rest;
            }
          });
    }
  }
  const auto share_of = [&](std::int64_t k) {
    return c.pairs == 0 ? 0.0 : 100.0 * static_cast<double>(k) / static_cast<double>(c.pairs);
  };
  std::printf(
      "%s: %ld welded vertices, %zu weight rows; %d triangles, %d with one row; %d intervals: %ld "
      "swept-box pairs, %ld sharing a vertex; one weight row %ld (%.1f %%), of them %ld sharing "
      "none, %ld of a single bone (%.1f %%)\n",
      path.c_str(),
      static_cast<long>(row_of.size()),
      rows.size(),
      nf,
      one_row_tris,
      intervals,
      static_cast<long>(c.pairs),
      static_cast<long>(c.sharing),
      static_cast<long>(c.one_row),
      share_of(c.one_row),
      static_cast<long>(c.one_row_apart),
      static_cast<long>(c.one_bone),
      share_of(c.one_bone));
  if (ccd) {
    const double all = tests[0].seconds + tests[1].seconds;
    std::printf(
        "  CCD tests of their feature pairs sharing no vertex (conservative): one row %ld VF + %ld "
        "EE, %ld hits, %.3f s; other %ld VF + %ld EE, %ld hits, %.3f s; one row's share of the "
        "time %.1f %%\n  exact contacts of one-row feature pairs: %zu, of them touching at rest "
        "%ld, not at rest %ld\n",
        static_cast<long>(tests[0].vf),
        static_cast<long>(tests[0].ee),
        static_cast<long>(tests[0].hits),
        tests[0].seconds,
        static_cast<long>(tests[1].vf),
        static_cast<long>(tests[1].ee),
        static_cast<long>(tests[1].hits),
        tests[1].seconds,
        all > 0.0 ? 100.0 * tests[0].seconds / all : 0.0,
        row_contacts.size(),
        static_cast<long>(row_contacts_at_rest),
        static_cast<long>(row_contacts.size()) - static_cast<long>(row_contacts_at_rest));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  const bool ccd = std::erase(args, std::string("--ccd")) > 0;
  if (args.empty() || args.size() > 2) {
    std::fprintf(stderr, "usage: rigid_pairs MODEL [STRIDE] [--ccd]\n");
    return 2;
  }
  const int stride = args.size() == 2 ? std::atoi(args[1].c_str()) : 1;
  if (stride < 1) {
    std::fprintf(stderr, "rigid_pairs: STRIDE must be a whole number from 1 on\n");
    return 2;
  }
  try {
    return run(args[0], stride, ccd);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rigid_pairs: %s\n", e.what());
    return 1;
  }
}
