// The gap diagnosis' data: the training and validation runs, the split of a single file, the
// measurement chain of each run and the noise floors it implies.
#include "fit/gap_parts.hpp"

#include "common/demand.hpp"
#include "common/error.hpp"
#include "measurement/measurement.hpp"
#include "table/table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>

namespace mcg::fit {

namespace {

std::vector<std::string> compared_outputs(const table::Table& t) {
  std::vector<std::string> out;
  for (const char* name : {"rpm", "i"}) {
    if (t.has(name)) out.emplace_back(name);
  }
  if (out.empty()) fail("{}: no measured column to compare with the model (rpm or i)", t.source);
  return out;
}

/// The row where a single file is split: the event nearest to `fraction` of the duration
/// within 40-80 % of it, else the row at `fraction`.
std::size_t split_row(const model::Inputs& in, double fraction, bool& at_event) {
  const std::size_t rows = in.t_s.size();
  const double t0 = in.t_s.front();
  const double span = in.t_s.back() - t0;
  const double target = t0 + fraction * span;
  std::size_t best = rows;
  for (std::size_t e : event_rows(in)) {
    const double t = in.t_s[e];
    if (t < t0 + 0.4 * span || t > t0 + 0.8 * span) continue;
    if (best == rows || std::abs(t - target) < std::abs(in.t_s[best] - target)) best = e;
  }
  at_event = best != rows;
  if (at_event) return best;
  return static_cast<std::size_t>(std::lower_bound(in.t_s.begin(), in.t_s.end(), target) - in.t_s.begin());
}

Run truncate(const Run& run, std::size_t rows) {
  Run out = run;
  for (auto* v : {&out.inputs.t_s, &out.inputs.v_V, &out.inputs.clutch, &out.inputs.r_load_ohm}) v->resize(rows);
  for (auto& y : out.measured) y.resize(rows);
  return out;
}

}  // namespace

namespace gap_detail {

/// Index of output `name` in `floors`, or npos.
std::size_t floor_index(const std::vector<OutputFloor>& floors, const std::string& name) {
  for (std::size_t k = 0; k < floors.size(); ++k) {
    if (floors[k].output == name) return k;
  }
  return std::string::npos;
}

std::size_t validation_count(const GapData& data) {
  std::size_t n = 0;
  for (const ScoredRun& sr : data.validate) n += sr.run.inputs.t_s.size() - sr.first_scored;
  return n;
}

double residual_noise(const GapData& data, const Evaluation& ev, const std::string& output) {
  MCG_DEMAND(ev.simulated.size() == data.validate.size());
  double sum_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const ScoredRun& sr = data.validate[r];
    const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), output);
    if (it == sr.run.outputs.end()) continue;
    const auto o = static_cast<std::size_t>(it - sr.run.outputs.begin());
    const auto& y = sr.run.measured[o];
    const auto& sim = ev.simulated[r][o];
    const auto residual = [&](std::size_t n) { return y[n] - sim[n]; };
    for (std::size_t n = sr.first_scored + 1; n + 1 < y.size(); ++n) {
      const double d = residual(n + 1) - 2.0 * residual(n) + residual(n - 1);
      if (!std::isfinite(d)) continue;
      sum_sq += d * d;
      ++count;
    }
  }
  return count > 0 ? std::sqrt(sum_sq / static_cast<double>(count) / 6.0) : 0.0;
}

