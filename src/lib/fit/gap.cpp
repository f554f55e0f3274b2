// The sim-to-real gap diagnosis (see gap.hpp for the method; gap_parts.hpp for its parts).
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <ostream>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "fit/discrepancy.hpp"
#include "fit/gap_parts.hpp"
#include "table/table.hpp"

namespace mcg::fit {

using namespace gap_detail;

namespace {

/// "; what is left lies mostly in direction reverse (82 % of it), speed < 150 rpm (70 %)...":
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

}  // namespace

GapReport diagnose_gap(const model::Model& model, const GapData& data, const GapSettings& settings) {
  MCG_DEMAND(!data.train.empty() && !data.validate.empty());
  check_excluded(settings.excluded);
  GapReport report;
  report.split_note = data.split_note;
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

  report.simulated_before = before.simulated;
  const Evaluation after = evaluate(report.candidates.front().model, data, report.floors);
  report.simulated_after = after.simulated;
  analyse(data, report.simulated_before, report.regimes_before, report.bands_before,
          report.current_regimes_before, report.white_before);
  analyse(data, report.simulated_after, report.regimes_after, report.bands_after,
          report.current_regimes_after, report.white_after);
  if (report.diagnosis == "unexplained") report.reason += where_left(report);
  if (report.diagnosis == "unexplained" || settings.discrepancy) {
    if (settings.progress) settings.progress("fitting the catalog-free discrepancy terms");
    // The reference is the diagnosis' model (for unexplained: the best candidate's).
    report.discrepancy =
        fit_discrepancy(report.candidates.front().model, data,
                        angle_orders(report.candidates.front().model, data.train, 2), report.floors);
  }
  return report;
}

int run_gap(const GapOptions& options, std::ostream& out, Diagnostics& diag) {
  const auto started = std::chrono::steady_clock::now();
  model::Model model;
  GapSettings settings;
  if (!options.config.empty()) {
    const config::Ini ini = config::Ini::load_all(options.config);
    model = model::model_from_ini(ini);
    settings.bounds = read_bounds(ini, model);
  }
  settings.fixed = fix_parameters(model, options.fix);
  check_excluded(options.exclude);
  settings.excluded = options.exclude;
  if (!(options.from_s < options.to_s))
    fail("--from {} s is not before --to {} s", options.from_s, options.to_s);
  auto load = [&](const std::vector<std::string>& paths) {
    std::vector<table::Table> tables;
    for (const auto& p : paths) {
      tables.push_back(select_time(table::read(open_input(p), input_name(p)), options.from_s, options.to_s));
    }
    return tables;
  };
  const std::vector<table::Table> train = load(options.train);
  const std::vector<table::Table> validate = load(options.validate);
  GapData data = prepare_gap_data(train, validate, model.params, options.split_fraction);
  for (auto& run : data.train) run.gear_ratio = options.gear_ratio;
  for (auto& sr : data.validate) sr.run.gear_ratio = options.gear_ratio;
  settings.threads = options.threads;
  settings.discrepancy = options.discrepancy;
  settings.deadline = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(options.budget_s));
  if (options.progress) {
    settings.progress = [&diag](const std::string& line) {
      diag.report(line);
      diag.stream().flush();
    };
  }
  const GapReport report = diagnose_gap(model, data, settings);
  if (!options.residuals.empty()) {
    std::ofstream file(options.residuals);
    if (!file) fail("--residuals: cannot open {} for writing", quote(options.residuals));
    write_gap_residuals(file, report, data);
  }
  if (options.format == "text") {
    write_gap_text(out, report);
  } else {
    write_gap_csv(out, report);
    write_gap_text(diag.stream(), report);
  }
  return report.partial ? k_gap_partial_exit : 0;
}

}  // namespace mcg::fit
