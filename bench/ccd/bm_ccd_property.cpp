// The long property run: conservative (and fast) against the exact reference on >= 10^6 random
// and near-degenerate queries (the mix of tests/ccd/random_queries.hpp, in chunks of 10,000 with
// seeds derived from --seed) plus the hard-case families of tests/ccd/hard_cases.hpp under 20
// seeds. Prints false negatives and positives per kind; exits 1 on any conservative false negative
// or any conservative toi_lower later than the exact first contact.
//
//   build/bench/ccd/bm_ccd_property [--queries 1000000] [--seed 1] [--threads 2]

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ccd/exact_ccd.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace {

using namespace skelcd::ccd;

struct Tally {
  std::int64_t queries = 0, exact_hits = 0;
  std::int64_t conservative_fn = 0, conservative_fp = 0, toi_violations = 0, iteration_limits = 0;
  std::int64_t fast_fn = 0, fast_fp = 0;

  Tally& operator+=(const Tally& o) {
    queries += o.queries;
    exact_hits += o.exact_hits;
    conservative_fn += o.conservative_fn;
    conservative_fp += o.conservative_fp;
    toi_violations += o.toi_violations;
    iteration_limits += o.iteration_limits;
    fast_fn += o.fast_fn;
    fast_fp += o.fast_fp;
    return *this;
  }
};

struct Shared {
  std::mutex mutex;
  std::map<std::string, Tally> per_kind;
  std::vector<std::string> failures;  // the first few, printed in full
};

void check(bool vertex_face, const std::array<Eigen::Vector3d, 8>& p, const std::string& kind,
           std::map<std::string, Tally>& tallies, std::vector<std::string>& failures) {
  const VertexFaceQuery vf{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  const EdgeEdgeQuery ee{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  const ExactCcdResult e = vertex_face ? vertex_face_ccd_rational(to_rational(vf)) : edge_edge_ccd_rational(to_rational(ee));
  const CcdResult c = vertex_face ? vertex_face_ccd(vf) : edge_edge_ccd(ee);
  const CcdResult f = vertex_face ? vertex_face_ccd(vf, Accuracy::fast) : edge_edge_ccd(ee, Accuracy::fast);
  Tally& t = tallies[kind];
  ++t.queries;
  t.exact_hits += e.hit;
  t.fast_fn += e.hit && !f.hit;
  t.fast_fp += !e.hit && f.hit;
  t.conservative_fp += !e.hit && c.hit;
  t.iteration_limits += c.status == CcdStatus::iteration_limit;
  const bool fn = e.hit && !c.hit;
  const bool late = e.hit && c.hit && mpq_class(c.toi_lower) > e.toi_hi;
  t.conservative_fn += fn;
  t.toi_violations += late;
  if ((fn || late) && failures.size() < 10) {
    std::string s = std::string(fn ? "false negative" : "toi_lower after the first contact") + " (" + kind + ", " +
                    (vertex_face ? "vf" : "ee") + "):";
    char buf[64];
    for (const auto& x : p) {
      for (int k = 0; k < 3; ++k) {
        std::snprintf(buf, sizeof buf, " %.17g", x[k]);
        s += buf;
      }
    }
    failures.push_back(s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::int64_t total = 1'000'000;
  std::uint64_t seed = 1;
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string opt = argv[i];
    if (opt == "--queries") total = std::atoll(argv[i + 1]);
    else if (opt == "--seed") seed = std::strtoull(argv[i + 1], nullptr, 10);
    else if (opt == "--threads") threads = static_cast<unsigned>(std::atoi(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: %s [--queries N] [--seed S] [--threads T]\n", argv[0]);
      return 2;
    }
  }
  constexpr std::int64_t kChunk = 10'000;
  constexpr int kHardSeeds = 20;
  const std::int64_t random_chunks = (total + kChunk - 1) / kChunk;
  const std::int64_t jobs = random_chunks + kHardSeeds;
  Shared shared;
  std::atomic<std::int64_t> next{0};
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < threads; ++w) {
    pool.emplace_back([&] {
      for (std::int64_t job; (job = next++) < jobs;) {
        std::map<std::string, Tally> tallies;
        std::vector<std::string> failures;
        if (job < random_chunks) {
          test::RandomQueryGenerator gen(seed * 1'000'003 + static_cast<std::uint64_t>(job));
          const std::int64_t n = std::min(kChunk, total - job * kChunk);
          for (std::int64_t i = 0; i < n; ++i) {
            const auto q = gen.next();
            check(q.vertex_face, q.points, std::string(q.kind), tallies, failures);
          }
        } else {
          for (const auto& c : test::hard_cases(seed * 7919 + static_cast<std::uint64_t>(job - random_chunks), 2)) {
            check(c.vertex_face, c.points, "hard-case " + c.family, tallies, failures);
          }
        }
        const std::lock_guard lock(shared.mutex);
        for (const auto& [kind, t] : tallies) shared.per_kind[kind] += t;
        for (auto& f : failures) {
          if (shared.failures.size() < 10) shared.failures.push_back(std::move(f));
        }
      }
    });
  }
  for (auto& t : pool) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  Tally all;
  std::printf("%-32s %9s %9s | %-22s | %-18s\n", "kind", "queries", "exact_hit", "conservative FN / FP", "fast FN / FP");
  for (const auto& [kind, t] : shared.per_kind) {
    std::printf("%-32s %9lld %9lld | %8lld / %-11lld | %7lld / %-8lld\n", kind.c_str(), static_cast<long long>(t.queries),
                static_cast<long long>(t.exact_hits), static_cast<long long>(t.conservative_fn),
                static_cast<long long>(t.conservative_fp), static_cast<long long>(t.fast_fn),
                static_cast<long long>(t.fast_fp));
    all += t;
  }
  const auto misses = std::max<std::int64_t>(1, all.queries - all.exact_hits);
  const auto hits = std::max<std::int64_t>(1, all.exact_hits);
  std::printf("\n%lld queries (seed %llu, %u threads, %.1f s), %lld exact hits\n", static_cast<long long>(all.queries),
              static_cast<unsigned long long>(seed), threads, seconds, static_cast<long long>(all.exact_hits));
  std::printf("conservative: %lld false negatives, %lld false positives (%.2f%% of misses), %lld toi_lower violations, "
              "%lld iteration limits\n",
              static_cast<long long>(all.conservative_fn), static_cast<long long>(all.conservative_fp),
              100.0 * static_cast<double>(all.conservative_fp) / static_cast<double>(misses),
              static_cast<long long>(all.toi_violations), static_cast<long long>(all.iteration_limits));
  std::printf("fast:         %lld false negatives (%.2f%% of hits), %lld false positives\n",
              static_cast<long long>(all.fast_fn), 100.0 * static_cast<double>(all.fast_fn) / static_cast<double>(hits),
              static_cast<long long>(all.fast_fp));
  for (const auto& f : shared.failures) std::printf("%s\n", f.c_str());
  return (all.conservative_fn > 0 || all.toi_violations > 0) ? 1 : 0;
}
