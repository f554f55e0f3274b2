// The sim-to-real gap diagnosis (see gap.hpp for the method; gap_parts.hpp for its parts).
#include "fit/gap_parts.hpp"

#include "common/error.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "table/table.hpp"

#include "common/demand.hpp"
#include <fstream>
#include <ostream>

namespace mcg::fit {

using namespace gap_detail;

GapReport diagnose_gap(const model::Model& model, const GapData& data, const GapSettings& settings) {
  MCG_DEMAND(!data.train.empty() && !data.validate.empty());
  GapReport report;
  report.split_note = data.split_note;
  report.validation_samples = validation_count(data);
  report.floors = noise_floors(data);
  const std::size_t outputs = report.floors.size();

  // The model as given; a gap when it misses by more than the noise allows.
  const Evaluation before = evaluate(model, data, report.floors);
  const bool gap = improves(static_cast<double>(outputs), before.score, outputs);
  decide(search_candidates(model, data, report.floors, before, gap, settings), gap, outputs, report);

  report.simulated_before = before.simulated;
  const Evaluation after = evaluate(report.candidates.front().model, data, report.floors);
  report.simulated_after = after.simulated;
  analyse(data, report.simulated_before, report.regimes_before, report.bands_before, report.current_regimes_before,
          report.white_before);
  analyse(data, report.simulated_after, report.regimes_after, report.bands_after, report.current_regimes_after,
          report.white_after);
  return report;
}

void run_gap(const GapOptions& options, std::ostream& out, std::ostream& err) {
  model::Model model;
  GapSettings settings;
  if (!options.config.empty()) {
    const config::Ini ini = config::Ini::load_all(options.config);
    model = model::model_from_ini(ini);
    settings.bounds = read_bounds(ini, model);
  }
  settings.fixed = fix_parameters(model, options.fix);
  if (!(options.from_s < options.to_s)) fail("--from {} s is not before --to {} s", options.from_s, options.to_s);
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
  if (stderr_is_terminal()) {
    settings.progress = [&err](const std::string& line) { err << "mcg-fit gap: " << line << std::endl; };
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
    write_gap_text(err, report);
  }
}

}  // namespace mcg::fit
