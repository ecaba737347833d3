// How many of a rig's near triangle pairs move as one by linear blend skinning (docs/benchmarks.md,
// "Pairs that skinning moves as one"): two triangles whose six corners have the same weight row
// get the same blended matrix M_s at every sample, so between two samples they move by one
// matrix blend (1 − t) M_s + t M_s+1 and keep their rest relation up to rounding. Counts, over
// every interval of the model's first clip, the triangle pairs (file triangles) whose swept boxes
// overlap, those that share a vertex, and those whose corners all have one weight row (and, of
// those, the ones whose row is a single bone: a rigid motion). A measurement, not a culling.
//   rigid_pairs MODEL [STRIDE]      (STRIDE: every STRIDE-th interval, default 1)
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "skinning/lbs.hpp"
#include "skinning/load.hpp"
#include "skinning/motion.hpp"
#include "skinning/rig.hpp"

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

int run(const std::string& path, int stride) {
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
  const auto& tris = model.mesh->triangles;
  const auto nf = static_cast<int>(tris.rows());
  std::vector<int> tri_row(static_cast<std::size_t>(nf), -1);
  int one_row_tris = 0;
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
  Positions x0;
  Positions x1;
  std::vector<Box> box(static_cast<std::size_t>(nf));
  std::vector<int> by_lo(static_cast<std::size_t>(nf));
  Counts c;
  int intervals = 0;
  for (int s = 0; s + 1 < n; s += stride) {
    ++intervals;
    motion->positions(s, x0);
    motion->positions(s + 1, x1);
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
    // Sweep on x: each triangle against those whose x range starts within its own.
    std::sort(by_lo.begin(), by_lo.end(), [&](int a, int b) {
      return box[static_cast<std::size_t>(a)][0] < box[static_cast<std::size_t>(b)][0];
    });
    for (std::size_t i = 0; i < by_lo.size(); ++i) {
      const int fi = by_lo[i];
      const Box& bi = box[static_cast<std::size_t>(fi)];
      for (std::size_t j = i + 1; j < by_lo.size(); ++j) {
        const int fj = by_lo[j];
        const Box& bj = box[static_cast<std::size_t>(fj)];
        if (bj[0] > bi[3]) break;
        if (bj[1] > bi[4] || bi[1] > bj[4] || bj[2] > bi[5] || bi[2] > bj[5]) continue;
        ++c.pairs;
        bool share = false;
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) share = share || tris(fi, a) == tris(fj, b);
        }
        c.sharing += share ? 1 : 0;
        const int r = tri_row[static_cast<std::size_t>(fi)];
        if (r >= 0 && r == tri_row[static_cast<std::size_t>(fj)]) {
          ++c.one_row;
          c.one_row_apart += share ? 0 : 1;
          c.one_bone += single_bone_row[static_cast<std::size_t>(r)] ? 1 : 0;
        }
      }
    }
  }
  const auto share_of = [&](std::int64_t k) {
    return c.pairs == 0 ? 0.0 : 100.0 * static_cast<double>(k) / static_cast<double>(c.pairs);
  };
  std::printf(
      "%s: %ld vertices, %zu weight rows; %d triangles, %d with one row; %d intervals: %ld "
      "swept-box pairs, %ld sharing a vertex; one weight row %ld (%.1f %%), of them %ld sharing "
      "none, %ld of a single bone (%.1f %%)\n",
      path.c_str(),
      static_cast<long>(w.rows()),
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
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: rigid_pairs MODEL [STRIDE]\n");
    return 2;
  }
  const int stride = argc == 3 ? std::atoi(argv[2]) : 1;
  if (stride < 1) {
    std::fprintf(stderr, "rigid_pairs: STRIDE must be a whole number from 1 on\n");
    return 2;
  }
  try {
    return run(argv[1], stride);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rigid_pairs: %s\n", e.what());
    return 1;
  }
}
