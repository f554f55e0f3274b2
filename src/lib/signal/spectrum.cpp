// Frequency-response estimators. FFTs by Eigen's FFT module (kissfft inside): it ships with
// libeigen3-dev, which mcg already requires, handles any segment length, and is fast enough
// (one million samples in well under the 0.5 s goal; see bench/bench_bode.cpp).
#include "signal/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/FFT>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/units.hpp"

namespace mcg::signal {

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

double mean_of(std::span<const double> v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

}  // namespace

std::size_t default_segment(std::size_t samples) {
  std::size_t segment = 256;
  while (segment * 2 <= samples / 8 && segment < 65536) segment *= 2;
  return std::min(segment, samples);
}

Response welch_h1(std::span<const double> x, std::span<const double> y, double dt_s, std::size_t segment,
                  double overlap) {
  MCG_DEMAND(x.size() == y.size() && dt_s > 0 && overlap >= 0 && overlap < 1);
  const std::size_t n = x.size();
  if (segment < 16) fail("--segment {}: needs at least 16 samples", segment);
  if (n < segment) fail("record too short: {} samples, one segment needs {}", n, segment);
  const auto step =
      std::max<std::size_t>(1, segment - clamp_to_integer(std::round(overlap * static_cast<double>(segment)),
                                                          std::size_t{0}, segment));
  const double seg = static_cast<double>(segment);

  std::vector<double> window(segment);
  for (std::size_t k = 0; k < segment; ++k) {
    window[k] = 0.5 - 0.5 * std::cos(2.0 * k_pi * static_cast<double>(k) / seg);
  }
  const std::size_t bins = segment / 2;
  std::vector<double> sxx(bins + 1, 0.0);
  std::vector<double> syy(bins + 1, 0.0);
  std::vector<std::complex<double>> sxy(bins + 1, 0.0);

  // Both real records go through one complex FFT, z = x + i y, and are separated by symmetry:
  // X_k = (Z_k + conj Z_{N-k}) / 2, Y_k = (Z_k - conj Z_{N-k}) / (2 i).
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> z(segment);
  std::vector<std::complex<double>> spectrum(segment);
  for (std::size_t start = 0; start + segment <= n; start += step) {
    const double mx = mean_of(x.subspan(start, segment));
    const double my = mean_of(y.subspan(start, segment));
    for (std::size_t k = 0; k < segment; ++k) {
      z[k] = {window[k] * (x[start + k] - mx), window[k] * (y[start + k] - my)};
    }
    fft.fwd(spectrum.data(), z.data(), static_cast<Eigen::Index>(segment));
    for (std::size_t k = 1; k <= bins; ++k) {
      const std::complex<double> zk = spectrum[k];
      const std::complex<double> zc = std::conj(spectrum[segment - k]);
      const std::complex<double> xk = 0.5 * (zk + zc);
      const std::complex<double> yk = std::complex<double>(0.0, -0.5) * (zk - zc);
      sxx[k] += std::norm(xk);
      syy[k] += std::norm(yk);
      sxy[k] += std::conj(xk) * yk;
    }
  }

  Response r;
  r.f_hz.reserve(bins);
  r.h.reserve(bins);
  r.coherence.reserve(bins);
  double max_sxx = 0.0;
  for (std::size_t k = 1; k <= bins; ++k) max_sxx = std::max(max_sxx, sxx[k]);
  for (std::size_t k = 1; k <= bins; ++k) {
    r.f_hz.push_back(static_cast<double>(k) / (seg * dt_s));
    // Input power at the round-off floor of the largest bin is no excitation at all.
    if (sxx[k] <= 1e-24 * max_sxx || max_sxx == 0.0) {
      r.h.emplace_back(k_nan, k_nan);
      r.coherence.push_back(k_nan);
      continue;
    }
    r.h.push_back(sxy[k] / sxx[k]);
    r.coherence.push_back(syy[k] > 0 ? std::min(1.0, std::norm(sxy[k]) / (sxx[k] * syy[k])) : 0.0);
  }
  return r;
}

Response line_response(std::span<const double> x, std::span<const double> y, double dt_s,
                       std::size_t period_samples, std::span<const int> harmonics) {
  MCG_DEMAND(x.size() == y.size() && dt_s > 0 && period_samples > 0);
  const std::size_t total_periods = x.size() / period_samples;
  if (total_periods == 0) {
    fail("record too short: {} samples, one multisine period needs {}", x.size(), period_samples);
  }
  for (int h : harmonics) {
    if (h <= 0 || 2 * static_cast<std::size_t>(h) >= period_samples) {
      fail("line {} Hz is not between 0 and the Nyquist frequency {} Hz",
           h / (static_cast<double>(period_samples) * dt_s), 0.5 / dt_s);
    }
  }
  const std::size_t skip = total_periods >= 2 ? 1 : 0;
  const std::size_t periods = total_periods - skip;
  const double np = static_cast<double>(period_samples);

  std::vector<std::complex<double>> twiddle(period_samples);
  for (std::size_t m = 0; m < period_samples; ++m) {
    twiddle[m] = std::polar(1.0, -2.0 * k_pi * static_cast<double>(m) / np);
  }
  Response r;
  for (int h : harmonics) {
    const auto step = static_cast<std::size_t>(h);
    double sxx = 0.0;
    double syy = 0.0;
    std::complex<double> sxy = 0.0;
    for (std::size_t p = skip; p < total_periods; ++p) {
      const double* xp = x.data() + p * period_samples;
      const double* yp = y.data() + p * period_samples;
      std::complex<double> xh = 0.0;
      std::complex<double> yh = 0.0;
      std::size_t index = 0;
      for (std::size_t k = 0; k < period_samples; ++k) {
        xh += xp[k] * twiddle[index];
        yh += yp[k] * twiddle[index];
        index += step;
        if (index >= period_samples) index -= period_samples;
      }
      sxx += std::norm(xh);
      syy += std::norm(yh);
      sxy += std::conj(xh) * yh;
    }
    r.f_hz.push_back(static_cast<double>(h) / (np * dt_s));
    if (sxx == 0.0) {
      fail("no excitation in the input at the line {} Hz", r.f_hz.back());
    }
    r.h.push_back(sxy / sxx);
    r.coherence.push_back(periods >= 2 && syy > 0 ? std::min(1.0, std::norm(sxy) / (sxx * syy)) : k_nan);
  }
  return r;
}

double magnitude_db(std::complex<double> h) { return 20.0 * std::log10(std::abs(h)); }

std::vector<double> unwrapped_phase_deg(std::span<const std::complex<double>> h) {
  std::vector<double> phase(h.size(), k_nan);
  double offset = 0.0;
  double previous = k_nan;
  for (std::size_t k = 0; k < h.size(); ++k) {
    if (std::isnan(h[k].real()) || std::isnan(h[k].imag())) continue;
    double p = std::arg(h[k]) * 180.0 / k_pi + offset;
    if (!std::isnan(previous)) {
      const double turns = std::round((previous - p) / 360.0);
      offset += 360.0 * turns;
      p += 360.0 * turns;
    }
    phase[k] = p;
    previous = p;
  }
  return phase;
}

Spacing spacing_of(std::span<const double> t_s) {
  MCG_DEMAND(t_s.size() >= 2);
  std::vector<double> steps(t_s.size() - 1);
  for (std::size_t k = 0; k + 1 < t_s.size(); ++k) steps[k] = t_s[k + 1] - t_s[k];
  const auto [lo, hi] = std::minmax_element(steps.begin(), steps.end());
  Spacing s{};
  s.min_dt_s = *lo;
  s.max_dt_s = *hi;
  const double mean = (t_s.back() - t_s.front()) / static_cast<double>(steps.size());
  s.uniform = std::abs(s.max_dt_s - mean) <= 1e-3 * mean && std::abs(s.min_dt_s - mean) <= 1e-3 * mean;
  auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());
  s.median_dt_s = *middle;
  return s;
}

std::vector<double> resample_linear(std::span<const double> t_s, std::span<const double> y, double dt_s) {
  MCG_DEMAND(t_s.size() == y.size() && t_s.size() >= 2 && dt_s > 0);
  const double t0 = t_s.front();
  // The caller has bounded the grid (it sizes the allocation).
  const std::optional<std::size_t> intervals =
      to_integer(std::floor((t_s.back() - t0) / dt_s + 1e-9), std::size_t{0}, std::size_t{1} << 40);
  MCG_DEMAND(intervals.has_value());
  const std::size_t n = *intervals + 1;
  std::vector<double> out(n);
  std::size_t j = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = t0 + static_cast<double>(k) * dt_s;
    while (j + 2 < t_s.size() && t_s[j + 1] <= t) ++j;
    const double u = std::clamp((t - t_s[j]) / (t_s[j + 1] - t_s[j]), 0.0, 1.0);
    out[k] = y[j] + u * (y[j + 1] - y[j]);
  }
  return out;
}

}  // namespace mcg::signal
