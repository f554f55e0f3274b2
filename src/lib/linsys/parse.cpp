// Recursive-descent parser for rational expressions in s or z with delays.
#include "linsys/parse.hpp"

#include "common/error.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>

namespace mcg::linsys {

namespace {

/// A rational function num/den times e^(−s·delay).
struct Value {
  Poly num{1.0};
  Poly den{1.0};
  double delay_s = 0.0;
};

Value constant(double c) {
  Value v;
  v.num = trim(Poly{c});
  return v;
}

/// Caps a single `^n`; the degree it makes is bounded by k_max_degree on its own.
constexpr int k_max_exponent = 64;

bool same_poly(const Poly& a, const Poly& b) { return trim(a) == trim(b); }

class Parser {
 public:
  Parser(std::string_view text, const std::string& where) : m_text(text), m_where(where) {}

  ParsedTf parse() {
    if (m_text.size() > k_max_tf_chars) {
      fail("{}: expression of {} characters above the limit of {}", m_where, m_text.size(), k_max_tf_chars);
    }
    skip_blanks();
    if (m_pos >= m_text.size()) error_at(m_pos, "empty expression");
    Value v = expr();
    skip_blanks();
    if (m_pos < m_text.size()) {
      if (m_text[m_pos] == ')') error_at(m_pos, "unexpected ')'");
      error_at(m_pos, fmt::format("unexpected {}", quote(m_text[m_pos])));
    }
    if (is_zero(v.num)) {
      Tf zero;
      zero.num = {};
      return ParsedTf{zero, m_domain};
    }
    if (v.delay_s < 0.0) fail("{}: negative delay {} s (a prediction) is not causal", m_where, -v.delay_s);
    Tf tf;
    tf.num = v.num;
    tf.den = v.den;
    tf.delay_s = v.delay_s;
    if (m_domain) tf.domain = *m_domain;
    if (tf.domain == Domain::z && v.delay_s != 0.0) fail("{}: exp() delays are for s; in z write z^-k", m_where);
    return ParsedTf{cancel_origin(tf), m_domain};
  }

 private:
  [[noreturn]] void error_at(std::size_t pos, const std::string& what) const {
    fail("{}: {} at character {}", m_where, what, pos + 1);
  }

  /// The bounds every intermediate result keeps: degrees within k_max_degree (so that nested
  /// powers cannot grow without end) and finite coefficients and delay.
  Value checked(Value v, std::size_t at) const {
    const int n = std::max(degree(trim(v.num)), degree(trim(v.den)));
    if (n > k_max_degree) error_at(at, fmt::format("degree {} above the limit of {}", n, k_max_degree));
    auto finite = [](const Poly& p) {
      return std::all_of(p.begin(), p.end(), [](double c) { return std::isfinite(c); });
    };
    if (!finite(v.num) || !finite(v.den) || !std::isfinite(v.delay_s)) error_at(at, "number out of range");
    return v;
  }

  void skip_blanks() {
    while (m_pos < m_text.size() && std::isspace(static_cast<unsigned char>(m_text[m_pos]))) ++m_pos;
  }

  bool accept(char c) {
    skip_blanks();
    if (m_pos < m_text.size() && m_text[m_pos] == c) {
      ++m_pos;
      return true;
    }
    return false;
  }

  Value expr() {
    Value acc = term();
    for (;;) {
      skip_blanks();
      const std::size_t at = m_pos;
      if (accept('+')) {
        acc = checked(sum(acc, term(), 1.0, at), at);
      } else if (accept('-')) {
        acc = checked(sum(acc, term(), -1.0, at), at);
      } else {
        return acc;
      }
    }
  }

  Value sum(const Value& a, const Value& b, double sign, std::size_t at) const {
    const bool a_zero = is_zero(a.num);
    const bool b_zero = is_zero(b.num);
    if (!a_zero && !b_zero && a.delay_s != b.delay_s) error_at(at, "terms with different delays added");
    Value r;
    r.delay_s = a_zero ? b.delay_s : a.delay_s;
    if (same_poly(a.den, b.den)) {
      r.num = add(a.num, scale(b.num, sign));
      r.den = a.den;
    } else {
      r.num = add(mul(a.num, b.den), scale(mul(b.num, a.den), sign));
      r.den = mul(a.den, b.den);
    }
    if (is_zero(r.num)) r.den = {1.0};
    return r;
  }

