// The gap diagnosis' report: where the residual lies (regimes, bands, whiteness) and the
// CSV, text and residual-series outputs.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <ostream>
#include <string_view>
#include <utility>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "config/ini.hpp"
#include "fit/discrepancy.hpp"
#include "fit/gap_parts.hpp"
#include "table/table.hpp"

namespace mcg::fit {

using namespace gap_detail;

namespace {

std::vector<RegimeStat> pool(const std::vector<std::vector<RegimeStat>>& parts) {
  if (parts.empty()) return {};
  std::vector<RegimeStat> out = parts.front();
  std::vector<double> sum_sq(out.size(), 0.0);
  for (auto& s : out) s.samples = 0;
  for (const auto& part : parts) {
    MCG_DEMAND(part.size() == out.size());
    for (std::size_t k = 0; k < part.size(); ++k) {
      if (part[k].samples == 0) continue;
      out[k].samples += part[k].samples;
      sum_sq[k] += part[k].rms * part[k].rms * static_cast<double>(part[k].samples);
    }
  }
  // The total is the "all" row of a regime table, or the sum of the rows of a band table.
  double total = 0.0;
  bool has_all = false;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (out[k].group == "all") {
      total = sum_sq[k];
      has_all = true;
    }
  }
  if (!has_all) {
    for (double v : sum_sq) total += v;
  }
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k].rms = out[k].samples > 0 ? std::sqrt(sum_sq[k] / static_cast<double>(out[k].samples)) : k_nan;
    out[k].share = total > 0.0 ? sum_sq[k] / total : 0.0;
  }
  return out;
}

/// The residual of output `name` of every validation run (NaN on unscored rows).
std::vector<std::vector<double>> residual_series(
    const GapData& data, const std::vector<std::vector<std::vector<double>>>& simulated,
    const std::string& name) {
  std::vector<std::vector<double>> out;
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const ScoredRun& sr = data.validate[r];
    std::vector<double> res(sr.run.inputs.t_s.size(), k_nan);
    const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), name);
    if (it != sr.run.outputs.end()) {
      const auto o = static_cast<std::size_t>(it - sr.run.outputs.begin());
      for (std::size_t n = sr.first_scored; n < res.size(); ++n)
        res[n] = sr.run.measured[o][n] - simulated[r][o][n];
    }
    out.push_back(std::move(res));
  }
  return out;
}

std::vector<double> measured_rpm(const Run& run) {
  const auto it = std::find(run.outputs.begin(), run.outputs.end(), "rpm");
  if (it == run.outputs.end()) return std::vector<double>(run.inputs.t_s.size(), k_nan);
  return run.measured[static_cast<std::size_t>(it - run.outputs.begin())];
}

}  // namespace

void gap_detail::analyse(const GapData& data, const std::vector<std::vector<std::vector<double>>>& simulated,
                         std::vector<RegimeStat>& regimes, std::vector<RegimeStat>& bands,
                         std::vector<RegimeStat>& current, Whiteness& white) {
  const auto rpm_res = residual_series(data, simulated, "rpm");
  const auto i_res = residual_series(data, simulated, "i");
  std::vector<std::vector<RegimeStat>> reg, band, cur;
  std::vector<double> joined_r;
  std::vector<double> joined_u;
  std::size_t max_lag = 50;
  std::size_t first_lag = 1;
  // One low-speed bound for every run (their tables are pooled): a share of the fastest
  // scored speed, named in the data's unit.
  double top_rpm = 0.0;
  for (const ScoredRun& sr : data.validate) {
    const std::vector<double> rpm = measured_rpm(sr.run);
    for (std::size_t n = sr.first_scored; n < rpm.size(); ++n) {
      if (std::isfinite(rpm[n])) top_rpm = std::max(top_rpm, std::abs(rpm[n]));
    }
  }
  const double low_rpm = k_low_speed_share * top_rpm;
  const std::string low_label =
      fmt::format("{:.3g} {}", data.speed_unit.per_rpm * low_rpm, data.speed_unit.name);
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const Run& run = data.validate[r].run;
    const std::vector<double> rpm = measured_rpm(run);
    const RegimeContext ctx{&run.inputs, rpm, speed_resolution(run), low_rpm, low_label};
    reg.push_back(regime_breakdown(ctx, rpm_res[r]));
    cur.push_back(regime_breakdown(ctx, i_res[r]));
    std::vector<double> dt;
    for (std::size_t n = 1; n < run.inputs.t_s.size(); ++n)
      dt.push_back(run.inputs.t_s[n] - run.inputs.t_s[n - 1]);
    std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
    const double dt_s = dt[dt.size() / 2];
    band.push_back(band_breakdown(rpm_res[r], dt_s));
    if (run.rpm_estimator) {
      first_lag =
          std::max(first_lag, clamp_to_integer(std::round(run.rpm_estimator->window_s / dt_s), std::size_t{0},
                                               std::numeric_limits<std::size_t>::max()) + 1);
    }
    joined_r.insert(joined_r.end(), rpm_res[r].begin(), rpm_res[r].end());
    // The drive's own input: a current- or torque-driven run's v is 0 throughout.
    const std::vector<double>& u = drive_command(run);
    joined_u.insert(joined_u.end(), u.begin(), u.end());
    joined_r.insert(joined_r.end(), max_lag, k_nan);
    joined_u.insert(joined_u.end(), max_lag, k_nan);
  }
  regimes = pool(reg);
  bands = pool(band);
  current = pool(cur);
  white = whiteness(joined_r, joined_u, max_lag, first_lag);
}

