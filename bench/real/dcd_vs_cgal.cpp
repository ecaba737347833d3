// dcd_vs_cgal: skelcd's DCD of posed frames against CGAL's `self_intersections` (issue 14, "DCD
// ahead of CGAL"), one thread each, with the pairs compared one by one.
//
//   dcd_vs_cgal MODEL [--clip NAME] [--samples S] [--repeat R] [--min-ms M] [--methods bvh,kdop]
//               [--json] [--cpu-time]
//
// --min-ms: each side runs at least R times and on until its runs add up to M ms (default 50, 0 for
// R runs only; at most 10,000 runs): with the fastest of three runs, a frame that takes 0.3 ms read
// anywhere from 3.7 to 6.9x CGAL from one run of the program to the next (ninja), and the small
// characters moved the geometric mean with them.
//
// --cpu-time times the calling thread's CPU time instead of the wall clock: on a machine shared
// with other jobs, where a thread waits for a core, it compares two builds without the waits (the
// figures it prints are not the wall-clock ones of the table).
//
// --json also gives each run's exact triangle tests (tt_tests): the pairs the traversal and the
// vertex fans left to test.
//
// Method `incremental` times the DCD of a clip check at a sample after the first: the previous
// sample's pairs updated from the CCD contacts of the interval (culling/incremental_dcd.hpp).
//
// For S samples spread evenly over the clip (every frame of a frame sequence, up to S) it poses
// the model, times skelcd's `detect_dcd` and CGAL 5.5's
// `Polygon_mesh_processing::self_intersections` (Epick kernel, Sequential_tag) — the fastest of R
// runs of each, the mesh built once outside the timing as skelcd's method is — and compares the
// pairs. CGAL has no triangle-soup overload in 5.5: the welded soup becomes a Surface_mesh through
// `orient_polygon_soup`, which duplicates a vertex where the soup is not manifold or not
// orientable there. Two faces that share such a vertex in our mesh no longer share it in CGAL's
// and touch at it, so CGAL reports them: those extra pairs are counted apart
// (`cgal_extra_at_duplicated`, each checked to share a duplicated vertex), everything else must be
// identical. CGAL's pairs that skelcd leaves out by definition (part-excluded pairs, duplicate
// faces on the same three vertices) are removed before comparing; triangles with a repeated vertex
// are not given to CGAL at all (skelcd skips them too).
//
// CGAL is used here only: this target is built when Debian's libcgal-dev is installed
// (`make bench-real` installs it) and skelcd never links it.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <iterator>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "culling/frame_result.hpp"
#include "culling/incremental_dcd.hpp"
#include "culling/method.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;
using skelcd::culling::TrianglePair;

struct Arguments {
  std::string model;
  std::string clip;
  int samples = 4;
  int repeat = 3;
  double min_ms = 50.0;
  std::vector<std::string> methods{"bvh"};
  bool json = false;
  bool cpu_time = false;
};

[[noreturn]] void usage(const std::string& message) {
  std::fprintf(
      stderr,
      "dcd_vs_cgal: %s\nusage: dcd_vs_cgal MODEL [--clip NAME] [--samples S] "
      "[--repeat R] [--min-ms M] [--methods bvh,kdop] [--json] [--cpu-time]\n",
      message.c_str());
  std::exit(2);
}

int positive(const std::string& flag, const char* text) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || value < 1 || value > 1'000'000) {
    usage(flag + " wants a positive integer, not '" + text + "'");
  }
  return static_cast<int>(value);
}

double non_negative(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !(value >= 0.0 && value <= 1e6)) {
    usage(flag + " wants a number of ms from 0 to 1e6, not '" + text + "'");
  }
  return value;
}

