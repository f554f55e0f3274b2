// Transfer functions: arithmetic, text, exact frequency response.
#include "linsys/tf.hpp"

#include "common/error.hpp"
#include "config/ini.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace mcg::linsys {

namespace {

int safe_degree(const Poly& p) { return degree(p); }

}  // namespace

Complex Tf::eval(Complex x) const { return linsys::eval(num, x) / linsys::eval(den, x); }

Complex Tf::freq(double omega_rad_s) const {
  const Complex x = discrete() ? std::polar(1.0, omega_rad_s * dt_s) : Complex(0.0, omega_rad_s);
  return eval(x) * std::polar(1.0, -omega_rad_s * delay_s);
}

bool Tf::proper() const { return safe_degree(num) <= safe_degree(den); }
bool Tf::strictly_proper() const { return safe_degree(num) < safe_degree(den); }

double Tf::dc_gain() const {
  const double x = discrete() ? 1.0 : 0.0;
  const double n = linsys::eval(num, x);
  const double d = linsys::eval(den, x);
  if (d == 0.0) return n == 0.0 ? std::nan("") : std::copysign(INFINITY, n);
  return n / d;
}

const char* var_name(Domain d) { return d == Domain::s ? "s" : "z"; }

Tf series(const Tf& a, const Tf& b) {
  if (a.domain != b.domain) fail("cannot connect a continuous (s) and a discrete (z) transfer function");
  if (a.discrete() && std::abs(a.dt_s - b.dt_s) > 1e-12 * a.dt_s) {
    fail("cannot connect discrete transfer functions with sample periods {} s and {} s", a.dt_s, b.dt_s);
  }
  Tf r = a;
  r.num = mul(a.num, b.num);
  r.den = mul(a.den, b.den);
  r.delay_s = a.delay_s + b.delay_s;
  return cancel_origin(r);
}

Tf scaled(const Tf& g, double k) {
  Tf r = g;
  r.num = scale(g.num, k);
  return r;
}

Tf cancel_origin(Tf g) {
  g.num = trim(g.num);
  g.den = trim(g.den);
  if (g.num.empty()) return g;
  const int k = std::min(zeros_at_origin(g.num), zeros_at_origin(g.den));
  if (k > 0) {
    g.num = drop_origin(g.num, k);
    g.den = drop_origin(g.den, k);
  }
  return g;
}

void check_degree(const Tf& g, const std::string& what) {
  const int n = std::max(degree(trim(g.num)), degree(trim(g.den)));
  if (n > k_max_degree) fail("{}: degree {} above the limit of {}", what, n, k_max_degree);
}

double delay_samples(double delay_s, double dt_s, int room, const std::string& what) {
  const double samples = delay_s / dt_s;
  // The same 1e-9 of a sample as the callers' floor and round: a whole count above room fails.
  if (!std::isfinite(samples) || std::floor(samples + 1e-9) > room) {
    fail("{}: delay {} s is {} samples of {} s; at most {} fit in the degree limit of {}", what,
         config::format_number(delay_s), config::format_number(samples), config::format_number(dt_s),
         std::max(room, 0), k_max_degree);
  }
  return samples;
}

Tf fold_delay(const Tf& g, const std::string& what) {
  if (!g.discrete() || g.delay_s == 0.0) return g;
  const double samples = delay_samples(g.delay_s, g.dt_s, k_max_degree - degree(trim(g.den)), what);
  const double k = std::round(samples);
  if (std::abs(samples - k) > 1e-9 * std::max(1.0, samples)) {
    fail("{}: delay {} s is not a whole number of samples of {} s", what, config::format_number(g.delay_s),
         config::format_number(g.dt_s));
  }
  Tf r = g;
  r.den = mul(g.den, monomial(static_cast<int>(k)));
  r.delay_s = 0.0;
  return r;
}

Tf feedback(const Tf& loop) {
  Tf r = loop;
  r.den = add(loop.den, loop.num);
  return r;
}

