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

class Expansion {
 public:
  Expansion() = default;

  /// The exact value x. Leaves far from 1 in magnitude are flagged unsafe up front: products of a
  /// few of them would leave the range where two-product is exact.
  explicit Expansion(double x) {
    if (x == 0.0) return;
    const double m = std::abs(x);
    unsafe_ = !(m >= kLeafMin && m <= kLeafMax);  // also catches NaN and infinities
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
  // |leaf| in [2^-300, 2^300]: the expressions of this library multiply at most a few differences
  // of leaves, and every product is checked again below.
  static constexpr double kLeafMin = 0x1p-300;
  static constexpr double kLeafMax = 0x1p+300;
  // Dekker's two-product is exact when the product stays within these bounds (the split halves and
  // the error term neither underflow nor overflow).
  static constexpr double kProductMin = 0x1p-800;
  static constexpr double kProductMax = 0x1p+900;
  static constexpr double kSplitter = 134217729.0;  // 2^27 + 1

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

  // x + y = a + b exactly, x = fl(a + b).
  static void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bv = x - a;
    const double av = x - bv;
    y = (a - av) + (b - bv);
  }

  static void split(double a, double& hi, double& lo) {
    const double c = kSplitter * a;
    hi = c - (c - a);
    lo = a - hi;
  }

  // x + y = a * b exactly, x = fl(a * b), unless `unsafe` is raised.
  static void two_product(double a, double b, double& x, double& y, bool& unsafe) {
    x = a * b;
    const double m = std::abs(x);
    if (!(m >= kProductMin && m <= kProductMax)) unsafe = true;  // a, b nonzero here
    double ahi, alo, bhi, blo;
    split(a, ahi, alo);
    split(b, bhi, blo);
    y = alo * blo - (((x - ahi * bhi) - alo * bhi) - ahi * blo);
  }

  // e + (negate ? -f : f), merged by increasing magnitude, zero components dropped (Shewchuk's
  // fast expansion sum, with two-sum in every step).
  static Expansion sum(const Expansion& e, const Expansion& f, bool negate) {
    const int m = e.size_;
    const int n = f.size_;
    const bool unsafe = e.unsafe_ || f.unsafe_;
    if (n == 0) {
      Expansion r = e;
      r.unsafe_ = unsafe;
      return r;
    }
    const double s = negate ? -1.0 : 1.0;
    if (m == 0) {
      Expansion r = f;
      if (negate) {
        double* d = r.data();
        for (int i = 0; i < n; ++i) d[i] = -d[i];
      }
      r.unsafe_ = unsafe;
      return r;
    }
    Expansion r = with_capacity(m + n);
    r.unsafe_ = unsafe;
    double* h = r.data();
    const double* ed = e.data();
    const double* fd = f.data();
    int i = 0;
    int j = 0;
    int k = 0;
    const auto next = [&]() {  // the smaller-magnitude of the two heads
      if (j >= n || (i < m && std::abs(ed[i]) <= std::abs(fd[j]))) return ed[i++];
      return s * fd[j++];
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
    r.size_ = k;
    return r;
  }

  // e * b for a double b (Shewchuk's scale expansion, zero components dropped).
  static Expansion scale(const Expansion& e, double b) {
    const int m = e.size_;
    Expansion r = with_capacity(2 * m);
    if (b == 0.0 || m == 0) return r;
    double* h = r.data();
    const double* ed = e.data();
    int k = 0;
    bool unsafe = false;
    double q, hh;
    two_product(ed[0], b, q, hh, unsafe);
    if (hh != 0.0) h[k++] = hh;
    for (int i = 1; i < m; ++i) {
      double p1, p0, s;
      two_product(ed[i], b, p1, p0, unsafe);
      two_sum(q, p0, s, hh);
      if (hh != 0.0) h[k++] = hh;
      two_sum(p1, s, q, hh);
      if (hh != 0.0) h[k++] = hh;
    }
    if (q != 0.0 || k == 0) h[k++] = q;
    if (k == 1 && h[0] == 0.0) k = 0;
    r.size_ = k;
    r.unsafe_ = unsafe || !std::isfinite(b);
    return r;
  }
};

}  // namespace skelcd::ccd::detail