Arguments parse(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) usage(a + " wants a value");
      return argv[++i];
    };
    if (a == "--clip") {
      args.clip = value();
    } else if (a == "--samples") {
      args.samples = positive(a, value());
    } else if (a == "--repeat") {
      args.repeat = positive(a, value());
    } else if (a == "--min-ms") {
      args.min_ms = non_negative(a, value());
    } else if (a == "--methods") {
      args.methods.clear();
      std::stringstream list(value());
      for (std::string m; std::getline(list, m, ',');) {
        if (!m.empty()) args.methods.push_back(m);
      }
      if (args.methods.empty()) usage("--methods is empty");
    } else if (a == "--json") {
      args.json = true;
    } else if (a == "--cpu-time") {
      args.cpu_time = true;
    } else if (a == "-h" || a == "--help") {
      usage("skelcd's DCD against CGAL's self_intersections on posed frames");
    } else if (!a.empty() && a[0] == '-') {
      usage("unknown option " + a);
    } else if (args.model.empty()) {
      args.model = a;
    } else {
      usage("one model only");
    }
  }
  if (args.model.empty()) usage("no model");
  return args;
}

/// The samples to pose: S spread evenly over [0, n).
std::vector<int> pick_samples(int n, int s) {
  std::vector<int> picked;
  if (n <= 0) return picked;
  if (s == 1 || n == 1) return {0};
  for (int j = 0; j < s; ++j) {
    const int k =
        static_cast<int>((static_cast<double>(j) * (n - 1)) / static_cast<double>(s - 1) + 0.5);
    if (picked.empty() || picked.back() != k) picked.push_back(k);
  }
  return picked;
}

bool g_cpu_time = false;  // --cpu-time

/// Milliseconds on the wall clock, or of this thread's CPU time with --cpu-time.
double now_ms() {
  if (g_cpu_time) {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
  }
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// The fastest of at least `repeat` runs, and of as many more as make `min_ms` in all (at most
/// kMaxRuns).
template <class F>
double best_ms(int repeat, double min_ms, F&& run) {
  constexpr int kMaxRuns = 10'000;
  double best = std::numeric_limits<double>::infinity();
  double total = 0.0;
  for (int r = 0; r < kMaxRuns && (r < repeat || total < min_ms); ++r) {
    const double start = now_ms();
    run();
    const double ms = now_ms() - start;
    best = std::min(best, ms);
    total += ms;
  }
  return best;
}

/// CGAL's view of the welded mesh: the soup made a Surface_mesh, and the way back to our ids.
struct CgalMesh {
  SurfaceMesh mesh;
  std::vector<std::int32_t> face_of;        ///< CGAL face index → our triangle
  std::vector<std::int32_t> welded_of;      ///< CGAL vertex index → our welded vertex
  std::vector<bool> welded_was_duplicated;  ///< per welded vertex: CGAL has more than one copy
};

CgalMesh make_cgal_mesh(
    const skelcd::skinning::Topology& topology, const skelcd::skinning::Positions& x) {
  const auto& tri = topology.welded_triangles;
  const std::int32_t w = topology.num_welded_vertices();
  std::vector<Point> points;
  points.reserve(static_cast<std::size_t>(w));
  for (std::int32_t v = 0; v < w; ++v) points.emplace_back(x(v, 0), x(v, 1), x(v, 2));
  std::vector<std::array<std::size_t, 3>> polygons;
  CgalMesh out;
  for (std::int32_t f = 0; f < tri.rows(); ++f) {
    const auto a = tri(f, 0), b = tri(f, 1), c = tri(f, 2);
    if (a == b || b == c || a == c) continue;  // skelcd skips these too
    polygons.push_back(
        {static_cast<std::size_t>(a), static_cast<std::size_t>(b), static_cast<std::size_t>(c)});
    out.face_of.push_back(f);
  }
  const std::vector<std::array<std::size_t, 3>> before = polygons;
  PMP::orient_polygon_soup(points, polygons);
  // Appended points are copies of welded ones; find each one's original in its polygon.
  out.welded_of.assign(points.size(), -1);
  for (std::int32_t v = 0; v < w; ++v) out.welded_of[static_cast<std::size_t>(v)] = v;
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    if (polygons[p].size() != 3) throw std::runtime_error("CGAL changed a triangle's size");
    for (const std::size_t q : polygons[p]) {
      if (q < static_cast<std::size_t>(w)) continue;
      for (const std::size_t o : before[p]) {
        if (points[o] == points[q]) out.welded_of[q] = static_cast<std::int32_t>(o);
      }
      if (out.welded_of[q] < 0) throw std::runtime_error("a duplicated point has no original");
    }
  }
  out.welded_was_duplicated.assign(static_cast<std::size_t>(w), false);
  for (std::size_t q = static_cast<std::size_t>(w); q < points.size(); ++q) {
    out.welded_was_duplicated[static_cast<std::size_t>(out.welded_of[q])] = true;
  }
  PMP::polygon_soup_to_polygon_mesh(points, polygons, out.mesh);
  if (out.mesh.number_of_faces() != polygons.size()) {
    throw std::runtime_error(
        "CGAL's mesh has " + std::to_string(out.mesh.number_of_faces()) + " faces for " +
        std::to_string(polygons.size()) + " polygons");
  }
  // The faces come in polygon order: check it on every face.
  for (const auto f : out.mesh.faces()) {
    std::array<std::int32_t, 3> ours{};
    std::array<std::int32_t, 3> theirs{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(out.mesh.halfedge(f), out.mesh)) {
      if (k < 3) theirs[static_cast<std::size_t>(k)] = out.welded_of[v.idx()];
      ++k;
    }
    const std::int32_t t = out.face_of[f.idx()];
    for (int j = 0; j < 3; ++j) ours[static_cast<std::size_t>(j)] = tri(t, j);
    std::sort(ours.begin(), ours.end());
    std::sort(theirs.begin(), theirs.end());
    if (k != 3 || ours != theirs) throw std::runtime_error("CGAL's faces are not in soup order");
  }
  return out;
}

