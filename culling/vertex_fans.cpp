#include "culling/vertex_fans.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "ccd/orientation.hpp"

namespace skelcd::culling {
VertexFans::VertexFans(
    std::span<const std::array<std::int32_t, 3>> triangles, std::int32_t num_vertices) {
  const auto nv = static_cast<std::size_t>(std::max(num_vertices, 0));
  // Per vertex, the oriented sides (a → b) of the triangles (v, a, b) around it (CSR).
  std::vector<std::int32_t> count(nv + 1, 0);
  std::vector<std::uint8_t> broken(nv, 0);
  for (const auto& t : triangles) {
    const bool degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    for (const auto v : t) {
      if (v < 0 || static_cast<std::size_t>(v) >= nv) continue;
      if (degenerate) broken[static_cast<std::size_t>(v)] = 1;
      ++count[static_cast<std::size_t>(v) + 1];
    }
  }
  for (std::size_t v = 0; v < nv; ++v) count[v + 1] += count[v];
  std::vector<std::pair<std::int32_t, std::int32_t>> sides(static_cast<std::size_t>(count[nv]));
  std::vector<std::int32_t> fill(count.begin(), count.end() - 1);
  for (const auto& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
      if (v >= nv) continue;
      sides[static_cast<std::size_t>(fill[v]++)] = {
          t[static_cast<std::size_t>((k + 1) % 3)], t[static_cast<std::size_t>((k + 2) % 3)]};
    }
  }
  offsets_.assign(nv + 1, 0);
  closed_.assign(nv, 0);
  std::vector<std::int32_t> ends;  // the sides' end spokes of one vertex, reused
  for (std::size_t v = 0; v < nv; ++v) {
    offsets_[v + 1] = offsets_[v];
    if (broken[v]) continue;
    const auto begin = sides.begin() + count[v];
    const auto end = sides.begin() + count[v + 1];
    const auto m = static_cast<std::size_t>(end - begin);
    if (m < 1) continue;
    std::sort(begin, end);
    // One chain: every spoke starts at most one side and ends at most one. A cycle when every
    // start is also an end (a closed vertex); else a path from the one start that is no end (a
    // boundary vertex). The walk must visit every side.
    bool ok = true;
    for (auto it = begin; it + 1 != end && ok; ++it) ok = it->first != (it + 1)->first;
    ends.clear();
    for (auto it = begin; it != end; ++it) ends.push_back(it->second);
    std::sort(ends.begin(), ends.end());
    for (std::size_t i = 0; i + 1 < m && ok; ++i) ok = ends[i] != ends[i + 1];
    if (!ok) continue;
    std::int32_t start = -1;
    int starts_only = 0;
    for (auto it = begin; it != end; ++it) {
      if (!std::binary_search(ends.begin(), ends.end(), it->first)) {
        start = it->first;
        ++starts_only;
      }
    }
    if (starts_only > 1) continue;
    const bool closed = starts_only == 0;
    if (closed && m < 3) continue;  // two triangles on the same three vertices, back to back
    if (closed) start = begin->first;
    const auto next = [&](std::int32_t a) -> std::int32_t {
      const auto it = std::lower_bound(begin, end, std::pair{a, INT32_MIN});
      return it != end && it->first == a ? it->second : -1;
    };
    const std::size_t first = spokes_.size();
    std::int32_t a = start;
    for (std::size_t i = 0; i < m && ok; ++i) {
      spokes_.push_back(a);
      a = next(a);
      ok = a >= 0 && (i + 1 == m ? (closed ? a == start : true) : a != start);
    }
    if (ok && !closed) spokes_.push_back(a);  // the path's last spoke
    if (!ok) {
      spokes_.resize(first);
      continue;
    }
    offsets_[v + 1] = static_cast<std::int32_t>(spokes_.size());
    closed_[v] = closed ? 1 : 0;
    ++num_fans_;
  }
}

