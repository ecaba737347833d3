// `brute`: no hierarchy. Every VF pair (vertex × face) and EE pair (edge × edge), or every
// triangle pair for DCD, with the shared rules and volume filter of culling/candidates.hpp — the
// reference the hierarchy methods must match exactly.
#include "culling/candidates.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/elementary.hpp"
#include "culling/vertex_bounds.hpp"

namespace skelcd::culling::detail {
namespace {

class BruteMethod final : public MethodBase {
 public:
  BruteMethod(
      const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options)
      : MethodBase("brute", mesh, topology, options) {
    const auto num_faces = static_cast<std::size_t>(topology_.num_triangles());
    bounds_.vertices.reserve(static_cast<std::size_t>(topology_.num_vertices()));
    bounds_.edges.reserve(static_cast<std::size_t>(topology_.num_edges()));
    bounds_.triangles.reserve(num_faces);
    pairs_.reserve(16 * num_faces);
    features_.vf.reserve(4 * num_faces);
    features_.ee.reserve(4 * num_faces);
  }

  void dcd(const Instant& at, FrameResult& out) override {
    const skinning::Positions& x = at.x;
    check_positions(x, "detect_dcd", "x");
    const auto t0 = Clock::now();
    static_vertex_bounds<3>(x, bounds_.vertices);
    bounds_.derive(topology_, /*with_edges=*/false);
    const auto t1 = Clock::now();
    pairs_.clear();
    dcd_candidates_brute_force<3>(topology_, bounds_.triangles, pairs_, out.counters);
    const auto t2 = Clock::now();
    run_dcd_tests(topology_, pairs_, x, tests_, out);
    const auto t3 = Clock::now();
    out.times.refit_us += micros(t0, t1);
    out.times.traverse_us += micros(t1, t2);
    out.times.elementary_us += micros(t2, t3);
  }

  void ccd(const Interval& interval, FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    check_positions(x_t0, "detect_ccd", "x_t0");
    check_positions(x_t1, "detect_ccd", "x_t1");
    const auto t0 = Clock::now();
    swept_vertex_bounds<3>(x_t0, x_t1, 0.5 * options_.min_separation, bounds_.vertices);
    bounds_.derive(topology_);
    const auto t1 = Clock::now();
    features_.clear();
    // The hierarchy methods' fan rule (pair_blocks.cpp).
    const bool fans = ccd_uses_fans(topology_, tests_, ccd_options_);
    if (fans) fans_.start(topology_.fans(), x_t0, x_t1, topology_.num_vertices());
    ccd_candidates_brute_force<3>(
        topology_,
        bounds_,
        features_,
        out.counters,
        fans ? &fans_ : nullptr,
        interval_ends(ccd_options_.min_separation, x_t0, x_t1));
    const auto t2 = Clock::now();
    run_ccd_tests(topology_, features_, x_t0, x_t1, tests_, options_.accuracy, ccd_options_, out);
    const auto t3 = Clock::now();
    out.times.refit_us += micros(t0, t1);
    out.times.traverse_us += micros(t1, t2);
    out.times.elementary_us += micros(t2, t3);
  }

 private:
  FeatureBounds<3> bounds_;
  std::vector<TrianglePair> pairs_;
  FeatureCandidates features_;
  IntervalFans fans_;  ///< the CCD query's fans over its interval
};

}  // namespace

std::unique_ptr<CullingMethod> make_brute_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options) {
  return std::make_unique<BruteMethod>(mesh, topology, options);
}

}  // namespace skelcd::culling::detail
