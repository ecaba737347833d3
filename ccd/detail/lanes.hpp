#pragma once
// Two doubles, each operation done once per lane (GCC/Clang vector extension: one SSE2
// instruction on x86-64, which is all the baseline build may use). Each lane's result is the
// scalar expression's, bit for bit, since a lane goes through the same IEEE operations in the
// same order; the kernels use lanes for two independent evaluations of one formula (two Bernstein
// coefficients of the coplanarity cubic, two inside quartics) without changing a single rounding.
// There is no FMA in the baseline instruction set, so nothing is contracted.

#include <Eigen/Core>
#include <bit>
#include <cstdint>

namespace skelcd::ccd::detail {

using Lanes = double __attribute__((vector_size(16)));
using LaneBits = std::uint64_t __attribute__((vector_size(16)));

/// |v| per lane as std::abs does it: the sign bit cleared.
inline Lanes lane_abs(Lanes v) {
  constexpr std::uint64_t kMagnitude = ~(std::uint64_t{1} << 63);
  return std::bit_cast<Lanes>(std::bit_cast<LaneBits>(v) & kMagnitude);
}

/// std::max(a, b) per lane, NaN behaviour included: (a < b) ? b : a.
inline Lanes lane_max(Lanes a, Lanes b) { return a < b ? b : a; }

/// A 3-vector per lane.
struct Lanes3 {
  Lanes x, y, z;
};

inline Lanes3 lanes3(const Eigen::Vector3d& lane0, const Eigen::Vector3d& lane1) {
  return {Lanes{lane0[0], lane1[0]}, Lanes{lane0[1], lane1[1]}, Lanes{lane0[2], lane1[2]}};
}

inline Lanes3 lane_abs(const Lanes3& v) { return {lane_abs(v.x), lane_abs(v.y), lane_abs(v.z)}; }

/// y x z per lane, as Eigen's cross: (y1 z2 - y2 z1, y2 z0 - y0 z2, y0 z1 - y1 z0).
inline Lanes3 cross(const Lanes3& y, const Lanes3& z) {
  return {y.y * z.z - y.z * z.y, y.z * z.x - y.x * z.z, y.x * z.y - y.y * z.x};
}

/// The permanent of y x z (absolute values, both products added), from |y| and |z|.
inline Lanes3 cross_permanent(const Lanes3& ay, const Lanes3& az) {
  return {ay.y * az.z + ay.z * az.y, ay.z * az.x + ay.x * az.z, ay.x * az.y + ay.y * az.x};
}

/// x . c per lane, summed left to right: (x0 c0 + x1 c1) + x2 c2.
inline Lanes dot(const Lanes3& x, const Lanes3& c) { return x.x * c.x + x.y * c.y + x.z * c.z; }

/// max_k |v_k| per lane (for finite v; the order of the comparisons then does not matter).
inline Lanes max_abs(const Lanes3& v) {
  return lane_max(lane_max(lane_abs(v.x), lane_abs(v.y)), lane_abs(v.z));
}

}  // namespace skelcd::ccd::detail