  /// A factor written right after another without '*' (`2s`, `2(s+1)`, `(s+1)(s+2)`) starts with
  /// '(' or a letter. A number never does: `2 3` or `s 2` would be a guess, so they stay errors.
  bool juxtaposed_factor_follows() {
    skip_blanks();
    if (m_pos >= m_text.size()) return false;
    const char c = m_text[m_pos];
    return c == '(' || std::isalpha(static_cast<unsigned char>(c)) || c == '_';
  }

  Value term() {
    Value acc = factor();
    bool divided = false;
    for (;;) {
      skip_blanks();
      const std::size_t at = m_pos;
      if (accept('*')) {
        const Value b = factor();
        acc.num = mul(acc.num, b.num);
        acc.den = mul(acc.den, b.den);
        acc.delay_s += b.delay_s;
      } else if (accept('/')) {
        const Value b = factor();
        if (is_zero(b.num)) error_at(at, "division by zero");
        acc.num = mul(acc.num, b.den);
        acc.den = mul(acc.den, b.num);
        acc.delay_s -= b.delay_s;
        divided = true;
      } else if (juxtaposed_factor_follows()) {
        // `1/2s` reads as 1/(2s) to some and (1/2)s to others: refuse rather than pick one.
        if (divided) error_at(at, "implicit multiplication after '/' is ambiguous (write '*' or parentheses)");
        const Value b = power();
        acc.num = mul(acc.num, b.num);
        acc.den = mul(acc.den, b.den);
        acc.delay_s += b.delay_s;
      } else {
        return reduce(acc);
      }
      acc = checked(reduce(acc), at);
    }
  }

  static Value reduce(Value v) {
    if (is_zero(v.num)) {
      v.den = {1.0};
      return v;
    }
    const int k = std::min(zeros_at_origin(v.num), zeros_at_origin(v.den));
    if (k > 0) {
      v.num = drop_origin(v.num, k);
      v.den = drop_origin(v.den, k);
    }
    return v;
  }

  /// Signs are counted in a loop, not by recursion: a chain of 10^5 of them costs no stack.
  Value factor() {
    bool negative = false;
    for (;;) {
      if (accept('-')) {
        negative = !negative;
      } else if (!accept('+')) {
        break;
      }
    }
    Value v = power();
    if (negative) v.num = scale(v.num, -1.0);
    return v;
  }

  Value power() {
    Value base = atom();
    skip_blanks();
    const std::size_t at = m_pos;
    if (!accept('^')) return base;
    skip_blanks();
    bool negative = false;
    if (accept('-')) {
      negative = true;
    } else {
      accept('+');
    }
    skip_blanks();
    const std::size_t start = m_pos;
    while (m_pos < m_text.size() && std::isdigit(static_cast<unsigned char>(m_text[m_pos]))) ++m_pos;
    if (start == m_pos) error_at(start, "expected a whole-number exponent");
    if (m_pos < m_text.size() && (m_text[m_pos] == '.' || m_text[m_pos] == 'e' || m_text[m_pos] == 'E')) {
      error_at(start, "expected a whole-number exponent");
    }
    int n = 0;
    const auto [end, ec] = std::from_chars(m_text.data() + start, m_text.data() + m_pos, n);
    if (ec != std::errc() || end != m_text.data() + m_pos || n > k_max_exponent) {
      error_at(start, fmt::format("exponent too large (at most {})", k_max_exponent));
    }
    if (negative && is_zero(base.num)) error_at(at, "division by zero");
    const int base_degree = std::max(degree(trim(base.num)), degree(trim(base.den)));
    if (base_degree * n > k_max_degree) {
      error_at(at, fmt::format("degree {} above the limit of {}", base_degree * n, k_max_degree));
    }
    Value r;
    for (int i = 0; i < n; ++i) {
      r.num = mul(r.num, base.num);
      r.den = mul(r.den, base.den);
      r.delay_s += base.delay_s;
    }
    if (negative) {
      std::swap(r.num, r.den);
      r.delay_s = -r.delay_s;
    }
    return checked(reduce(r), at);
  }

