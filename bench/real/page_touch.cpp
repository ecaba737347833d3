// What first touching memory costs on this machine (docs/benchmarks.md, "Page faults, and malloc
// on transparent huge pages"): a fresh anonymous mapping written one byte per 4 KiB page, the
// same after MADV_POPULATE_WRITE (the kernel maps every page in one call), and after
// MADV_HUGEPAGE (2 MiB pages where the kernel's THP mode allows), each against a second pass over
// the pages once they are there. Prints one line per round.
//   page_touch [MiB] [ROUNDS]        (default 64 MiB, 3 rounds)
#include <sys/mman.h>

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14
#endif

namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kPage = 4096;

double ms_since(Clock::time_point from) {
  return std::chrono::duration<double, std::milli>(Clock::now() - from).count();
}

/// Milliseconds to write one byte of every page of `p`, `n` bytes.
double touch(volatile char* p, std::size_t n) {
  const auto start = Clock::now();
  for (std::size_t i = 0; i < n; i += kPage) p[i] = 1;
  return ms_since(start);
}

char* fresh(std::size_t n) {
  void* p = mmap(nullptr, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) {
    std::perror("page_touch: mmap");
    std::exit(1);
  }
  return static_cast<char*>(p);
}

}  // namespace

int main(int argc, char** argv) {
  const long mib = argc > 1 ? std::atol(argv[1]) : 64;
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 3;
  if (mib < 1 || mib > 4096 || rounds < 1) {
    std::fprintf(stderr, "usage: page_touch [MiB 1..4096] [ROUNDS >= 1]\n");
    return 2;
  }
  const std::size_t n = static_cast<std::size_t>(mib) << 20;
  const double pages = static_cast<double>(n / kPage);
  for (int r = 0; r < rounds; ++r) {
    char* a = fresh(n);
    const double first = touch(a, n);
    const double again = touch(a, n);
    munmap(a, n);

    char* b = fresh(n);
    auto start = Clock::now();
    const int populated = madvise(b, n, MADV_POPULATE_WRITE);
    const double populate = ms_since(start);
    const double after_populate = touch(b, n);
    munmap(b, n);

    char* c = fresh(n);
    const int advised = madvise(c, n, MADV_HUGEPAGE);
    const double huge = touch(c, n);
    munmap(c, n);

    std::printf(
        "%ld MiB: first touch %.1f ms (%.2f us per 4 KiB page), again %.1f ms; "
        "MADV_POPULATE_WRITE %.1f ms%s then touch %.1f ms; MADV_HUGEPAGE%s first touch %.1f ms\n",
        mib,
        first,
        1000.0 * first / pages,
        again,
        populate,
        populated == 0 ? "" : " (refused)",
        after_populate,
        advised == 0 ? "" : " (refused)",
        huge);
  }
  return 0;
}
