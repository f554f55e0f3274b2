// The analysis subcommands: the loop resolved, analysed and written as INI or CSV.
#include "cmd/design/analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <ostream>
#include <vector>

#include "common/error.hpp"
#include "common/quote.hpp"
#include "common/range.hpp"
#include "config/ini.hpp"
#include "linsys/response.hpp"
#include "mcg/version.hpp"
#include "table/table.hpp"

namespace mcg::cmd {

namespace {

using config::format_number;
using config::Ini;
using design::parse_list;
using design::single_loop;
using design::Tf;
using design::write_margins;
using linsys::Complex;

constexpr double k_pi = std::numbers::pi;
constexpr double k_inf = std::numeric_limits<double>::infinity();

void add_controller(CLI::App& app, std::string& controller) {
  app.add_option("--controller", controller,
                 "controller text in s or z (default: [controller] of --config, or 1)");
}

void plot_range(const BodeOptions& o, const std::vector<Tf>& factors, double& lo, double& hi) {
  lo = INFINITY;
  hi = 0.0;
  double dt = 0.0;
  for (const Tf& f : factors) {
    const linsys::FreqEval fe(f);
    for (double c : fe.corner_frequencies()) {
      lo = std::min(lo, c / 100.0);
      hi = std::max(hi, c * 100.0);
    }
    if (f.discrete()) dt = dt == 0.0 ? f.dt_s : std::min(dt, f.dt_s);
  }
  if (!std::isfinite(lo)) {
    lo = 0.01;
    hi = 1e4;
  }
  if (dt > 0.0) hi = std::min(hi, k_pi / dt);
  if (lo >= hi) lo = hi / 1e4;
  if (!std::isnan(o.f_min_hz)) lo = 2.0 * k_pi * o.f_min_hz;
  if (!std::isnan(o.f_max_hz)) hi = 2.0 * k_pi * o.f_max_hz;
  if (!(lo > 0.0) || !(hi > lo)) fail("--f-min/--f-max: need 0 < f-min < f-max");
}

void write_frequency(const BodeOptions& o, const std::vector<Tf>& factors, std::ostream& out, bool nyquist,
                     const std::string& tool) {
  double lo = 0.0;
  double hi = 0.0;
  plot_range(o, factors, lo, hi);
  const int points = o.points > 0 ? o.points : 500;
  const linsys::LoopEval le(factors);
  table::Writer w(out);
  w.meta("source", tool + " " + k_version);
  std::string loop;
  for (const Tf& f : factors) loop += (loop.empty() ? "" : " * ") + linsys::tf_text(f);
  w.meta("loop", loop);
  if (nyquist) {
    w.header({"f_hz", "re", "im"});
  } else {
    w.header({"f_hz", "mag_db", "phase_deg"});
  }
  for (double x : linsys::log_grid(lo, hi, std::max(points, 2))) {
    if (nyquist) {
      const Complex v = le.value(x);
      w.row({x / (2.0 * k_pi), v.real(), v.imag()});
    } else {
      w.row({x / (2.0 * k_pi), le.log_mag(x) * 20.0 / std::log(10.0), le.phase_rad(x) * 180.0 / k_pi});
    }
  }
  w.finish();
}

void write_rlocus(const RlocusOptions& o, const std::vector<Tf>& factors, std::ostream& out,
                  const std::string& tool) {
  std::string note;
  Tf loop = single_loop(factors, &note);
  if (loop.discrete()) loop = linsys::fold_delay(loop, "loop");
  if (!loop.discrete() && loop.delay_s > 0.0) {
    loop.delay_s = 0.0;
    loop = linsys::series(loop, linsys::pade(single_loop(factors, nullptr).delay_s, 6));
    note = "delay as its [6/6] Pade approximant";
  }
  const auto ranges = linsys::stable_gain_ranges(loop);
  const auto bounds = linsys::boundary_gains(loop);
  double k_max = o.k_max;
  if (std::isnan(k_max)) k_max = bounds.empty() ? 100.0 : 3.0 * bounds.back();
  if (!(k_max > 0.0)) fail("--k-max: must be positive");
  const int points = o.points > 0 ? o.points : 400;
  std::vector<double> ks{0.0};
  for (double k : linsys::log_grid(k_max * 1e-4, k_max, std::max(points, 2))) ks.push_back(k);
  for (double k : bounds) {
    if (k <= k_max) ks.push_back(k);
  }
  std::sort(ks.begin(), ks.end());
  table::Writer w(out);
  w.meta("source", tool + " " + k_version);
  w.meta("loop", linsys::tf_text(loop));
  if (!note.empty()) w.meta("note", note);
  for (const auto& g : ranges)
    w.meta("k_stable", fmt::format("{} .. {}", format_number(g.k_low), format_number(g.k_high)));
  w.meta("boundary", loop.discrete() ? "unit circle" : "imaginary axis");
  // n − m branches leave for infinity along rays from the centroid (Σp − Σz)/(n − m) at
  // (2q + 1)·180/(n − m) degrees.
  const std::vector<Complex> poles = linsys::roots(linsys::trim(loop.den));
  const std::vector<Complex> zeros = linsys::roots(linsys::trim(loop.num));
  if (poles.size() > zeros.size()) {
    const double excess = static_cast<double>(poles.size() - zeros.size());
    double centre = 0.0;
    for (const Complex& p : poles) centre += p.real();
    for (const Complex& z : zeros) centre -= z.real();
    std::string angles;
    for (std::size_t q = 0; q < poles.size() - zeros.size(); ++q) {
      angles +=
          (angles.empty() ? "" : " ") + format_number((2.0 * static_cast<double>(q) + 1.0) * 180.0 / excess);
    }
    w.meta("asymptote_centre", format_number(centre / excess));
    w.meta("asymptote_angles_deg", angles);
  }
  w.header({"k", "branch", "re", "im"});
  std::vector<Complex> prev;
  for (double k : ks) {
    std::vector<Complex> p = linsys::roots(linsys::add(loop.den, linsys::scale(loop.num, k)));
    if (!prev.empty() && p.size() == prev.size()) {
      // Keep branches continuous: each previous pole takes its nearest new one.
      std::vector<Complex> ordered(prev.size());
      std::vector<bool> used(p.size(), false);
      for (std::size_t i = 0; i < prev.size(); ++i) {
        std::size_t best = 0;
        double best_d = INFINITY;
        for (std::size_t j = 0; j < p.size(); ++j) {
          if (!used[j] && std::abs(p[j] - prev[i]) < best_d) {
            best_d = std::abs(p[j] - prev[i]);
            best = j;
          }
        }
        used[best] = true;
        ordered[i] = p[best];
      }
      p = ordered;
    }
    for (std::size_t i = 0; i < p.size(); ++i)
      w.row({k, static_cast<double>(i + 1), p[i].real(), p[i].imag()});
    prev = p;
  }
  w.finish();
}

linsys::StepLimits step_limits(const StepOptions& o) {
  linsys::StepLimits lim;
  if (!o.rise_pct.empty()) {
    const std::vector<double> v = parse_list(o.rise_pct, "--rise");
    if (v.size() != 2 || !(v[0] >= 0.0 && v[0] < v[1] && v[1] <= 100.0)) {
      fail("--rise: expected LOW,HIGH with 0 <= LOW < HIGH <= 100 (percent), got {}", quote(o.rise_pct));
    }
    lim.rise_low = v[0] / 100.0;
    lim.rise_high = v[1] / 100.0;
  }
  if (!std::isnan(o.settling_pct)) lim.settling = o.settling_pct / 100.0;
  return lim;
}

void write_step(const StepOptions& o, const design::ResolvedPlant& r, std::ostream& out,
                const std::string& tool) {
  const std::optional<Tf> c = design::analysis_controller(o.controller, r);
  Tf plant = r.setup.plant;
  std::string note;
  if (c && c->discrete() && !plant.discrete()) {
    plant = linsys::c2d(plant, c->dt_s, linsys::C2dMethod::zoh, 0.0, r.raw_where);
    note = "plant sampled through a zero-order hold";
  }
  const double t_end = std::isnan(o.t_end_s) ? 0.0 : o.t_end_s;
  if (!std::isnan(o.t_end_s) && !(o.t_end_s > 0.0)) fail("--t-end: must be positive");
  const linsys::StepLimits lim = step_limits(o);
  const linsys::StepResponse s =
      linsys::step_response(plant, c, t_end, o.points > 0 ? o.points : 2000, o.open_loop);
  const linsys::StepMetrics m = linsys::step_info(s, 1.0, lim);
  std::vector<std::pair<std::string, double>> metrics{{"final_value", m.final_value},
                                                      {"rise_time_s", m.rise_time_s},
                                                      {"transient_time_s", m.transient_time_s},
                                                      {"settling_time_s", m.settling_time_s},
                                                      {"settling_min", m.settling_min},
                                                      {"settling_max", m.settling_max},
                                                      {"overshoot_pct", m.overshoot_pct},
                                                      {"undershoot_pct", m.undershoot_pct},
                                                      {"peak", m.peak},
                                                      {"peak_time_s", m.peak_time_s}};
  if (!o.open_loop) metrics.emplace_back("steady_state_error", m.steady_state_error);
  const std::string loop_kind = o.open_loop ? "open" : "closed";
  const std::string levels =
      fmt::format("rise {}-{} %, settling {} %", format_number(100.0 * lim.rise_low),
                  format_number(100.0 * lim.rise_high), format_number(100.0 * lim.settling));
  const char* timing = s.sampled ? "at the sample instants" : "interpolated between samples";
  if (o.metrics) {
    Ini ini;
    ini.set("step", "loop", loop_kind);
    for (const auto& [k, v] : metrics) ini.set("step", k, v);
    ini.set("step", "levels", levels);
    ini.set("step", "times", timing);
    if (!note.empty()) ini.set("step", "note", note);
    if (!s.note.empty()) ini.set("step", "simulation", s.note);
    ini.write(out);
    return;
  }
  table::Writer w(out);
  w.meta("source", tool + " " + k_version);
  w.meta("loop", linsys::tf_text(c ? linsys::series(*c, plant) : plant));
  w.meta("step", loop_kind);
  if (!note.empty()) w.meta("note", note);
  if (!s.note.empty()) w.meta("simulation", s.note);
  for (const auto& [k, v] : metrics) w.meta(k, format_number(v));
  w.meta("levels", levels);
  w.meta("times", timing);
  if (o.open_loop) {
    w.header({"t", "r", "y", "u"});
    for (std::size_t k = 0; k < s.t_s.size(); ++k) w.row({s.t_s[k], 1.0, s.y[k], s.u[k]});
  } else {
    w.header({"t", "r", "y", "e", "u"});
    for (std::size_t k = 0; k < s.t_s.size(); ++k) w.row({s.t_s[k], 1.0, s.y[k], 1.0 - s.y[k], s.u[k]});
  }
  w.finish();
}

}  // namespace

void Margins::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_controller(app, options.controller);
}

