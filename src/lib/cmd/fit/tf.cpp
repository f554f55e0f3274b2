// mcg-fit tf: the response or run read, fit_tf or fit_tf_time, [plant] and [fit.tf] written.
#include "cmd/fit/tf.hpp"

#include <fmt/format.h>

#include <optional>

#include "boardunits/plant_units.hpp"
#include "cmd/fit/ini_text.hpp"
#include "common/error.hpp"
#include "common/quote.hpp"
#include "common/range.hpp"
#include "config/ini.hpp"
#include "mcg/version.hpp"
#include "measurement/board_excitation.hpp"  // parse_board_excitation
#include "table/table.hpp"

namespace mcg::cmd {

using namespace mcg::fit;

namespace {

/// Phase RMS (degrees) above which a fit without a delay is checked against the alternatives.
constexpr double k_tf_phase_warn_deg = 5.0;

/// The `tool` tf command line of `o` on `file`.
std::string tf_command(const std::string& tool, const TfFitOptions& o, const std::string& file) {
  std::string cmd = fmt::format("{} tf --poles {}", tool, o.poles);
  if (o.zeros > 0) cmd += fmt::format(" --zeros {}", o.zeros);
  if (o.f_min_hz > 0.0) cmd += fmt::format(" --f-min {}", config::format_number(o.f_min_hz));
  if (o.f_max_hz < 1e300) cmd += fmt::format(" --f-max {}", config::format_number(o.f_max_hz));
  if (!o.use_coherence) cmd += " --no-coherence";
  if (o.fit_delay) cmd += " --delay";
  return cmd + (file == "-" ? "" : " " + file);
}

void check_phase_residual(const FrequencyResponse& fr, const FitTfOptions& options, const TfFit& fit,
                          Io& io) {
  if (options.fit.fit_delay || !(fit.rms_phase_deg > k_tf_phase_warn_deg)) return;
  std::vector<TfFitOptions> alternatives;
  TfFitOptions delayed = options.fit;
  delayed.fit_delay = true;
  alternatives.push_back(delayed);
  if (options.fit.poles < 12) {
    TfFitOptions more = options.fit;
    ++more.poles;
    alternatives.push_back(more);
  }
  double best_rms = fit.rms_phase_deg;
  std::string best;
  for (const TfFitOptions& alt : alternatives) {
    try {
      const TfFit f = fit_tf(fr, alt);
      if (f.rms_phase_deg < 0.5 * best_rms) {
        best_rms = f.rms_phase_deg;
        best = tf_command(io.tool, alt, options.file);
      }
    } catch (const Error&) {
      // An alternative that cannot be fitted (too few points for more poles) is no advice.
    }
  }
  if (best.empty()) return;
  io.diag.warning(
      fmt::format("the fit leaves {:.3g} degrees RMS of phase (sampled data lag: a zero-order hold alone "
                  "by half a sample period); `{}` leaves {:.3g}",
                  fit.rms_phase_deg, best, best_rms));
}

/// The fit's `[plant] maps` and the words for its comment: the response's units (its metadata or
/// --units), canonical when they are a plant's; refused when neither says.
std::pair<std::string, std::string> fitted_units(const FrequencyResponse& fr, const std::string& given) {
  const auto known = [](const std::string& text) { return boardunits::parse_plant_units(text); };
  const auto canonical = [&](const std::string& text) {
    const auto u = known(text);
    return u ? boardunits::units_text(*u) : text;
  };
  if (!given.empty() && !known(given) && given.find("->") == std::string::npos) {
    fail(
        "--units: {} are not units of a response: give IN -> OUT (v -> rpm, duty -> rpm, v -> omega) or "
        "rpm/V, "
        "rad/s/V, rpm/duty",
        quote(given));
  }
  if (!given.empty() && !fr.units.empty() && canonical(given) != canonical(fr.units)) {
    fail("--units: {} disagrees with the response's {} ({})", quote(given), quote(fr.units), fr.source);
  }
  const std::string text = given.empty() ? fr.units : given;
  if (text.empty()) {
    fail(
        "{}: the response does not say its units (no '# response: IN -> OUT' line, as mcg-sweep bode writes "
        "it): "
        "give --units, e.g. --units 'v -> rpm'",
        fr.source);
  }
  if (const auto u = known(text)) return {boardunits::units_text(*u), boardunits::units_words(*u)};
  return {text, "units mcg-design does not convert"};
}

/// [plant] and the Bode form's numbers of [fit.tf], the same for both kinds of data.
config::Ini plant_ini(const TfFit& fit, const TfFitOptions& o, const std::string& maps,
                      const std::string& words, const std::string& tool) {
  config::Ini ini;
  ini.set("plant", "tf", format_factored(fit), fmt::format("{}, {}", maps, words));
  std::string num;
  std::string den;
  for (double c : fit.tf.num) num += (num.empty() ? "" : " ") + config::format_number(c);
  for (double c : fit.tf.den) den += (den.empty() ? "" : " ") + config::format_number(c);
  ini.set("plant", "num", num, "descending powers of s");
  ini.set("plant", "den", den, "descending powers of s");
  ini.set("plant", "domain", "s");
  const bool physical = maps == boardunits::units_text({});
  ini.set("plant", "maps", maps,
          fmt::format("{}: mcg-design {}applies the loop chain", words,
                      physical ? "" : "converts it to rad/s per V and "));
  if (o.fit_delay) ini.set("plant", "delay_s", num6(fit.delay_s), se_comment(fit.delay_se, "s"));
  const std::string sec = "fit.tf";
  ini.set(sec, "source", fmt::format("{} {}", tool, k_version));
  ini.set(sec, "poles", static_cast<double>(o.poles));
  ini.set(sec, "zeros", static_cast<double>(o.zeros));
  ini.set(sec, "gain", num6(fit.gain), se_comment(fit.gain_se, ""));
  const auto corners = [&](const std::vector<Factor>& list, const char* what) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      const Factor& f = list[k];
      const std::string key = fmt::format("{}{}", what, k + 1);
      ini.set(sec, key + "_rad_s", num6(f.corner_rad_s),
              fmt::format("{}{}", se_comment(f.corner_se, "rad/s"),
                          f.complex_pair ? ", complex pair" : (f.unstable ? ", right half-plane" : "")));
      if (f.complex_pair) ini.set(sec, key + "_zeta", num6(f.zeta), se_comment(f.zeta_se, ""));
    }
  };
  corners(fit.poles, "pole");
  corners(fit.zeros, "zero");
  return ini;
}