namespace {

double at_or_nan(const std::vector<double>& v, std::size_t k) { return k < v.size() ? v[k] : k_nan; }

/// sqrt(max(0, rms^2 - floor^2)): the part of an RMS above the noise.
double above_noise(double rms, double floor) {
  return std::isfinite(rms) ? std::sqrt(std::max(0.0, rms * rms - floor * floor)) : k_nan;
}

/// The runs are a linear axis' (--linear): the shaft stands for it, a rad of it a m of travel.
bool linear_axis(const GapReport& report) { return report.speed_unit.key == "m_s"; }

/// What the parameters' names say on a linear axis (the header's linear_axis, the summary's line).
constexpr std::string_view k_linear_axis_note =
    "the shaft stands for the axis, a rad of it a m of travel: parameters named _Nm are in N, _Nm_s_rad in "
    "N s/m, _kg_m2 in kg, _rad_s in m/s";

/// `text` with each shaft unit named as the linear axis' (N m: N, N m s/rad: N s/m, kg m^2: kg,
/// rad/s: m/s), when `linear`; an angle (a phase in rad) stays one.
std::string axis_units(std::string text, bool linear) {
  if (!linear) return text;
  static constexpr std::pair<std::string_view, std::string_view> k_units[] = {{"N m s^3/rad^3", "N s^3/m^3"},
                                                                              {"N m s^2/rad^2", "N s^2/m^2"},
                                                                              {"N m s/rad", "N s/m"},
                                                                              {"N m/rad", "N/m"},
                                                                              {"N m/A", "N/A"},
                                                                              {"kg m^2", "kg"},
                                                                              {"N m", "N"},
                                                                              {"rad/s", "m/s"}};
  const auto letter = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '^'; };
  for (const auto& [rotary, linear_unit] : k_units) {
    for (std::size_t at = text.find(rotary); at != std::string::npos; at = text.find(rotary, at)) {
      const std::size_t end = at + rotary.size();
      if ((at > 0 && letter(text[at - 1])) ||
          (end < text.size() && (letter(text[end]) || text[end] == '/'))) {
        at = end;
        continue;
      }
      text.replace(at, rotary.size(), linear_unit);
      at += linear_unit.size();
    }
  }
  return text;
}

std::string number(double v, int digits = 4) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:.{}g}", config::without_negative_zero(v), digits);
}

