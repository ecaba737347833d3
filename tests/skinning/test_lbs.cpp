// Linear blend skinning: the kernel against hand-computed blends, and proof that posing a rig
// again allocates nothing.
//
// The allocation guard has three layers: this test program replaces every global operator new
// (std containers, strings, shared_ptr — counted in any build); under AddressSanitizer a malloc
// hook counts Eigen's own heap too (it allocates with malloc); and with asserts on, Eigen's
// EIGEN_RUNTIME_NO_MALLOC check fires inside Eigen code compiled in this file.
#define EIGEN_RUNTIME_NO_MALLOC
#include <Eigen/Core>

#include "skinning/lbs.hpp"

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include <gtest/gtest.h>

#if defined(__SANITIZE_ADDRESS__)
#if __has_include(<sanitizer/allocator_interface.h>)
#include <sanitizer/allocator_interface.h>
#else
// The ASan runtime's hook installer (declared by hand where GCC's sanitizer headers are absent).
extern "C" int __sanitizer_install_malloc_and_free_hooks(
    void (*malloc_hook)(const volatile void*, std::size_t),
    void (*free_hook)(const volatile void*));
#endif
#endif

#include "skinning/rig_motion.hpp"
#include "tests/skinning/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace {

std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void note_allocation() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}

void* allocate(std::size_t size) {
  note_allocation();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

void* allocate_aligned(std::size_t size, std::align_val_t alignment) {
  note_allocation();
  const auto a = static_cast<std::size_t>(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}

#if defined(__SANITIZE_ADDRESS__)
void on_malloc(const volatile void*, std::size_t) { note_allocation(); }
void on_free(const volatile void*) {}
[[maybe_unused]] const int kHooks = __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free);
#endif

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  note_allocation();
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  note_allocation();
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t a) { return allocate_aligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocate_aligned(size, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

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
  const auto rig = std::make_shared<const Rig>(test::two_bone_rig());
  const RigMotion motion(rig, RigMotionOptions{.clip = 0, .rate_hz = 10});
  Positions out;
  motion.positions(0, out);  // sizes `out` and this thread's pose scratch
  const auto* data = out.data();
  g_allocations = 0;
  Eigen::internal::set_is_malloc_allowed(false);
  g_counting = true;
  for (int i = 0; i < motion.num_samples(); ++i) motion.positions(i, out);
  g_counting = false;
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(g_allocations.load(), 0) << "allocations while posing";
  EXPECT_EQ(out.data(), data) << "the output buffer was reallocated";
  // The guard itself works: a fresh buffer is counted.
  g_counting = true;
  auto fresh = std::make_unique<std::vector<double>>(100);
  g_counting = false;
  EXPECT_GT(g_allocations.load(), 0);
}

}  // namespace
}  // namespace skelcd::skinning
