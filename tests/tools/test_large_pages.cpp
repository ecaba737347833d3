// The skelcd executable's operator new (tools/cli/large_pages.hpp), linked into this test binary as
// into the executable: where large allocations land and what the kernel was told about them.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "tests/support/test_support.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/large_pages.hpp"

namespace skelcd::tools {
namespace {

/// A cache line, as the feature stage's over-aligned records.
struct alignas(64) Line64 {
  double x[8];
};

bool kernel_has_huge_pages() {
  return std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled");
}

TEST(LargePages, OnlyZeroOffAndNoTurnThemOff) {
  EXPECT_TRUE(large_pages_wanted(nullptr));
  EXPECT_TRUE(large_pages_wanted("1"));
  EXPECT_TRUE(large_pages_wanted(""));
  EXPECT_FALSE(large_pages_wanted("0"));
  EXPECT_FALSE(large_pages_wanted("off"));
  EXPECT_FALSE(large_pages_wanted("no"));
}

TEST(LargePages, OnlyWholeHugePagesOfAnAlignedBlockAreAdvised) {
  const auto* aligned = reinterpret_cast<const void*>(std::uintptr_t{7} * kHugePage);
  EXPECT_EQ(advised_length(aligned, 3 * kHugePage + 17), 3 * kHugePage);
  EXPECT_EQ(advised_length(aligned, kHugePage), kHugePage);
  EXPECT_EQ(advised_length(aligned, kHugePage - 1), 0U);
  const auto* off = reinterpret_cast<const void*>(std::uintptr_t{7} * kHugePage + 4096);
  EXPECT_EQ(advised_length(off, 3 * kHugePage), 0U);
}

TEST(LargePages, ABlockEndsOnAHugePageWhereThatAddsAQuarterAtMost) {
  EXPECT_EQ(large_block_size(kHugePage), kHugePage);
  EXPECT_EQ(large_block_size(3 * kHugePage), 3 * kHugePage);
  // 3.5 MiB: 0.5 MiB more (a seventh) ends it on its second huge page.
  EXPECT_EQ(large_block_size(7 * kHugePage / 4), 2 * kHugePage);
  // 5 MiB: 1 MiB more (a fifth).
  EXPECT_EQ(large_block_size(5 * kHugePage / 2), 3 * kHugePage);
  // 2.8 MiB (the cloth-ball step's per-vertex records): 1.2 MiB more would be 43 %; as asked.
  EXPECT_EQ(large_block_size(7 * kHugePage / 5), 7 * kHugePage / 5);
  EXPECT_EQ(large_block_size(kHugePage + 1), kHugePage + 1);
  // Either side of a quarter, about 6.4 MiB: e more bytes to 8 MiB with 4 e <= 8 MiB − e.
  const std::size_t e = 4 * kHugePage / 5;  // 1,677,721
  EXPECT_EQ(large_block_size(4 * kHugePage - e), 4 * kHugePage);
  EXPECT_EQ(large_block_size(4 * kHugePage - e - 1), 4 * kHugePage - e - 1);
}

// Run in this process (SKELCD_LARGE_PAGES unset: on) and again by the next test in a child with
// SKELCD_LARGE_PAGES=0 (off): what a large vector gets must follow the setting either way.
TEST(LargePages, ALargeVectorFollowsTheSetting) {
  const bool on = large_pages_wanted(std::getenv("SKELCD_LARGE_PAGES"));
  // Placed (on a 2 MiB boundary) and advised ("hg" in its mapping's VmFlags, where the kernel
  // has transparent huge pages), or neither.
  const auto expect_follows = [on](const void* data) {
    const bool aligned = reinterpret_cast<std::uintptr_t>(data) % kHugePage == 0;
    const std::string flags = test::vm_flags_at(data);
    ASSERT_FALSE(flags.empty()) << "no mapping of /proc/self/smaps holds " << data;
    const bool advised = flags.find(" hg") != std::string::npos;
    if (on) {
      EXPECT_TRUE(aligned) << data;
      EXPECT_EQ(advised, kernel_has_huge_pages()) << flags;
    } else {
      // malloc's own mapping: its block starts past the chunk's header, never on a boundary.
      EXPECT_FALSE(aligned) << data;
      EXPECT_FALSE(advised) << flags;
    }
  };
  const std::vector<float> large(3 * kHugePage / sizeof(float) + 5, 1.0F);  // 6 MiB and a little
  expect_follows(large.data());
  // An over-aligned type's vector (operator new with std::align_val_t), aligned either way.
  const std::vector<Line64> lines(3 * kHugePage / sizeof(Line64));
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(lines.data()) % alignof(Line64), 0U);
  expect_follows(lines.data());
  // The array form.
  const std::unique_ptr<double[]> array(new double[kHugePage / sizeof(double) * 2]);
  expect_follows(array.get());
  // A block that ends a seventh short of a huge page ends on it: its last byte is advised too;
  // one that would need 43 % more keeps its tail on small pages.
  const std::vector<char> rounded(7 * kHugePage / 4, 'r');
  const std::string rounded_end = test::vm_flags_at(&rounded.back());
  EXPECT_EQ(rounded_end.find(" hg") != std::string::npos, on && kernel_has_huge_pages())
      << rounded_end;
  const std::vector<char> as_asked(7 * kHugePage / 5, 'a');
  const std::string as_asked_end = test::vm_flags_at(&as_asked.back());
  EXPECT_EQ(as_asked_end.find(" hg"), std::string::npos) << as_asked_end;
}

/// The main heap's range (what brk has grown: the "[heap]" lines of /proc/self/maps, several once
/// part of it is advised), or {0, 0}.
std::pair<std::uintptr_t, std::uintptr_t> heap_range() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  std::pair<std::uintptr_t, std::uintptr_t> range{0, 0};
  while (std::getline(maps, line)) {
    if (line.find("[heap]") == std::string::npos) continue;
    std::uintptr_t lo = 0;
    std::uintptr_t hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (!(head >> std::hex >> lo >> dash >> hi) || dash != '-') continue;
    range = range.second == 0 ? std::pair{lo, hi}
                              : std::pair{std::min(range.first, lo), std::max(range.second, hi)};
  }
  return range;
}