/// "stribeck.v_s_rad_s=7.9+-0.4 ..." for the added effects first, then the nominal scales.
std::string params_text(const GapCandidate& c) {
  std::vector<std::string> effect_part;
  std::vector<std::string> nominal_part;
  for (std::size_t k = 0; k < c.free.size(); ++k) {
    const std::string item =
        fmt::format("{}={}+-{}", c.free[k], number(c.values[k]), number(c.std_errors[k], 2));
    (c.free[k].rfind("param_mismatch.", 0) == 0 ? nominal_part : effect_part).push_back(item);
  }
  // What the runs do not set is held, not fitted: shown without an error (the status says why).
  for (const PinnedParameter& pin : c.pinned) {
    const std::string item = fmt::format("{}={} (pinned)", pin.name, number(pin.value));
    (pin.name.starts_with("param_mismatch.") ? nominal_part : effect_part).push_back(item);
  }
  // A harmonic order is picked from the data's spectrum, not fitted: shown without an error.
  for (const auto& name : c.effects) {
    const model::EffectSpec* spec = model::find_effect(name);
    const model::Effect* e = c.model.effect(name);
    if (c.evaluated && spec != nullptr && e != nullptr && !spec->plan.angle_order_key.empty()) {
      effect_part.push_back(fmt::format("{}.{}={}", name, spec->plan.angle_order_key,
                                        number(e->get(spec->plan.angle_order_key))));
    }
  }
  std::string out;
  for (const auto& part : {effect_part, nominal_part}) {
    for (const auto& item : part) {
      if (!out.empty()) out += ' ';
      out += item;
    }
  }
  return out;
}

/// A report's text as one CSV cell: its commas (an error's message, a status of several
/// clauses) become semicolons, so that no column after it shifts.
std::string cell(std::string text) {
  std::replace(text.begin(), text.end(), ',', ';');
  return text;
}

/// The fit's flags in a few words each, "; " between them (the CSV's flags column).
std::string flags_text(const GapCandidate& c) {
  std::string out;
  for (const FitFlag& f : c.flags) {
    std::string item;
    switch (f.kind) {
      case FitFlag::Kind::at_bound:
        item = f.names.front() + " at a bound";
        break;
      case FitFlag::Kind::undetermined:
        item = f.names.front() + " not determined";
        break;
      case FitFlag::Kind::too_precise:
        item = f.names.front() + " error too small to be true";
        break;
      case FitFlag::Kind::correlated:
        item = fmt::format("{} and {} correlated beyond {}", f.names.front(), f.names.back(), k_max_correlation);
        break;
      case FitFlag::Kind::impossible:
        item = f.names.front() + " physically impossible";
        break;
    }
    out += (out.empty() ? "" : "; ") + item;
  }
  return out;
}

struct Summary {
  std::size_t rpm = std::string::npos;
  std::size_t i = std::string::npos;
  double floor_rpm = k_nan;
  double floor_i = k_nan;
};

Summary summary_of(const GapReport& report) {
  Summary s;
  s.rpm = floor_index(report.floors, "rpm");
  s.i = floor_index(report.floors, "i");
  if (s.rpm != std::string::npos) s.floor_rpm = report.floors[s.rpm].floor;
  if (s.i != std::string::npos) s.floor_i = report.floors[s.i].floor;
  return s;
}

void write_regime_table(std::ostream& out, const std::string& title, const std::vector<RegimeStat>& before,
                        const std::vector<RegimeStat>& after, const std::string& unit, int digits,
                        double scale = 1.0) {
  out << fmt::format("{}\n  {:<22} {:>8} {:>12} {:>7} {:>12} {:>7}\n", title, "regime", "samples",
                     fmt::format("before {}", unit), "share", fmt::format("after {}", unit), "share");
  for (std::size_t k = 0; k < before.size() && k < after.size(); ++k) {
    const auto& b = before[k];
    const auto& a = after[k];
    if (b.samples == 0) continue;
    out << fmt::format("  {:<22} {:>8} {:>12.{}f} {:>6.1f}% {:>12.{}f} {:>6.1f}%\n", b.group + " " + b.regime,
                       b.samples, scale * b.rms, digits, 100.0 * b.share, scale * a.rms, digits,
                       100.0 * a.share);
  }
}

/// An output's name and scale in the report: the speed in the data's own unit and column
/// ("omega", rad/s), the current as it is.
std::string output_name(const GapReport& report, const std::string& output) {
  return output == "rpm" ? report.speed_unit.column : output;
}
double output_scale(const GapReport& report, const std::string& output) {
  return output == "rpm" ? report.speed_unit.per_rpm : 1.0;
}

