// Linear blend skinning: the kernel against hand-computed blends, and proof that posing a rig
// again allocates nothing.

#include "skinning/lbs.hpp"

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "skinning/rig_motion.hpp"
#include "tests/skinning/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

// Every operator new of the test program is counted (std containers, shared_ptr, strings, …).
// Eigen's own heap goes through malloc; the Debug build checks it with EIGEN_RUNTIME_NO_MALLOC.
namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace skelcd::skinning {
namespace {

using skelcd::test::expect_matrix_near;

BoneTransform translation(double x, double y, double z) {
  BoneTransform t = BoneTransform::Zero();
  t.leftCols<3>().setIdentity();
  t.col(3) << x, y, z;
  return t;
}

TEST(LinearBlendSkinning, BlendsTransformsByWeight) {
  Positions rest(3, 3);
  rest << 1, 2, 3,  //
      4, 5, 6,      //
      7, 8, 9;
  SkinWeights w(3, 2);
  std::vector<Eigen::Triplet<double>> entries{{0, 0, 1.0}, {1, 0, 0.25}, {1, 1, 0.75}};  // row 2 empty
  w.setFromTriplets(entries.begin(), entries.end());
  BoneTransform scale2 = BoneTransform::Zero();
  scale2.leftCols<3>() = 2 * Eigen::Matrix3d::Identity();
  const std::vector<BoneTransform> transforms{translation(10, 0, 0), scale2};
  Positions out;
  linear_blend_skinning(rest, w, transforms, out);
  Positions expected(3, 3);
  expected << 11, 2, 3,                                   // moved by 10 in x
      0.25 * 14 + 0.75 * 8, 0.25 * 5 + 0.75 * 10, 0.25 * 6 + 0.75 * 12,  // a quarter moved, three quarters doubled
      7, 8, 9;                                            // no weight: stays
  EXPECT_TRUE(expect_matrix_near(out, expected, 1e-15));
}

TEST(LinearBlendSkinning, WeightsOfTheRigAddRigidAttachmentsForUnweightedVertices) {
  Rig rig = test::two_bone_rig();
  rig.weights.coeffRef(3, 0) = 0.0;
  rig.weights.prune(0.0);
  rig.part_attachments = {{1, Eigen::Affine3d::Identity()}};
  const LinearBlendSkinning lbs(rig);
  ASSERT_EQ(lbs.weights().cols(), 3);  // 2 bones + 1 part
  EXPECT_EQ(lbs.weights().coeff(3, 2), 1.0);
  EXPECT_EQ(lbs.weights().row(3).nonZeros(), 1);
  // Rows with weights are untouched and still sum to 1.
  for (Eigen::Index v = 0; v < 4; ++v) EXPECT_DOUBLE_EQ(lbs.weights().row(v).sum(), 1.0);
}

TEST(LinearBlendSkinning, PosingAgainAllocatesNothing) {
#ifdef EIGEN_RUNTIME_NO_MALLOC
  constexpr bool kEigenChecked = true;
#else
  constexpr bool kEigenChecked = false;
#endif
  const auto rig = std::make_shared<const Rig>(test::two_bone_rig());
  const RigMotion motion(rig, RigMotionOptions{.clip = 0, .rate_hz = 10});
  Positions out;
  motion.positions(0, out);  // sizes `out` and this thread's pose scratch
  const auto* data = out.data();
  const long before = g_allocations.load();
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(false);
#endif
  for (int i = 0; i < motion.num_samples(); ++i) motion.positions(i, out);
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(true);
#endif
  EXPECT_EQ(g_allocations.load(), before) << "operator new called while posing";
  EXPECT_EQ(out.data(), data) << "the output buffer was reallocated";
  (void)kEigenChecked;
}

}  // namespace
}  // namespace skelcd::skinning