void set_points(CgalMesh& cgal, const skelcd::skinning::Positions& x) {
  for (const auto v : cgal.mesh.vertices()) {
    const auto w = cgal.welded_of[v.idx()];
    cgal.mesh.point(v) = Point(x(w, 0), x(w, 1), x(w, 2));
  }
}

struct Comparison {
  std::size_t cgal_pairs = 0;      ///< after removing what skelcd leaves out by definition
  std::size_t same = 0;            ///< in both
  std::size_t skelcd_only = 0;     ///< skelcd reports, CGAL does not
  std::size_t cgal_extra_dup = 0;  ///< CGAL only, the faces share a vertex CGAL duplicated
  std::size_t cgal_only = 0;       ///< CGAL only, anything else
  std::size_t removed_excluded = 0;
  std::size_t removed_duplicate_faces = 0;
};

bool excluded(const skelcd::skinning::Mesh& mesh, std::int32_t a, std::int32_t b) {
  auto pa = mesh.face_part[static_cast<std::size_t>(a)];
  auto pb = mesh.face_part[static_cast<std::size_t>(b)];
  if (pa > pb) std::swap(pa, pb);
  return std::find(
             mesh.excluded_part_pairs.begin(), mesh.excluded_part_pairs.end(), std::pair{pa, pb}) !=
         mesh.excluded_part_pairs.end();
}