Tf pade(double delay_s, int order) {
  // Coefficients of the [n/n] Padé approximant of e^(−x): c_k = (2n−k)! n! / ((2n)! k! (n−k)!).
  Poly num;
  Poly den;
  const int n = order;
  std::vector<double> c(static_cast<std::size_t>(n) + 1);
  c[0] = 1.0;
  for (int k = 1; k <= n; ++k) {
    c[static_cast<std::size_t>(k)] =
        c[static_cast<std::size_t>(k) - 1] * static_cast<double>(n - k + 1) / static_cast<double>((2 * n - k + 1) * k);
  }
  for (int k = n; k >= 0; --k) {
    const double ck = c[static_cast<std::size_t>(k)] * std::pow(delay_s, k);
    num.push_back(k % 2 == 0 ? ck : -ck);
    den.push_back(ck);
  }
  Tf r;
  r.num = trim(num);
  r.den = trim(den);
  return r;
}

std::string poly_text(const Poly& p0, const char* var) {
  const Poly p = trim(p0);
  if (p.empty()) return "0";
  std::string out;
  const int n = static_cast<int>(p.size()) - 1;
  for (int i = 0; i <= n; ++i) {
    const double c = p[static_cast<std::size_t>(i)];
    if (c == 0.0) continue;
    const int power = n - i;
    const double mag = std::abs(c);
    if (out.empty()) {
      if (c < 0.0) out += "-";
    } else {
      out += c < 0.0 ? " - " : " + ";
    }
    const bool unit = mag == 1.0 && power > 0;
    if (!unit) out += config::format_number(mag);
    if (power > 0) {
      if (!unit) out += "*";
      out += var;
      if (power > 1) out += fmt::format("^{}", power);
    }
  }
  return out;
}

std::string tf_text(const Tf& g) {
  const char* var = var_name(g.domain);
  const Poly num = trim(g.num);
  const Poly den = trim(g.den);
  const bool unit_den = den.size() == 1 && den[0] == 1.0;
  std::string out = num.size() <= 1 && unit_den ? poly_text(num, var) : "(" + poly_text(num, var) + ")";
  if (!unit_den) out += "/(" + poly_text(den, var) + ")";
  if (g.delay_s != 0.0) {
    if (g.discrete()) {
      out += fmt::format("*z^-{}", static_cast<long>(std::lround(g.delay_s / g.dt_s)));
    } else {
      out += "*exp(-" + config::format_number(g.delay_s) + "*s)";
    }
  }
  return out;
}

std::string list_text(const std::vector<double>& v) {
  std::string out;
  for (double x : v) {
    if (!out.empty()) out += ' ';
    out += config::format_number(x);
  }
  return out;
}

FreqEval::FreqEval(const Tf& g) : m_tf(g) {
  const Poly num = trim(g.num);
  const Poly den = trim(g.den);
  m_zeros = roots(num);
  m_poles = roots(den);
  const double k = num.empty() ? 0.0 : num.front() / den.front();
  m_log_k = std::log(std::abs(k));
  m_arg_k = k < 0.0 ? std::numbers::pi : 0.0;
}

Complex FreqEval::point(double omega_rad_s) const {
  return m_tf.discrete() ? std::polar(1.0, omega_rad_s * m_tf.dt_s) : Complex(0.0, omega_rad_s);
}

double FreqEval::log_mag(double omega_rad_s) const {
  const Complex x = point(omega_rad_s);
  double acc = m_log_k;
  for (const Complex& z : m_zeros) acc += std::log(std::abs(x - z));
  for (const Complex& p : m_poles) acc -= std::log(std::abs(x - p));
  return acc;
}

double FreqEval::phase_rad(double omega_rad_s) const {
  const Complex x = point(omega_rad_s);
  double acc = m_arg_k - omega_rad_s * m_tf.delay_s;
  for (const Complex& z : m_zeros) acc += std::arg(x - z);
  for (const Complex& p : m_poles) acc -= std::arg(x - p);
  return acc;
}

std::vector<double> FreqEval::corner_frequencies() const {
  std::vector<double> out;
  auto add_root = [&](Complex r) {
    if (m_tf.discrete()) {
      if (std::abs(r) == 0.0) return;
      const double w = std::abs(std::log(r)) / m_tf.dt_s;
      if (w > 0.0) out.push_back(w);
    } else if (std::abs(r) > 0.0) {
      out.push_back(std::abs(r));
    }
  };
  for (const Complex& z : m_zeros) add_root(z);
  for (const Complex& p : m_poles) add_root(p);
  return out;
}

}  // namespace mcg::linsys
