#include "culling/vertex_bounds.hpp"

#include <cassert>

namespace skelcd::culling {

template <int N>
void swept_vertex_bounds(
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<Dop<N>>& out) {
  assert(x_t0.rows() == x_t1.rows());
  const auto n = static_cast<std::size_t>(x_t0.rows());
  out.resize(n);
  // The segment's projection on any axis lies between its endpoints' projections, so the union
  // of the two endpoint volumes bounds the whole linear motion.
  for (std::size_t w = 0; w < n; ++w) {
    const auto i = static_cast<Eigen::Index>(w);
    Dop<N> d = Dop<N>::of_point(x_t0(i, 0), x_t0(i, 1), x_t0(i, 2));
    d.merge(Dop<N>::of_point(x_t1(i, 0), x_t1(i, 1), x_t1(i, 2)));
    d.inflate(half_width);
    out[w] = d;
  }
}

template <int N>
void static_vertex_bounds(const skinning::Positions& x, std::vector<Dop<N>>& out) {
  const auto n = static_cast<std::size_t>(x.rows());
  out.resize(n);
  for (std::size_t w = 0; w < n; ++w) {
    const auto i = static_cast<Eigen::Index>(w);
    out[w] = Dop<N>::of_point(x(i, 0), x(i, 1), x(i, 2));
  }
}

template void swept_vertex_bounds<3>(
    const skinning::Positions&, const skinning::Positions&, double, std::vector<Dop<3>>&);
template void swept_vertex_bounds<8>(
    const skinning::Positions&, const skinning::Positions&, double, std::vector<Dop<8>>&);
template void static_vertex_bounds<3>(const skinning::Positions&, std::vector<Dop<3>>&);
template void static_vertex_bounds<8>(const skinning::Positions&, std::vector<Dop<8>>&);

}  // namespace skelcd::culling