/// The time-domain fit of run_tf.
void run_tf_time(const table::Table& table, const FitTfOptions& options, Io& io) {
  if (options.band_given) {
    fail("{}: --f-min, --f-max and --no-coherence apply to a frequency response; this is a time-domain run",
         table.source);
  }
  // A board capture says which column the board drove (its `# excitation:` line).
  std::string in = options.in_column;
  if (in.empty()) {
    const auto text = table.meta.get("excitation");
    const auto played =
        text ? measurement::parse_board_excitation(*text, table.meta.where(table.source, "excitation"))
             : std::nullopt;
    in = played ? played->column : "v";
  }
  const std::string out_col = options.out_column.empty()
                                  ? (table.has("rpm") || !table.has("omega") ? "rpm" : "omega")
                                  : options.out_column;
  const TimeSeries run = read_time_series(table, in, out_col);
  if (!run.skipped_note.empty()) io.diag.note(run.skipped_note);
  FrequencyResponse columns;
  columns.source = run.source;
  columns.units = fmt::format("{} -> {}", in, out_col);
  const auto [maps, words] = fitted_units(columns, options.units);
  const TimeTfFit fit = fit_tf_time(run, options.fit);
  std::optional<double> held_out;
  if (!options.validate.empty()) {
    const TimeSeries other = read_time_series(table::read_path(options.validate), in, out_col);
    if (!other.skipped_note.empty()) io.diag.note(other.skipped_note);
    held_out = validation_fit_percent(fit, other);
  }
  config::Ini ini = plant_ini(fit.fit, options.fit, maps, words, io.tool);
  const std::string sec = "fit.tf";
  ini.set(sec, "data", fmt::format("time series, output error: {} -> {}", in, out_col));
  ini.set(sec, "samples", static_cast<double>(fit.fit.points));
  ini.set(sec, "dt_s", num6(run.dt_s), "s");
  ini.set(sec, "skipped_rows", static_cast<double>(run.skipped), "leading rows without a measured value");
  if (run.window_samples > 0) {
    ini.set(sec, "output_window_s", num6(static_cast<double>(run.window_samples) * run.dt_s),
            "the model's output averaged over the rpm_estimator's window");
  }
  ini.set(sec, "u_ref", num6(fit.u_ref),
          se_comment(fit.u_ref_se, in + ": the run starts settled at this input"));
  ini.set(sec, "y0", num6(fit.y0), se_comment(fit.y0_se, out_col + " there"));
  ini.set(sec, "fit_percent", num6(fit.fit_percent), "100 (1 - |y - y_hat| / |y - mean y|)");
  ini.set(sec, "rms", num6(fit.rms), out_col + ", y - y_hat");
  if (held_out) {
    ini.set(sec, "validate", options.validate);
    ini.set(sec, "validate_fit_percent", num6(*held_out), "the held-out run, its offset re-estimated");
  }
  ini.set(sec, "iterations", static_cast<double>(fit.fit.nls.iterations));
  ini.write(io.out);
}

}  // namespace