namespace {

using Spoke = std::array<double, 3>;

/// Room for n spoke differences: on the stack for fans of up to 32 spokes (`stack`), else in this
/// thread's buffer (kept).
template <std::size_t kStack>
std::span<Spoke> spoke_room(std::size_t n, std::array<Spoke, kStack>& stack) {
  thread_local std::vector<Spoke> heap;
  if (n <= kStack) return {stack.data(), n};
  if (heap.size() < n) heap.resize(n);
  return {heap.data(), n};
}

/// d[i] = spoke i − v at x for the spokes s, and d[s.size()] = d[0] (spoke m of a closed fan is
/// spoke 0): every sign of a certificate is a function of these differences, each rounded from one
/// subtraction of input coordinates (what the static filters allow for), taken once.
[[gnu::always_inline]] inline void spoke_differences(
    const skinning::Positions& x,
    std::int32_t v,
    std::span<const std::int32_t> s,
    std::span<Spoke> d) {
  const double cx = x(v, 0), cy = x(v, 1), cz = x(v, 2);
  for (std::size_t i = 0; i < s.size(); ++i) {
    d[i] = {x(s[i], 0) - cx, x(s[i], 1) - cy, x(s[i], 2) - cz};
  }
  d[s.size()] = d[0];
}

/// Adds the (approximate) normals of the m sectors (d[i], d[i + 1]) to n.
[[gnu::always_inline]] inline void add_normal(std::span<const Spoke> d, std::size_t m, Spoke& n) {
  for (std::size_t i = 0; i < m; ++i) {
    const Spoke& a = d[i];
    const Spoke& b = d[i + 1];
    n[0] += a[1] * b[2] - a[2] * b[1];
    n[1] += a[2] * b[0] - a[0] * b[2];
    n[2] += a[0] * b[1] - a[1] * b[0];
  }
}

/// The axis along which n is largest (the first of equals).
inline std::size_t largest_axis(const Spoke& n) {
  std::size_t k = 0;
  if (std::abs(n[1]) > std::abs(n[0])) k = 1;
  if (std::abs(n[2]) > std::abs(n[k])) k = 2;
  return k;
}

/// The orientation sign(p, q) of spoke differences in the coordinate projection that drops axis k:
/// the k-th component of p × q by the static filter ccd::detail::cross_sign_static.
inline auto dropping_axis(std::size_t k) {
  return [i = (k + 1) % 3, j = (k + 2) % 3](const Spoke& p, const Spoke& q) {
    return ccd::detail::cross_sign_static(p[i], p[j], q[i], q[j]);
  };
}

/// `holds(sign, axes)` in a projection, sign(p, q) the orientation of spoke differences p, q there:
/// first the coordinate projection that drops the axis where n is largest (any choice is sound;
/// this one makes the certificate likely), the sign the k-th component of p × q by the static
/// filter ccd::detail::cross_sign_static, and `axes` the two coordinates kept (i, j); then, if that
/// fails, the projection along n itself — a fan that no coordinate axis sees injectively (a cube's
/// corner, a cone's tip, a crease turned away from the axes) may still be seen so — the sign
/// n · (p × q) = det[p; q; n] by the static orient3d filter (n is exact as computed: a difference
/// rounded zero times), and `axes` null.
template <class Holds>
bool holds_in_a_projection(const Spoke& n, const Holds& holds) {
  const std::size_t k = largest_axis(n);
  const std::array<std::size_t, 2> axes{(k + 1) % 3, (k + 2) % 3};
  if (holds(dropping_axis(k), &axes)) return true;
  if (!(std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]) > 0.0)) return false;
  const auto along_normal = [&](const Spoke& p, const Spoke& q) {
    return ccd::detail::det3_sign_static(p[0], p[1], p[2], q[0], q[1], q[2], n[0], n[1], n[2]);
  };
  return holds(along_normal, static_cast<const std::array<std::size_t, 2>*>(nullptr));
}

/// Conditions (1) and (2) of the certificate for a closed fan of m sectors (d[m] = d[0]) in the
/// coordinate projection onto `axes` (i, j), `sign` its filtered orientations. Every sector
/// strictly of one orientation s, the fan winds w times around v and every direction lies in
/// exactly w of the half-open sectors [d_i, d_i+1); for the direction e = (1, 0) that is
/// s·orient(d_i, e) = −s·d_i[j] >= 0 and s·orient(e, d_i+1) = s·d_i+1[j] > 0 (a sector narrower
/// than a half-turn). These are signs of coordinate differences, exact as rounded: so condition
/// (2) costs no orientation test, where winds_once needs m − 2 more.
template <class Sign>
bool closed_winds_once_in_axes(
    std::span<const Spoke> d, std::size_t m, std::size_t j, const Sign& sign) {
  const int s = sign(d[0], d[1]);
  if (s == ccd::detail::kUndecided) return false;
  int covering = 0;
  for (std::size_t i = 0; i < m; ++i) {
    if (i > 0 && sign(d[i], d[i + 1]) != s) return false;  // undecided or of the other sign
    const double from = s > 0 ? -d[i][j] : d[i][j];
    const double to = s > 0 ? d[i + 1][j] : -d[i + 1][j];
    covering += static_cast<int>((from >= 0.0) & (to > 0.0));
  }
  return covering == 1;
}

constexpr std::size_t kStackSpokes = 32;

