// mcg-sweep's two halves: excitation tables out, frequency responses of measured tables.
#include "signal/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <random>
#include <sstream>

#include "common/checked.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/quote.hpp"
#include "config/ini.hpp"
#include "mcg/version.hpp"
#include "measurement/board_excitation.hpp"  // parse_board_excitation
#include "signal/excitation.hpp"
#include "signal/spectrum.hpp"
#include "table/table.hpp"

namespace mcg::signal {

namespace {

using config::format_number;

std::string unit_of(const std::string& column) {
  if (column == "v") return " V";
  if (column == "rpm_cmd") return " rev/min";
  return "";
}

std::string join_numbers(const std::vector<double>& values) {
  std::string text;
  for (const double v : values) {
    if (!text.empty()) text += ' ';
    text += format_number(v);
  }
  return text;
}

// Whole number of samples of dt in `seconds`, at most `max`, or an error naming the option.
// `dt_name` names the step: "--dt", or a measured table's sample period.
std::size_t whole_samples(double seconds, double dt_s, std::string_view option, std::size_t max = k_max_rows,
                          std::string_view dt_name = "--dt") {
  const double n = seconds / dt_s;
  const double rounded = std::round(n);
  if (!(rounded >= 1) || std::abs(n - rounded) > 1e-6 * rounded) {
    fail("{} {} s is not a whole number of {} {} s samples", option, format_number(seconds), dt_name,
         format_number(dt_s));
  }
  const std::optional<std::size_t> count = to_integer(rounded, std::size_t{1}, max);
  if (!count) {
    fail("{} {} s is {} samples of {} {} s, more than the {} it may span", option, format_number(seconds),
         format_number(rounded), dt_name, format_number(dt_s), max);
  }
  return *count;
}

// What sets the table's length, for a message about it.
std::string duration_text(Generator g, const GeneratorOptions& o, double duration_s) {
  const std::string d = format_number(duration_s);
  if (o.duration_s) return fmt::format("--duration {} s", d);
  switch (g) {
    case Generator::step:
      return fmt::format("the default --duration {} s (1 s past the last step, --at or --then)", d);
    case Generator::staircase:
      return fmt::format("the default --duration {} s ((4 --steps + 1) x --hold)", d);
    case Generator::chirp:
      break;
    case Generator::multisine:
      return fmt::format("the default --duration {} s (three periods: --period, else 1/--f0)", d);
    case Generator::prbs:
    case Generator::aprbs:
      return fmt::format("the default --duration {} s (two periods of --order {} at --clock)", d, o.order);
  }
  return fmt::format("the default --duration {} s", d);
}

void check_band(const GeneratorOptions& o) {
  if (o.f1_hz <= o.f0_hz) {
    fail("--f1 {} Hz must be above --f0 {} Hz", format_number(o.f1_hz), format_number(o.f0_hz));
  }
  const double nyquist = 0.5 / o.dt_s;
  if (o.f1_hz >= nyquist) {
    fail("--f1 {} Hz is not below the Nyquist frequency {} Hz of --dt {} s", format_number(o.f1_hz),
         format_number(nyquist), format_number(o.dt_s));
  }
}

ChirpSpacing spacing_of_option(const std::string& text, ChirpSpacing fallback) {
  if (text.empty()) return fallback;
  return text == "log" ? ChirpSpacing::log : ChirpSpacing::linear;
}

const char* spacing_name(ChirpSpacing s) { return s == ChirpSpacing::log ? "log" : "linear"; }

// Everything a generator produces besides the sample grid.
struct Excitation {
  std::vector<double> x;
  table::Metadata meta;
};

double default_duration_s(Generator g, const GeneratorOptions& o, const std::vector<Change>& then) {
  switch (g) {
    case Generator::step:
      return std::max(1.0, (then.empty() ? o.at_s : then.back().time_s) + 1.0);
    case Generator::staircase:
      return o.hold_s * (4.0 * o.steps + 1.0);
    case Generator::chirp:
      return 10.0;
    case Generator::multisine:
      return 3.0 * o.period_s.value_or(1.0 / o.f0_hz);
    case Generator::prbs:
    case Generator::aprbs:
      return 2.0 * (std::ldexp(1.0, o.order) - 1.0) * o.clock_s.value_or(o.dt_s);
  }
  return 1.0;
}

Excitation excite(Generator g, const GeneratorOptions& o, const std::vector<double>& t,
                  const std::vector<Change>& then, double duration_s) {
  Excitation e;
  const std::string unit = unit_of(o.column);
  const std::string about = fmt::format("about bias {}{}", format_number(o.bias), unit);
  const std::string kind = fmt::format("on {}:", o.column);
  switch (g) {
    case Generator::step: {
      e.x = step_signal(t, o.level, o.at_s, then);
      std::string steps = fmt::format("{}{} at {} s", format_number(o.level), unit, format_number(o.at_s));
      for (const Change& c : then) {
        steps += fmt::format(", {}{} at {} s", format_number(c.value), unit, format_number(c.time_s));
      }
      e.meta.set("excitation", fmt::format("step {} {}, {}", kind, steps, about));
      break;
    }
    case Generator::staircase:
      e.x = staircase_signal(t, o.amp, o.steps, o.hold_s);
      e.meta.set("excitation",
                 fmt::format("staircase {5} 0 -> {1}{0} -> -{1}{0} -> 0 in steps of {2}{0}, {3} s each, {4}", unit,
                             format_number(o.amp), format_number(o.amp / o.steps), format_number(o.hold_s),
                             about, kind));
      break;
    case Generator::chirp: {
      check_band(o);
      const ChirpSpacing spacing = spacing_of_option(o.spacing, ChirpSpacing::linear);
      e.x = chirp_signal(t, o.amp, o.f0_hz, o.f1_hz, duration_s, spacing);
      e.meta.set("excitation", fmt::format("chirp {} {} {}..{} Hz over {} s, amplitude {}{}, {}{}", kind,
                                           spacing_name(spacing), format_number(o.f0_hz), format_number(o.f1_hz),
                                           format_number(duration_s), format_number(o.amp), unit, about,
                                           o.settle_s > 0 ? fmt::format(" ({} s before and after)",
                                                                        format_number(o.settle_s))
                                                          : std::string()));
      e.meta.set("excitation_band_hz", fmt::format("{} {}", format_number(o.f0_hz), format_number(o.f1_hz)));
      break;
    }
    case Generator::multisine: {
      check_band(o);
      const ChirpSpacing spacing = spacing_of_option(o.spacing, ChirpSpacing::log);
      // The period is a whole number of samples, so every line is an exact DFT bin.
      const std::size_t period_samples =
          o.period_s ? whole_samples(*o.period_s, o.dt_s, "--period")
                     : whole_samples(std::max(1.0, std::ceil(1.0 / o.f0_hz / o.dt_s - 1e-9)) * o.dt_s, o.dt_s,
                                     "the period 1/--f0");
      // Each line costs one cosine per sample of the period.
      const double terms = static_cast<double>(o.lines) * static_cast<double>(period_samples);
      if (terms > k_max_multisine_terms) {
        fail("--lines {} over a period of {} samples is {} terms, more than the {} a multisine computes "
             "(fewer --lines, a shorter --period or higher --f0, a larger --dt)",
             o.lines, period_samples, format_number(terms), format_number(k_max_multisine_terms));
      }
      const double period = static_cast<double>(period_samples) * o.dt_s;
      const auto harmonics = multisine_harmonics(o.f0_hz, o.f1_hz, o.lines, period, spacing);
      std::vector<double> phases;
      if (o.phases == "schroeder") {
        phases = schroeder_phases(harmonics.size());
      } else if (o.phases == "random") {
        std::mt19937_64 rng(o.seed);
        std::uniform_real_distribution<double> angle(-3.141592653589793, 3.141592653589793);
        for (std::size_t j = 0; j < harmonics.size(); ++j) phases.push_back(angle(rng));
        e.meta.set("seed", std::to_string(o.seed));
      } else {
        phases.assign(harmonics.size(), 0.0);
      }
      e.x = multisine_signal(t.size(), o.amp, period_samples, harmonics, phases);
      std::vector<double> lines;
      for (int h : harmonics) lines.push_back(static_cast<double>(h) / period);
      e.meta.set("excitation",
                 fmt::format("multisine {} {} lines {} spaced {}..{} Hz, {} phases, period {} s, peak {}{}, {}",
                             kind, harmonics.size(), spacing_name(spacing), format_number(lines.front()),
                             format_number(lines.back()), o.phases, format_number(period), format_number(o.amp),
                             unit, about));
      e.meta.set("excitation_band_hz", fmt::format("{} {}", format_number(lines.front()), format_number(lines.back())));
      e.meta.set("multisine_period_s", format_number(period));
      e.meta.set("multisine_lines_hz", join_numbers(lines));
      break;
    }
    case Generator::prbs:
    case Generator::aprbs: {
      const double clock = o.clock_s.value_or(o.dt_s);
      const std::size_t clock_samples = whole_samples(clock, o.dt_s, "--clock");
      std::mt19937_64 rng(o.seed);
      const std::uint32_t state = prbs_initial_state(o.order, rng);
      const double period = (std::ldexp(1.0, o.order) - 1.0) * clock;
      if (g == Generator::prbs) {
        e.x = prbs_signal(t.size(), o.amp, o.order, clock_samples, state);
      } else {
        e.x = aprbs_signal(t.size(), o.amp, o.order, clock_samples, state, rng);
      }
      e.meta.set("excitation",
                 fmt::format("{} {} order {} (period {} s), bit time {} s, {}{}{}, {}",
                             g == Generator::prbs ? "prbs" : "aprbs", kind, o.order, format_number(period),
                             format_number(clock), g == Generator::prbs ? "levels +-" : "levels uniform in +-",
                             format_number(o.amp), unit, about));
      e.meta.set("seed", std::to_string(o.seed));
      break;
    }
  }
  return e;
}

void check_values(const std::vector<Change>& changes, const char* option, bool clutch) {
  for (const Change& c : changes) {
    if (clutch && c.value != 0 && c.value != 1 && c.value != 2) {
      fail("{}: clutch state {} is not 0, 1 or 2", option, format_number(c.value));
    }
    if (!clutch && !(c.value >= 0)) fail("{}: r_load {} ohm is negative", option, format_number(c.value));
  }
}

// Parses a list of numbers "1,2.5, 10".
std::vector<double> parse_list(const std::string& text, const char* option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    double v = 0;
    if (!table::parse_number(item, v) || !std::isfinite(v)) fail("{}: invalid number {}", option, quote(item));
    values.push_back(v);
  }
  if (values.empty()) fail("{}: no numbers in {}", option, quote(text));
  return values;
}

std::vector<double> numbers_in(const std::string& text);

// A metadata value that is one finite number, if present.
std::optional<double> meta_number(const table::Metadata& meta, std::string_view key) {
  const auto text = meta.get(key);
  if (!text) return std::nullopt;
  double v = 0;
  if (!table::parse_number(*text, v) || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<double> numbers_in(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (in >> item) {
    double v = 0;
    if (table::parse_number(item, v) && std::isfinite(v)) values.push_back(v);
  }
  return values;
}

}  // namespace

void generate(Generator generator, const GeneratorOptions& o, std::ostream& out) {
  const std::vector<Change> then = o.then.empty() ? std::vector<Change>{} : parse_schedule(o.then, "--then");
  const std::vector<Change> clutch =
      o.clutch_schedule.empty() ? std::vector<Change>{} : parse_schedule(o.clutch_schedule, "--clutch-schedule");
  const std::vector<Change> r_load =
      o.r_load_schedule.empty() ? std::vector<Change>{} : parse_schedule(o.r_load_schedule, "--r-load-schedule");
  check_values(clutch, "--clutch-schedule", true);
  check_values(r_load, "--r-load-schedule", false);

  const double duration = o.duration_s.value_or(default_duration_s(generator, o, then));
  // The table's size is checked before anything is allocated: its rows, and a chirp's frame.
  const std::optional<std::size_t> samples = grid_samples(o.dt_s, duration);
  if (!samples) {
    fail("{} at --dt {} s is {} rows, more than the {} written at most",
         duration_text(generator, o, duration), format_number(o.dt_s),
         format_number(std::floor(duration / o.dt_s)), k_max_rows);
  }
  if (*samples < 2) {
    fail("--duration {} s holds fewer than two samples of --dt {} s", format_number(duration),
         format_number(o.dt_s));
  }
  // A chirp is framed by the bias alone, so that the plant is settled when the sweep starts
  // and every Welch segment that holds part of the sweep lies inside the record.
  const std::size_t lead =
      generator == Generator::chirp && o.settle_s > 0 ? whole_samples(o.settle_s, o.dt_s, "--settle") : 0;
  if (2 * lead + *samples > k_max_rows) {
    fail("--settle {} s twice and {} at --dt {} s is {} rows, more than the {} written at most",
         format_number(o.settle_s), duration_text(generator, o, duration), format_number(o.dt_s),
         2 * lead + *samples, k_max_rows);
  }
  const std::vector<double> t_excitation = time_grid(o.dt_s, duration);
  Excitation e = excite(generator, o, t_excitation, then, duration);
  if (lead > 0) {
    std::vector<double> framed(lead, 0.0);
    framed.insert(framed.end(), e.x.begin(), e.x.end());
    framed.resize(framed.size() + lead, 0.0);
    e.x = std::move(framed);
    const double start = static_cast<double>(lead) * o.dt_s;
    e.meta.set("excitation_start_s", format_number(start));
    e.meta.set("excitation_end_s", format_number(start + static_cast<double>(t_excitation.size()) * o.dt_s));
  }

  table::Writer w(out);
  w.meta("source", fmt::format("{} {}", o.tool, k_version));
  w.meta("sample_period", format_number(o.dt_s));
  for (const auto& [key, value] : e.meta.entries()) w.meta(key, value);
  w.header({"t", o.column, "clutch", "r_load"});
  w.set_digits(std::size_t{1}, 12);
  ScheduleCursor clutch_now(o.clutch, clutch);
  ScheduleCursor r_load_now(o.r_load_ohm, r_load);
  for (std::size_t k = 0; k < e.x.size(); ++k) {
    const double t = static_cast<double>(k) * o.dt_s;
    w.row({t, o.bias + e.x[k], clutch_now.at(t), r_load_now.at(t)});
  }
  w.finish();
}

void bode(const BodeOptions& o, std::ostream& out, Diagnostics& diag) {
  bode(table::read_path(o.input), o, out, diag);
}

void bode(const table::Table& input, const BodeOptions& options, std::ostream& out, Diagnostics& diag) {
  table::Table tbl = input;
  BodeOptions o = options;
  // A board capture says what the board played: its column is the input, a chirp's sweep the band.
  std::optional<measurement::BoardExcitation> played;
  if (const auto text = tbl.meta.get("excitation")) {
    played = measurement::parse_board_excitation(*text, tbl.meta.where(tbl.source, "excitation"));
  }
  if (o.in_column.empty()) o.in_column = played ? played->column : "v";
  if (o.out_column.empty()) o.out_column = !tbl.has("omega") && tbl.has("rpm") ? "rpm" : "omega";
  if (played && played->kind == "chirp" && !o.f_min_hz && !o.f_max_hz) {
    const auto f0 = played->value("f0");
    const auto f1 = played->value("f1");
    if (f0 && f1 && *f0 != *f1) {
      o.f_min_hz = std::min(*f0, *f1);
      o.f_max_hz = std::max(*f0, *f1);
    }
  }
  // A capture starts with rows the speed estimator has not filled yet: skipped, and said so.
  if (const auto skipped = table::leading_unmeasured(tbl, {o.in_column, o.out_column}); skipped.rows > 0) {
    diag.note(table::skipped_note(tbl, skipped));
    tbl = table::drop_leading(tbl, skipped.rows);
  }
  const std::vector<double>& t_in = tbl.col("t");
  const std::vector<double>& x_in = tbl.col(o.in_column);
  const std::vector<double>& y_in = tbl.col(o.out_column);
  table::require_increasing(tbl, "t");
  table::require_finite(tbl, o.in_column);
  table::require_finite(tbl, o.out_column);
  if (tbl.rows() < 32) {
    fail("{}: {} rows, too short for a frequency response (at least 32)", tbl.source, tbl.rows());
  }

  const Spacing spacing = spacing_of(t_in);
  double dt = (t_in.back() - t_in.front()) / static_cast<double>(tbl.rows() - 1);
  std::vector<double> x_even;
  std::vector<double> y_even;
  std::span<const double> x = x_in;
  std::span<const double> y = y_in;
  if (!spacing.uniform) {
    double nominal = spacing.median_dt_s;
    std::string nominal_from = fmt::format("the median step {} s", format_number(nominal));
    if (const auto period = tbl.meta.get("sample_period")) {
      double v = 0;
      if (table::parse_number(*period, v) && v > 0 && std::isfinite(v)) {
        nominal = v;
        nominal_from = fmt::format("{}: sample_period {} s", tbl.meta.where(tbl.source, "sample_period"),
                                   format_number(v));
      }
    }
    // The resampled grid is allocated twice (input and output): its size is checked first.
    const double span_s = t_in.back() - t_in.front();
    const std::optional<std::size_t> samples =
        to_integer(std::floor(span_s / nominal + 1e-9) + 1.0, std::size_t{0}, k_max_rows);
    if (!samples) {
      fail("{} resamples the {} s of uneven rows to {} samples, more than the {} resampled to at most",
           nominal_from, format_number(span_s), format_number(std::floor(span_s / nominal) + 1.0),
           k_max_rows);
    }
    if (*samples < 32) {
      fail("{} resamples the {} s of uneven rows to {} samples, too short for a frequency response "
           "(at least 32)",
           nominal_from, format_number(span_s), *samples);
    }
    dt = nominal;
    x_even = resample_linear(t_in, x_in, dt);
    y_even = resample_linear(t_in, y_in, dt);
    x = x_even;
    y = y_even;
    diag.warning(
        fmt::format("{}: uneven sampling (steps {:.4g} to {:.4g} s); resampled to {:.6g} s by linear "
                    "interpolation",
                    tbl.source, spacing.min_dt_s, spacing.max_dt_s, dt));
  }

  // Lines come from --lines/--period, else from the multisine generator's metadata.
  std::vector<double> lines;
  std::optional<double> period = o.period_s;
  std::string period_name = "--period";
  std::string lines_name = "--lines";
  if (!o.lines_hz.empty()) {
    lines = parse_list(o.lines_hz, "--lines");
  } else if (o.method != BodeMethod::welch) {
    if (const auto meta_lines = tbl.meta.get("multisine_lines_hz")) {
      lines = numbers_in(*meta_lines);
      lines_name = fmt::format("{}: multisine_lines_hz", tbl.meta.where(tbl.source, "multisine_lines_hz"));
    }
  }
  // A chirp the board repeats is periodic: its period is a whole number of updates, the phase starting
  // from 0 in each. Over two whole periods or more the lines k / period in its band are read as a
  // multisine's, the first period (the start's transient) skipped. Welch over one short sweep reads
  // little of its lowest octave: a 0.5 -> 20 Hz sweep of 4 s spends 0.3 s below 2 Hz, and a 1 Hz bin
  // came out 8.5 % high there.
  std::string chirp_note;
  if (played && played->kind == "chirp" && lines.empty() && !period && o.method == BodeMethod::automatic) {
    const auto f0 = played->value("f0");
    const auto f1 = played->value("f1");
    const auto sweep = played->value("sweep");
    const auto update = played->value("update");
    if (f0 && f1 && sweep && update && *update > 0 && *sweep >= *update) {
      const double chirp_period = std::floor(*sweep / *update + 1e-9) * *update;
      const double span_s = static_cast<double>(x.size()) * dt;
      if (span_s + 1e-9 >= 2.0 * chirp_period) {
        const double lo = std::max(std::min(*f0, *f1), o.f_min_hz.value_or(0.0));
        const double hi = std::min({std::max(*f0, *f1), o.f_max_hz.value_or(*f1 + *f0), 0.5 / dt});
        for (double k = std::ceil(lo * chirp_period - 1e-9); k <= std::floor(hi * chirp_period + 1e-9); ++k) {
          if (k >= 1 && k / chirp_period < 0.5 / dt) lines.push_back(k / chirp_period);
        }
        if (!lines.empty()) {
          period = chirp_period;
          period_name = fmt::format("{}: excitation", tbl.meta.where(tbl.source, "excitation"));
          lines_name = period_name;
          chirp_note = fmt::format(", the lines k / {} s of the board's chirp", format_number(chirp_period));
        }
      }
    }
  }
  if (!period && !lines.empty()) {
    if (const auto meta_period = tbl.meta.get("multisine_period_s")) {
      const auto values = numbers_in(*meta_period);
      if (values.size() == 1 && values[0] > 0) {
        period = values[0];
        period_name = fmt::format("{}: multisine_period_s", tbl.meta.where(tbl.source, "multisine_period_s"));
      }
    }
  }
  const bool use_lines = o.method == BodeMethod::lines || (o.method == BodeMethod::automatic && !lines.empty());
  if (use_lines && lines.empty()) fail("--method lines: no lines (give --lines, or a multisine table's metadata)");
  if (use_lines && !period) fail("--lines needs --period (the multisine's period, s)");

  Response r;
  table::Metadata meta = tbl.meta;
  meta.erase("sample_period");
  meta.erase("timing");
  meta.set("source", fmt::format("{} {} bode", o.tool, k_version));
  meta.set("response", fmt::format("{} -> {}", o.in_column, o.out_column));
  if (use_lines) {
    // One period at least must fit the record (line_response says so for a shorter one).
    const std::size_t period_samples =
        whole_samples(*period, dt, period_name, std::max<std::size_t>(x.size(), 1), "the sample period");
    const double exact_period = static_cast<double>(period_samples) * dt;
    std::vector<int> harmonics;
    for (double f : lines) {
      const double h = f * exact_period;
      if (h < 0.5 || std::abs(h - std::round(h)) > 1e-6 * std::max(1.0, h)) {
        fail("{}: {} Hz is not a multiple of 1/period = {} Hz", lines_name, format_number(f),
             format_number(1.0 / exact_period));
      }
      const std::optional<int> harmonic = to_integer(std::round(h), 1, std::numeric_limits<int>::max());
      if (!harmonic || 2 * static_cast<double>(*harmonic) >= static_cast<double>(period_samples)) {
        fail("{}: {} Hz is not below the Nyquist frequency {} Hz", lines_name, format_number(f),
             format_number(0.5 / dt));
      }
      harmonics.push_back(*harmonic);
    }
    r = line_response(x, y, dt, period_samples, harmonics);
    const std::size_t periods = x.size() / period_samples;
    meta.set("estimator", fmt::format("multisine lines, DFT over {} whole period(s) of {} s{}{}",
                                      periods >= 2 ? periods - 1 : periods, format_number(exact_period),
                                      periods >= 2 ? ", first period skipped" : "", chirp_note));
  } else {
    // A framed excitation (a chirp with settling time) is analysed from half a segment before
    // its start to half a segment after its end: every segment holding the sweep, no more.
    const auto start = meta_number(tbl.meta, "excitation_start_s");
    const auto end = meta_number(tbl.meta, "excitation_end_s");
    std::size_t segment = o.segment;
    if (start && end && *end > *start) {
      // Metadata beyond the record means its ends.
      const auto first = clamp_to_integer(std::round((*start - t_in.front()) / dt), std::size_t{0}, x.size());
      const auto last = clamp_to_integer(std::round((*end - t_in.front()) / dt), std::size_t{0}, x.size());
      if (segment == 0) segment = default_segment(last > first ? last - first : x.size());
      const std::size_t from = first > segment / 2 ? first - segment / 2 : 0;
      const std::size_t to = std::min(x.size(), last + segment / 2);
      if (to > from && to - from >= segment) {
        x = x.subspan(from, to - from);
        y = y.subspan(from, to - from);
      }
    }
    if (segment == 0) segment = default_segment(x.size());
    r = welch_h1(x, y, dt, segment, o.overlap);
    const auto step = std::max<std::size_t>(
        1, segment - clamp_to_integer(std::round(o.overlap * static_cast<double>(segment)), std::size_t{0},
                                      segment));
    meta.set("estimator",
             fmt::format("Welch H1, Hann window, segment {} samples ({} Hz resolution), overlap {}, {} averages",
                         segment, format_number(1.0 / (static_cast<double>(segment) * dt)),
                         format_number(o.overlap), 1 + (x.size() - segment) / step));
  }

  double f_min = o.f_min_hz.value_or(0.0);
  double f_max = o.f_max_hz.value_or(std::numeric_limits<double>::infinity());
  if (!use_lines && !o.f_min_hz && !o.f_max_hz) {
    if (const auto band = tbl.meta.get("excitation_band_hz")) {
      const auto values = numbers_in(*band);
      if (values.size() == 2 && values[0] < values[1]) {
        f_min = values[0];
        f_max = values[1];
      }
    }
  }
  std::vector<std::size_t> keep;
  for (std::size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] >= f_min * (1 - 1e-9) && r.f_hz[k] <= f_max * (1 + 1e-9) && !std::isnan(r.h[k].real())) {
      keep.push_back(k);
    }
  }
  if (keep.empty() && f_min == 0.0 && std::isinf(f_max)) {
    fail("{}: no excitation in column {}", tbl.source, quote(o.in_column));
  }
  if (keep.empty()) {
    fail("{}: no excitation in column {} between {} and {} Hz", tbl.source, quote(o.in_column), format_number(f_min),
         format_number(f_max));
  }
  std::vector<std::complex<double>> h;
  for (std::size_t k : keep) h.push_back(r.h[k]);
  const std::vector<double> phase = unwrapped_phase_deg(h);

  table::Writer w(out);
  w.metadata(meta);
  w.header({"f_hz", "mag_db", "phase_deg", "coherence"});
  for (std::size_t j = 0; j < keep.size(); ++j) {
    const std::size_t k = keep[j];
    w.row({r.f_hz[k], magnitude_db(h[j]), phase[j], r.coherence[k]});
  }
  w.finish();
}

}  // namespace mcg::signal
