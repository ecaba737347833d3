#include "tools/io/ccd_query_file.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <limits>
#include <numeric>
#include <sstream>

#include "ccd/exact_ccd.hpp"
#include "skinning/errors.hpp"

namespace skelcd::tools {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Half an ulp of |v|: the most round-to-nearest can move a number to v.
double half_ulp(double v) {
  const double a = std::abs(v);
  return (std::nextafter(a, std::numeric_limits<double>::infinity()) - a) * 0.5;
}

bool is_power_of_two(std::uint64_t x) { return x != 0 && (x & (x - 1)) == 0; }

// Is digits * 10^shift exactly the double v? `digits` are the mantissa digits as written (the
// decimal point removed), given as two pieces. Decided without big numbers when the significant
// digits fit in 64 bits; otherwise "no" (the safe answer: it only adds a rounding margin).
bool decimal_is_exact(std::string_view int_part, std::string_view frac_part, long shift, double v) {
  std::uint64_t d = 0;
  int significant = 0;
  for (const std::string_view part : {int_part, frac_part}) {
    for (const char c : part) {
      if (significant == 0 && c == '0') continue;
      if (++significant > 19) return false;
      d = d * 10 + static_cast<std::uint64_t>(c - '0');
    }
  }
  if (d == 0) return true;  // zero
  while (shift < 0 && d % 10 == 0) {
    d /= 10;
    ++shift;
  }
  if (shift >= 0) {
    // d * 10^shift = d * 5^shift * 2^shift: exact if d * 5^shift < 2^53.
    for (long i = 0; i < shift; ++i) {
      if (d > (std::uint64_t{1} << 53) / 5) return false;
      d *= 5;
    }
    return d < (std::uint64_t{1} << 53) &&
           std::ldexp(static_cast<double>(d), static_cast<int>(shift)) == std::abs(v);
  }
  // d / 10^k = (d / 5^k) / 2^k: exact if 5^k divides d and the quotient has at most 53 bits.
  const long k = -shift;
  if (k > 27) return false;
  std::uint64_t five = 1;
  for (long i = 0; i < k; ++i) five *= 5;
  if (d % five != 0) return false;
  const std::uint64_t m = d / five;
  return m < (std::uint64_t{1} << 53) &&
         std::ldexp(static_cast<double>(m), static_cast<int>(shift)) == std::abs(v);
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s) {
    if (!is_digit(c)) return false;
  }
  return true;
}

// p/q with p = [+-]digits, q = digits (not zero).
bool parse_rational(
    std::string_view token, double& value, mpq_class* exact, double& rounding, std::string& fault) {
  const auto slash = token.find('/');
  std::string_view num = token.substr(0, slash);
  const std::string_view den = token.substr(slash + 1);
  bool negative = false;
  if (!num.empty() && (num.front() == '+' || num.front() == '-')) {
    negative = num.front() == '-';
    num.remove_prefix(1);
  }
  if (!all_digits(num) || !all_digits(den)) {
    fault = "not a number (expected a decimal or p/q with integer p and q)";
    return false;
  }
  if (den.find_first_not_of('0') == std::string_view::npos) {
    fault = "zero denominator";
    return false;
  }
  // Small p and q are exact doubles, and one IEEE division rounds to nearest.
  std::uint64_t p = 0, q = 0;
  const bool small = num.size() <= 15 && den.size() <= 15 &&
                     std::from_chars(num.data(), num.data() + num.size(), p).ec == std::errc() &&
                     std::from_chars(den.data(), den.data() + den.size(), q).ec == std::errc();
  mpq_class r;
  if (!small || exact != nullptr) {
    r = mpq_class(mpz_class(std::string(num)), mpz_class(std::string(den)));
    r.canonicalize();
    if (negative) r = -r;
  }
  bool exact_double = false;
  if (small) {
    value = static_cast<double>(p) / static_cast<double>(q);
    if (negative) value = -value;
    // p/q is a double iff, in lowest terms, q is a power of two and p has at most 53 bits.
    const std::uint64_t g = std::gcd(p, q);
    exact_double = is_power_of_two(q / g) && p / g < (std::uint64_t{1} << 53);
  } else {
    value = ccd::round_to_nearest(r);
    exact_double = std::isfinite(value) && mpq_class(value) == r;
  }
  if (!std::isfinite(value)) {
    fault = "beyond the range of a double";
    return false;
  }
  // A small p/q (both below 10^15) cannot underflow; a big one can round to zero.
  if (value == 0.0 && !small && sgn(r) != 0) {
    fault = "beyond the range of a double (nonzero, below the smallest subnormal)";
    return false;
  }
  rounding = exact_double ? 0.0 : half_ulp(value);
  if (exact != nullptr) *exact = r;
  return true;
}