Comparison compare(
    const skelcd::skinning::Mesh& mesh,
    const skelcd::skinning::Topology& topology,
    const CgalMesh& cgal,
    const std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>>& cgal_faces,
    const std::vector<TrianglePair>& ours) {
  const auto& tri = topology.welded_triangles;
  auto corners = [&](std::int32_t f) {
    std::array<std::int32_t, 3> c{tri(f, 0), tri(f, 1), tri(f, 2)};
    std::sort(c.begin(), c.end());
    return c;
  };
  Comparison c;
  std::vector<TrianglePair> theirs;
  for (const auto& [fa, fb] : cgal_faces) {
    std::int32_t a = cgal.face_of[fa.idx()];
    std::int32_t b = cgal.face_of[fb.idx()];
    if (a == b) continue;  // a degenerate face reported with itself
    if (a > b) std::swap(a, b);
    if (excluded(mesh, a, b)) {
      ++c.removed_excluded;
      continue;
    }
    if (corners(a) == corners(b)) {
      ++c.removed_duplicate_faces;
      continue;
    }
    theirs.push_back({a, b});
  }
  std::sort(theirs.begin(), theirs.end());
  theirs.erase(std::unique(theirs.begin(), theirs.end()), theirs.end());
  c.cgal_pairs = theirs.size();
  std::vector<TrianglePair> mine = ours;
  std::sort(mine.begin(), mine.end());
  std::vector<TrianglePair> both;
  std::vector<TrianglePair> only_mine;
  std::vector<TrianglePair> only_theirs;
  std::set_intersection(
      mine.begin(), mine.end(), theirs.begin(), theirs.end(), std::back_inserter(both));
  std::set_difference(
      mine.begin(), mine.end(), theirs.begin(), theirs.end(), std::back_inserter(only_mine));
  std::set_difference(
      theirs.begin(), theirs.end(), mine.begin(), mine.end(), std::back_inserter(only_theirs));
  c.same = both.size();
  c.skelcd_only = only_mine.size();
  for (const auto& p : only_theirs) {
    const auto ca = corners(p.a);
    const auto cb = corners(p.b);
    bool shares_duplicated = false;
    for (const auto v : ca) {
      if (std::find(cb.begin(), cb.end(), v) != cb.end() &&
          cgal.welded_was_duplicated[static_cast<std::size_t>(v)]) {
        shares_duplicated = true;
      }
    }
    ++(shares_duplicated ? c.cgal_extra_dup : c.cgal_only);
  }
  return c;
}

/// a / b for the JSON output, or null where it is not a number (a time below the clock's
/// resolution: JSON has no infinity).
std::string json_ratio(double a, double b) {
  const double r = a / b;
  if (!std::isfinite(r)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", r);
  return text;
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (static_cast<unsigned char>(ch) < 0x20) continue;
    out += ch;
  }
  return out + "\"";
}

