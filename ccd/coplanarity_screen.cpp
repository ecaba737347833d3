// The coplanarity screen of four queries at once: detail::trilinear_screen and certified_sign
// (detail/trilinear_cubic.hpp, detail/conservative_pipeline.hpp) with one query per lane of a
// four-double vector. Each lane goes through the scalar code's IEEE operations in its order (no
// FMA: the build passes -ffp-contract=off), so each bit is the scalar decision.

#include "ccd/coplanarity_screen.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstring>
#include <limits>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/lanes.hpp"
#include "ccd/detail/screen_x4.hpp"

// Four-double vectors are passed between the inline helpers below (and detail/lanes.hpp's);
// where the baseline ABI has no AVX they are split, which is what the note is about. Nothing
// crosses a library boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace skelcd::ccd {
namespace {

using detail::cross;
using detail::dot;
using detail::lane_max;
using detail::max_abs;
using V = detail::Lanes4;
using V3 = detail::LaneVec3<V>;
using VBits = std::int64_t __attribute__((vector_size(32)));

/// Coordinates of one point role across four queries: lane k is query k's point `role`.
[[gnu::always_inline]] inline V3 gather(const double* x, ScreenQuads q, std::size_t role) {
  const double* p0 = x + 3 * static_cast<std::ptrdiff_t>(q[0][role]);
  const double* p1 = x + 3 * static_cast<std::ptrdiff_t>(q[1][role]);
  const double* p2 = x + 3 * static_cast<std::ptrdiff_t>(q[2][role]);
  const double* p3 = x + 3 * static_cast<std::ptrdiff_t>(q[3][role]);
  return {
      V{p0[0], p1[0], p2[0], p3[0]}, V{p0[1], p1[1], p2[1], p3[1]}, V{p0[2], p1[2], p2[2], p3[2]}};
}

[[gnu::always_inline]] inline V3 minus(const V3& a, const V3& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

/// The bits of v, and the vector of bits b. By memcpy, which compiles to nothing: GCC 12's UBSan
/// reports std::bit_cast of these 32-byte vectors as a load of a null pointer.
[[gnu::always_inline]] inline VBits bits_of(const V& v) {
  VBits b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
[[gnu::always_inline]] inline V from_bits(const VBits& b) {
  V v;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

/// The screens of the triples X, Y, Z at t0 and t1 (c(t) = X . (Y x Z)), lane k query k's. `x0` …
/// `z1` are the differences, formed as the kernels form them.
[[gnu::always_inline]] inline CoplanarityScreens screen(
    const V3& x0, const V3& y0, const V3& z0, const V3& x1, const V3& y1, const V3& z1) {
  // trilinear_coefficients: the dets d_ijk = X_i . (Y_j x Z_k).
  const V3 c00 = cross(y0, z0);
  const V3 c10 = cross(y1, z0);
  const V3 c01 = cross(y0, z1);
  const V3 c11 = cross(y1, z1);
  const V d000 = dot(x0, c00);
  const V d010 = dot(x0, c10);
  const V d100 = dot(x1, c00);
  const V d110 = dot(x1, c10);
  const V d001 = dot(x0, c01);
  const V d011 = dot(x0, c11);
  const V d101 = dot(x1, c01);
  const V d111 = dot(x1, c11);
  const V b0 = d000;
  const V b1 = ((d100 + d010) + d001) / 3.0;
  const V b2 = ((d011 + d101) + d110) / 3.0;
  const V b3 = d111;
  // trilinear_screen's error bound from the largest coordinate magnitudes.
  const V x = lane_max(max_abs(x0), max_abs(x1));
  const V y = lane_max(max_abs(y0), max_abs(y1));
  const V z = lane_max(max_abs(z0), max_abs(z1));
  const V q = y * z;
  const V cross_perm = q + q;
  const V r = x * cross_perm;
  const V det_perm = (r + r) + r;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const V perm = det_perm < 0x1p1020 ? det_perm * detail::kRoundUp : V{kInf, kInf, kInf, kInf};
  const V rounding = detail::rounding_bound(11, 1.0) * perm;
  // detail::times_subnormal_power_of_two<1070>(1 + x), both of its branches per lane. The scaled
  // branch scales 1 + x only in the lanes that take it (1 + x >= 2^48, or NaN), and 2^48 in the
  // others: its products are then normal numbers in every lane. Scaling 1 + x < 2^48 there gave
  // a subnormal product in every real screen, and with it the CPU's slow path for one (a fifth of
  // this screen's samples sat on it) for a value the lane then discarded.
  const V one_x = 1.0 + x;
  const auto in_range = (one_x >= 0.0) & (one_x < 0x1p48);
  const V shifted = one_x * 16.0 + 0x1p52;
  const V in_units = from_bits(bits_of(shifted) - std::bit_cast<std::int64_t>(0x1p52));
  const V normal_input = in_range ? V{0x1p48, 0x1p48, 0x1p48, 0x1p48} : one_x;
  const V scaled = (normal_input * 0x1p-600) * detail::power_of_two(600 - 1070);
  const V underflow = in_range ? in_units : scaled;
  const V error = (rounding + underflow) * detail::kRoundUp;
  // certified_sign: finite coefficients, all above the error or all below its negative.
  constexpr double kMax = std::numeric_limits<double>::max();
  const VBits finite = (detail::lane_abs(b0) <= kMax) & (detail::lane_abs(b1) <= kMax) &
                       (detail::lane_abs(b2) <= kMax) & (detail::lane_abs(b3) <= kMax);
  const VBits positive = (b0 > error) & (b1 > error) & (b2 > error) & (b3 > error);
  const VBits negative = (-b0 > error) & (-b1 > error) & (-b2 > error) & (-b3 > error);
  const VBits certified = finite & (positive | negative);
  CoplanarityScreens out;
  for (std::size_t k = 0; k < 4; ++k) {
    out.apart |= static_cast<unsigned>(certified[k] != 0) << k;
    out.coefficients[k] = {b0[k], b1[k], b2[k], b3[k]};
    // trilinear_screen's magnitude, std::max({x, y, z}): the largest, the first of equals.
    out.magnitude[k] = std::max({x[k], y[k], z[k]});
  }
  return out;
}

/// The screens of four queries of one kind, the differences formed as the kernels form them:
/// vertex-face (vertex_face.cpp) X = v - f0, Y = f1 - f0, Z = f2 - f0; edge-edge (edge_edge.cpp)
/// X = eb0 - ea0, Y = ea1 - ea0, Z = eb1 - eb0.
template <bool kVertexFace>
[[gnu::always_inline]] inline CoplanarityScreens body(
    const double* x_t0, const double* x_t1, ScreenQuads q) {
  // Roles: vertex-face (v, f0, f1, f2), edge-edge (ea0, ea1, eb0, eb1).
  const V3 p0_t0 = gather(x_t0, q, 0), p1_t0 = gather(x_t0, q, 1);
  const V3 p2_t0 = gather(x_t0, q, 2), p3_t0 = gather(x_t0, q, 3);
  const V3 p0_t1 = gather(x_t1, q, 0), p1_t1 = gather(x_t1, q, 1);
  const V3 p2_t1 = gather(x_t1, q, 2), p3_t1 = gather(x_t1, q, 3);
  if constexpr (kVertexFace) {
    return screen(
        minus(p0_t0, p1_t0),
        minus(p2_t0, p1_t0),
        minus(p3_t0, p1_t0),
        minus(p0_t1, p1_t1),
        minus(p2_t1, p1_t1),
        minus(p3_t1, p1_t1));
  } else {
    return screen(
        minus(p2_t0, p0_t0),
        minus(p1_t0, p0_t0),
        minus(p3_t0, p2_t0),
        minus(p2_t1, p0_t1),
        minus(p1_t1, p0_t1),
        minus(p3_t1, p2_t1));
  }
}

/// Face k's corner `role` at one end, lane k.
[[gnu::always_inline]] inline V3 gather(const FaceCorners& f, std::size_t role) {
  const double* p0 = f[0][role];
  const double* p1 = f[1][role];
  const double* p2 = f[2][role];
  const double* p3 = f[3][role];
  return {
      V{p0[0], p1[0], p2[0], p3[0]}, V{p0[1], p1[1], p2[1], p3[1]}, V{p0[2], p1[2], p2[2], p3[2]}};
}

/// body<true> for one point against four faces given by their corners.
[[gnu::always_inline]] inline CoplanarityScreens point_faces_body(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1) {
  const auto broadcast = [](const double* p) __attribute__((always_inline)) {
    return V3{V{p[0], p[0], p[0], p[0]}, V{p[1], p[1], p[1], p[1]}, V{p[2], p[2], p[2], p[2]}};
  };
  const V3 v0 = broadcast(v_t0), v1 = broadcast(v_t1);
  const V3 a0 = gather(f_t0, 0), b0 = gather(f_t0, 1), c0 = gather(f_t0, 2);
  const V3 a1 = gather(f_t1, 0), b1 = gather(f_t1, 1), c1 = gather(f_t1, 2);
  return screen(
      minus(v0, a0), minus(b0, a0), minus(c0, a0), minus(v1, a1), minus(b1, a1), minus(c1, a1));
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
[[gnu::target("avx2")]] CoplanarityScreens point_faces_body_avx2(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1) {
  return point_faces_body(v_t0, v_t1, f_t0, f_t1);
}
#endif

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
/// body compiled for AVX2: one instruction per operation on the four lanes.
template <bool kVertexFace>
[[gnu::target("avx2")]] CoplanarityScreens body_avx2(
    const double* x_t0, const double* x_t1, ScreenQuads q) {
  return body<kVertexFace>(x_t0, x_t1, q);
}
#endif

template <bool kVertexFace>
CoplanarityScreens dispatch(const double* x_t0, const double* x_t1, ScreenQuads q) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (detail::cpu_has_avx2()) return body_avx2<kVertexFace>(x_t0, x_t1, q);
#endif
  return body<kVertexFace>(x_t0, x_t1, q);
}

}  // namespace

CoplanarityScreens vertex_face_screen_x4(
    const double* x_t0, const double* x_t1, ScreenQuads queries) {
  return dispatch<true>(x_t0, x_t1, queries);
}

CoplanarityScreens edge_edge_screen_x4(
    const double* x_t0, const double* x_t1, ScreenQuads queries) {
  return dispatch<false>(x_t0, x_t1, queries);
}

CoplanarityScreens point_faces_screen_x4(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (detail::cpu_has_avx2()) return point_faces_body_avx2(v_t0, v_t1, f_t0, f_t1);
#endif
  return point_faces_body(v_t0, v_t1, f_t0, f_t1);
}

namespace detail {

CoplanarityScreens vertex_face_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries) {
  return body<true>(x_t0, x_t1, queries);
}

CoplanarityScreens point_faces_screen_x4_baseline(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1) {
  return point_faces_body(v_t0, v_t1, f_t0, f_t1);
}

CoplanarityScreens edge_edge_screen_x4_baseline(
    const double* x_t0, const double* x_t1, ScreenQuads queries) {
  return body<false>(x_t0, x_t1, queries);
}

}  // namespace detail
}  // namespace skelcd::ccd
