// Bodies with limbs: the octopus (8 tentacles round an octagonal body) and the hand (a palm with
// four fingers and a thumb). One closed surface each: a prism over a convex polygon whose side
// faces carry box-section limbs (walls meet the body along shared vertex columns; the body's top
// and bottom are fans). Limb j's chain: bone 0 leaves the body and never bends relative to it;
// joints 1 … n−1 turn about the vertical axis.
//
// Known answer: limbs move in mirror-image pairs (one turns +θ, its partner −θ about planes of
// symmetry of the rest shape), so a limb touches its partner exactly when it reaches the mirror
// plane between them: the margin is the largest signed distance of a limb's vertices past that
// plane.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "skinning/generators_common.hpp"

namespace skelcd::skinning::generators {
namespace {

constexpr double kPi = std::numbers::pi;

struct LimbSpec {
  int side = 0;          ///< polygon side it stands on (side k runs from corner k to k + 1)
  double center = 0.0;   ///< distance of its centre from corner `side` along the side
  double width = 0.0;
  double length = 0.0;
  int bones = 1;
  double bend = 0.0;     ///< +1 turns towards the next corner (counter-clockwise), −1 back, 0 still
};

struct BodySpec {
  std::vector<Eigen::Vector2d> corners;  ///< counter-clockwise
  double height = 0.0;
  std::vector<LimbSpec> limbs;           ///< sorted by side, then centre
};

struct MirrorPair {
  std::size_t limb;            ///< the limb whose vertices are measured
  Eigen::Vector3d point;       ///< on the mirror plane
  Eigen::Vector3d towards;     ///< unit normal of the plane, from the limb towards its partner
};

struct LimbResolution {
  std::int64_t nw = 1;  ///< segments across a limb's width
  std::int64_t nh = 1;  ///< segments up the height (everywhere)
  std::vector<std::int64_t> rings;  ///< rings per limb (>= 2)
};

std::int64_t count_triangles(const BodySpec& body, const LimbResolution& r) {
  const std::int64_t limbs = static_cast<std::int64_t>(body.limbs.size());
  const std::int64_t corners = static_cast<std::int64_t>(body.corners.size());
  const std::int64_t outline = corners + limbs * (r.nw + 1);
  const std::int64_t perimeter = 2 * (r.nw + r.nh);
  std::int64_t t = 2 * outline + 2 * r.nh * (corners + limbs);  // fans, strips
  for (const std::int64_t k : r.rings) t += 2 * perimeter * (k - 1) + 2 * r.nw * r.nh;
  return t;
}

// Picks the resolution whose triangle count is nearest `triangles` with cells near square.
LimbResolution choose_resolution(const BodySpec& body, std::int64_t triangles) {
  const double w = body.limbs.front().width;
  double total_length = 0;
  for (const LimbSpec& l : body.limbs) total_length += l.length;
  LimbResolution best;
  double best_score = std::numeric_limits<double>::infinity();
  for (std::int64_t nw = 1; nw <= 512; ++nw) {
    LimbResolution r;
    r.nw = nw;
    r.nh = round_at_least(static_cast<double>(nw) * body.height / w, 1);
    r.rings.assign(body.limbs.size(), 2);
    const std::int64_t base = count_triangles(body, r);  // every limb one ring segment long
    const double per_length = 2.0 * static_cast<double>(2 * (r.nw + r.nh));
    // Extra ring segments spread in proportion to length to reach the target.
    const double spacing = total_length * per_length / std::max(1.0, static_cast<double>(triangles - base) + per_length * static_cast<double>(body.limbs.size()));
    for (std::size_t l = 0; l < body.limbs.size(); ++l) r.rings[l] = round_at_least(body.limbs[l].length / spacing, 1) + 1;
    const double t = static_cast<double>(count_triangles(body, r));
    const double aspect = spacing / (w / static_cast<double>(nw));  // 1 = square cells
    const double score = std::abs(std::log(t / static_cast<double>(triangles))) * 20.0 + std::abs(std::log(aspect));
    if (score < best_score) {
      best_score = score;
      best = r;
    }
    if (t > 4.0 * static_cast<double>(triangles) && nw > 1) break;
  }
  return best;
}

struct BuiltBody {
  MeshBuilder mesh;
  std::vector<std::int32_t> vertex_limb;  ///< limb of each vertex, −1 on the body
  std::vector<double> vertex_s;           ///< arc length along its limb
  std::vector<Eigen::Affine3d> limb_frames;  ///< x out of the body, y along the side, z up
};

BuiltBody build_body(const BodySpec& body, const LimbResolution& res) {
  BuiltBody b;
  const double h = body.height;
  const auto nh = res.nh;
  const auto nw = res.nw;
  const auto add = [&](const Eigen::Vector3d& p, std::int32_t limb, double s) {
    b.vertex_limb.push_back(limb);
    b.vertex_s.push_back(s);
    return b.mesh.add(p);
  };
  const auto z_at = [&](std::int64_t j) { return -0.5 * h + h * static_cast<double>(j) / static_cast<double>(nh); };

  // Limb rings: loop index m runs counter-clockwise in the limb's (y, z): bottom edge (y up),
  // right edge (z up), top edge (y down), left edge (z down).
  const std::int64_t perimeter = 2 * (nw + nh);
  std::vector<std::vector<std::vector<std::int32_t>>> rings(body.limbs.size());
  const auto loop_yz = [&](const LimbSpec& l, std::int64_t m) -> Eigen::Vector2d {
    const double w = l.width;
    const auto fw = [&](std::int64_t i) { return -0.5 * w + w * static_cast<double>(i) / static_cast<double>(nw); };
    if (m < nw) return {fw(m), -0.5 * h};
    if (m < nw + nh) return {0.5 * w, z_at(m - nw)};
    if (m < 2 * nw + nh) return {fw(nw - (m - nw - nh)), 0.5 * h};
    return {-0.5 * w, z_at(nh - (m - 2 * nw - nh))};
  };
  for (std::size_t li = 0; li < body.limbs.size(); ++li) {
    const LimbSpec& l = body.limbs[li];
    const Eigen::Vector2d c0 = body.corners[static_cast<std::size_t>(l.side)];
    const Eigen::Vector2d c1 = body.corners[static_cast<std::size_t>((l.side + 1) % static_cast<int>(body.corners.size()))];
    const Eigen::Vector2d t = (c1 - c0).normalized();
    const Eigen::Vector2d n(t.y(), -t.x());
    const Eigen::Vector2d o = c0 + l.center * t;
    Eigen::Affine3d frame = Eigen::Affine3d::Identity();
    frame.linear().col(0) = Eigen::Vector3d(n.x(), n.y(), 0);
    frame.linear().col(1) = Eigen::Vector3d(t.x(), t.y(), 0);
    frame.linear().col(2) = Eigen::Vector3d::UnitZ();
    frame.translation() = Eigen::Vector3d(o.x(), o.y(), 0);
    b.limb_frames.push_back(frame);
    const std::int64_t k_rings = res.rings[li];
    for (std::int64_t k = 0; k < k_rings; ++k) {
      const double s = l.length * static_cast<double>(k) / static_cast<double>(k_rings - 1);
      std::vector<std::int32_t> ring;
      for (std::int64_t m = 0; m < perimeter; ++m) {
        const Eigen::Vector2d yz = loop_yz(l, m);
        ring.push_back(add(frame * Eigen::Vector3d(s, yz.x(), yz.y()), static_cast<std::int32_t>(li), s));
      }
      rings[li].push_back(std::move(ring));
    }
    // Walls.
    for (std::int64_t k = 0; k + 1 < k_rings; ++k) {
      const auto& r0 = rings[li][static_cast<std::size_t>(k)];
      const auto& r1 = rings[li][static_cast<std::size_t>(k + 1)];
      for (std::int64_t m = 0; m < perimeter; ++m) {
        const auto a = static_cast<std::size_t>(m);
        const auto c = static_cast<std::size_t>((m + 1) % perimeter);
        b.mesh.quad(r0[a], r0[c], r1[c], r1[a]);
      }
    }
    // Tip cap: an (nw + 1) × (nh + 1) grid whose border is the last ring.
    const auto& last = rings[li].back();
    const auto border = [&](std::int64_t i, std::int64_t j) -> std::int32_t {
      if (j == 0) return last[static_cast<std::size_t>(i)];
      if (i == nw) return last[static_cast<std::size_t>(nw + j)];
      if (j == nh) return last[static_cast<std::size_t>(nw + nh + (nw - i))];
      return last[static_cast<std::size_t>((2 * nw + nh + (nh - j)) % perimeter)];
    };
    std::vector<std::int32_t> grid(static_cast<std::size_t>((nw + 1) * (nh + 1)));
    for (std::int64_t i = 0; i <= nw; ++i) {
      for (std::int64_t j = 0; j <= nh; ++j) {
        const bool on_border = i == 0 || j == 0 || i == nw || j == nh;
        const double y = -0.5 * l.width + l.width * static_cast<double>(i) / static_cast<double>(nw);
        grid[static_cast<std::size_t>(i * (nh + 1) + j)] =
            on_border ? border(i, j) : add(frame * Eigen::Vector3d(l.length, y, z_at(j)), static_cast<std::int32_t>(li), l.length);
      }
    }
    const auto g = [&](std::int64_t i, std::int64_t j) { return grid[static_cast<std::size_t>(i * (nh + 1) + j)]; };
    for (std::int64_t i = 0; i < nw; ++i) {
      for (std::int64_t j = 0; j < nh; ++j) b.mesh.quad(g(i, j), g(i + 1, j), g(i + 1, j + 1), g(i, j + 1));
    }
  }

  // Body: vertical columns at the corners, strips between consecutive columns round the polygon,
  // and fans over the top and bottom outlines.
  std::vector<std::vector<std::int32_t>> corner_columns;
  for (const Eigen::Vector2d& c : body.corners) {
    std::vector<std::int32_t> column;
    for (std::int64_t j = 0; j <= nh; ++j) column.push_back(add({c.x(), c.y(), z_at(j)}, -1, 0));
    corner_columns.push_back(std::move(column));
  }
  const auto limb_column = [&](std::size_t li, bool right) {
    std::vector<std::int32_t> column;
    const auto& r0 = rings[li][0];
    for (std::int64_t j = 0; j <= nh; ++j) {
      const std::int64_t m = right ? nw + j : (2 * nw + nh + (nh - j)) % perimeter;
      column.push_back(r0[static_cast<std::size_t>(m)]);
    }
    return column;
  };
  std::vector<std::int32_t> top;
  std::vector<std::int32_t> bottom;
  const auto strip = [&](const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& c) {
    for (std::int64_t j = 0; j < nh; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      b.mesh.quad(a[jj], c[jj], c[jj + 1], a[jj + 1]);
    }
  };
  std::size_t next_limb = 0;
  for (std::size_t side = 0; side < body.corners.size(); ++side) {
    std::vector<std::int32_t> column = corner_columns[side];
    top.push_back(column.back());
    bottom.push_back(column.front());
    while (next_limb < body.limbs.size() && body.limbs[next_limb].side == static_cast<int>(side)) {
      strip(column, limb_column(next_limb, false));
      const auto& r0 = rings[next_limb][0];
      for (std::int64_t i = 0; i <= nw; ++i) {
        bottom.push_back(r0[static_cast<std::size_t>(i)]);
        top.push_back(r0[static_cast<std::size_t>(nw + nh + (nw - i))]);
      }
      column = limb_column(next_limb, true);
      ++next_limb;
    }
    strip(column, corner_columns[(side + 1) % body.corners.size()]);
  }
  const std::int32_t top_center = add({0, 0, 0.5 * h}, -1, 0);
  const std::int32_t bottom_center = add({0, 0, -0.5 * h}, -1, 0);
  for (std::size_t i = 0; i < top.size(); ++i) {
    const std::size_t i1 = (i + 1) % top.size();
    b.mesh.tri(top_center, top[i], top[i1]);
    b.mesh.tri(bottom_center, bottom[i1], bottom[i]);
  }
  return b;
}

GeneratedRig generate_body(
    const BodySpec& body,
    const std::vector<MirrorPair>& pairs,
    std::int64_t triangles,
    int frames,
    double turn_end,
    const std::string& name,
    const std::string& clip_name) {
  const LimbResolution res = choose_resolution(body, triangles);
  BuiltBody built = build_body(body, res);

  RigBuilder builder;
  const std::int32_t root = builder.add_node(name + "_body", -1, Eigen::Affine3d::Identity());
  std::vector<Chain> chains;
  std::vector<std::int32_t> moving;
  std::vector<double> sign;
  for (std::size_t li = 0; li < body.limbs.size(); ++li) {
    const LimbSpec& l = body.limbs[li];
    std::vector<double> joints;
    for (int j = 0; j < l.bones; ++j) joints.push_back(l.length * j / l.bones);
    chains.push_back(add_chain(builder, name + "_limb" + std::to_string(li) + "_", root, built.limb_frames[li], joints, l.length));
    if (l.bend != 0.0) {
      for (std::size_t j = 1; j < chains.back().nodes.size(); ++j) {
        moving.push_back(chains.back().nodes[j]);
        sign.push_back(l.bend);
      }
    }
  }
  for (std::size_t v = 0; v < built.vertex_limb.size(); ++v) {
    const std::int32_t li = built.vertex_limb[v];
    if (li < 0) {
      builder.weight(static_cast<std::int32_t>(v), root, 1.0);
      continue;
    }
    const Chain& chain = chains[static_cast<std::size_t>(li)];
    for (const auto& [bone, w] : chain_weights(chain, built.vertex_s[v], 1.0)) {
      builder.weight(static_cast<std::int32_t>(v), chain.nodes[static_cast<std::size_t>(bone)], w);
    }
  }
  const std::vector<Eigen::Vector3d> axes(moving.size(), Eigen::Vector3d::UnitZ());
  Clip clip = rotation_clip(clip_name, builder, moving, axes, frames,
                            [&](std::size_t k, double tau) { return sign[k] * turn_end * tau; });

  GeneratedRig g;
  std::vector<std::int32_t> vertex_limb = built.vertex_limb;
  std::vector<double> vertex_s = built.vertex_s;
  g.rig = builder.finish(std::move(built.mesh), name, std::move(clip), "gen:" + name);

  g.answer.rule = "margin = largest signed distance of a moving limb's vertices past the mirror plane between it and its "
                  "partner (the partner is its mirror image); intersecting iff > 0";
  posed_frames(g.rig, frames, [&](int, const Positions& p) {
    double margin = -std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < vertex_limb.size(); ++v) {
      if (vertex_limb[v] < 0 || vertex_s[v] == 0.0) continue;  // body, and limb roots on the body
      for (const MirrorPair& pair : pairs) {
        if (pair.limb != static_cast<std::size_t>(vertex_limb[v])) continue;
        margin = std::max(margin, (p.row(static_cast<Eigen::Index>(v)).transpose() - pair.point).dot(pair.towards));
      }
    }
    g.answer.margin.push_back(margin);
  });
  decide(g.answer, 1e-9);
  return g;
}

}  // namespace

