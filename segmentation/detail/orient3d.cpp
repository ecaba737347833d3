#include "segmentation/detail/orient3d.hpp"

#include <cassert>
#include <cmath>
#include <limits>

#include <gmpxx.h>

namespace skelcd::segmentation::detail {

namespace {

// Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric predicates"
// (1997): |det_fp − det| ≤ (7 + 56ε) ε · permanent with ε = 2⁻⁵³ (half an ulp of 1).
constexpr double kHalfUlp = std::numeric_limits<double>::epsilon() / 2.0;
constexpr double kErrBound = (7.0 + 56.0 * kHalfUlp) * kHalfUlp;

}  // namespace

int orient3d_sign_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  // Doubles convert to rationals exactly; differences and products are then exact.
  const mpq_class adx = mpq_class(a.x()) - d.x(), ady = mpq_class(a.y()) - d.y(),
                  adz = mpq_class(a.z()) - d.z();
  const mpq_class bdx = mpq_class(b.x()) - d.x(), bdy = mpq_class(b.y()) - d.y(),
                  bdz = mpq_class(b.z()) - d.z();
  const mpq_class cdx = mpq_class(c.x()) - d.x(), cdy = mpq_class(c.y()) - d.y(),
                  cdz = mpq_class(c.z()) - d.z();
  const mpq_class det = adx * (bdy * cdz - bdz * cdy) + bdx * (cdy * adz - cdz * ady) +
                        cdx * (ady * bdz - adz * bdy);
  return sgn(det);
}

int orient3d_sign(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  assert(a.allFinite() && b.allFinite() && c.allFinite() && d.allFinite());
  const double adx = a.x() - d.x(), ady = a.y() - d.y(), adz = a.z() - d.z();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y(), bdz = b.z() - d.z();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y(), cdz = c.z() - d.z();

  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;

  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  const double bound = kErrBound * permanent;
  // The bound holds while no product underflowed by more than a negligible amount: below that
  // range (tiny coordinates, or all products zero) decide exactly.
  if (permanent > std::numeric_limits<double>::min() * 0x1p64) {
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  return orient3d_sign_exact(a, b, c, d);
}

}  // namespace skelcd::segmentation::detail