// What `check` calls first (tools/cli/main.cpp). ctest runs each test in a process of its own, so
// malloc's settings changed here reach no other test.
TEST(LargePages, TheHeapsTopIsAdvisedAndEveryThreadAllocatesThere) {
  const auto before = heap_range();
  heap_on_huge_pages(kHeapOnHugePages);
  const auto after = heap_range();
  ASSERT_NE(after.second, 0U) << "no [heap] in /proc/self/maps";
  // The heap grew by the block at once, and kept it as its free top (not trimmed).
  EXPECT_GE(after.second - before.second, kHeapOnHugePages);
  // Its huge pages advised where the kernel has them (the middle of the block is in one).
  const auto* middle = reinterpret_cast<const void*>(before.second + kHeapOnHugePages / 2);
  const std::string flags = test::vm_flags_at(middle);
  EXPECT_EQ(flags.find(" hg") != std::string::npos, kernel_has_huge_pages()) << flags;
  // A thread of its own allocates from that heap (no arena mapped apart for it).
  const std::size_t bytes = std::size_t{100} << 10;
  void* from_thread = nullptr;
  std::thread([&] { from_thread = std::malloc(bytes); }).join();
  ASSERT_NE(from_thread, nullptr);
  const auto block = reinterpret_cast<std::uintptr_t>(from_thread);
  EXPECT_TRUE(after.first <= block && block + bytes <= after.second)
      << from_thread << " outside the heap " << std::hex << after.first << "-" << after.second;
  std::free(from_thread);
  EXPECT_EQ(heap_range().second, after.second);
}

/// The triangle counts `skelcd check ASSET --frames 0:2 --json` tells the hook, in order.
std::vector<std::int64_t> triangles_told_checking(const std::string& asset) {
  std::vector<std::int64_t> told;
  on_check_model_loaded([&told](std::int64_t triangles) { told.push_back(triangles); });
  CLI::App app;
  add_check_command(app);
  const std::string path = test::asset(asset).string();
  const char* argv[] = {"skelcd", "check", path.c_str(), "--frames", "0:2", "--json"};
  app.parse(static_cast<int>(std::size(argv)), argv);
  on_check_model_loaded({});
  return told;
}

// Where the executable decides (tools/cli/main.cpp): `check` tells the hook the loaded mesh's
// triangles before it sets up the check, and only a mesh of 64Ki triangles or more takes the
// heap's top on huge pages (CesiumMan's 4,672 do not; the cloth-ball step's 92,230 do).
TEST(LargePages, CheckTellsTheLoadedMeshsSizeAndOnlyLargeMeshesPay) {
  EXPECT_EQ(triangles_told_checking("characters/CesiumMan.glb"), std::vector<std::int64_t>{4672});
  EXPECT_FALSE(heap_on_huge_pages_pays(4672));
  EXPECT_FALSE(heap_on_huge_pages_pays(kHeapOnHugePagesMinTriangles - 1));
  EXPECT_TRUE(heap_on_huge_pages_pays(kHeapOnHugePagesMinTriangles));
  EXPECT_TRUE(heap_on_huge_pages_pays(92230));
}

// A scene's checks are all set up before the first runs, so they hold memory together: the hook is
// told once, with the triangles of every object the scene checks, once they are all loaded.
// cape.toml checks CesiumMan (4,672 triangles) and a cape sheet of 12 × 20 cells (480).
TEST(LargePages, ASceneTellsTheTrianglesOfTheObjectsItChecksOnce) {
  EXPECT_EQ(
      triangles_told_checking("scenes/cape.toml"), std::vector<std::int64_t>{4672 + 12 * 20 * 2});
}

TEST(LargePages, TheEnvironmentTurnsThemOff) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    setenv("SKELCD_LARGE_PAGES", "0", 1);
    execl(
        "/proc/self/exe",
        "large_pages_child",
        "--gtest_filter=LargePages.ALargeVectorFollowsTheSetting",
        static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace skelcd::tools
