// The sim-to-real gap diagnosis (see gap.hpp for the method; gap_parts.hpp for its parts).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <ostream>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "fit/discrepancy.hpp"
#include "fit/gap_parts.hpp"
#include "table/table.hpp"

namespace mcg::fit {

using namespace gap_detail;

namespace {

/// "; what is left lies mostly in direction reverse (82 % of it), speed < 12.5 rad/s (70 %)...":
/// per group of regimes (and the frequency bands) the regime carrying most of the residual
/// left, named when it carries clearly more than its share of the samples.
std::string where_left(const GapReport& report) {
  const bool speed = floor_index(report.floors, "rpm") != std::string::npos;
  const std::vector<RegimeStat>& regimes = speed ? report.regimes_after : report.current_regimes_after;
  std::size_t all = 0;
  for (const auto& r : regimes) {
    if (r.group == "all") all = r.samples;
  }
  std::vector<std::string> parts;
  auto strongest = [&](const std::vector<RegimeStat>& stats, std::string_view group, bool by_samples) {
    const RegimeStat* best = nullptr;
    for (const auto& r : stats) {
      if (r.group == group && r.samples > 0 && (best == nullptr || r.share > best->share)) best = &r;
    }
    if (best == nullptr || best->share < 0.5) return;
    // A regime holding most of the samples holds most of any residual: not a finding.
    if (by_samples && all > 0 &&
        best->share < 1.25 * static_cast<double>(best->samples) / static_cast<double>(all)) {
      return;
    }
    parts.push_back(fmt::format("{} {} ({:.0f} %)", group, best->regime, 100.0 * best->share));
  };
  for (const char* group : {"direction", "speed", "clutch", "load", "timing"})
    strongest(regimes, group, true);
  if (speed) strongest(report.bands_after, "band", false);
  if (parts.empty()) return "; what is left is spread over every regime and band";
  std::string out =
      fmt::format("; what is left of the {} residual lies mostly in", speed ? "speed" : "current");
  for (std::size_t k = 0; k < parts.size(); ++k) out += (k == 0 ? " " : ", ") + parts[k];
  return out;
}

/// "; the discrepancy finds a torque of 2.0 +- 0.1 mN m sin(1 theta + 0.3 +- 0.05 rad), once per
/// revolution: an imbalance ... (closing 85 % of the rest)": the verdict's shape, every
/// surviving term (the catalog part is the best candidate the verdict names beside it).
std::string shape_found(const DiscrepancyResult& d, const GapCandidate& best) {
  if (d.terms.empty()) return {};
  std::string out = "; the discrepancy finds";
  for (std::size_t k = 0; k < d.terms.size(); ++k) {
    const DiscrepancyTerm& t = d.terms[k];
    const std::string value =
        t.order != 0.0 ? fmt::format("{:.3g} +- {:.2g} {} at phase {:.2f} +- {:.2f} rad", t.coefficient,
                                     t.std_error, t.unit, t.phase_rad, t.phase_se_rad)
                       : fmt::format("{:.3g} +- {:.2g} {}", t.coefficient, t.std_error, t.unit);
    out += fmt::format("{} {} ({}: {})", k == 0 ? "" : ",", t.basis, value, t.reading);
  }
  out += closing_text(d);
  if (!best.effects.empty()) out += fmt::format(" beside the catalog's {}", best.name);
  return out;
}

/// "; the training runs drive the shaft one way only, where ... act alike": while the shaft
/// turns one way, a Coulomb level (against the motion), a brush drop (against the current) and
/// a dead band of the drive (against the drive) are one constant torque, apart from where the
/// current reverses as the shaft slows down, so the speed alone hardly tells them apart; a
/// measured current tells the friction from the two voltages, and the voltages from each other
/// only where it reverses. Which effect has which shape is its plan's (seeded_by). Names the
/// diagnosis' effect and the others of its class with their scores: the verdict is the class,
/// and the runs that would tell its members apart. Empty when none of this applies.
std::string alike_one_way(const GapReport& report, const GapData& data) {
  using Shape = model::TermShape;
  bool forward = false;
  bool reverse = false;
  bool current = false;
  bool i_forward = false;
  bool i_reverse = false;
  const std::size_t f_i = floor_index(report.floors, "i");
  for (const Run& run : data.train) {
    for (double v : drive_command(run)) {
      forward = forward || v > 0.0;
      reverse = reverse || v < 0.0;
    }
    const auto o = std::find(run.outputs.begin(), run.outputs.end(), "i");
    if (o == run.outputs.end() || f_i == std::string::npos) continue;
    current = true;
    // A reversal counts when it stands clear of the reading's noise.
    const double clear = 3.0 * report.floors[f_i].floor;
    for (double i : run.measured[static_cast<std::size_t>(o - run.outputs.begin())]) {
      i_forward = i_forward || i > clear;
      i_reverse = i_reverse || i < -clear;
    }
  }
  if ((forward && reverse) || (i_forward && i_reverse)) return {};
  const auto shape_of = [&](std::string_view name) {
    const model::EffectSpec* spec = model::find_effect(name);
    if (spec == nullptr || !not_applicable(spec->plan, data.train).empty()) return Shape::none;
    return offset_shape(name, !current);
  };
  const GapCandidate& diagnosis = report.candidates.front();
  std::string mine;
  for (const std::string& name : diagnosis.effects) {
    if (shape_of(name) != Shape::none) mine = name;
  }
  if (mine.empty()) return {};
  std::vector<std::string> others;
  for (const model::EffectSpec& spec : model::effect_catalog()) {
    const Shape s = shape_of(spec.name);
    if (s == Shape::none || spec.name == mine) continue;
    std::string score;
    for (const GapCandidate& c : report.candidates) {
      if (c.name == spec.name && c.evaluated && std::isfinite(c.score)) {
        score = fmt::format(", score {:.3g}", c.score);
      }
    }
    others.push_back(fmt::format("{} ({}{})", model::term_shape_text(s), spec.name, score));
  }
  if (others.empty()) return {};
  std::string list;
  for (std::size_t k = 0; k < others.size(); ++k) {
    list += (k == 0 ? "" : k + 1 == others.size() ? " and " : ", ") + others[k];
  }
  return fmt::format(
      "; the training runs drive the shaft one way only, where {} ({}) acts on the {} as {} would{}: these "
      "runs hardly tell them apart (runs in both directions{} do)",
      model::term_shape_text(shape_of(mine)), mine, current ? "speed and the current" : "speed", list,
      current ? "" : " save where the current reverses", current ? "" : ", or the current measured,");
}

/// "; with a dead band of the drive (hbridge) in place of a brush drop (brush_drop), ... explains
/// these runs as well": a dead band and a brush drop beside a Coulomb level differ only where the
/// current and the drive oppose (a drive braking from a speed), a few rows that measurement noise
/// can hide. When the mixture that swaps one of the diagnosis' offsets for one of another shape
/// scores no significantly worse, the verdict says so: the runs named the class, not the member.
/// `shape_of` gives an effect's offset shape. Empty when no such mixture was fitted.
template <class ShapeOf>
std::string alike_in_place(const GapReport& report, const ShapeOf& shape_of) {
  const GapCandidate& diagnosis = report.candidates.front();
  const auto holds = [](const GapCandidate& c, const std::string& e) {
    return std::find(c.effects.begin(), c.effects.end(), e) != c.effects.end();
  };
  for (const GapCandidate& c : report.candidates) {
    if (&c == &diagnosis || c.effects.size() != diagnosis.effects.size() || !c.evaluated ||
        !std::isfinite(c.score) || improves(diagnosis.score, c.score, report.floors.size()))
      continue;
    std::vector<std::string> out;
    std::vector<std::string> in;
    for (const std::string& e : diagnosis.effects) {
      if (!holds(c, e)) out.push_back(e);
    }
    for (const std::string& e : c.effects) {
      if (!holds(diagnosis, e)) in.push_back(e);
    }
    if (out.size() != 1 || in.size() != 1) continue;
    const model::TermShape shape_out = shape_of(out.front());
    const model::TermShape shape_in = shape_of(in.front());
    if (shape_out == model::TermShape::none || shape_in == model::TermShape::none || shape_in == shape_out)
      continue;
    return fmt::format(
        "; with {} ({}) in place of {} ({}), {} explains these runs as well (score {:.3g} against {:.3g}): "
        "they hardly tell the two apart (a drive braking from a speed, where the current opposes the drive, "
        "with less noise tells them apart)",
        model::term_shape_text(shape_in), in.front(), model::term_shape_text(shape_out), out.front(), c.name,
        c.score, diagnosis.score);
  }
  return {};
}

/// "; hbridge (a dead band of the drive) explains these runs too ...": in both directions a
/// Coulomb level and a dead band of the drive still act alike wherever the shaft turns, and a
/// drive that brakes at zero leaves only the coasts and reversals to tell them apart, which
/// measurement noise can hide. When an effect of that class outside the diagnosis explains the
/// gap alone by the verdict's own rule (near the noise, or most of the excess removed), the
/// verdict says so: the diagnosis' levels may hold the other's. Empty when that is not so.
std::string alike_both_ways(const GapReport& report) {
  using Shape = model::TermShape;
  const bool current = floor_index(report.floors, "i") != std::string::npos;
  const auto shape_of = [&](std::string_view name) { return offset_shape(name, !current); };
  const GapCandidate& diagnosis = report.candidates.front();
  const auto none = std::find_if(report.candidates.begin(), report.candidates.end(),
                                 [](const GapCandidate& c) { return c.name == "none"; });
  if (none == report.candidates.end() || !std::isfinite(none->score)) return {};
  const auto outputs = static_cast<double>(report.floors.size());
  const auto explains = [&](const GapCandidate& c) {
    return c.evaluated && std::isfinite(c.score) &&
           (c.score <= (1.0 + k_gap_near_noise) * outputs ||
            none->score - c.score >= k_gap_explained_share * (none->score - outputs));
  };
  std::string mine;
  for (const std::string& name : diagnosis.effects) {
    // A diagnosis holding two of the class (a dead band beside a Coulomb level): the runs told the
    // two apart, but perhaps not one of them from a third shape in its place.
    if (shape_of(name) != Shape::none && !mine.empty() && shape_of(name) != shape_of(mine))
      return alike_in_place(report, shape_of);
    if (shape_of(name) != Shape::none) mine = name;
  }
  if (mine.empty()) return {};
  for (const GapCandidate& c : report.candidates) {
    if (c.effects.size() != 1 || shape_of(c.name) == Shape::none || shape_of(c.name) == shape_of(mine) ||
        std::find(diagnosis.effects.begin(), diagnosis.effects.end(), c.name) != diagnosis.effects.end() ||
        !explains(c)) {
      continue;
    }
    return fmt::format(
        "; {} ({}) alone explains these runs too (score {:.3g} against {:.3g}): they hardly tell it from {} "
        "({}), whose levels may hold it (coasts at zero drive and slow reversals with less noise tell them "
        "apart)",
        model::term_shape_text(shape_of(c.name)), c.name, c.score, diagnosis.score,
        model::term_shape_text(shape_of(mine)), mine);
  }
  return {};
}

/// Catalog effects seeded from the discrepancy's terms (catalog_seeds): each started from
/// its term's values and fitted on the training runs; one that then closes the gap by the
/// decision's rule (near the noise, or k_gap_explained_share of the excess removed) with
/// every parameter determined becomes the diagnosis.
void seed_catalog(GapReport& report, const GapData& data, const GapSettings& settings, double before_score) {
  const std::size_t outputs = report.floors.size();
  const GapCandidate reference = report.candidates.front();
  const double excess = before_score - static_cast<double>(outputs);
  for (const model::Effect& seed : catalog_seeds(*report.discrepancy, reference.model)) {
    if (std::find(settings.excluded.begin(), settings.excluded.end(), seed.name) != settings.excluded.end()) {
      continue;
    }
    const model::EffectSpec* spec = model::find_effect(seed.name);
    if (!not_applicable(spec->plan, data.train).empty()) continue;
    FitProblem problem;
    problem.model = reference.model;
    problem.model.effects.push_back(seed);
    hold_unfitted(problem.model.effects.back(), data.train);
    problem.runs = data.train;
    for (const std::string& key : fitted_keys(*spec, data.train)) {
      if (key != spec->plan.angle_order_key) problem.free.push_back(seed.name + "." + key);
    }
    problem.bounds = settings.bounds;
    problem.nls.max_evaluations = 60 * static_cast<int>(problem.free.size() + 1);
    const auto deadline = settings.deadline;
    problem.nls.stop = [deadline] { return std::chrono::steady_clock::now() > deadline; };
    FitResult fit;
    try {
      fit = fit_model(problem);
    } catch (const Error&) {
      continue;
    }
    const Evaluation ev = evaluate(fit.model, data, report.floors);
    const bool determined =
        std::none_of(fit.flags.begin(), fit.flags.end(), [](const FitFlag& f) { return f.undetermined(); });
    DiscrepancySeed result;
    result.effect = model::format_effect(*fit.model.effect(seed.name));
    result.rms_rpm = ev.rms[floor_index(report.floors, "rpm")];
    result.closes =
        determined && (ev.score <= (1.0 + k_gap_near_noise) * static_cast<double>(outputs) ||
                       (excess > 0.0 && (before_score - ev.score) / excess >= k_gap_explained_share));
    report.discrepancy->seeds.push_back(result);
    if (!result.closes || report.diagnosis != "unexplained") continue;
    GapCandidate c;
    c.name = seed.name;
    c.effects = reference.effects;
    c.effects.push_back(seed.name);
    if (reference.effects.size() > 0) c.name = reference.name + "+" + seed.name;
    c.status = "fitted (seeded from the discrepancy)";
    c.model = fit.model;
    c.free = fit.nls.names;
    for (Eigen::Index k = 0; k < fit.nls.values.size(); ++k) {
      c.values.push_back(fit.nls.values[k]);
      c.std_errors.push_back(fit.reported_se(static_cast<std::size_t>(k)));
    }
    c.added_parameters = reference.added_parameters + c.free.size();
    c.score = ev.score;
    c.rms = ev.rms;
    c.fpe = fpe(ev.score, reference.free.size() + c.free.size(),
                static_cast<double>(report.validation_samples * outputs));
    c.train_rms_rpm = training_speed_rms(fit.model, data.train, problem.sim);
    c.significant = true;
    c.evaluated = true;
    c.warnings = fit.warnings;
    c.flags = fit.flags;
    report.reason = fmt::format(
        "{} started from the discrepancy term of its shape and fitted closes the gap (validation rpm RMS "
        "{:.3g} -> {:.3g}): {}",
        seed.name, report.discrepancy->rms_before_rpm, result.rms_rpm, result.effect);
    report.diagnosis = c.name;
    report.candidates.insert(report.candidates.begin(), std::move(c));
  }
}

}  // namespace

GapReport diagnose_gap(const model::Model& model, const GapData& data, const GapSettings& settings) {
  MCG_DEMAND(!data.train.empty() && !data.validate.empty());
  check_excluded(settings.excluded);
  // One pool for the whole diagnosis: candidates, their grid points, Jacobian columns and runs.
  const parallel::Pool pool(settings.threads);
  GapReport report;
  report.split_note = data.split_note;
  report.speed_unit = data.speed_unit;
  report.drive_input = drive_name(data.validate.front().run);
  report.validation_samples = validation_count(data);
  report.floors = noise_floors(data);
  const std::size_t outputs = report.floors.size();

  // The model as given; a gap when it misses by more than the noise allows.
  Evaluation before = evaluate(model, data, report.floors);
  // Measurement noise is part of every model's residual: a data estimate above the RMS of
  // the model as given has caught signal (steps, fast excitation), and the chain stands.
  // Noise above what the chain states (a noisier sensor, interference the metadata cannot
  // know) shows in the model's residual, where the excitation's steps no longer count: the
  // residual's own estimate stands when it exceeds the chain by k_gap_data_floor_factor.
  bool reverted = false;
  for (std::size_t f = 0; f < outputs; ++f) {
    OutputFloor& of = report.floors[f];
    const double residual = residual_noise(data, before, of.output);
    if (of.noise.chain > 0.0 && residual > k_gap_data_floor_factor * of.noise.chain) {
      of.noise.data = residual;
      of.floor = residual;
      reverted = true;
      continue;
    }
    if (of.noise.chain > 0.0 && of.floor > of.noise.chain && of.floor > before.rms[f]) {
      of.floor = std::max(of.noise.chain, 1e-3 * before.rms[f]);
      reverted = true;
    }
  }
  if (reverted) before = evaluate(model, data, report.floors);
  const bool gap = improves(static_cast<double>(outputs), before.score, outputs);
  decide(search_candidates(model, data, report.floors, before, gap, settings), gap, outputs, report);
  // Pinned only now: held during the search, a pin changed which candidates were significant.
  if (report.diagnosis != "none" && report.diagnosis != "unexplained") {
    converge_diagnosis(report.candidates.front(), data, report.floors, settings);
    pin_diagnosis(report.candidates.front(), model, data, report.floors, settings);
    widen_diagnosis_scales(report.candidates.front(), data, report.floors, settings);
    profile_nominal_breakaway(report.candidates.front(), data, report.floors, settings);
  }
  for (GapCandidate& c : report.candidates) flag_infinite_errors(c);

  const bool diagnosed = report.diagnosis != "unexplained";
  // The discrepancy terms are a fit of their own: one the time budget leaves no room for is not begun.
  if ((!diagnosed || settings.discrepancy) && std::chrono::steady_clock::now() < settings.deadline) {
    if (settings.progress) settings.progress("fitting the catalog-free discrepancy terms");
    // The reference is the diagnosis' model (for unexplained: the best candidate's).
    const auto deadline = settings.deadline;
    report.discrepancy = fit_discrepancy(
        report.candidates.front().model, data, angle_orders(report.candidates.front().model, data.train, 2),
        report.floors, [deadline] { return std::chrono::steady_clock::now() > deadline; });
    if (!diagnosed) seed_catalog(report, data, settings, before.score);
  }
  report.simulated_before = before.simulated;
  const Evaluation after = evaluate(report.candidates.front().model, data, report.floors);
  report.simulated_after = after.simulated;
  analyse(data, report.simulated_before, report.regimes_before, report.bands_before,
          report.current_regimes_before, report.white_before);
  analyse(data, report.simulated_after, report.regimes_after, report.bands_after,
          report.current_regimes_after, report.white_after);
  if (report.diagnosis != "none") {
    const std::string one_way = alike_one_way(report, data);
    report.reason += one_way.empty() ? alike_both_ways(report) : one_way;
  }
  if (report.diagnosis == "unexplained") {
    report.reason += where_left(report);
    if (report.discrepancy) report.reason += shape_found(*report.discrepancy, report.candidates.front());
  }
  return report;
}

void warn_flags(const GapReport& report, Diagnostics& diag) {
  const GapCandidate& diagnosis = report.candidates.front();
  for (const PinnedParameter& pin : diagnosis.pinned)
    diag.note(fmt::format("{}: {}", diagnosis.name, pinned_text(pin)));
  for (const auto& w : diagnosis.warnings) diag.warning(fmt::format("{}: {}", diagnosis.name, w));
}

int run_gap(const GapOptions& options, std::ostream& out, Diagnostics& diag) {
  const auto started = std::chrono::steady_clock::now();
  model::Model model;
  GapSettings settings;
  measurement::SpeedPath speed;  // the model's [measurement]: gear ratio and speed filter
  if (!options.config.empty()) {
    const config::Ini ini = config::Ini::load_all(options.config);
    model = model::model_from_ini(ini);
    settings.bounds = read_bounds(ini, model);
    speed = measurement::speed_path_from_ini(ini);
  }
  settings.fixed = fix_parameters(model, options.fix);
  check_excluded(options.exclude);
  settings.excluded = options.exclude;
  if (!(options.from_s < options.to_s))
    fail("--from {} s is not before --to {} s", options.from_s, options.to_s);
  auto load = [&](const std::vector<std::string>& paths) {
    std::vector<table::Table> tables;
    for (const auto& p : paths) {
      tables.push_back(select_time(
          with_speed_from_position(table::read(open_input(p), input_name(p)), options.position_column),
          options.from_s, options.to_s));
    }
    return tables;
  };
  const std::vector<table::Table> train = load(options.train);
  const std::vector<table::Table> validate = load(options.validate);
  GapData data = prepare_gap_data(train, validate, model.params, options.split_fraction, options.split_given,
                                  options.drive);
  if (options.linear) {
    if (data.speed_unit.column != "omega")
      fail("--linear: the runs must measure the axis' speed as omega, m/s");
    data.speed_unit.name = "m/s";
    data.speed_unit.key = "m_s";
  }
  for (auto& run : data.train) apply_speed_path(run, speed, options.gear_ratio);
  for (auto& sr : data.validate) apply_speed_path(sr.run, speed, options.gear_ratio);
  settings.threads = options.threads;
  settings.discrepancy = options.discrepancy;
  settings.sensitivities = options.sensitivities;
  settings.deadline = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(options.budget_s));
  if (options.progress) {
    settings.progress = [&diag](const std::string& line) {
      diag.report(line);
      diag.stream().flush();
    };
  }
  GapReport report = diagnose_gap(model, data, settings);
  report.source = options.tool + " gap";
  if (!options.residuals.empty()) {
    std::ofstream file(options.residuals);
    if (!file) fail("--residuals: cannot open {} for writing", quote(options.residuals));
    write_gap_residuals(file, report, data);
  }
  if (options.format == "text") {
    write_gap_text(out, report);
    warn_flags(report, diag);
  } else {
    write_gap_csv(out, report);
    write_gap_text(diag.stream(), report);
  }
  return report.partial ? k_gap_partial_exit : 0;
}

}  // namespace mcg::fit
