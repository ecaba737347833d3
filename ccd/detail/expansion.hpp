#pragma once
// Exact sums and products of doubles as floating-point expansions (Shewchuk, "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997): a value is the exact sum
// of a few doubles, nonoverlapping and ordered by increasing magnitude, so its sign is the sign of
// its last (largest) component. Every step is an error-free transformation (two-sum, Dekker's
// two-product), so results are exact — no rounding, no gcd, no allocation for small expressions.
//
// This is the middle stage of exact_sign (filtered.hpp): the filtered double decides generic
// inputs; an expansion decides what the filter cannot — above all the exact zeros of coplanar and
// collinear corners on real meshes, which the filter can never certify; GMP rationals remain for
// inputs where a product could underflow or overflow (then an error term would not be exact).

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>

namespace skelcd::ccd::detail {

/// The steps of an expansion on plain arrays (components by increasing magnitude, zeros
/// dropped): Expansion's arithmetic and the fixed-size triple_product_sign below share them.
namespace expansion_steps {

/// |leaf| in [2^-300, 2^300]: the expressions of this library multiply at most a few differences
/// of leaves, and every product is checked again (two_product).
inline constexpr double kLeafMin = 0x1p-300;
inline constexpr double kLeafMax = 0x1p+300;
/// Dekker's two-product is exact when the product stays within these bounds (the split halves and
/// the error term neither underflow nor overflow).
inline constexpr double kProductMin = 0x1p-800;
inline constexpr double kProductMax = 0x1p+900;
inline constexpr double kSplitter = 134217729.0;  // 2^27 + 1

/// A nonzero leaf outside [kLeafMin, kLeafMax] (or not finite): products of a few of them would
/// leave the range where two-product is exact.
[[nodiscard]] inline bool unsafe_leaf(double x) {
  const double m = std::abs(x);
  return x != 0.0 && !(m >= kLeafMin && m <= kLeafMax);
}

/// x + y = a + b exactly, x = fl(a + b).
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a;
  const double av = x - bv;
  y = (a - av) + (b - bv);
}

inline void split(double a, double& hi, double& lo) {
  const double c = kSplitter * a;
  hi = c - (c - a);
  lo = a - hi;
}

/// x + y = a * b exactly, x = fl(a * b), unless `unsafe` is raised (a, b nonzero).
inline void two_product(double a, double b, double& x, double& y, bool& unsafe) {
  x = a * b;
  const double m = std::abs(x);
  if (!(m >= kProductMin && m <= kProductMax)) unsafe = true;
  double ahi, alo, bhi, blo;
  split(a, ahi, alo);
  split(b, bhi, blo);
  y = alo * blo - (((x - ahi * bhi) - alo * bhi) - ahi * blo);
}

/// h = e + s f (s = ±1; e of m components, f of n, both nonzero), merged by increasing magnitude,
/// zero components dropped (Shewchuk's fast expansion sum, with two-sum in every step); h holds
/// m + n. Returns the components written.
inline int sum_into(const double* e, int m, const double* f, int n, double s, double* h) {
  int i = 0;
  int j = 0;
  int k = 0;
  const auto next = [&]() {  // the smaller-magnitude of the two heads
    if (j >= n || (i < m && std::abs(e[i]) <= std::abs(f[j]))) return e[i++];
    return s * f[j++];
  };
  double q = next();
  while (i < m || j < n) {
    double qn, hh;
    two_sum(q, next(), qn, hh);
    q = qn;
    if (hh != 0.0) h[k++] = hh;
  }
  if (q != 0.0 || k == 0) h[k++] = q;
  if (k == 1 && h[0] == 0.0) k = 0;
  return k;
}

/// h = e b (e of m > 0 components, b nonzero; Shewchuk's scale expansion, zero components
/// dropped); h holds 2 m. Returns the components written; raises `unsafe` as two_product.
inline int scale_into(const double* e, int m, double b, double* h, bool& unsafe) {
  int k = 0;
  double q, hh;
  two_product(e[0], b, q, hh, unsafe);
  if (hh != 0.0) h[k++] = hh;
  for (int i = 1; i < m; ++i) {
    double p1, p0, s;
    two_product(e[i], b, p1, p0, unsafe);
    two_sum(q, p0, s, hh);
    if (hh != 0.0) h[k++] = hh;
    two_sum(p1, s, q, hh);
    if (hh != 0.0) h[k++] = hh;
  }
  if (q != 0.0 || k == 0) h[k++] = q;
  if (k == 1 && h[0] == 0.0) k = 0;
  return k;
}

/// e + s f for any m, n (either may be 0).
inline int add_into(const double* e, int m, const double* f, int n, double s, double* h) {
  if (n == 0) {
    for (int i = 0; i < m; ++i) h[i] = e[i];
    return m;
  }
  if (m == 0) {
    for (int j = 0; j < n; ++j) h[j] = s * f[j];
    return n;
  }
  return sum_into(e, m, f, n, s, h);
}

/// The sign of an expansion of n components (its largest, the last; 0 when n is 0).
[[nodiscard]] inline int sign_of(const double* e, int n) {
  if (n == 0) return 0;
    // e[0 .. n) was written by the step that returned n; GCC cannot see it through the calls.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  const double top = e[n - 1];
#pragma GCC diagnostic pop
  return (top > 0.0) - (top < 0.0);
}

}  // namespace expansion_steps