// Octopus: a regular octagonal body (circumradius 1, height 0.4) with a tentacle 3 long and
// 0.3 wide (8 bones) on each side; tentacles 2k and 2k + 1 curl towards each other, each joint
// by 12° · τ.
GeneratedRig generate_octopus(std::int64_t triangles, int frames) {
  BodySpec body;
  body.height = 0.4;
  for (int k = 0; k < 8; ++k) {
    const double a = (k - 0.5) * kPi / 4;
    body.corners.emplace_back(std::cos(a), std::sin(a));
  }
  const double side = 2 * std::sin(kPi / 8);
  std::vector<MirrorPair> pairs;
  for (int k = 0; k < 8; ++k) {
    body.limbs.push_back({k, side / 2, 0.3, 3.0, 8, k % 2 == 0 ? 1.0 : -1.0});
    if (k % 2 == 0) {
      const double beta = (k + 0.5) * kPi / 4;  // bisector between tentacles k and k + 1
      pairs.push_back({static_cast<std::size_t>(k), Eigen::Vector3d::Zero(), Eigen::Vector3d(-std::sin(beta), std::cos(beta), 0)});
    }
  }
  return generate_body(body, pairs, triangles, frames, 12.0 * kPi / 180.0, "octopus", "curl");
}

// Hand: a palm 1 × 0.8 × 0.2 with four fingers (0.14 wide, 0.1 apart, 1 long, 5 bones) on its +y
// side and a still thumb (0.2 wide, 0.6 long) on its −x side; fingers 1 & 2 and 3 & 4 bend
// sideways towards each other, each joint by 2° · τ.
GeneratedRig generate_hand(std::int64_t triangles, int frames) {
  BodySpec body;
  body.height = 0.2;
  body.corners = {{-0.5, -0.4}, {0.5, -0.4}, {0.5, 0.4}, {-0.5, 0.4}};
  // Side 2 runs from (0.5, 0.4) to (−0.5, 0.4): finger centres x = 0.36, 0.12, −0.12, −0.36.
  for (int f = 0; f < 4; ++f) body.limbs.push_back({2, 0.14 + 0.24 * f, 0.14, 1.0, 5, f % 2 == 0 ? 1.0 : -1.0});
  // Side 3 runs from (−0.5, 0.4) to (−0.5, −0.4): thumb centre y = −0.1.
  body.limbs.push_back({3, 0.5, 0.2, 0.6, 3, 0.0});
  const std::vector<MirrorPair> pairs = {{0, {0.24, 0, 0}, {-1, 0, 0}}, {2, {-0.24, 0, 0}, {-1, 0, 0}}};
  return generate_body(body, pairs, triangles, frames, 2.0 * kPi / 180.0, "hand", "spread");
}

}  // namespace skelcd::skinning::generators
