// Refit, traversal, feature stage and elementary stage allocate nothing once warmed up.
//
// Three guards, from weakest to strongest:
// - Eigen's runtime check (EIGEN_RUNTIME_NO_MALLOC + set_is_malloc_allowed(false)): only bites with
//   asserts on (Debug / sanitizer build), and only where this TU's copy of Eigen's allocator is
//   the one linked (at -O0 it is: this object file precedes the libraries on the link line).
// - This executable replaces the global operator new: every std::vector growth (and any other
//   `new`) inside the measured window is counted — in Release too.
// - Under AddressSanitizer, malloc hooks count every malloc (Eigen allocates with malloc).
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cstdlib>
#include <new>

#include "culling/method.hpp"
#include "tests/culling/procedural_meshes.hpp"

#if defined(__SANITIZE_ADDRESS__)
// From the sanitizer runtime's allocator interface (GCC does not ship that header).
extern "C" int __sanitizer_install_malloc_and_free_hooks(
    void (*malloc_hook)(const volatile void*, std::size_t),
    void (*free_hook)(const volatile void*));
#endif

namespace {

std::atomic<bool> g_counting{false};
std::atomic<std::int64_t> g_allocations{0};

void* counted_alloc(std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

void* counted_aligned_alloc(std::size_t n, std::align_val_t al) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
  const auto a = static_cast<std::size_t>(al);
  void* p = std::aligned_alloc(a, (n + a - 1) / a * a);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

#if defined(__SANITIZE_ADDRESS__)
void malloc_hook(const volatile void*, std::size_t) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
}
void free_hook(const volatile void*) {}
[[maybe_unused]] const int kHooksInstalled =
    __sanitizer_install_malloc_and_free_hooks(malloc_hook, free_hook);
#endif

}  // namespace

void* operator new(std::size_t n) { return counted_alloc(n); }
void* operator new[](std::size_t n) { return counted_alloc(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t n, std::align_val_t al) { return counted_aligned_alloc(n, al); }
void* operator new[](std::size_t n, std::align_val_t al) { return counted_aligned_alloc(n, al); }
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

namespace skelcd::culling {
namespace {

/// Counts allocations made while it is alive (and forbids Eigen's, when asserts are on).
class AllocationWindow {
 public:
  AllocationWindow() {
    g_allocations = 0;
    Eigen::internal::set_is_malloc_allowed(false);
    g_counting = true;
  }
  ~AllocationWindow() { stop(); }
  std::int64_t stop() {
    g_counting = false;
    Eigen::internal::set_is_malloc_allowed(true);
    return g_allocations.load();
  }
};

// Elementary tests that allocate nothing and report a deterministic share of pairs as hits, so
// the contact paths run too (the guard is about culling's own code).
ccd::CcdResult fake_vf(const ccd::VertexFaceQuery& q, ccd::Accuracy, const ccd::CcdOptions&) {
  const bool hit = q.v_t1.z() > q.f0_t1.z();
  return {
      hit,
      hit ? 0.25 : 1.0,
      hit ? 0.5 : 1.0,
      hit ? ccd::CcdStatus::contact : ccd::CcdStatus::separated};
}
ccd::CcdResult fake_ee(const ccd::EdgeEdgeQuery& q, ccd::Accuracy, const ccd::CcdOptions&) {
  const bool hit = q.ea0_t1.x() < q.eb0_t1.x();
  return {
      hit,
      hit ? 0.25 : 1.0,
      hit ? 0.5 : 1.0,
      hit ? ccd::CcdStatus::contact : ccd::CcdStatus::separated};
}
bool fake_tt(const ccd::TriangleTriangleQuery& q, const ccd::SharedCorners&) {
  return q.a0.y() < q.b0.y();
}

struct Motion {
  skinning::Mesh mesh;
  skinning::Topology topo;
  std::vector<skinning::Positions> x;
};

/// A tube squashed through itself: the first interval (samples 0 → 2) has the most motion.
Motion squashed_tube(int around, int along) {
  Motion m;
  m.mesh = test::tube(around, along, 0.4, 2.0);
  m.topo = test::simple_topology(m.mesh);
  const auto rest = test::welded(m.topo, m.mesh.rest_positions);
  for (const double s : {0.0, 0.5, 1.0, 0.95, 0.9}) m.x.push_back(test::squashed(rest, s));
  return m;
}

void expect_no_allocation_after_warm_up(
    const std::string& name,
    const MethodOptions& options,
    int around = 20,
    int along = 24) {
  const Motion m = squashed_tube(around, along);
  auto method = make_method(name, m.mesh, m.topo, options);
  FrameResult out;
  // Warm-up on the interval with the most motion (most candidates), and one DCD instant.
  method->detect_ccd(m.x[0], m.x[2], out);
  const auto contacts_capacity = out.contacts.capacity();
  out.clear();
  method->detect_dcd(m.x[2], out);
  out.clear();
  method->detect_ccd(m.x[0], m.x[2], out);
  ASSERT_GT(out.counters.vf_tests + out.counters.ee_tests, 200) << "the interval tests little";
  ASSERT_GT(out.contacts.size(), 0u);
  out.clear();

  // Measured: the same interval again, smaller intervals, DCD instants.
  std::int64_t allocations = 0;
  std::int64_t tests = 0;
  {
    AllocationWindow window;
    method->detect_ccd(m.x[0], m.x[2], out);
    tests += out.counters.vf_tests + out.counters.ee_tests;
    out.clear();
    for (std::size_t i = 2; i + 1 < m.x.size(); ++i) {
      method->detect_ccd(m.x[i], m.x[i + 1], out);
      tests += out.counters.vf_tests + out.counters.ee_tests;
      out.clear();
      method->detect_dcd(m.x[i + 1], out);
      tests += out.counters.tt_tests;
      out.clear();
    }
    allocations = window.stop();
  }
  EXPECT_EQ(allocations, 0) << name;
  EXPECT_GT(tests, 0);
  EXPECT_EQ(out.contacts.capacity(), contacts_capacity) << name;
}

TEST(Allocation, MethodsAllocateNothingPerIntervalAfterWarmUp) {
  const MethodOptions options{.elementary = {&fake_vf, &fake_ee, &fake_tt}};
  for (const char* name : {"bvh", "kdop", "brute"})
    expect_no_allocation_after_warm_up(name, options);
  MethodOptions leafy = options;
  leafy.bvh.leaf_size = 4;
  expect_no_allocation_after_warm_up("bvh", leafy);
  expect_no_allocation_after_warm_up(
      "kdop", {.min_separation = 1e-3, .elementary = options.elementary});
}

TEST(Allocation, WithTheCcdKernelsToo) {
  // The conservative kernels are hot loops as well (DESIGN.md: allocate nothing).
  // A smaller tube: the walls crossing keep the conservative solver busy (minutes under ASan).
  expect_no_allocation_after_warm_up("bvh", {}, 12, 12);
  expect_no_allocation_after_warm_up("kdop", {}, 12, 12);
}

TEST(Allocation, TheCounterSeesAllocations) {
  // The guard itself works: a vector growing inside a window is counted.
  std::int64_t n = 0;
  {
    AllocationWindow window;
    std::vector<int> v;
    v.push_back(1);
    n = window.stop();
    EXPECT_EQ(v[0], 1);  // keeps the vector (and its allocation) observable
  }
  EXPECT_GE(n, 1);
}

}  // namespace
}  // namespace skelcd::culling
