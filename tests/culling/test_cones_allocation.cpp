// The cone methods and `auto` allocate nothing per query once warmed up (DESIGN.md: hot loops
// allocate nothing). A separate executable: it replaces the global operator new to count every
// allocation inside the measured window, in Release too (and, with asserts on, Eigen's own
// runtime check forbids its allocations there as well).
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cstdlib>
#include <new>

#include "culling/cones_method.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/method.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"

namespace {

std::atomic<bool> g_on{false};
std::atomic<std::int64_t> g_count{0};

void* allocate(std::size_t n) {
  if (g_on.load(std::memory_order_relaxed)) g_count.fetch_add(1);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace skelcd::culling {
namespace {

/// Counts what is allocated between construction and stop().
struct Window {
  Window() {
    g_count = 0;
    Eigen::internal::set_is_malloc_allowed(false);
    g_on = true;
  }
  std::int64_t stop() {
    g_on = false;
    Eigen::internal::set_is_malloc_allowed(true);
    return g_count.load();
  }
  ~Window() { stop(); }
};

void expect_quiet(std::unique_ptr<CullingMethod> m, const test::OpenScene& s, const char* what) {
  FrameResult out;
  // Warm-up: every query once (buffers reach their sizes).
  for (std::size_t i = 0; i + 1 < s.frames.size(); ++i) {
    m->detect_ccd(s.frames[i], s.frames[i + 1], out);
    out.clear();
    m->detect_dcd(s.frames[i + 1], out);
    out.clear();
  }
  std::int64_t work = 0;
  Window window;
  for (std::size_t i = 0; i + 1 < s.frames.size(); ++i) {
    m->detect_ccd(s.frames[i], s.frames[i + 1], out);
    work += out.counters.vf_tests + out.counters.ee_tests;
    out.clear();
    m->detect_dcd(s.frames[i + 1], out);
    work += out.counters.tt_tests;
    out.clear();
  }
  EXPECT_EQ(window.stop(), 0) << what;
  EXPECT_GT(work, 0) << what;
}

TEST(ConesAllocation, NothingPerQueryAfterWarmUp) {
  const test::OpenScene s = test::skirt_body_scene(9, 14, 16, 10, {0.3, 0.4, 0.5});
  for (const char* name : {"enhanced-dual-cone", "normal-cone", "dual-cone", "auto"}) {
    expect_quiet(make_method(name, s.mesh, s.topo), s, name);
    expect_quiet(make_method(name, s.mesh, s.topo, {.bvh = {.leaf_size = 4}}), s, name);
  }
  expect_quiet(
      make_enhanced_dual_cone_method(
          s.mesh, s.topo, {}, {.grandchildren_descent = false, .triangles = {}}),
      s,
      "enhanced-dual-cone top-down");
  expect_quiet(make_method("auto", s.mesh, s.topo, {.min_separation = 1e-3}), s, "auto, distance");
}

TEST(ConesAllocation, TheCounterSeesAllocations) {
  Window window;
  auto* v = new std::vector<int>(100);
  const std::int64_t n = window.stop();
  delete v;
  EXPECT_GE(n, 2);
}

}  // namespace
}  // namespace skelcd::culling