/// Decimals that show a speed in the report's unit to the noise floor's second significant
/// digit (at least 2: 0.86 rpm and 0.0017 rad/s both read).
int speed_decimals(const GapReport& report, double floor_rpm) {
  const double f = report.speed_unit.per_rpm * floor_rpm;
  if (!(f > 0.0) || !std::isfinite(f)) return 2;
  return std::clamp(1 - static_cast<int>(std::floor(std::log10(f))), 2, 9);
}

}  // namespace

void write_gap_csv(std::ostream& out, const GapReport& report) {
  const Summary s = summary_of(report);
  const std::string& key = report.speed_unit.key;
  const double k = report.speed_unit.per_rpm;
  const GapCandidate& none = *std::find_if(report.candidates.begin(), report.candidates.end(),
                                           [](const auto& c) { return c.name == "none"; });
  const double before_rpm = k * at_or_nan(none.rms, s.rpm);
  const double floor_rpm = k * s.floor_rpm;
  const double before_i = at_or_nan(none.rms, s.i);
  table::Writer w(out);
  if (!report.source.empty()) w.meta("source", report.source);
  w.meta("diagnosis", report.diagnosis);
  if (report.partial)
    w.meta("partial", "the time budget ran out; the ranking is of the candidates fitted so far");
  if (!report.split_note.empty()) w.meta("split", report.split_note);
  for (const auto& f : report.floors) {
    const double u = output_scale(report, f.output);
    w.meta("noise_floor_" + output_name(report, f.output),
           fmt::format("{} (measurement chain {}, from the data {})", number(u * f.floor),
                       number(u * f.noise.chain), number(u * f.noise.data)));
  }
  w.meta("validation_samples", std::to_string(report.validation_samples));
  const bool linear = linear_axis(report);
  if (linear) w.meta("linear_axis", std::string(k_linear_axis_note));
  if (report.discrepancy) {
    const DiscrepancyResult& d = *report.discrepancy;
    for (const auto& term : d.terms) {
      const DiscrepancyTerm t = in_speed_unit(term, report.speed_unit);
      w.meta("discrepancy_term", axis_units(t.equation + "  (" + t.reading + ")", linear));
    }
    for (const auto& t : d.dropped) w.meta("discrepancy_dropped", t + " (the held-out runs do not gain)");
    if (!d.joint.empty()) w.meta("discrepancy_joint", d.joint);
    for (const auto& sd : d.seeds) {
      w.meta("discrepancy_seed",
             fmt::format("{} (validation {} RMS {}{})", sd.effect, report.speed_unit.column,
                         number(k * sd.rms_rpm), sd.closes ? ", closes the gap" : ""));
    }
    if (d.terms.empty()) {
      w.meta("discrepancy", d.note);
    } else {
      w.meta("discrepancy", explained_text(d, true, report.speed_unit));
    }
  }
  w.header({"effect", "rms_before_" + key, "rms_after_" + key, "shrink_pct", "gap_before_" + key,
            "gap_after_" + key, "gap_shrink_pct", "rms_before_i_A", "rms_after_i_A", "train_rms_" + key,
            "score", "fpe", "n_params", "n_added", "params", "significant", "status", "flags"});
  for (const auto& c : report.candidates) {
    const double after_rpm = k * at_or_nan(c.rms, s.rpm);
    const double gap_before = above_noise(before_rpm, floor_rpm);
    const double gap_after = above_noise(after_rpm, floor_rpm);
    const double shrink = 100.0 * (before_rpm - after_rpm) / before_rpm;
    const double gap_shrink = gap_before > 0.0 ? 100.0 * (gap_before - gap_after) / gap_before : k_nan;
    w.text_row({c.name, number(before_rpm, 6), number(after_rpm, 6), number(shrink, 4), number(gap_before, 6),
                number(gap_after, 6), number(gap_shrink, 4), number(before_i, 6),
                number(at_or_nan(c.rms, s.i), 6), number(k * c.train_rms_rpm, 6), number(c.score, 6),
                number(c.fpe, 6), std::to_string(c.free.size()), std::to_string(c.added_parameters),
                cell(params_text(c)), c.significant ? "1" : "0", cell(c.status), cell(flags_text(c))});
  }
  w.finish();
}