/// The sign along n of sector (a, b): det[a; b; n] by the static orient3d filter on the transposed
/// rows (a_x, b_x, n_x), (a_y, b_y, n_y), (a_z, b_z, n_z) — the same determinant, whose 2 × 2
/// minors are then the components of a × b. `certify` is 1.3–1.5× faster on the fans that reach
/// the normal than with the rows (a, b, n) (docs/culling.md, "Closed fans along the normal,
/// cheaper").
inline int sector_sign_along(const Spoke& a, const Spoke& b, const Spoke& n) {
  return ccd::detail::det3_sign_static(a[0], b[0], n[0], a[1], b[1], n[1], a[2], b[2], n[2]);
}

}  // namespace

bool VertexFans::certified(const skinning::Positions& x, std::int32_t v) const {
  std::size_t axis = 3;  // no projection to try first
  return certified(x, v, axis);
}

bool VertexFans::certified(const skinning::Positions& x, std::int32_t v, std::size_t& axis) const {
  const std::span<const std::int32_t> s = spokes(v);
  const bool closed = closed_[static_cast<std::size_t>(v)] != 0;
  // m triangles: (v, s[i], s[i + 1]), the last one wrapping around when the fan is closed.
  const std::size_t m = closed ? s.size() : (s.empty() ? 0 : s.size() - 1);
  if (m < (closed ? 3u : 1u)) return false;
  std::array<Spoke, kStackSpokes + 1> stack;
  const std::span<Spoke> d = spoke_room(s.size() + 1, stack);
  spoke_differences(x, v, s, d);
  // A closed fan first in the projection `axis` names, when it names one: every projection is
  // sound, and this one needs no normal.
  const std::size_t tried = closed && axis < 3 ? axis : 3;
  if (tried < 3 && closed_winds_once_in_axes(d, m, (tried + 2) % 3, dropping_axis(tried))) {
    return true;
  }
  Spoke n{0.0, 0.0, 0.0};
  add_normal(d, m, n);
  axis = largest_axis(n);
  return holds_in_a_projection(n, [&](const auto& sign, const std::array<std::size_t, 2>* axes) {
    if (closed) {
      if (axes == nullptr) return closed_along_normal(d, m, n);
      return axis != tried && closed_winds_once_in_axes(d, m, (*axes)[1], sign);
    }
    return winds_once(m, closed, [&](std::size_t p, std::size_t q) { return sign(d[p], d[q]); });
  });
}

bool VertexFans::closed_along_normal(std::span<const Spoke> d, std::size_t m, const Spoke& n) {
  // (1) every sector's det[d_i; d_i+1; n] of one strict sign s (sector_sign_along). (2) The fan
  // winds once: every direction of the plane lies in exactly w half-open sectors, w the winding
  // number, as in the coordinate projection; take the direction e of axis a (where |n| is
  // smallest, so that e is not along n) projected onto the plane. The sign along n of (p, e) is
  // det[p; e; n] = det[p; u_a; n] = (n × p)_a (e − u_a is parallel to n), a 2 × 2 minor of n and
  // p: one filtered sign per spoke, where winds_once needs one determinant per spoke from spoke
  // 0. Sector [d_i, d_i+1) holds e when s·(n × d_i)_a >= 0 and −s·(n × d_i+1)_a > 0, which needs
  // exact zeros: a spoke whose sign the filter leaves open (a spoke in the plane of n and u_a —
  // the corner of an axis-aligned box) hands the covering to winds_once.
  if (!(std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]) > 0.0)) return false;
  const int sign = sector_sign_along(d[0], d[1], n);
  if (sign == ccd::detail::kUndecided) return false;
  for (std::size_t i = 1; i < m; ++i) {
    if (sector_sign_along(d[i], d[i + 1], n) != sign) return false;
  }
  std::size_t a = 0;
  if (std::abs(n[1]) < std::abs(n[0])) a = 1;
  if (std::abs(n[2]) < std::abs(n[a])) a = 2;
  const std::size_t b = (a + 1) % 3;
  const std::size_t c = (a + 2) % 3;
  const auto toward_e = [&](const Spoke& p) {  // sign of (n × p)_a = n_b p_c − n_c p_b
    return ccd::detail::cross_sign_static(n[b], n[c], p[b], p[c]);
  };
  int covering = 0;
  int t_i = toward_e(d[0]);
  const int t_0 = t_i;
  bool decided = t_i != ccd::detail::kUndecided;
  for (std::size_t i = 0; i < m && decided; ++i) {
    const int t_next = i + 1 < m ? toward_e(d[i + 1]) : t_0;
    decided = t_next != ccd::detail::kUndecided;
    covering += static_cast<int>((sign * t_i >= 0) & (-sign * t_next > 0));
    t_i = t_next;
  }
  if (decided) return covering == 1;
  return winds_once(m, true, [&](std::size_t p, std::size_t q) {
    if (q == p + 1) return sector_sign_along(d[p], d[q], n);
    return ccd::detail::det3_sign_static(
        d[p][0], d[p][1], d[p][2], d[q][0], d[q][1], d[q][2], n[0], n[1], n[2]);
  });
}