/// h = e f (e of m > 0 components, f of n > 0, nonzero; each of f's components times e, summed):
/// at most 2 m n components, which h holds; `scratch` holds 2 m (n + 1) ≤ 4 m n. Raises `unsafe`
/// as two_product.
inline int product_into(
    const double* e, int m, const double* f, int n, double* h, double* scratch, bool& unsafe) {
  using namespace expansion_steps;
  int size = scale_into(e, m, f[0], h, unsafe);
  double* const term = scratch;
  double* const acc = scratch + 2 * m;
  for (int j = 1; j < n; ++j) {
    const int t = scale_into(e, m, f[j], term, unsafe);
    const int a = add_into(h, size, term, t, 1.0, acc);
    for (int i = 0; i < a; ++i) h[i] = acc[i];
    size = a;
  }
  return size;
}

/// A coordinate difference x − y as an expansion of at most two components (Knuth's
/// two-difference: exact, zeros dropped).
struct Difference {
  double c[2];
  int n = 0;
};
[[nodiscard]] inline Difference difference(double x, double y) {
  Difference d;
  double hi, lo;
  expansion_steps::two_sum(x, -y, hi, lo);
  if (lo != 0.0) d.c[d.n++] = lo;
  if (hi != 0.0) d.c[d.n++] = hi;
  return d;
}

/// The sign of (u × v) · w computed exactly as an expansion on fixed arrays (no allocation), for
/// vectors whose coordinates are expansions of at most two components (differences of
/// coordinates; one component where the difference is exact) — at most 192 components, which an
/// Expansion would build on the heap. Raises `unsafe` (the sign is then meaningless) where a
/// product leaves two-product's exact range (expansion_steps::two_product); the callers check the
/// leaves as Expansion does.
[[nodiscard]] inline int triple_product_sign(
    const Difference* u, const Difference* v, const Difference* w, bool& unsafe) {
  using namespace expansion_steps;
  // (u × v)_k = u_i v_j − u_j v_i (i = k + 1, j = k + 2): up to 8 + 8 components; times w_k.
  double terms[3][64];
  int sizes[3];
  double scratch[128];  // product_into's 2 m (n + 1) for the largest product, 16 components by 2
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3;
    const int j = (k + 2) % 3;
    double left[8], right[8], cross[16];
    const int nl = u[i].n != 0 && v[j].n != 0
                       ? product_into(u[i].c, u[i].n, v[j].c, v[j].n, left, scratch, unsafe)
                       : 0;
    const int nr = u[j].n != 0 && v[i].n != 0
                       ? product_into(u[j].c, u[j].n, v[i].c, v[i].n, right, scratch, unsafe)
                       : 0;
    const int nc = add_into(left, nl, right, nr, -1.0, cross);
    sizes[k] = nc != 0 && w[k].n != 0
                   ? product_into(cross, nc, w[k].c, w[k].n, terms[k], scratch, unsafe)
                   : 0;
  }
  double pair[128];
  double all[192];
  const int np = add_into(terms[0], sizes[0], terms[1], sizes[1], 1.0, pair);
  const int n = add_into(pair, np, terms[2], sizes[2], 1.0, all);
  return sign_of(all, n);
}

/// The sign of bx cy − by cx, exactly, for coordinates that are expansions of at most two
/// components (differences of coordinates), on fixed arrays: at most 16 components. Raises
/// `unsafe` as triple_product_sign.
[[nodiscard]] inline int cross2_sign(
    const Difference& bx,
    const Difference& by,
    const Difference& cx,
    const Difference& cy,
    bool& unsafe) {
  using namespace expansion_steps;
  double left[8], right[8], all[16], scratch[16];
  const int nl =
      bx.n != 0 && cy.n != 0 ? product_into(bx.c, bx.n, cy.c, cy.n, left, scratch, unsafe) : 0;
  const int nr =
      by.n != 0 && cx.n != 0 ? product_into(by.c, by.n, cx.c, cx.n, right, scratch, unsafe) : 0;
  return sign_of(all, add_into(left, nl, right, nr, -1.0, all));
}