void write_gap_text(std::ostream& out, const GapReport& report) {
  const Summary s = summary_of(report);
  const GapCandidate& diag = report.candidates.front();
  const GapCandidate& none = *std::find_if(report.candidates.begin(), report.candidates.end(),
                                           [](const auto& c) { return c.name == "none"; });
  const SpeedUnit& unit = report.speed_unit;
  const double k = unit.per_rpm;
  const int dec = speed_decimals(report, s.floor_rpm);
  out << fmt::format("diagnosis: {}\n  {}.\n", report.diagnosis, report.reason);
  if (!report.split_note.empty()) out << "split: " << report.split_note << "\n";
  for (const auto& f : report.floors) {
    const std::string& u = f.output == "rpm" ? unit.name : "A";
    const double x = output_scale(report, f.output);
    out << fmt::format("noise floor {}: {} {} (measurement chain {}, estimated from the data {})\n",
                       output_name(report, f.output), number(x * f.floor), u, number(x * f.noise.chain),
                       number(x * f.noise.data));
  }
  if (s.rpm != std::string::npos) {
    const double b = k * none.rms[s.rpm];
    const double a = k * diag.rms[s.rpm];
    out << fmt::format(
        "validation {} RMS: {:.{}f} -> {:.{}f} {} ({:.0f} % less); above the noise {:.{}f} -> {:.{}f} {}\n",
        unit.column, b, dec, a, dec, unit.name, 100.0 * (b - a) / b, above_noise(b, k * s.floor_rpm), dec,
        above_noise(a, k * s.floor_rpm), dec, unit.name);
  }
  if (s.i != std::string::npos) {
    out << fmt::format("validation i RMS: {:.4f} -> {:.4f} A\n", none.rms[s.i], diag.rms[s.i]);
  }
  if (!diag.free.empty()) {
    out << (report.diagnosis == "unexplained" ? "best candidate's fitted parameters" : "fitted parameters")
        << " (+- one standard error): " << params_text(diag) << "\n";
  }
  for (const PinnedParameter& pin : diag.pinned) out << "note: " << pinned_text(pin) << "\n";
  const bool linear = linear_axis(report);
  if (linear) out << "linear axis: " << k_linear_axis_note << "\n";
  for (const auto& w : diag.warnings) out << "warning: " << axis_units(w, linear) << "\n";
  if (report.discrepancy) {
    const DiscrepancyResult& d = *report.discrepancy;
    if (d.terms.empty()) {
      out << "discrepancy (catalog-free): " << d.note << "\n";
    } else {
      out << fmt::format(
          "discrepancy (catalog-free, {} of {} library terms kept): what the model lacks, on the motor "
          "shaft, in its circuit or in a reading, {}:\n",
          d.terms.size(), d.library_size,
          linear ? "w in m/s along the axis, theta in m" : "w in rad/s at the motor, theta in rad");
      for (const auto& term : d.terms) {
        const DiscrepancyTerm t = in_speed_unit(term, unit);
        out << axis_units(fmt::format("  {}: {}   (+- {:.2g}{})   {}\n", t.place, t.equation, t.std_error,
                                      t.unit == "1" ? "" : " " + t.unit, t.reading),
                          linear);
      }
      for (const auto& t : d.dropped) out << "  left out, the held-out runs do not gain: " << t << "\n";
      if (!d.joint.empty()) out << "  joint refit with the nominal scales: " << d.joint << "\n";
      for (const auto& sd : d.seeds) {
        out << fmt::format("  seeds the catalog: {} (validation {} RMS {:.{}f}{})\n", sd.effect, unit.column,
                           k * sd.rms_rpm, dec, sd.closes ? ", closes the gap" : "");
      }
      out << "  " << explained_text(d, false, unit) << "\n";
    }
  }
  out << "\ncandidates, diagnosis first (score = validation MSE in noise units summed over outputs; FPE "
         "ranks):\n";
  out << fmt::format("  {:<32} {:>10} {:>10} {:>9} {:>3}  {}\n", "effect", "rms " + unit.name, "score", "fpe",
                     "sig", "status");
  for (const auto& c : report.candidates) {
    out << fmt::format("  {:<32} {:>10} {:>10} {:>9} {:>3}  {}{}\n", c.name,
                       number(k * at_or_nan(c.rms, s.rpm)), number(c.score), number(c.fpe),
                       c.significant ? "yes" : "no", c.status,
                       c.flags.empty() ? "" : ", flagged: " + flags_text(c));
  }
  out << "\n";
  if (s.rpm != std::string::npos) {
    write_regime_table(
        out, fmt::format("where the speed gap lies (validation residual {}, before and after):", unit.name),
        report.regimes_before, report.regimes_after, unit.name, dec, k);
    write_regime_table(out, "by frequency band:", report.bands_before, report.bands_after, unit.name, dec, k);
  }
  if (s.i != std::string::npos) {
    write_regime_table(out,
                       "where the current gap lies (validation residual i):", report.current_regimes_before,
                       report.current_regimes_after, "A", 4);
  }
  auto checks = [&](const char* label, const Whiteness& w) {
    out << fmt::format(
        "  {}: autocorrelation Q = {:.0f} (99 % limit {:.0f}, {}; largest {:.3f} at lag {}), "
        "cross-correlation with {} Q = {:.0f} (limit {:.0f}, {}; largest {:.3f} at lag {})\n",
        label, w.q_auto, w.q_auto_limit, w.white() ? "white" : "not white", w.max_auto, w.max_auto_lag,
        report.drive_input, w.q_cross, w.q_cross_limit, w.independent() ? "independent" : "correlated",
        w.max_cross, w.max_cross_lag);
  };
  out << fmt::format(
      "residual checks (speed; whiteness from lag {}, past the estimator window, to 50 samples):\n",
      report.white_before.first_lag);
  checks("before", report.white_before);
  checks("after ", report.white_after);
}