int run(const Arguments& args) {
  const skelcd::skinning::LoadedModel model = skelcd::skinning::load_model(args.model);
  const auto motion = model.motion({.clip = args.clip});
  const skelcd::skinning::Mesh& mesh = motion->mesh();
  const skelcd::skinning::Topology topology = skelcd::skinning::build_topology(mesh);
  const std::vector<int> samples = pick_samples(motion->num_samples(), args.samples);

  // "incremental": the DCD a clip check runs at a sample after the first (culling/
  // incremental_dcd.hpp) — the pairs at the previous sample updated from the CCD contacts of the
  // interval between them (both computed untimed with `bvh`, as the check has them already).
  std::vector<std::unique_ptr<skelcd::culling::CullingMethod>> methods;
  for (const auto& name : args.methods) {
    methods.push_back(
        skelcd::culling::make_method(name == "incremental" ? "bvh" : name, mesh, topology));
  }
  std::unique_ptr<skelcd::culling::DcdUpdater> updater;
  if (std::find(args.methods.begin(), args.methods.end(), "incremental") != args.methods.end()) {
    updater = std::make_unique<skelcd::culling::DcdUpdater>(mesh, topology);
  }
  skelcd::skinning::Positions previous_posed;
  skelcd::skinning::Positions previous_welded;
  skelcd::skinning::Positions posed;
  skelcd::skinning::Positions welded;
  std::unique_ptr<CgalMesh> cgal;
  bool identical_everywhere = true;
  if (!args.json) {
    std::printf(
        "# %s: %lld triangles, %d welded vertices, samples of %d\n",
        args.model.c_str(),
        static_cast<long long>(mesh.num_triangles()),
        topology.num_welded_vertices(),
        motion->num_samples());
  }
  for (const int k : samples) {
    motion->positions(k, posed);
    skelcd::skinning::gather_welded(topology, posed, welded);
    if (!cgal) {
      cgal = std::make_unique<CgalMesh>(make_cgal_mesh(topology, welded));
    }
    set_points(*cgal, welded);
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> cgal_faces;
    const double cgal_ms = best_ms(args.repeat, args.min_ms, [&] {
      cgal_faces.clear();
      PMP::self_intersections<CGAL::Sequential_tag>(
          faces(cgal->mesh), cgal->mesh, std::back_inserter(cgal_faces));
    });
    for (std::size_t m = 0; m < methods.size(); ++m) {
      skelcd::culling::FrameResult result;
      const skelcd::culling::Instant at{.x = welded, .sample = k};
      double ms = 0.0;
      if (args.methods[m] == "incremental") {
        // From the sample before (after, for the first): the interval's direction does not matter.
        const int previous = k > 0 ? k - 1 : std::min(1, motion->num_samples() - 1);
        motion->positions(previous, previous_posed);
        skelcd::skinning::gather_welded(topology, previous_posed, previous_welded);
        skelcd::culling::FrameResult before, interval;
        methods[m]->detect_dcd(previous_welded, before);
        methods[m]->detect_ccd(previous_welded, welded, interval);
        ms = best_ms(args.repeat, args.min_ms, [&] {
          result.clear();
          updater->update(before.dcd_pairs, interval.contacts, welded, {}, result);
        });
      } else {
        ms = best_ms(args.repeat, args.min_ms, [&] {
          result.clear();
          methods[m]->detect_dcd(at, result);
        });
      }
      const Comparison c = compare(mesh, topology, *cgal, cgal_faces, result.dcd_pairs);
      const bool identical = c.skelcd_only == 0 && c.cgal_only == 0;
      identical_everywhere = identical_everywhere && identical;
      if (args.json) {
        std::printf(
            "{\"model\": %s, \"sample\": %d, \"triangles\": %lld, \"method\": %s, "
            "\"skelcd_ms\": %.4f, \"cgal_ms\": %.4f, \"speedup\": %s, \"skelcd_pairs\": %zu, "
            "\"cgal_pairs\": %zu, \"same\": %zu, \"skelcd_only\": %zu, \"cgal_only\": %zu, "
            "\"cgal_extra_at_duplicated\": %zu, \"cgal_duplicated_vertices\": %zu, "
            "\"removed_excluded\": %zu, \"removed_duplicate_faces\": %zu, \"tt_tests\": %lld, "
            "\"identical\": %s}\n",
            quoted(args.model).c_str(),
            k,
            static_cast<long long>(mesh.num_triangles()),
            quoted(args.methods[m]).c_str(),
            ms,
            cgal_ms,
            json_ratio(cgal_ms, ms).c_str(),
            result.dcd_pairs.size(),
            c.cgal_pairs,
            c.same,
            c.skelcd_only,
            c.cgal_only,
            c.cgal_extra_dup,
            static_cast<std::size_t>(std::count(
                cgal->welded_was_duplicated.begin(), cgal->welded_was_duplicated.end(), true)),
            c.removed_excluded,
            c.removed_duplicate_faces,
            static_cast<long long>(result.counters.tt_tests),
            identical ? "true" : "false");
      } else {
        std::printf(
            "sample %4d  %-6s skelcd %9.4f ms  CGAL %9.3f ms  %6.2fx  pairs %zu/%zu  "
            "skelcd-only %zu  CGAL-only %zu (+%zu at duplicated vertices)%s\n",
            k,
            args.methods[m].c_str(),
            ms,
            cgal_ms,
            cgal_ms / ms,
            result.dcd_pairs.size(),
            c.cgal_pairs,
            c.skelcd_only,
            c.cgal_only,
            c.cgal_extra_dup,
            identical ? "" : "  DIFFERENT");
      }
      std::fflush(stdout);
    }
  }
  return identical_everywhere ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const Arguments args = parse(argc, argv);
  g_cpu_time = args.cpu_time;
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dcd_vs_cgal: %s: %s\n", args.model.c_str(), e.what());
    return 2;
  }
}