class Expansion {
 public:
  Expansion() = default;

  /// The exact value x. Leaves far from 1 in magnitude are flagged unsafe up front: products of a
  /// few of them would leave the range where two-product is exact.
  explicit Expansion(double x) {
    if (x == 0.0) return;
    unsafe_ = expansion_steps::unsafe_leaf(x);  // also catches NaN and infinities
    data()[0] = x;
    size_ = 1;
  }

  Expansion(const Expansion& other) { copy_from(other); }
  Expansion& operator=(const Expansion& other) {
    if (this != &other) copy_from(other);
    return *this;
  }
  Expansion(Expansion&& other) noexcept { move_from(std::move(other)); }
  Expansion& operator=(Expansion&& other) noexcept {
    if (this != &other) move_from(std::move(other));
    return *this;
  }
  ~Expansion() = default;

  /// -1, 0 or 1: the sign of the largest component (meaningful only when !unsafe()).
  [[nodiscard]] int sign() const {
    if (size_ == 0) return 0;
    const double top = data()[size_ - 1];
    return (top > 0.0) - (top < 0.0);
  }
  /// True when some step may have underflowed or overflowed: the value may not be exact.
  [[nodiscard]] bool unsafe() const { return unsafe_; }
  [[nodiscard]] int size() const { return size_; }

  friend Expansion operator+(const Expansion& e, const Expansion& f) { return sum(e, f, false); }
  friend Expansion operator-(const Expansion& e, const Expansion& f) { return sum(e, f, true); }
  friend Expansion operator*(const Expansion& e, const Expansion& f) {
    if (e.size_ == 0 || f.size_ == 0) return flagged(e.unsafe_ || f.unsafe_);
    const Expansion& longer = e.size_ >= f.size_ ? e : f;
    const Expansion& shorter = e.size_ >= f.size_ ? f : e;
    Expansion product = scale(longer, shorter.data()[0]);
    for (int i = 1; i < shorter.size_; ++i) product = product + scale(longer, shorter.data()[i]);
    product.unsafe_ = product.unsafe_ || e.unsafe_ || f.unsafe_;
    return product;
  }

 private:
  static constexpr int kInline = 16;

  double inline_[kInline];  // the first kInline components live here (size_ of them are set)
  std::unique_ptr<double[]> heap_;
  int size_ = 0;
  int capacity_ = kInline;
  bool unsafe_ = false;

  double* data() { return heap_ ? heap_.get() : inline_; }
  [[nodiscard]] const double* data() const { return heap_ ? heap_.get() : inline_; }

  static Expansion flagged(bool unsafe) {
    Expansion z;
    z.unsafe_ = unsafe;
    return z;
  }

  static Expansion with_capacity(int n) {
    Expansion r;
    if (n > kInline) {
      r.heap_ = std::make_unique<double[]>(static_cast<std::size_t>(n));
      r.capacity_ = n;
    }
    return r;
  }

  void copy_from(const Expansion& other) {
    if (other.size_ > capacity_) {
      heap_ = std::make_unique<double[]>(static_cast<std::size_t>(other.size_));
      capacity_ = other.size_;
    }
    if (other.size_ > 0) {
      std::memcpy(data(), other.data(), sizeof(double) * static_cast<std::size_t>(other.size_));
    }
    size_ = other.size_;
    unsafe_ = other.unsafe_;
  }

  void move_from(Expansion&& other) {
    if (other.heap_) {
      heap_ = std::move(other.heap_);
      capacity_ = other.capacity_;
      size_ = other.size_;
      unsafe_ = other.unsafe_;
      other.capacity_ = kInline;
      other.size_ = 0;
      return;
    }
    copy_from(other);
  }

  // e + (negate ? -f : f) (expansion_steps::sum_into).
  static Expansion sum(const Expansion& e, const Expansion& f, bool negate) {
    const int m = e.size_;
    const int n = f.size_;
    Expansion r = with_capacity(m + n);
    r.unsafe_ = e.unsafe_ || f.unsafe_;
    r.size_ = expansion_steps::add_into(e.data(), m, f.data(), n, negate ? -1.0 : 1.0, r.data());
    return r;
  }

  // e * b for a double b (expansion_steps::scale_into).
  static Expansion scale(const Expansion& e, double b) {
    const int m = e.size_;
    Expansion r = with_capacity(2 * m);
    if (b == 0.0 || m == 0) return r;
    bool unsafe = false;
    r.size_ = expansion_steps::scale_into(e.data(), m, b, r.data(), unsafe);
    r.unsafe_ = unsafe || !std::isfinite(b);
    return r;
  }
};

}  // namespace skelcd::ccd::detail