void write_gap_residuals(std::ostream& out, const GapReport& report, const GapData& data) {
  table::Writer w(out);
  if (!report.source.empty()) w.meta("source", report.source);
  w.meta("diagnosis", report.diagnosis);
  if (linear_axis(report)) w.meta("linear_axis", std::string(k_linear_axis_note));
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    w.meta(fmt::format("run_{}", r + 1), data.validate[r].run.source);
  }
  // The drive's own column as the data log it (v, a current loop's i, the torque column), so
  // that a driven run's residual is plotted against what drove it.
  const std::string drive = data.validate.empty() ? "v" : drive_name(data.validate.front().run);
  std::vector<std::string> names = {"run", "t", drive, "clutch", "r_load", "transient"};
  for (const auto& f : report.floors) {
    for (const char* suffix : {"", "_before", "_after", "_res_before", "_res_after"})
      names.push_back(output_name(report, f.output) + suffix);
  }
  w.header(names);
  std::vector<double> row(names.size());
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const ScoredRun& sr = data.validate[r];
    const model::Inputs& in = sr.run.inputs;
    const std::vector<bool> transient = transient_mask(in);
    for (std::size_t n = sr.first_scored; n < in.t_s.size(); ++n) {
      row[0] = static_cast<double>(r + 1);
      row[1] = in.t_s[n];
      row[2] = drive_command(sr.run)[n];
      row[3] = in.clutch[n];
      row[4] = in.r_load_ohm[n];
      row[5] = transient[n] ? 1.0 : 0.0;
      std::size_t k = 6;
      for (const auto& f : report.floors) {
        const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), f.output);
        const bool has = it != sr.run.outputs.end();
        const auto o = static_cast<std::size_t>(it - sr.run.outputs.begin());
        const double u = output_scale(report, f.output);
        const double y = has ? u * sr.run.measured[o][n] : k_nan;
        const double b = has ? u * report.simulated_before[r][o][n] : k_nan;
        const double a = has ? u * report.simulated_after[r][o][n] : k_nan;
        row[k++] = y;
        row[k++] = b;
        row[k++] = a;
        row[k++] = y - b;
        row[k++] = y - a;
      }
      w.row(row);
    }
  }
  w.finish();
}

}  // namespace mcg::fit
