// The four-query coplanarity screens (ccd/coplanarity_screen.hpp), in both builds (AVX2 where the
// CPU has it, and the baseline instruction set): each lane's decision, coefficients and magnitude
// are the kernel's scalar screen's bit for bit (detail::trilinear_screen, certified_sign); a
// query they certify apart is one the kernel answers "no contact"; the others, continued with
// *_ccd_after_screen, get the kernel's own answer bit for bit. On the random mix at every scale,
// the hard-case families, the ground-truthed cloth-funnel step and non-finite input.

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/coplanarity_screen.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/screen_x4.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "ccd/filters.hpp"
#include "tests/ccd/cloth_funnel.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

using Points = std::array<Eigen::Vector3d, 8>;  // file order: four points at t0, then at t1

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

bool same(const CcdResult& a, const CcdResult& b) {
  return a.hit == b.hit && a.status == b.status && same_bits(a.toi_lower, b.toi_lower) &&
         same_bits(a.toi_upper, b.toi_upper);
}

VertexFaceQuery vf_query(const Points& p) {
  return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
}
EdgeEdgeQuery ee_query(const Points& p) { return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]}; }

/// The kernel's own screen of a query: the difference triples as vertex_face.cpp and
/// edge_edge.cpp form them.
detail::TrilinearScreen scalar_screen(bool vertex_face, const Points& p) {
  if (vertex_face) {
    return detail::trilinear_screen(
        {p[0] - p[1], p[2] - p[1], p[3] - p[1]}, {p[4] - p[5], p[6] - p[5], p[7] - p[5]});
  }
  return detail::trilinear_screen(
      {p[2] - p[0], p[1] - p[0], p[3] - p[2]}, {p[6] - p[4], p[5] - p[4], p[7] - p[6]});
}

struct Tally {
  int queries = 0;
  int apart = 0;
  int continued = 0;
  int hits = 0;
};

/// Queries of one kind, screened four at a time in both builds and checked lane by lane.
class Checker {
 public:
  explicit Checker(bool vertex_face, CcdOptions options = {})
      : vertex_face_(vertex_face), options_(options) {}

  void add(const Points& p, const std::string& what) {
    batch_.push_back(p);
    names_.push_back(what);
    if (batch_.size() == 4) flush();
  }

  /// Checks what is left, the last query repeated to fill four lanes.
  void flush() {
    if (batch_.empty()) return;
    const std::size_t used = batch_.size();
    while (batch_.size() < 4) {
      batch_.push_back(batch_.back());
      names_.push_back(names_.back());
    }
    // Positions laid out as a mesh's: query k's point r is vertex 4 k + r, in shuffled order so
    // that the indices are not simply consecutive.
    std::array<std::array<std::int32_t, 4>, 4> quads;
    std::vector<double> x_t0(3 * 16), x_t1(3 * 16);
    for (std::size_t k = 0; k < 4; ++k) {
      for (std::size_t r = 0; r < 4; ++r) {
        const auto v = static_cast<std::int32_t>((4 * k + r) * 7 % 16);
        quads[k][r] = v;
        for (std::size_t c = 0; c < 3; ++c) {
          x_t0[3 * static_cast<std::size_t>(v) + c] = batch_[k][r][static_cast<Eigen::Index>(c)];
          x_t1[3 * static_cast<std::size_t>(v) + c] =
              batch_[k][r + 4][static_cast<Eigen::Index>(c)];
        }
      }
    }
    const CoplanarityScreens fast = vertex_face_
                                        ? vertex_face_screen_x4(x_t0.data(), x_t1.data(), quads)
                                        : edge_edge_screen_x4(x_t0.data(), x_t1.data(), quads);
    const CoplanarityScreens baseline =
        vertex_face_ ? detail::vertex_face_screen_x4_baseline(x_t0.data(), x_t1.data(), quads)
                     : detail::edge_edge_screen_x4_baseline(x_t0.data(), x_t1.data(), quads);
    for (std::size_t k = 0; k < 4; ++k) {
      for (const CoplanarityScreens* s : {&fast, &baseline}) {
        check_lane(*s, k, k < used);
        if (::testing::Test::HasFailure()) return;
      }
    }
    batch_.clear();
    names_.clear();
  }

  [[nodiscard]] const Tally& tally() const { return tally_; }

 private:
  void check_lane(const CoplanarityScreens& s, std::size_t k, bool count) {
    const Points& p = batch_[k];
    const std::string& what = names_[k];
    const detail::TrilinearScreen ref = scalar_screen(vertex_face_, p);
    const bool apart = (s.apart >> k & 1u) != 0;
    ASSERT_EQ(apart, detail::certified_sign(ref.coefficients, ref.error_upper)) << what;
    for (std::size_t i = 0; i < 4; ++i)
      ASSERT_TRUE(same_bits(s.coefficients[k][i], ref.coefficients[i])) << what << " b" << i;
    ASSERT_TRUE(same_bits(s.magnitude[k], ref.magnitude)) << what;
    const CcdResult full = vertex_face_
                               ? vertex_face_ccd(vf_query(p), Accuracy::conservative, options_)
                               : edge_edge_ccd(ee_query(p), Accuracy::conservative, options_);
    if (count) ++tally_.queries;
    if (apart) {
      // The kernel says no contact: at its screen, or at the swept boxes before it.
      ASSERT_FALSE(full.hit) << what;
      if (count) ++tally_.apart;
      return;
    }
    // The rest of the kernel from the screen on; the swept boxes must overlap (its precondition),
    // and then it is the kernel after them, which is the kernel itself.
    if (vertex_face_ ? swept_aabbs_disjoint(vf_query(p), 0.0)
                     : swept_aabbs_disjoint(ee_query(p), 0.0)) {
      return;
    }
    const int lane = static_cast<int>(k);
    const CcdResult rest = vertex_face_
                               ? vertex_face_ccd_after_screen(vf_query(p), options_, s, lane)
                               : edge_edge_ccd_after_screen(ee_query(p), options_, s, lane);
    ASSERT_TRUE(same(rest, full)) << what << ": hit " << rest.hit << " vs " << full.hit;
    if (count) {
      ++tally_.continued;
      tally_.hits += full.hit;
    }
  }