template <class Orient>
bool VertexFans::winds_once(std::size_t m, bool closed, const Orient& orient) {
  int sign = 0;
  int covering = 0;
  // orient(0, i) of the sector before (decided: an undecided sign has returned). orient(i, 0) is
  // its negation: a decided sign is the exact one, and the exact one is antisymmetric.
  int to_spoke_i = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const int o = orient(i, i + 1);
    if (o == ccd::detail::kUndecided) return false;
    if (sign == 0) sign = o;
    if (o != sign) return false;
    // Does the ray from v through spoke 0 lie in the half-open sector [a, b)? Sector 0 starts on
    // it; a closed fan's last sector ends on it (excluded); the others need two decided signs
    // (each sector is narrower than a half-turn, so both signs equal to the fan's mean inside).
    if (i == 0) {
      ++covering;
      to_spoke_i = o;  // orient(0, 1)
    } else if (!closed || i + 1 < m) {
      const int o1 = -to_spoke_i;  // orient(i, 0)
      const int o2 = orient(0, i + 1);
      if (o2 == ccd::detail::kUndecided) return false;
      if (o1 == sign && o2 == sign) ++covering;
      to_spoke_i = o2;
    }
  }
  // Closed: the fan winds exactly once. Open: no sector after the first reaches the ray again
  // (and the last spoke is off it: its sign was decided above), so the sectors do not overlap.
  return covering == 1;
}

bool VertexFans::certified_over(
    const skinning::Positions& x_t0, const skinning::Positions& x_t1, std::int32_t v) const {
  const std::span<const std::int32_t> s = spokes(v);
  // Closed fans only: with every sector strictly oriented throughout, a closed fan's winding
  // number is an integer that varies continuously, hence constant; an open fan's total angle
  // could grow past a full turn between the ends without any sector flattening.
  if (closed_[static_cast<std::size_t>(v)] == 0 || s.size() < 3) return false;
  const std::size_t m = s.size();
  // Spoke i relative to v on the straight-line motion: p(t) = (1 − t) d0[i] + t d1[i].
  std::array<Spoke, 2 * (kStackSpokes + 1)> stack;
  const std::span<Spoke> room = spoke_room(2 * (m + 1), stack);
  const std::span<Spoke> d0 = room.first(m + 1);
  const std::span<Spoke> d1 = room.subspan(m + 1);
  spoke_differences(x_t0, v, s, d0);
  spoke_differences(x_t1, v, s, d1);
  Spoke n{0.0, 0.0, 0.0};  // the summed normal at both ends: any direction is sound
  add_normal(d0, m, n);
  add_normal(d1, m, n);
  // In a fixed projection, sector i's orientation at t is that of the cross product of
  // (1 − t) p0 + t p1 and (1 − t) q0 + t q1 (p, q its spokes): (1 − t)² ⟨p0, q0⟩ +
  // t (1 − t) (⟨p0, q1⟩ + ⟨p1, q0⟩) + t² ⟨p1, q1⟩. The four signs equal make it strict on [0, 1].
  // The closed fan winds once at t = 0 in the same projection (closed_winds_once_in_axes, or
  // winds_once along the normal); it keeps doing so.
  return holds_in_a_projection(n, [&](const auto& sign, const std::array<std::size_t, 2>* axes) {
    const auto at_start = [&](std::size_t p, std::size_t q) { return sign(d0[p], d0[q]); };
    if (axes != nullptr ? !closed_winds_once_in_axes(d0, m, (*axes)[1], sign)
                        : !winds_once(m, true, at_start)) {
      return false;
    }
    const int o = at_start(0, 1);
    for (std::size_t i = 0; i < m; ++i) {
      if (sign(d0[i], d1[i + 1]) != o || sign(d1[i], d0[i + 1]) != o ||
          sign(d1[i], d1[i + 1]) != o) {
        return false;
      }
    }
    return true;
  });
}

void VertexFans::certify(const skinning::Positions& x, std::vector<std::uint8_t>& out) const {
  const std::size_t nv = closed_.size();
  out.resize(nv);
  // Consecutive vertices of a mesh are mostly neighbours, with normals along the same axis: each
  // closed fan first tries the projection certified() last chose (no normal to sum), then its
  // own. Any projection is sound; this certifies every fan certified(x, v) does and a few more.
  std::size_t axis = 3;  // none yet
  for (std::size_t v = 0; v < nv; ++v) {
    out[v] = certified(x, static_cast<std::int32_t>(v), axis) ? 1 : 0;
  }
}

}  // namespace skelcd::culling