int Margins::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, false);
  Ini ini;
  const std::vector<Tf> f = design::analysis_factors(options.controller, r);
  for (const Tf& x : f) {
    if (!x.proper()) fail("margins need a proper loop");
  }
  design::write_margins(ini, "margins", f, r.dt_s);
  ini.write(io.out);
  return 0;
}

void Bode::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_controller(app, options.controller);
  app.add_option("--f-min", options.f_min_hz, "lowest frequency, Hz")->check(mcg::Range(1e-12, k_inf));
  app.add_option("--f-max", options.f_max_hz, "highest frequency, Hz")->check(mcg::Range(1e-12, k_inf));
  app.add_option("--points", options.points, "number of frequencies (500)")->check(mcg::Range(2, 1000000));
}

int Bode::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, false);
  write_frequency(options, design::analysis_factors(options.controller, r), io.out, m_nyquist, io.tool);
  return 0;
}

void Rlocus::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_controller(app, options.controller);
  app.add_option("--k-max", options.k_max, "largest gain")->check(mcg::Range(1e-12, k_inf));
  app.add_option("--points", options.points, "number of gains (400)")->check(mcg::Range(2, 1000000));
}

int Rlocus::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, false);
  write_rlocus(options, design::analysis_factors(options.controller, r), io.out, io.tool);
  return 0;
}

void Step::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_controller(app, options.controller);
  app.add_flag("--open-loop", options.open_loop,
               "the step of the plant (times the controller) as typed, no feedback");
  app.add_option("--rise", options.rise_pct, "rise-time limits LOW,HIGH, % of the final value (10,90)");
  app.add_option("--settling", options.settling_pct, "settling band, % (2)")->check(mcg::Range(1e-9, 100.0));
  app.add_option("--t-end", options.t_end_s, "duration, s (10 time constants of the slowest pole)")
      ->check(mcg::Range(1e-12, k_inf));
  app.add_option("--points", options.points, "samples of a continuous loop (2000)")
      ->check(mcg::Range(2, 1000000));
  app.add_flag("--metrics", options.metrics, "write the step metrics as INI instead of the series");
}

int Step::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, false);
  write_step(options, r, io.out, io.tool);
  return 0;
}

}  // namespace mcg::cmd