void FitTf::define(CLI::App& app) {
  m_app = &app;
  FitTfOptions& tf = options;
  CLI::App* tfc = &app;
  tfc->add_option("--poles", tf.fit.poles, "number of poles")
      ->check(mcg::Range(1, 12))
      ->capture_default_str();
  tfc->add_option("--zeros", tf.fit.zeros, "number of zeros")
      ->check(mcg::Range(0, 12))
      ->capture_default_str();
  tfc->add_option("--f-min,--fmin", tf.fit.f_min_hz, "ignore frequencies below, Hz")
      ->check(mcg::Range(0.0, 1e9));
  tfc->add_option("--f-max,--fmax", tf.fit.f_max_hz, "ignore frequencies above, Hz")
      ->check(mcg::Range(0.0, 1e9));
  tfc->add_flag("!--no-coherence", tf.fit.use_coherence, "weight all frequencies alike");
  tfc->add_flag("--delay", tf.fit.fit_delay, "fit a transport delay too (written as delay_s)");
  tfc->add_option(
      "--units", tf.units,
      "what the response maps when its metadata does not say: 'v -> rpm', 'duty -> rpm', 'v -> omega'");
  tfc->add_option("--in", tf.in_column,
                  "time-domain run: the input column (default: the excitation line's column, else v)");
  tfc->add_option("--out", tf.out_column, "time-domain run: the output column (rpm, else omega)");
  tfc->add_option("--validate", tf.validate, "time-domain run: a held-out run the fit is scored on");
  tfc->add_option(
         "file", tf.file,
         "f_hz,mag_db,phase_deg[,coherence] table, or a run with t and the two columns ('-' = stdin)")
      ->capture_default_str();
}

int FitTf::run(Io& io) {
  options.band_given = m_app->count("--f-min") + m_app->count("--f-max") + m_app->count("--no-coherence") > 0;
  const table::Table table = table::read_path(options.file);
  if (!table.has("f_hz") && table.has("t")) {
    run_tf_time(table, options, io);
    return 0;
  }
  if (!options.in_column.empty() || !options.out_column.empty() || !options.validate.empty()) {
    fail("{}: --in, --out and --validate apply to a time-domain run; this is a frequency response",
         table.source);
  }
  const FrequencyResponse fr = read_frequency_response(table);
  if (fr.window_zeros > 0) {
    io.diag.note(
        fmt::format("{}: left out {} frequencies near the zeros of the rpm estimator's {} s window, "
                    "which hide the response there",
                    fr.source, fr.window_zeros, num6(fr.output_window_s)));
  }
  const TfFit fit = fit_tf(fr, options.fit);
  const auto [maps, words] = fitted_units(fr, options.units);
  check_phase_residual(fr, options, fit, io);
  config::Ini ini = plant_ini(fit, options.fit, maps, words, io.tool);
  const std::string sec = "fit.tf";
  if (fr.output_window_s > 0.0) {
    ini.set(sec, "output_window_s", num6(fr.output_window_s),
            "the rpm_estimator's window, divided out of the response: the fit is the plant's");
  }
  ini.set(sec, "points", static_cast<double>(fit.points));
  ini.set(sec, "rms_mag_db", num6(fit.rms_mag_db));
  ini.set(sec, "rms_phase_deg", num6(fit.rms_phase_deg));
  ini.set(sec, "iterations", static_cast<double>(fit.nls.iterations));
  ini.write(io.out);
  return 0;
}

}  // namespace mcg::cmd
