#pragma once
// Two doubles, each operation done once per lane (GCC/Clang vector extension: one SSE2
// instruction on x86-64, which is all the baseline build may use). Each lane's result is the
// scalar expression's, bit for bit, since a lane goes through the same IEEE operations in the
// same order; the kernels use lanes for two independent evaluations of one formula (two Bernstein
// coefficients of the coplanarity cubic, two inside quartics) without changing a single rounding.
// There is no FMA in the baseline instruction set, so nothing is contracted. Four doubles
// (Lanes4) likewise, for the AVX2 builds chosen at run time (algebraic_filter.cpp).

#include <Eigen/Core>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SKELCD_LANES_PTEST 1
#include <immintrin.h>
#endif

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace skelcd::ccd::detail {

using Lanes = double __attribute__((vector_size(16)));
using LaneBits = std::uint64_t __attribute__((vector_size(16)));

// Four lanes, for code built for AVX2 (a target("avx2") function that inlines the helpers below;
// elsewhere GCC splits them into pairs). Passed by reference: where the baseline ABI has no AVX,
// a 32-byte vector argument would change it.
using Lanes4 = double __attribute__((vector_size(32)));
using LaneBits4 = std::uint64_t __attribute__((vector_size(32)));

/// Whether this CPU has AVX2, for the builds chosen at run time (the coplanarity screen, the
/// quartics and their filter, the culling feature stage). Asked once per process.
inline bool cpu_has_avx2() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  static const bool kHas = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return kHas;
#else
  return false;
#endif
}

/// Whether this CPU and its OS have AVX-512 F, VL and DQ: builds of the AVX2 code that may also
/// use the 16 further vector registers (and the mask registers) EVEX encodes, chosen at run time
/// (the culling feature stage). libgcc's check includes the OS's saving of the AVX-512 state.
/// Valgrind's CPU has no AVX-512, so under it the AVX2 builds run. Asked once per process.
inline bool cpu_has_avx512vl() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  static const bool kHas = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0 &&
           __builtin_cpu_supports("avx512dq") != 0;
  }();
  return kHas;
#else
  return false;
#endif
}

/// |v| per lane as std::abs does it: the sign bit cleared.
inline Lanes lane_abs(Lanes v) {
  constexpr std::uint64_t kMagnitude = ~(std::uint64_t{1} << 63);
  return std::bit_cast<Lanes>(std::bit_cast<LaneBits>(v) & kMagnitude);
}
/// The same on four lanes (a vector cast reinterprets the bits: GCC 12's UBSan takes std::bit_cast
/// of a 32-byte vector for a load of a null pointer).
[[gnu::always_inline]] inline Lanes4 lane_abs(const Lanes4& v) {
  constexpr std::uint64_t kMagnitude = ~(std::uint64_t{1} << 63);
  return reinterpret_cast<Lanes4>(reinterpret_cast<LaneBits4>(v) & kMagnitude);
}

/// std::max(a, b) per lane, NaN behaviour included: (a < b) ? b : a.
inline Lanes lane_max(Lanes a, Lanes b) { return a < b ? b : a; }
[[gnu::always_inline]] inline Lanes4 lane_max(const Lanes4& a, const Lanes4& b) {
  return a < b ? b : a;
}

/// Some lane set, every lane set.
inline bool any_lane(const LaneBits& b) { return (b[0] | b[1]) != 0; }
inline bool all_lanes(const LaneBits& b) { return (b[0] & b[1]) != 0; }
// On four lanes (each all ones or all zeros), one vptest with GCC on x86-64: its code for the
// plain expressions extracts and combines the lanes one by one. The builtins are declared by
// <immintrin.h>'s target pragmas and expanded in the target("avx2") functions these are inlined
// into (the only callers: a call from code built for the baseline does not compile).
[[gnu::always_inline]] inline bool any_lane(const LaneBits4& b) {
#if defined(SKELCD_LANES_PTEST)
  using V4di = long long __attribute__((vector_size(32)));
  return __builtin_ia32_ptestz256(reinterpret_cast<V4di>(b), reinterpret_cast<V4di>(b)) == 0;
#else
  return (b[0] | b[1] | b[2] | b[3]) != 0;
#endif
}
[[gnu::always_inline]] inline bool all_lanes(const LaneBits4& b) {
#if defined(SKELCD_LANES_PTEST)
  using V4di = long long __attribute__((vector_size(32)));
  // CF: no bit of the all-ones mask outside b.
  return __builtin_ia32_ptestc256(reinterpret_cast<V4di>(b), V4di{-1, -1, -1, -1}) != 0;
#else
  return (b[0] & b[1] & b[2] & b[3]) != 0;
#endif
}

/// A 3-vector per lane.
template <class L>
struct LaneVec3 {
  L x, y, z;
};
using Lanes3 = LaneVec3<Lanes>;

inline Lanes3 lanes3(const Eigen::Vector3d& lane0, const Eigen::Vector3d& lane1) {
  return {Lanes{lane0[0], lane1[0]}, Lanes{lane0[1], lane1[1]}, Lanes{lane0[2], lane1[2]}};
}
/// Lane k of each coordinate from *v[k], for two or four lanes.
template <class L, std::size_t W>
[[gnu::always_inline]] inline LaneVec3<L> lanes_of(const std::array<const Eigen::Vector3d*, W>& v) {
  static_assert(W == 2 || W == 4);
  if constexpr (W == 2) {
    return lanes3(*v[0], *v[1]);
  } else {
    const auto& a = *v[0];
    const auto& b = *v[1];
    const auto& c = *v[2];
    const auto& d = *v[3];
    return {L{a[0], b[0], c[0], d[0]}, L{a[1], b[1], c[1], d[1]}, L{a[2], b[2], c[2], d[2]}};
  }
}

template <class L>
[[gnu::always_inline]] inline LaneVec3<L> lane_abs(const LaneVec3<L>& v) {
  return {lane_abs(v.x), lane_abs(v.y), lane_abs(v.z)};
}

/// y x z per lane, as Eigen's cross: (y1 z2 - y2 z1, y2 z0 - y0 z2, y0 z1 - y1 z0).
template <class L>
[[gnu::always_inline]] inline LaneVec3<L> cross(const LaneVec3<L>& y, const LaneVec3<L>& z) {
  return {y.y * z.z - y.z * z.y, y.z * z.x - y.x * z.z, y.x * z.y - y.y * z.x};
}

/// The permanent of y x z (absolute values, both products added), from |y| and |z|.
template <class L>
[[gnu::always_inline]] inline LaneVec3<L> cross_permanent(
    const LaneVec3<L>& ay, const LaneVec3<L>& az) {
  return {ay.y * az.z + ay.z * az.y, ay.z * az.x + ay.x * az.z, ay.x * az.y + ay.y * az.x};
}

/// x . c per lane, summed left to right: (x0 c0 + x1 c1) + x2 c2.
template <class L>
[[gnu::always_inline]] inline L dot(const LaneVec3<L>& x, const LaneVec3<L>& c) {
  return x.x * c.x + x.y * c.y + x.z * c.z;
}

/// max_k |v_k| per lane (for finite v; the order of the comparisons then does not matter).
template <class L>
[[gnu::always_inline]] inline L max_abs(const LaneVec3<L>& v) {
  return lane_max(lane_max(lane_abs(v.x), lane_abs(v.y)), lane_abs(v.z));
}

}  // namespace skelcd::ccd::detail

#pragma GCC diagnostic pop
