#include "ccd/detail/rational_polynomial.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

namespace skelcd::ccd::detail {
namespace {

int sign_of(const mpq_class& x) {
  const int s = mpq_sgn(x.get_mpq_t());
  return (s > 0) - (s < 0);
}

// C(i,k)/C(n,k), the power-to-Bernstein weights, for n <= 8.
const mpq_class& bernstein_weight(int n, int i, int k) {
  static const auto table = [] {
    std::vector<mpq_class> t(9 * 9 * 9);
    for (int nn = 0; nn <= 8; ++nn) {
      for (int ii = 0; ii <= nn; ++ii) {
        for (int kk = 0; kk <= ii; ++kk) {
          mpz_class a, b;
          mpz_bin_uiui(a.get_mpz_t(), static_cast<unsigned long>(ii), static_cast<unsigned long>(kk));
          mpz_bin_uiui(b.get_mpz_t(), static_cast<unsigned long>(nn), static_cast<unsigned long>(kk));
          t[static_cast<std::size_t>((nn * 9 + ii) * 9 + kk)] = mpq_class(a, b);
        }
      }
    }
    for (auto& x : t) x.canonicalize();
    return t;
  }();
  assert(n <= 8);
  return table[static_cast<std::size_t>((n * 9 + i) * 9 + k)];
}

// Interval arithmetic on doubles, rounded outward: after each rounded operation the bounds move
// one ulp out, so [lo, hi] always contains the exact result (no directed rounding mode needed).
struct Interval {
  double lo, hi;
};

double down(double x) { return std::nextafter(x, -std::numeric_limits<double>::infinity()); }
double up(double x) { return std::nextafter(x, std::numeric_limits<double>::infinity()); }

Interval add(const Interval& a, const Interval& b) { return {down(a.lo + b.lo), up(a.hi + b.hi)}; }

Interval mul(const Interval& a, const Interval& b) {
  const double p1 = a.lo * b.lo, p2 = a.lo * b.hi, p3 = a.hi * b.lo, p4 = a.hi * b.hi;
  if (std::isnan(p1) || std::isnan(p2) || std::isnan(p3) || std::isnan(p4)) {
    return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  }
  return {down(std::min({p1, p2, p3, p4})), up(std::max({p1, p2, p3, p4}))};
}

// Largest double <= q and smallest double >= q.
std::pair<double, double> bracket(const mpq_class& q) {
  double d = q.get_d();  // rounds toward zero
  if (!std::isfinite(d)) return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  const int c = cmp(q, d);
  if (c == 0) return {d, d};
  return c > 0 ? std::pair{d, up(d)} : std::pair{down(d), d};
}

// The Sturm sequence f, f', -rem(f, f'), ... of a square-free f.
std::vector<RationalPolynomial> sturm_sequence(const RationalPolynomial& f) {
  std::vector<RationalPolynomial> seq{f, f.derivative()};
  while (!seq.back().is_zero()) {
    const auto& a = seq[seq.size() - 2];
    const auto& b = seq.back();
    seq.push_back(-remainder(a, b));
  }
  seq.pop_back();
  return seq;
}

// Number of sign changes in the Sturm sequence at x, zeros dropped.
int sign_changes(const std::vector<RationalPolynomial>& seq, const mpq_class& x) {
  int changes = 0;
  int last = 0;
  for (const auto& p : seq) {
    const int s = p.sign_at(x);
    if (s == 0) continue;
    if (last != 0 && s != last) ++changes;
    last = s;
  }
  return changes;
}

// Sturm's theorem: number of distinct roots of a square-free f in the half-open (lo, hi].
int roots_in(const std::vector<RationalPolynomial>& seq, const mpq_class& lo, const mpq_class& hi) {
  return sign_changes(seq, lo) - sign_changes(seq, hi);
}

void isolate(const RationalPolynomial& f,
             const std::vector<RationalPolynomial>& seq,
             const mpq_class& lo,
             const mpq_class& hi,
             std::vector<RealRoot>& out) {
  const int n = roots_in(seq, lo, hi);
  if (n == 0) return;
  if (n == 1) {
    if (f.sign_at(hi) == 0) {
      out.push_back({true, hi, hi});
      return;
    }
    // The root is inside (lo, hi); it is isolated once lo is not itself a root (a root at lo
    // belongs to the interval on the left).
    if (f.sign_at(lo) != 0) {
      out.push_back({false, lo, hi});
      return;
    }
  }
  const mpq_class mid = (lo + hi) / 2;
  isolate(f, seq, lo, mid, out);
  isolate(f, seq, mid, hi, out);
}

}  // namespace

RationalPolynomial::RationalPolynomial(std::vector<mpq_class> coefficients) : c_(std::move(coefficients)) {
  trim();
}

RationalPolynomial RationalPolynomial::constant(const mpq_class& c) { return RationalPolynomial({c}); }

RationalPolynomial RationalPolynomial::linear(const mpq_class& c0, const mpq_class& c1) {
  return RationalPolynomial({c0, c1});
}

void RationalPolynomial::trim() {
  while (!c_.empty() && c_.back() == 0) c_.pop_back();
}

mpq_class RationalPolynomial::operator()(const mpq_class& t) const {
  mpq_class r = 0;
  for (auto it = c_.rbegin(); it != c_.rend(); ++it) r = r * t + *it;
  return r;
}

int RationalPolynomial::sign_at(const mpq_class& t) const {
  if (c_.empty()) return 0;
  if (t == 0) return sign_of(c_.front());
  const auto [lo, hi] = bracket(t);
  const int s = certain_sign_on(lo, hi);
  if (s != 0) return s;
  return sign_of((*this)(t));
}

int RationalPolynomial::certain_sign_on(double lo, double hi) const {
  if (c_.empty()) return 0;
  if (bounds_.empty()) {
    bounds_.reserve(c_.size());
    for (const auto& c : c_) bounds_.push_back(bracket(c));
  }
  // Horner on intervals.
  const Interval t{lo, hi};
  Interval r{bounds_.back().first, bounds_.back().second};
  for (std::size_t i = bounds_.size() - 1; i-- > 0;) {
    r = add(mul(r, t), Interval{bounds_[i].first, bounds_[i].second});
  }
  // Comparisons written so that NaN gives "undecided".
  if (r.lo > 0) return 1;
  if (r.hi < 0) return -1;
  return 0;
}

RationalPolynomial RationalPolynomial::derivative() const {
  if (c_.size() <= 1) return {};
  std::vector<mpq_class> d(c_.size() - 1);
  for (std::size_t i = 1; i < c_.size(); ++i) d[i - 1] = c_[i] * static_cast<unsigned long>(i);
  return RationalPolynomial(std::move(d));
}

RationalPolynomial operator+(const RationalPolynomial& a, const RationalPolynomial& b) {
  std::vector<mpq_class> r(std::max(a.c_.size(), b.c_.size()));
  for (std::size_t i = 0; i < a.c_.size(); ++i) r[i] += a.c_[i];
  for (std::size_t i = 0; i < b.c_.size(); ++i) r[i] += b.c_[i];
  return RationalPolynomial(std::move(r));
}

RationalPolynomial operator-(const RationalPolynomial& a, const RationalPolynomial& b) {
  std::vector<mpq_class> r(std::max(a.c_.size(), b.c_.size()));
  for (std::size_t i = 0; i < a.c_.size(); ++i) r[i] += a.c_[i];
  for (std::size_t i = 0; i < b.c_.size(); ++i) r[i] -= b.c_[i];
  return RationalPolynomial(std::move(r));
}

RationalPolynomial operator-(const RationalPolynomial& a) {
  std::vector<mpq_class> r(a.c_.size());
  for (std::size_t i = 0; i < a.c_.size(); ++i) r[i] = -a.c_[i];
  return RationalPolynomial(std::move(r));
}

RationalPolynomial operator*(const RationalPolynomial& a, const RationalPolynomial& b) {
  if (a.c_.empty() || b.c_.empty()) return {};
  std::vector<mpq_class> r(a.c_.size() + b.c_.size() - 1);
  for (std::size_t i = 0; i < a.c_.size(); ++i) {
    if (a.c_[i] == 0) continue;
    for (std::size_t j = 0; j < b.c_.size(); ++j) r[i + j] += a.c_[i] * b.c_[j];
  }
  return RationalPolynomial(std::move(r));
}

namespace {
// Long division a = q b + r.
void divide(const RationalPolynomial& a,
            const RationalPolynomial& b,
            std::vector<mpq_class>& q,
            std::vector<mpq_class>& r) {
  assert(!b.is_zero());
  r = a.coefficients();
  const auto& bc = b.coefficients();
  const std::size_t nb = bc.size();
  q.assign(r.size() >= nb ? r.size() - nb + 1 : 0, mpq_class(0));
  while (r.size() >= nb) {
    const std::size_t shift = r.size() - nb;
    const mpq_class factor = r.back() / bc.back();
    q[shift] = factor;
    for (std::size_t i = 0; i < nb; ++i) r[shift + i] -= factor * bc[i];
    r.pop_back();  // the leading term cancels exactly
    while (!r.empty() && r.back() == 0) r.pop_back();
  }
}
}  // namespace

// Sign of g on the closed [lo, hi] when its Bernstein coefficients there all have one strict sign;
// 0 when they do not (g may or may not vanish in [lo, hi]).
int bernstein_sign(const RationalPolynomial& g, const mpq_class& lo, const mpq_class& hi) {
  if (g.is_zero()) return 0;
  const int n = g.degree();
  // Taylor shift: coefficients of g(lo + x), by repeated synthetic division.
  std::vector<mpq_class> q = g.coefficients();
  for (int i = 0; i < n; ++i) {
    for (int j = n - 1; j >= i; --j) q[static_cast<std::size_t>(j)] += lo * q[static_cast<std::size_t>(j) + 1];
  }
  // Scale x = w s so the interval becomes s in [0,1].
  const mpq_class w = hi - lo;
  mpq_class wk = 1;
  for (int k = 0; k <= n; ++k) {
    q[static_cast<std::size_t>(k)] *= wk;
    wk *= w;
  }
  // Power basis on [0,1] -> Bernstein basis: b_i = sum_{k<=i} C(i,k)/C(n,k) q_k.
  int sign = 0;
  for (int i = 0; i <= n; ++i) {
    mpq_class b = 0;
    for (int k = 0; k <= i; ++k) b += bernstein_weight(n, i, k) * q[static_cast<std::size_t>(k)];
    const int s = sign_of(b);
    if (s == 0) return 0;
    if (sign != 0 && s != sign) return 0;
    sign = s;
  }
  return sign;
}

RationalPolynomial remainder(const RationalPolynomial& a, const RationalPolynomial& b) {
  std::vector<mpq_class> q, r;
  divide(a, b, q, r);
  return RationalPolynomial(std::move(r));
}

RationalPolynomial quotient(const RationalPolynomial& a, const RationalPolynomial& b) {
  std::vector<mpq_class> q, r;
  divide(a, b, q, r);
  return RationalPolynomial(std::move(q));
}

RationalPolynomial gcd(const RationalPolynomial& a, const RationalPolynomial& b) {
  RationalPolynomial x = a;
  RationalPolynomial y = b;
  while (!y.is_zero()) {
    RationalPolynomial r = remainder(x, y);
    x = std::move(y);
    y = std::move(r);
  }
  if (x.is_zero()) return x;
  const mpq_class lead = x.leading();
  std::vector<mpq_class> c = x.coefficients();
  for (auto& ci : c) ci /= lead;
  return RationalPolynomial(std::move(c));
}

RationalPolynomial square_free(const RationalPolynomial& p) {
  if (p.is_zero()) return p;
  const RationalPolynomial g = gcd(p, p.derivative());
  RationalPolynomial s = quotient(p, g);
  const mpq_class lead = s.leading();
  std::vector<mpq_class> c = s.coefficients();
  for (auto& ci : c) ci /= lead;
  return RationalPolynomial(std::move(c));
}

std::vector<RealRoot> isolate_roots_in_unit_interval(const RationalPolynomial& f) {
  assert(!f.is_zero());
  std::vector<RealRoot> out;
  if (f.degree() <= 0) return out;
  const auto& c = f.coefficients();
  const auto in_unit = [](const mpq_class& t) { return t >= 0 && t <= 1; };
  if (f.degree() == 1) {
    // Linear: the root is rational.
    const mpq_class t = -c[0] / c[1];
    if (in_unit(t)) out.push_back({true, t, t});
    return out;
  }
  if (f.degree() == 2) {
    // Quadratic with a rational discriminant root: both roots rational.
    const mpq_class disc = c[1] * c[1] - 4 * c[2] * c[0];
    if (disc > 0 && mpz_perfect_square_p(disc.get_num_mpz_t()) && mpz_perfect_square_p(disc.get_den_mpz_t())) {
      mpz_class num, den;
      mpz_sqrt(num.get_mpz_t(), disc.get_num_mpz_t());
      mpz_sqrt(den.get_mpz_t(), disc.get_den_mpz_t());
      const mpq_class r(num, den);
      mpq_class t1 = (-c[1] - r) / (2 * c[2]);
      mpq_class t2 = (-c[1] + r) / (2 * c[2]);
      t1.canonicalize();
      t2.canonicalize();
      if (t2 < t1) std::swap(t1, t2);
      if (in_unit(t1)) out.push_back({true, t1, t1});
      if (in_unit(t2)) out.push_back({true, t2, t2});
      return out;
    }
  }
  if (f.sign_at(0) == 0) out.push_back({true, 0, 0});
  const auto seq = sturm_sequence(f);
  isolate(f, seq, mpq_class(0), mpq_class(1), out);
  return out;
}

RootPoint::RootPoint(const mpq_class& t) : root_{true, t, t} {
  std::tie(lo_d_, hi_d_) = bracket(t);
}

RootPoint::RootPoint(const RationalPolynomial& f, const RealRoot& root) : f_(f), root_(root) {
  lo_d_ = bracket(root_.lo).first;
  hi_d_ = bracket(root_.hi).second;
  if (!root_.rational) sign_f_lo_ = f_.sign_at(root_.lo);
}

void RootPoint::bisect() {
  assert(!root_.rational);
  const mpq_class mid = (root_.lo + root_.hi) / 2;
  const int s_mid = f_.sign_at(mid);
  if (s_mid == 0) {
    root_ = {true, mid, mid};
    std::tie(lo_d_, hi_d_) = bracket(mid);
    return;
  }
  if (sign_f_lo_ * s_mid < 0) {
    root_.hi = mid;
    hi_d_ = bracket(mid).second;
  } else {
    root_.lo = mid;
    lo_d_ = bracket(mid).first;
    sign_f_lo_ = s_mid;
  }
}

void RootPoint::refine(const mpq_class& width) {
  while (!root_.rational && root_.hi - root_.lo > width) bisect();
}

int RootPoint::sign(const RationalPolynomial& g) {
  if (g.is_zero()) return 0;
  if (root_.rational) return g.sign_at(root_.lo);
  bool zero_excluded = false;
  for (int step = 0;; ++step) {
    // A double-interval evaluation over the whole isolating interval, then the exact test.
    int s = g.certain_sign_on(lo_d_, hi_d_);
    if (s != 0) return s;
    if (step >= 2 && !zero_excluded) {
      // g(t*) = 0 iff t* is a root of h = gcd(f, g). h divides the square-free f, so its roots
      // are simple and t* is its only possible root in (lo, hi): h vanishes at t* iff it changes
      // sign there.
      const RationalPolynomial h = gcd(f_, g);
      if (h.degree() >= 1 && h.sign_at(root_.lo) * h.sign_at(root_.hi) < 0) return 0;
      zero_excluded = true;
    }
    if (zero_excluded) {
      // g(t*) != 0: shrink the interval until g has one strict sign on all of it (its Bernstein
      // coefficients converge to g(t*) as the interval shrinks, so this terminates).
      s = bernstein_sign(g, root_.lo, root_.hi);
      if (s != 0) return s;
    }
    bisect();
    if (root_.rational) return g.sign_at(root_.lo);
  }
}

PolynomialVector operator+(const PolynomialVector& a, const PolynomialVector& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

PolynomialVector operator-(const PolynomialVector& a, const PolynomialVector& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

PolynomialVector cross(const PolynomialVector& a, const PolynomialVector& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

RationalPolynomial dot(const PolynomialVector& a, const PolynomialVector& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

bool is_zero(const PolynomialVector& a) { return a[0].is_zero() && a[1].is_zero() && a[2].is_zero(); }

}  // namespace skelcd::ccd::detail