// [+-] digits [. digits] [(e|E) [+-] digits], with at least one mantissa digit.
bool parse_decimal(
    std::string_view token, double& value, mpq_class* exact, double& rounding, std::string& fault) {
  const auto not_a_number = [&] {
    fault = "not a number (expected a decimal or p/q with integer p and q)";
    return false;
  };
  std::size_t i = 0;
  bool negative = false;
  if (i < token.size() && (token[i] == '+' || token[i] == '-')) {
    negative = token[i] == '-';
    ++i;
  }
  const std::size_t int_begin = i;
  while (i < token.size() && is_digit(token[i])) ++i;
  const std::string_view int_part = token.substr(int_begin, i - int_begin);
  std::string_view frac_part;
  if (i < token.size() && token[i] == '.') {
    const std::size_t frac_begin = ++i;
    while (i < token.size() && is_digit(token[i])) ++i;
    frac_part = token.substr(frac_begin, i - frac_begin);
  }
  if (int_part.empty() && frac_part.empty()) return not_a_number();
  long exponent = 0;
  if (i < token.size() && (token[i] == 'e' || token[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < token.size() && (token[i] == '+' || token[i] == '-')) {
      exp_negative = token[i] == '-';
      ++i;
    }
    const std::string_view exp_digits = token.substr(i);
    if (!all_digits(exp_digits)) return not_a_number();
    if (exp_digits.size() > 6) {
      fault = "exponent out of range";
      return false;
    }
    std::from_chars(exp_digits.data(), exp_digits.data() + exp_digits.size(), exponent);
    if (exp_negative) exponent = -exponent;
    i = token.size();
  }
  if (i != token.size()) return not_a_number();
  // The nearest double (std::from_chars rounds correctly; it does not take a leading '+').
  const std::string_view unsigned_part =
      token.substr(token.front() == '+' || token.front() == '-' ? 1 : 0);
  const auto [end, ec] =
      std::from_chars(unsigned_part.data(), unsigned_part.data() + unsigned_part.size(), value);
  if (ec != std::errc() || end != unsigned_part.data() + unsigned_part.size() ||
      !std::isfinite(value)) {
    fault = "beyond the range of a double";
    return false;
  }
  if (negative) value = -value;
  const long shift = exponent - static_cast<long>(frac_part.size());
  rounding = decimal_is_exact(int_part, frac_part, shift, value) ? 0.0 : half_ulp(value);
  if (exact != nullptr) {
    // digits * 10^shift, exactly.
    std::string digits(int_part);
    digits.append(frac_part);
    const auto first = digits.find_first_not_of('0');
    if (first == std::string::npos) {
      *exact = 0;
    } else {
      mpq_class r{mpz_class(digits.substr(first))};
      mpz_class power;
      mpz_ui_pow_ui(power.get_mpz_t(), 10, static_cast<unsigned long>(std::labs(shift)));
      if (shift >= 0) {
        r *= power;
      } else {
        r /= power;
      }
      r.canonicalize();
      *exact = negative ? mpq_class(-r) : r;
    }
  }
  return true;
}

std::string quote(std::string_view s) {
  std::string r = "'";
  r.append(s.substr(0, 40));
  if (s.size() > 40) r += "...";
  r += "'";
  return r;
}

}  // namespace

bool parse_ccd_number(
    std::string_view token, double& value, mpq_class* exact, double& rounding, std::string& fault) {
  rounding = 0.0;
  if (token.find('/') != std::string_view::npos)
    return parse_rational(token, value, exact, rounding, fault);
  return parse_decimal(token, value, exact, rounding, fault);
}

std::vector<CcdQueryRecord> parse_ccd_queries(
    std::istream& in, const std::string& name, bool keep_exact) {
  std::vector<CcdQueryRecord> out;
  std::string line;
  std::vector<std::string_view> tokens;
  int line_number = 0;
  const auto fail = [&](const std::string& what) {
    throw InvalidInput(name + ":" + std::to_string(line_number) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++line_number;
    std::string_view text(line);
    if (const auto hash = text.find('#'); hash != std::string_view::npos)
      text = text.substr(0, hash);
    tokens.clear();
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() &&
             (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == ','))
        ++i;
      const std::size_t start = i;
      while (i < text.size() &&
             !(text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == ','))
        ++i;
      if (i > start) tokens.push_back(text.substr(start, i - start));
    }
    if (tokens.empty()) continue;
    CcdQueryRecord r;
    r.line = line_number;
    if (keep_exact) r.exact.resize(24);
    if (tokens[0] == "vf") {
      r.vertex_face = true;
    } else if (tokens[0] == "ee") {
      r.vertex_face = false;
    } else {
      fail("expected 'vf' or 'ee' first, got " + quote(tokens[0]));
    }
    if (tokens.size() != 25 && tokens.size() != 26) {
      fail(
          "expected 24 coordinates and an optional expected result 0/1 after '" +
          std::string(tokens[0]) + "', got " + std::to_string(tokens.size() - 1) + " values");
    }
    std::string fault;
    for (std::size_t k = 0; k < 24; ++k) {
      double rounding = 0.0;
      if (!parse_ccd_number(
              tokens[k + 1],
              r.coordinates[k],
              keep_exact ? &r.exact[k] : nullptr,
              rounding,
              fault)) {
        fail("coordinate " + std::to_string(k + 1) + " " + quote(tokens[k + 1]) + ": " + fault);
      }
      r.rounding = std::max(r.rounding, rounding);
    }
    if (tokens.size() == 26) {
      if (tokens[25] == "0") {
        r.expected = false;
      } else if (tokens[25] == "1") {
        r.expected = true;
      } else {
        fail("expected result must be 0 or 1, got " + quote(tokens[25]));
      }
    }
    out.push_back(std::move(r));
  }
  if (in.bad()) throw IoError(name + ": read error after line " + std::to_string(line_number));
  return out;
}

std::vector<CcdQueryRecord> read_ccd_queries(const std::string& path, bool keep_exact) {
  if (path == "-") return parse_ccd_queries(std::cin, "<stdin>", keep_exact);
  std::ifstream file(path);
  if (!file) throw IoError(path + ": cannot open (no such file or not readable)");
  return parse_ccd_queries(file, path, keep_exact);
}

}  // namespace skelcd::tools
