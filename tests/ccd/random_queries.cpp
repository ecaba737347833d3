#include "tests/ccd/random_queries.hpp"

#include <cmath>

namespace skelcd::ccd::test {

using V = Eigen::Vector3d;

RandomQuery RandomQueryGenerator::next_uniform() { return uniform_query(); }

RandomQuery RandomQueryGenerator::uniform_query() {
  RandomQuery q;
  q.vertex_face = integer(0, 1) == 0;
  q.kind = "uniform";
  for (auto& p : q.points) p = point(1.0);
  return q;
}

RandomQuery RandomQueryGenerator::grid_query() {
  // Coordinates in {-1, -1/2, 0, 1/2, 1}: exact degeneracies everywhere.
  RandomQuery q;
  q.vertex_face = integer(0, 1) == 0;
  q.kind = "grid";
  for (auto& p : q.points) p = V(integer(-2, 2), integer(-2, 2), integer(-2, 2)) * 0.5;
  // Often keep some points still, or merge two of them (zero-length edge / repeated corner).
  if (integer(0, 2) == 0) {
    for (int i = 0; i < 4; ++i) {
      if (integer(0, 1) == 0) q.points[static_cast<std::size_t>(i) + 4] = q.points[static_cast<std::size_t>(i)];
    }
  }
  if (integer(0, 3) == 0) {
    const auto i = static_cast<std::size_t>(integer(1, 3));
    q.points[i] = q.points[i - 1];
    q.points[i + 4] = q.points[i + 3];
  }
  return q;
}

// A contact built at (t*, u, v), then one coordinate nudged.
RandomQuery RandomQueryGenerator::contact_query(bool nudge_ulps) {
  RandomQuery q;
  q.vertex_face = integer(0, 1) == 0;
  q.kind = nudge_ulps ? "contact+ulps" : "contact+relative";
  for (auto& p : q.points) p = point(1.0);
  // Time of contact: often exactly 0 or 1.
  const int tk = integer(0, 9);
  const double t = tk == 0 ? 0.0 : (tk == 1 ? 1.0 : uniform(0.0, 1.0));
  // Parameters: often on an edge or a corner.
  double u = uniform(0, 1), v = uniform(0, 1);
  switch (integer(0, 5)) {
    case 0: u = 0; break;
    case 1: v = 0; break;
    case 2: u = 0; v = 0; break;
    case 3: if (q.vertex_face) { v = 1 - u; } else { u = 1; } break;
    default: break;
  }
  if (q.vertex_face && u + v > 1) {
    u = 1 - u;
    v = 1 - v;
  }
  const auto at = [&](std::size_t i) { return V((1 - t) * q.points[i] + t * q.points[i + 4]); };
  if (q.vertex_face) {
    const V a = at(1), b = at(2), c = at(3);
    const V x = a + u * (b - a) + v * (c - a);
    // Move the vertex so that it is at x at time t.
    if (t == 0) {
      q.points[0] = x;
    } else {
      q.points[4] = q.points[0] + (x - q.points[0]) / t;
    }
  } else {
    const V xa = at(0) + u * (at(1) - at(0));
    const V xb = at(2) + v * (at(3) - at(2));
    const V shift = xa - xb;
    // Translate edge b (both ends, at the time that moves it to contact).
    if (t == 0) {
      q.points[2] += shift;
      q.points[3] += shift;
    } else {
      q.points[6] += shift / t;
      q.points[7] += shift / t;
    }
  }
  // Nudge one coordinate: a few ulps, or by 10^-k relative.
  auto& p = q.points[static_cast<std::size_t>(integer(0, 7))];
  double& x = p[integer(0, 2)];
  if (nudge_ulps) {
    const int steps = integer(-4, 4);
    for (int i = 0; i < std::abs(steps); ++i) x = std::nextafter(x, steps > 0 ? 10.0 : -10.0);
  } else {
    x += (integer(0, 1) == 0 ? 1.0 : -1.0) * std::pow(10.0, -integer(6, 15));
  }
  return q;
}

RandomQuery RandomQueryGenerator::coplanar_query() {
  // Everything in the plane z = alpha x + beta y (dyadic slopes keep it nearly exact), with contacts
  // arranged half of the time.
  RandomQuery q = integer(0, 1) == 0 ? contact_query(true) : uniform_query();
  q.kind = "coplanar";
  const double alpha = integer(-4, 4) / 4.0, beta = integer(-4, 4) / 4.0;
  for (auto& p : q.points) p.z() = alpha * p.x() + beta * p.y();
  return q;
}

void RandomQueryGenerator::scale_and_translate(RandomQuery& q) {
  const double s = std::pow(10.0, integer(-6, 6));
  const V shift = integer(0, 1) == 0 ? V::Zero() : V(point(1.0) * std::pow(10.0, integer(0, 6)));
  for (auto& p : q.points) p = p * s + shift;
}

RandomQuery RandomQueryGenerator::next() {
  RandomQuery q;
  switch (integer(0, 5)) {
    case 0: q = uniform_query(); break;
    case 1: q = grid_query(); break;
    case 2: q = contact_query(true); break;
    case 3: q = contact_query(false); break;
    default: q = coplanar_query(); break;
  }
  if (integer(0, 2) == 0) scale_and_translate(q);
  return q;
}

}  // namespace skelcd::ccd::test
