// Hard CCD cases with known answers. Each family is built in a canonical frame where the answer is
// obvious (the triangle a=(0,0,0), b=(1,0,0), c=(0,1,0) in z=0; edge b from (0,0,0) to (1,0,0)), then
// moved by transforms. An answer stays "analytic" only if every transformed coordinate is exact
// (checked against the same transform in rationals): affine maps preserve contact and contact time.

#include "tests/ccd/hard_cases.hpp"

#include <functional>
#include <sstream>
#include <random>

#include <Eigen/LU>

namespace skelcd::ccd::test {
namespace {

using V = Eigen::Vector3d;
using Points = std::array<V, 8>;

struct Base {
  std::string family;
  std::string variant;
  bool vertex_face;
  Points points;
  bool hit;
  std::optional<mpq_class> toi;
};

// Vertex-face base: vertex from p0 to p1, triangle corners static at a, b, c (a moving frame is
// added by a transform).
Base vf(std::string family, std::string variant, V p0, V p1, V a, V b, V c, bool hit,
        std::optional<mpq_class> toi) {
  return {std::move(family), std::move(variant), true, {p0, a, b, c, p1, a, b, c}, hit, std::move(toi)};
}

Base vf_moving(std::string family, std::string variant, const Points& pts, bool hit, std::optional<mpq_class> toi) {
  return {std::move(family), std::move(variant), true, pts, hit, std::move(toi)};
}

// Edge-edge base: edge a from (a0, a1) at t=0 to (a0', a1') at t=1, edge b static.
Base ee(std::string family, std::string variant, V a0, V a1, V a0_t1, V a1_t1, V b0, V b1, bool hit,
        std::optional<mpq_class> toi) {
  return {std::move(family), std::move(variant), false, {a0, a1, b0, b1, a0_t1, a1_t1, b0, b1}, hit,
          std::move(toi)};
}

mpq_class q(double x) { return mpq_class(x); }
mpq_class frac(long n, long d) { return mpq_class(n, d); }

std::string name(const char* side, double d) {
  std::ostringstream os;
  os << side << " d=" << d;
  return os.str();
}

// A dyadic value k/64 in [lo, hi].
double dyadic(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_int_distribution<int> k(static_cast<int>(lo * 64), static_cast<int>(hi * 64));
  return k(rng) / 64.0;
}

void vertex_face_bases(std::mt19937_64& rng, int randoms, std::vector<Base>& out) {
  const V a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  const auto seps = near_miss_separations();

  // Through the face interior (random points strictly inside / outside), crossing z=0 at k/(k+m).
  for (int i = 0; i < randoms + 1; ++i) {
    const double x = dyadic(rng, 1.0 / 16, 0.5);
    const double y = dyadic(rng, 1.0 / 16, 7.0 / 8 - x);
    const int k = std::uniform_int_distribution<int>(1, 8)(rng);
    const int m = std::uniform_int_distribution<int>(1, 8)(rng);
    const double h0 = k / 8.0, h1 = -m / 8.0;
    out.push_back(vf("vf/face-crossing", "inside", V(x, y, h0), V(x, y, h1), a, b, c, true, frac(k, k + m)));
    const double xo = dyadic(rng, 0.625, 1.5);
    out.push_back(vf("vf/face-crossing", "outside", V(xo, 1.0 - xo + 0.5, h0), V(xo, 1.5 - xo, h1), a, b, c,
                     false, std::nullopt));
  }

  // Coplanar motion: the vertex slides in the plane of the triangle, entering at x = 0.
  for (int i = 0; i < randoms + 1; ++i) {
    const double y = dyadic(rng, 1.0 / 16, 7.0 / 8);
    const int s0 = std::uniform_int_distribution<int>(1, 8)(rng);
    const int s1 = std::uniform_int_distribution<int>(1, 8)(rng);
    out.push_back(vf("vf/coplanar-motion", "enters", V(-s0 / 4.0, y, 0), V(s1 / 4.0, y, 0), a, b, c, true,
                     frac(s0, s0 + s1)));
    out.push_back(vf("vf/coplanar-motion", "passes below", V(-s0 / 4.0, -y, 0), V(s1 / 4.0, -y, 0), a, b, c,
                     false, std::nullopt));
    out.push_back(vf("vf/coplanar-motion", "passes above", V(-s0 / 4.0, 1 + y, 0), V(s1 / 4.0, 1 + y, 0), a, b,
                     c, false, std::nullopt));
  }
  // The triangle sweeps over a still vertex in its plane (corners move, the vertex does not).
  out.push_back(vf_moving("vf/coplanar-motion", "triangle sweeps",
                          {V(2, 0.25, 0), a, b, c, V(2, 0.25, 0), V(2, 0, 0), V(3, 0, 0), V(2, 1, 0)}, true,
                          frac(5, 8)));  // relative position (2 - 2t, 1/4): x + y <= 1 from t = 5/8

  // Sliding along the line of edge ab (coplanar, collinear), and next to it at distance d.
  out.push_back(vf("vf/edge-sliding", "on the edge line", V(-1, 0, 0), V(2, 0, 0), a, b, c, true, frac(1, 3)));
  for (const double d : seps) {
    out.push_back(vf("vf/edge-sliding", name("inside", d), V(-1, d, 0), V(2, d, 0), a, b, c, true, frac(1, 3)));
    out.push_back(vf("vf/edge-sliding", name("outside", d), V(-1, -d, 0), V(2, -d, 0), a, b, c, false,
                     std::nullopt));
  }

  // Crossing the plane exactly on an edge (ab, then the hypotenuse bc), and d to either side.
  out.push_back(vf("vf/edge-touch", "on ab", V(0.5, 0, 1), V(0.5, 0, -1), a, b, c, true, frac(1, 2)));
  out.push_back(vf("vf/edge-touch", "on bc", V(0.5, 0.5, 1), V(0.5, 0.5, -1), a, b, c, true, frac(1, 2)));
  for (const double d : seps) {
    out.push_back(vf("vf/edge-touch", name("inside ab", d), V(0.5, d, 1), V(0.5, d, -1), a, b, c, true, frac(1, 2)));
    out.push_back(vf("vf/edge-touch", name("outside ab", d), V(0.5, -d, 1), V(0.5, -d, -1), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/edge-touch", name("inside bc", d), V(0.5, 0.5 - d, 1), V(0.5, 0.5 - d, -1), a, b, c,
                     true, frac(1, 2)));
    out.push_back(vf("vf/edge-touch", name("outside bc", d), V(0.5, 0.5 + d, 1), V(0.5, 0.5 + d, -1), a, b, c,
                     false, std::nullopt));
  }

  // Through a corner, and next to it.
  out.push_back(vf("vf/corner", "through a", V(0, 0, 1), V(0, 0, -1), a, b, c, true, frac(1, 2)));
  out.push_back(vf("vf/corner", "through b", V(1, 0, 0.5), V(1, 0, -1.5), a, b, c, true, frac(1, 4)));
  out.push_back(vf("vf/corner", "sliding through c", V(0, 2, 0), V(0, -2, 0), a, b, c, true, frac(1, 4)));
  for (const double d : seps) {
    out.push_back(vf("vf/corner", name("inside a", d), V(d, d, 1), V(d, d, -1), a, b, c, true, frac(1, 2)));
    out.push_back(vf("vf/corner", name("outside a", d), V(-d, -d, 1), V(-d, -d, -1), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/corner", name("outside b", d), V(1 + d, 0, 1), V(1 + d, 0, -1), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/corner", name("beside c, sliding", d), V(-d, 2, 0), V(-d, -2, 0), a, b, c, false,
                     std::nullopt));
  }

  // Contact exactly at t = 0 (then moving away) and at t = 1 (arriving); d short of it.
  out.push_back(vf("vf/contact-t0", "inside", V(0.25, 0.25, 0), V(0.25, 0.25, 1), a, b, c, true, frac(0, 1)));
  out.push_back(vf("vf/contact-t0", "on edge", V(0.5, 0, 0), V(0.5, -1, 1), a, b, c, true, frac(0, 1)));
  out.push_back(vf("vf/contact-t1", "inside", V(0.25, 0.25, 1), V(0.25, 0.25, 0), a, b, c, true, frac(1, 1)));
  out.push_back(vf("vf/contact-t1", "at corner", V(-1, -1, 1), V(0, 0, 0), a, b, c, true, frac(1, 1)));
  for (const double d : seps) {
    out.push_back(vf("vf/contact-t0", name("above", d), V(0.25, 0.25, d), V(0.25, 0.25, 1), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/contact-t1", name("short", d), V(0.25, 0.25, 1), V(0.25, 0.25, d), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/contact-t1", name("through", d), V(0.25, 0.25, 1), V(0.25, 0.25, -d), a, b, c, true,
                     mpq_class(1) / (1 + q(d))));
  }

  // Zero-area triangles: collinear corners, a zero-length edge, all corners at one point.
  const V m(0.5, 0, 0), e(2, 0, 0), pt(0.25, 0.25, 0);
  out.push_back(vf("vf/zero-area", "collinear, through", V(0.5, 0, 1), V(0.5, 0, -1), a, b, e, true, frac(1, 2)));
  out.push_back(vf("vf/zero-area", "zero-length edge, through", V(0.75, 0, 1), V(0.75, 0, -1), a, a, b, true,
                   frac(1, 2)));
  out.push_back(vf("vf/zero-area", "point triangle, through", V(0.25, 0.25, 1), V(0.25, 0.25, -1), pt, pt, pt,
                   true, frac(1, 2)));
  out.push_back(vf("vf/zero-area", "collinear, sliding onto", V(-1, 0, 0), V(2, 0, 0), a, m, b, true, frac(1, 3)));
  for (const double d : seps) {
    out.push_back(vf("vf/zero-area", name("collinear, beside", d), V(0.5, d, 1), V(0.5, d, -1), a, b, e, false,
                     std::nullopt));
    out.push_back(vf("vf/zero-area", name("collinear, other side", d), V(0.5, -d, 1), V(0.5, -d, -1), a, b, e,
                     false, std::nullopt));
    out.push_back(vf("vf/zero-area", name("point triangle, beside", d), V(0.25 + d, 0.25, 1),
                     V(0.25 + d, 0.25, -1), pt, pt, pt, false, std::nullopt));
    out.push_back(vf("vf/zero-area", name("collinear, sliding beside", d), V(-1, d, 0), V(2, d, 0), a, m, b,
                     false, std::nullopt));
  }

  // Nothing moves.
  out.push_back(vf("vf/static", "inside", V(0.25, 0.5, 0), V(0.25, 0.5, 0), a, b, c, true, frac(0, 1)));
  out.push_back(vf("vf/static", "on edge", V(0.5, 0.5, 0), V(0.5, 0.5, 0), a, b, c, true, frac(0, 1)));
  for (const double d : seps) {
    out.push_back(vf("vf/static", name("above", d), V(0.25, 0.5, d), V(0.25, 0.5, d), a, b, c, false,
                     std::nullopt));
    out.push_back(vf("vf/static", name("beside", d), V(0.5, 0.5 + d, 0), V(0.5, 0.5 + d, 0), a, b, c, false,
                     std::nullopt));
  }
}

void edge_edge_bases(std::mt19937_64& rng, int randoms, std::vector<Base>& out) {
  const V b0(0, 0, 0), b1(1, 0, 0);
  const auto seps = near_miss_separations();

  // Edge a sweeps down through edge b at x, crossing z = 0 at t = k/(k+m).
  for (int i = 0; i < randoms + 1; ++i) {
    const double x = dyadic(rng, 1.0 / 16, 15.0 / 16);
    const int k = std::uniform_int_distribution<int>(1, 8)(rng);
    const int m = std::uniform_int_distribution<int>(1, 8)(rng);
    const double h0 = k / 8.0, h1 = -m / 8.0;
    out.push_back(ee("ee/crossing", "interior", V(x, -1, h0), V(x, 1, h0), V(x, -1, h1), V(x, 1, h1), b0, b1,
                     true, frac(k, k + m)));
    const double xo = dyadic(rng, 1.0 + 1.0 / 16, 2);
    out.push_back(ee("ee/crossing", "beyond the end", V(xo, -1, h0), V(xo, 1, h0), V(xo, -1, h1), V(xo, 1, h1),
                     b0, b1, false, std::nullopt));
  }
  out.push_back(ee("ee/crossing", "through endpoint b0", V(0, -1, 1), V(0, 1, 1), V(0, -1, -1), V(0, 1, -1),
                   b0, b1, true, frac(1, 2)));
  out.push_back(ee("ee/crossing", "endpoint a0 on b", V(0.5, 0, 1), V(0.5, 1, 1), V(0.5, 0, -1), V(0.5, 1, -1),
                   b0, b1, true, frac(1, 2)));
  for (const double d : seps) {
    out.push_back(ee("ee/crossing", name("beside b0", d), V(-d, -1, 1), V(-d, 1, 1), V(-d, -1, -1),
                     V(-d, 1, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/crossing", name("inside b1", d), V(1 - d, -1, 1), V(1 - d, 1, 1), V(1 - d, -1, -1),
                     V(1 - d, 1, -1), b0, b1, true, frac(1, 2)));
    out.push_back(ee("ee/crossing", name("a0 short of b", d), V(0.5, d, 1), V(0.5, 1, 1), V(0.5, d, -1),
                     V(0.5, 1, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/crossing", name("a0 past b", d), V(0.5, -d, 1), V(0.5, 1, 1), V(0.5, -d, -1),
                     V(0.5, 1, -1), b0, b1, true, frac(1, 2)));
  }

  // Parallel edges: a runs along x over b and comes down onto it.
  out.push_back(ee("ee/parallel", "overlapping", V(0.5, 0, 1), V(1.5, 0, 1), V(0.5, 0, -1), V(1.5, 0, -1), b0,
                   b1, true, frac(1, 2)));
  out.push_back(ee("ee/parallel", "end to end", V(1, 0, 1), V(2, 0, 1), V(1, 0, -3), V(2, 0, -3), b0, b1, true,
                   frac(1, 4)));
  out.push_back(ee("ee/parallel", "contained", V(0.25, 0, 1), V(0.75, 0, 1), V(0.25, 0, -1), V(0.75, 0, -1), b0,
                   b1, true, frac(1, 2)));
  for (const double d : seps) {
    out.push_back(ee("ee/parallel", name("gap along", d), V(1 + d, 0, 1), V(2, 0, 1), V(1 + d, 0, -1),
                     V(2, 0, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/parallel", name("offset sideways", d), V(0.5, d, 1), V(1.5, d, 1), V(0.5, d, -1),
                     V(1.5, d, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/parallel", name("stops short", d), V(0.5, 0, 1), V(1.5, 0, 1), V(0.5, 0, d),
                     V(1.5, 0, d), b0, b1, false, std::nullopt));
  }

  // Collinear throughout: a slides along the x axis onto b.
  out.push_back(ee("ee/collinear", "slides onto", V(2, 0, 0), V(3, 0, 0), V(0.5, 0, 0), V(1.5, 0, 0), b0, b1, true,
                   frac(2, 3)));
  out.push_back(ee("ee/collinear", "reaches at t=1", V(2, 0, 0), V(3, 0, 0), V(1, 0, 0), V(2, 0, 0), b0, b1, true,
                   frac(1, 1)));
  out.push_back(ee("ee/collinear", "overlapping at t=0", V(0.5, 0, 0), V(1.5, 0, 0), V(0.5, 0, 0), V(1.5, 0, 0),
                   b0, b1, true, frac(0, 1)));
  for (const double d : seps) {
    out.push_back(ee("ee/collinear", name("stops short", d), V(2, 0, 0), V(3, 0, 0), V(1 + d, 0, 0),
                     V(2 + d, 0, 0), b0, b1, false, std::nullopt));
  }

  // Zero-length edges: a point crossing b; two points.
  out.push_back(ee("ee/zero-length", "point through b", V(0.5, 0, 1), V(0.5, 0, 1), V(0.5, 0, -1),
                   V(0.5, 0, -1), b0, b1, true, frac(1, 2)));
  out.push_back(ee("ee/zero-length", "point through point", V(0, 0, 1), V(0, 0, 1), V(0, 0, -1), V(0, 0, -1), b0,
                   b0, true, frac(1, 2)));
  out.push_back(ee("ee/zero-length", "point sliding onto b", V(3, 0, 0), V(3, 0, 0), V(0, 0, 0), V(0, 0, 0), b0,
                   b1, true, frac(2, 3)));
  for (const double d : seps) {
    out.push_back(ee("ee/zero-length", name("point beside b", d), V(0.5, d, 1), V(0.5, d, 1), V(0.5, d, -1),
                     V(0.5, d, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/zero-length", name("point past b1", d), V(1 + d, 0, 1), V(1 + d, 0, 1),
                     V(1 + d, 0, -1), V(1 + d, 0, -1), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/zero-length", name("point beside point", d), V(d, 0, 1), V(d, 0, 1), V(d, 0, -1),
                     V(d, 0, -1), b0, b0, false, std::nullopt));
  }

  // Coplanar motion: a (along y) slides in z=0 toward b's end x = 1, reached at t = 2/3.
  out.push_back(ee("ee/coplanar-motion", "sweeps onto end", V(2, -1, 0), V(2, 1, 0), V(0.5, -1, 0),
                   V(0.5, 1, 0), b0, b1, true, frac(2, 3)));
  out.push_back(ee("ee/coplanar-motion", "endpoint meets endpoint", V(2, 0, 0), V(2, 1, 0), V(0.5, 0, 0),
                   V(0.5, 1, 0), b0, b1, true, frac(2, 3)));
  for (const double d : seps) {
    out.push_back(ee("ee/coplanar-motion", name("passes above", d), V(2, d, 0), V(2, 1, 0), V(0.5, d, 0),
                     V(0.5, 1, 0), b0, b1, false, std::nullopt));
    out.push_back(ee("ee/coplanar-motion", name("stops short", d), V(2, -1, 0), V(2, 1, 0), V(1 + d, -1, 0),
                     V(1 + d, 1, 0), b0, b1, false, std::nullopt));
  }

  // Contact exactly at t = 0 / t = 1.
  out.push_back(ee("ee/contact-t0", "crossing", V(0.5, -1, 0), V(0.5, 1, 0), V(0.5, -1, 1), V(0.5, 1, 1), b0, b1,
                   true, frac(0, 1)));
  out.push_back(ee("ee/contact-t1", "crossing", V(0.5, -1, 1), V(0.5, 1, 1), V(0.5, -1, 0), V(0.5, 1, 0), b0, b1,
                   true, frac(1, 1)));
  for (const double d : seps) {
    out.push_back(ee("ee/contact-t0", name("above", d), V(0.5, -1, d), V(0.5, 1, d), V(0.5, -1, 1), V(0.5, 1, 1),
                     b0, b1, false, std::nullopt));
    out.push_back(ee("ee/contact-t1", name("short", d), V(0.5, -1, 1), V(0.5, 1, 1), V(0.5, -1, d),
                     V(0.5, 1, d), b0, b1, false, std::nullopt));
  }

  // Nothing moves.
  out.push_back(ee("ee/static", "crossing", V(0.5, -1, 0), V(0.5, 1, 0), V(0.5, -1, 0), V(0.5, 1, 0), b0, b1,
                   true, frac(0, 1)));
  for (const double d : seps) {
    out.push_back(ee("ee/static", name("above", d), V(0.5, -1, d), V(0.5, 1, d), V(0.5, -1, d), V(0.5, 1, d), b0,
                     b1, false, std::nullopt));
  }
}

// A transform of all 8 points, given twice: in double and in exact rationals.
struct Transform {
  std::string name;
  std::function<V(const V&, bool t1)> apply;
  std::function<std::array<mpq_class, 3>(const std::array<mpq_class, 3>&, bool t1)> apply_exact;
};

std::vector<Transform> transforms(std::mt19937_64& rng) {
  std::vector<Transform> out;
  out.push_back({"identity", [](const V& p, bool) { return p; },
                 [](const std::array<mpq_class, 3>& p, bool) { return p; }});
  // An integer matrix with nonzero determinant and a dyadic translation.
  Eigen::Matrix3i m;
  do {
    for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = std::uniform_int_distribution<int>(-2, 2)(rng);
  } while (m.determinant() == 0);
  const V shift(dyadic(rng, -4, 4), dyadic(rng, -4, 4), dyadic(rng, -4, 4));
  out.push_back({"affine",
                 [m, shift](const V& p, bool) { return V(m.cast<double>() * p + shift); },
                 [m, shift](const std::array<mpq_class, 3>& p, bool) {
                   std::array<mpq_class, 3> r;
                   for (int i = 0; i < 3; ++i) {
                     r[static_cast<std::size_t>(i)] = mpq_class(shift[i]);
                     for (int j = 0; j < 3; ++j) r[static_cast<std::size_t>(i)] += m(i, j) * p[static_cast<std::size_t>(j)];
                   }
                   return r;
                 }});
  // A moving frame: every point gets the same extra velocity (relative motion unchanged).
  const V w(dyadic(rng, -2, 2), dyadic(rng, -2, 2), dyadic(rng, -2, 2));
  out.push_back({"moving frame", [w](const V& p, bool t1) { return t1 ? V(p + w) : p; },
                 [w](const std::array<mpq_class, 3>& p, bool t1) {
                   if (!t1) return p;
                   return std::array<mpq_class, 3>{p[0] + w.x(), p[1] + w.y(), p[2] + w.z()};
                 }});
  for (const double s : {0x1p-20, 0x1p20, 1e-6, 1e6}) {
    out.push_back({"scale " + std::to_string(s), [s](const V& p, bool) { return V(p * s); },
                   [s](const std::array<mpq_class, 3>& p, bool) {
                     return std::array<mpq_class, 3>{p[0] * s, p[1] * s, p[2] * s};
                   }});
  }
  const V far(1e6, -1e6, 1e6);
  out.push_back({"translate 1e6", [far](const V& p, bool) { return V(p + far); },
                 [far](const std::array<mpq_class, 3>& p, bool) {
                   return std::array<mpq_class, 3>{p[0] + far.x(), p[1] + far.y(), p[2] + far.z()};
                 }});
  return out;
}

}  // namespace

VertexFaceQuery HardCase::vf() const {
  const auto& p = points;
  return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
}

EdgeEdgeQuery HardCase::ee() const {
  const auto& p = points;
  return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
}

std::vector<double> near_miss_separations() { return {1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15}; }

std::vector<HardCase> hard_cases(std::uint64_t seed, int random_per_family) {
  std::mt19937_64 rng(seed);
  std::vector<Base> bases;
  vertex_face_bases(rng, random_per_family, bases);
  edge_edge_bases(rng, random_per_family, bases);
  const auto all = transforms(rng);
  std::vector<HardCase> out;
  out.reserve(bases.size() * all.size());
  for (const auto& base : bases) {
    for (const auto& tr : all) {
      HardCase c;
      c.family = base.family;
      c.variant = base.variant + ", " + tr.name;
      c.vertex_face = base.vertex_face;
      if (const auto at = base.variant.find("d="); at != std::string::npos) {
        c.separation = std::stod(base.variant.substr(at + 2));
      }
      bool exact = true;
      for (std::size_t i = 0; i < 8; ++i) {
        const bool t1 = i >= 4;
        c.points[i] = tr.apply(base.points[i], t1);
        const auto r = tr.apply_exact({mpq_class(base.points[i].x()), mpq_class(base.points[i].y()),
                                       mpq_class(base.points[i].z())},
                                      t1);
        for (int k = 0; k < 3; ++k) {
          if (mpq_class(c.points[i][k]) != r[static_cast<std::size_t>(k)]) exact = false;
        }
      }
      if (exact) {
        c.analytic_hit = base.hit;
        if (base.hit) c.analytic_toi = base.toi;
      }
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace skelcd::ccd::test
