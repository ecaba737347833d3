#include "ccd/orientation.hpp"

#include "ccd/detail/filtered.hpp"

namespace skelcd::ccd {

int orient3d_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  using detail::lift;
  return detail::exact_sign([&]<typename T>() -> T {
    const auto pa = lift<T>(a);
    return detail::dot(detail::cross(lift<T>(b) - pa, lift<T>(c) - pa), lift<T>(d) - pa);
  });
}

}  // namespace skelcd::ccd