  bool vertex_face_;
  CcdOptions options_;
  std::vector<Points> batch_;
  std::vector<std::string> names_;
  Tally tally_;
};

TEST(CoplanarityScreen, EachLaneIsTheKernelsScreenOnTheRandomMixAtEveryScale) {
  test::RandomQueryGenerator generator(53);
  std::mt19937_64 rng(53);
  CcdOptions options;
  options.max_iterations = 2000;  // the far scales run the solver long; both sides alike
  Checker vf(true, options), ee(false, options);
  for (int n = 0; n < 6000; ++n) {
    const test::RandomQuery q = generator.next();
    Points p = q.points;
    // Scaled by 2^-1060 … 2^300 now and then, so that subnormal products and the screen's
    // underflow term are reached (the magnitudes the error bound switches on).
    if (n % 4 == 0) {
      const double scale = std::ldexp(1.0, std::uniform_int_distribution<int>(-1060, 300)(rng));
      for (auto& point : p) point *= scale;
    }
    (q.vertex_face ? vf : ee).add(p, "random " + std::to_string(n) + " " + std::string(q.kind));
    if (HasFatalFailure()) return;
  }
  vf.flush();
  ee.flush();
  if (HasFatalFailure()) return;
  // Both outcomes occur often, and the continued queries find contacts: the comparison has teeth.
  for (const Checker* c : {&vf, &ee}) {
    EXPECT_GT(c->tally().apart, 150);
    EXPECT_GT(c->tally().continued, 1000);
    EXPECT_GT(c->tally().hits, 500);
  }
}

TEST(CoplanarityScreen, EachLaneIsTheKernelsScreenOnTheHardCases) {
  Checker vf(true), ee(false);
  for (const test::HardCase& c : test::hard_cases(7, 4)) {
    (c.vertex_face ? vf : ee).add(c.points, c.family + " " + c.variant);
    if (HasFatalFailure()) return;
  }
  vf.flush();
  ee.flush();
  if (HasFatalFailure()) return;
  EXPECT_GT(vf.tally().hits + ee.tally().hits, 2000);
}

TEST(CoplanarityScreen, EachLaneIsTheKernelsScreenOnTheClothFunnelStep) {
  Checker vf(true), ee(false);
  for (const char* kind : {"vf", "ee"}) {
    for (const auto& c : test::load_cloth_funnel(kind)) {
      Points p;
      if (c.vertex_face) {
        const VertexFaceQuery v = c.vf();
        p = {v.v_t0, v.f0_t0, v.f1_t0, v.f2_t0, v.v_t1, v.f0_t1, v.f1_t1, v.f2_t1};
      } else {
        const EdgeEdgeQuery e = c.ee();
        p = {e.ea0_t0, e.ea1_t0, e.eb0_t0, e.eb1_t0, e.ea0_t1, e.ea1_t1, e.eb0_t1, e.eb1_t1};
      }
      (c.vertex_face ? vf : ee).add(p, std::string("cloth funnel ") + kind);
      if (HasFatalFailure()) return;
    }
  }
  vf.flush();
  ee.flush();
  if (HasFatalFailure()) return;
  EXPECT_GT(vf.tally().queries + ee.tally().queries, 300);
  EXPECT_GT(vf.tally().hits + ee.tally().hits, 50);
}

TEST(CoplanarityScreen, NonFiniteAndHugeCoordinatesAreNeverCertified) {
  // Each coordinate of a query in turn inf, -inf, NaN, huge or the smallest subnormal: the lanes
  // still match the scalar screen, which certifies nothing non-finite.
  test::RandomQueryGenerator generator(59);
  const double specials[] = {
      std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::quiet_NaN(),
      0x1p1000,
      -0x1p1020,
      0x1p-1074};
  CcdOptions options;
  options.max_iterations = 200;  // non-finite input runs the solver to its budget
  Checker vf(true, options), ee(false, options);
  for (int i = 0; i < 100; ++i) {
    const test::RandomQuery q = generator.next();
    for (int k = 0; k < 24; ++k) {
      Points p = q.points;
      p[static_cast<std::size_t>(k / 3)][k % 3] = specials[static_cast<std::size_t>((i + k) % 6)];
      (q.vertex_face ? vf : ee).add(p, "special " + std::to_string(i) + "/" + std::to_string(k));
      if (HasFatalFailure()) return;
    }
  }
  vf.flush();
  ee.flush();
  EXPECT_GT(vf.tally().queries + ee.tally().queries, 2000);
}

}  // namespace
}  // namespace skelcd::ccd