std::vector<OutputFloor> noise_floors(const GapData& data) {
  std::vector<OutputFloor> floors;
  for (const char* name : {"rpm", "i"}) {
    double chain_sq = 0.0;
    double data_sq = 0.0;
    double signal_sq = 0.0;
    std::size_t rows = 0;
    bool stated = true;
    for (const ScoredRun& sr : data.validate) {
      const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), name);
      if (it == sr.run.outputs.end()) continue;
      const auto& y = sr.run.measured[static_cast<std::size_t>(it - sr.run.outputs.begin())];
      const std::span<const double> part(y.data() + sr.first_scored, y.size() - sr.first_scored);
      std::vector<bool> transient = transient_mask(sr.run.inputs);
      transient.erase(transient.begin(), transient.begin() + static_cast<std::ptrdiff_t>(sr.first_scored));
      NoiseFloor nf;
      if (std::string_view(name) == "rpm") {
        const RpmEstimator est = sr.run.rpm_estimator.value_or(RpmEstimator{});
        nf = rpm_noise_floor(part, transient, est.window_s, est.counts_per_rev);
        stated = stated && sr.run.rpm_estimator.has_value();
      } else {
        const double step = std::isfinite(sr.i_step_A) ? sr.i_step_A : 0.0;
        const double sigma = std::isfinite(sr.i_sigma_A) ? sr.i_sigma_A : 0.0;
        nf = current_noise_floor(part, transient, step, sigma);
        stated = stated && (std::isfinite(sr.i_step_A) || std::isfinite(sr.i_sigma_A));
      }
      const auto n = static_cast<double>(part.size());
      chain_sq += nf.chain * nf.chain * n;
      data_sq += nf.data * nf.data * n;
      const double r = rms_finite(part);
      if (std::isfinite(r)) signal_sq += r * r * n;
      rows += part.size();
    }
    if (rows == 0) continue;
    OutputFloor of;
    of.output = name;
    of.noise.chain = std::sqrt(chain_sq / static_cast<double>(rows));
    of.noise.data = std::sqrt(data_sq / static_cast<double>(rows));
    const bool chain_holds = stated && of.noise.chain > 0.0 && of.noise.data <= k_gap_data_floor_factor * of.noise.chain;
    of.floor = chain_holds ? of.noise.chain : of.noise.data;
    // Noise-free data (a simulation without a measurement chain) still needs a scale:
    // 0.1 % of the signal's RMS.
    of.floor = std::max(of.floor, 1e-3 * std::sqrt(signal_sq / static_cast<double>(rows)));
    if (of.floor > 0.0) floors.push_back(of);
  }
  if (floors.empty()) fail("no noise floor: the validation runs measure neither rpm nor i with any noise");
  return floors;
}

}  // namespace gap_detail

GapData prepare_gap_data(const std::vector<table::Table>& train, const std::vector<table::Table>& validate,
                         const model::Params& params, double split_fraction) {
  if (train.empty()) fail("--train: no training file");
  GapData data;
  // make_run() drops the current samples at the rails of the run's stated chain.
  auto make = [&](const table::Table& measured) {
    const table::Table t = with_rpm(measured);
    return make_run(t, compared_outputs(t), params);
  };
  auto scored = [&](const table::Table& t, Run run, std::size_t first) {
    ScoredRun sr{std::move(run), first};
    if (const auto text = t.meta.get("i_measurement")) {
      const measurement::CurrentChain chain =
          measurement::parse_i_measurement(*text, fmt::format("{}: i_measurement", t.source));
      sr.i_step_A = chain.step_A();
      sr.i_sigma_A = chain.sigma_A;
    }
    return sr;
  };
  if (validate.empty()) {
    if (train.size() != 1) fail("--validate: no validation file (only a single --train file is split)");
    const table::Table& t = train.front();
    Run whole = make(t);
    bool at_event = false;
    const std::size_t split = split_row(whole.inputs, split_fraction, at_event);
    if (split < 50 || whole.inputs.t_s.size() - split < 50) {
      fail("{}: too short to split into training and validation parts (50 rows each)", t.source);
    }
    data.train.push_back(truncate(whole, split));
    const double t_split = whole.inputs.t_s[split];
    const double pct = 100.0 * (t_split - whole.inputs.t_s.front()) /
                       (whole.inputs.t_s.back() - whole.inputs.t_s.front());
    data.split_note = fmt::format(
        "single file split at t = {:.3f} s ({:.0f} % of its duration{}): rows before train, rows from there on "
        "validate (simulated from the start, scored after the split)",
        t_split, pct, at_event ? ", at an input event" : "");
    data.validate.push_back(scored(t, std::move(whole), split));
  } else {
    for (const auto& t : train) data.train.push_back(make(t));
    for (const auto& t : validate) data.validate.push_back(scored(t, make(t), 0));
  }
  return data;
}

}  // namespace mcg::fit