  void set_domain(Domain d, std::size_t at) {
    if (m_domain && *m_domain != d) error_at(at, "s and z mixed");
    m_domain = d;
  }

  Value atom() {
    skip_blanks();
    if (m_pos >= m_text.size()) error_at(m_pos, "unexpected end of expression");
    const char c = m_text[m_pos];
    const std::size_t at = m_pos;
    if (c == '(') {
      ++m_pos;
      const Nest nest(*this, at);
      Value v = expr();
      skip_blanks();
      if (!accept(')')) {
        if (m_pos >= m_text.size()) error_at(at, "unbalanced '('");
        error_at(m_pos, fmt::format("unexpected {}", quote(m_text[m_pos])));
      }
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t end = m_pos;
      while (end < m_text.size() &&
             (std::isalnum(static_cast<unsigned char>(m_text[end])) || m_text[end] == '_')) {
        ++end;
      }
      const std::string_view name = m_text.substr(m_pos, end - m_pos);
      m_pos = end;
      if (name == "s" || name == "S" || name == "z" || name == "Z") {
        set_domain(name == "s" || name == "S" ? Domain::s : Domain::z, at);
        Value v;
        v.num = {1.0, 0.0};
        return v;
      }
      if (name == "exp") return exponential(at);
      error_at(at, fmt::format("unknown symbol {}", quote(name)));
    }
    if (c == ')') error_at(at, "unexpected ')'");
    error_at(at, fmt::format("unexpected {}", quote(c)));
  }

  Value exponential(std::size_t at) {
    skip_blanks();
    if (!accept('(')) error_at(m_pos, "expected '(' after exp");
    const std::size_t open = m_pos - 1;
    const Nest nest(*this, open);
    const Value arg = expr();
    skip_blanks();
    if (!accept(')')) {
      if (m_pos >= m_text.size()) error_at(open, "unbalanced '('");
      error_at(m_pos, fmt::format("unexpected {}", quote(m_text[m_pos])));
    }
    const Poly den = trim(arg.den);
    const Poly num = trim(arg.num);
    if (arg.delay_s != 0.0 || den.size() != 1 || num.size() > 2) {
      error_at(at, "exp() takes c - tau*s (a delay)");
    }
    if (num.size() == 2 && m_domain == Domain::z) error_at(at, "exp() delays are for s; in z write z^-k");
    const double slope = num.size() == 2 ? num[0] / den[0] : 0.0;
    const double offset = num.empty() ? 0.0 : num.back() / den[0];
    Value v = constant(std::exp(offset));
    v.delay_s = -slope;
    return checked(v, at);
  }

  Value number() {
    const std::size_t start = m_pos;
    double value = 0.0;
    const char* first = m_text.data() + m_pos;
    const char* last = m_text.data() + m_text.size();
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec == std::errc::result_out_of_range) error_at(start, "number out of range");
    if (ec != std::errc() || ptr == first) error_at(start, "invalid number");
    m_pos = static_cast<std::size_t>(ptr - m_text.data());
    if (!std::isfinite(value)) error_at(start, "number out of range");
    return constant(value);
  }

  /// One level of '(' (or exp's): every level is a few frames of recursion, so the depth is
  /// capped well inside the smallest stack the tools run on (a sanitizer's too).
  class Nest {
   public:
    Nest(Parser& p, std::size_t at) : m_parser(p) {
      if (++m_parser.m_depth > k_max_tf_depth) {
        m_parser.error_at(at, fmt::format("parentheses nested deeper than {}", k_max_tf_depth));
      }
    }
    ~Nest() { --m_parser.m_depth; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;

   private:
    Parser& m_parser;
  };

  std::string_view m_text;
  std::string m_where;
  std::size_t m_pos = 0;
  int m_depth = 0;
  std::optional<Domain> m_domain;
};

}  // namespace

ParsedTf parse_tf(std::string_view text, const std::string& where) { return Parser(text, where).parse(); }

}  // namespace mcg::linsys
