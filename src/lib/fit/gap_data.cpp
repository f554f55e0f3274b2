// The gap diagnosis' data: the training and validation runs, the split of a single file, the
// measurement chain of each run and the noise floors it implies.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/units.hpp"
#include "fit/gap_parts.hpp"
#include "measurement/measurement.hpp"
#include "table/table.hpp"

namespace mcg::fit {

namespace {

std::vector<std::string> compared_outputs(const table::Table& t, const DriveInput& drive) {
  std::vector<std::string> out;
  for (const char* name : {"rpm", "i"}) {
    if (t.has(name) && !(drive.current && std::string_view(name) == "i")) out.emplace_back(name);
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

/// What rows [first, last) of a run excite, per direction (0 forward, 1 reverse): the largest
/// drive level |v| that way, and whether the measured speed turns that way (beyond 5 % of the
/// run's largest speed, so that noise around standstill does not count).
struct Coverage {
  std::array<double, 2> level{0.0, 0.0};
  const char* unit = "V";
  std::array<bool, 2> turns{false, false};
};

Coverage coverage(const Run& run, std::size_t first, std::size_t last) {
  Coverage c;
  // The drive's own command: the voltage, a current loop's current or the drive torque.
  const auto& v = drive_command(run);
  c.unit = !run.inputs.i_cmd_A.empty() ? "A" : !run.drive_torque.empty() ? "(drive torque)" : "V";
  double v_max = 0.0;
  for (double x : v) v_max = std::max(v_max, std::abs(x));
  for (std::size_t n = first; n < last; ++n) {
    if (std::abs(v[n]) > 1e-3 * v_max) {
      const std::size_t d = v[n] > 0.0 ? 0 : 1;
      c.level[d] = std::max(c.level[d], std::abs(v[n]));
    }
  }
  const auto it = std::find(run.outputs.begin(), run.outputs.end(), "rpm");
  if (it == run.outputs.end()) return c;
  const auto& y = run.measured[static_cast<std::size_t>(it - run.outputs.begin())];
  double y_max = 0.0;
  for (double x : y) {
    if (std::isfinite(x)) y_max = std::max(y_max, std::abs(x));
  }
  for (std::size_t n = first; n < last; ++n) {
    if (std::isfinite(y[n]) && std::abs(y[n]) > 0.05 * y_max) c.turns[y[n] > 0.0 ? 0 : 1] = true;
  }
  return c;
}

/// What the training rows before `split` lack of what the scored rows after it hold (empty:
/// nothing): a drive direction, a direction the motor turns, or the range of drive levels
/// (its largest level in a direction below k_split_level_share of the scored part's).
std::string split_lacks(const Run& run, std::size_t split) {
  const Coverage train = coverage(run, 0, split);
  const Coverage scored = coverage(run, split, run.inputs.t_s.size());
  for (std::size_t d = 0; d < 2; ++d) {
    const char* way = d == 0 ? "forward" : "reverse";
    if (scored.level[d] > 0.0 && train.level[d] == 0.0) return fmt::format("training never drives {}", way);
    if (scored.turns[d] && !train.turns[d]) return fmt::format("the motor never turns {} in training", way);
    if (train.level[d] < k_split_level_share * scored.level[d]) {
      return fmt::format("training's largest {} drive {:.3g} {} is below {:.0f} % of the {:.3g} {} scored",
                         way, train.level[d], train.unit, 100.0 * k_split_level_share, scored.level[d],
                         train.unit);
    }
  }
  return {};
}

/// The automatic split: split_row()'s choice when training covers what is scored (split_lacks),
/// else the nearest to `fraction` of the other events in 40-80 % of the duration, then of
/// the rows at 40, 45, ..., 80 %, that covers it. Throws when none does.
std::size_t covering_split(const Run& run, const std::string& source, double fraction, bool& at_event) {
  const model::Inputs& in = run.inputs;
  const std::size_t rows = in.t_s.size();
  const std::size_t first = split_row(in, fraction, at_event);
  const auto fits = [&](std::size_t n) { return n >= 50 && rows - n >= 50 && split_lacks(run, n).empty(); };
  if (fits(first)) return first;
  const double t0 = in.t_s.front();
  const double span = in.t_s.back() - t0;
  const double target = t0 + fraction * span;
  const auto nearest_first = [&](std::vector<std::size_t> rows_in) {
    std::stable_sort(rows_in.begin(), rows_in.end(), [&](std::size_t a, std::size_t b) {
      return std::abs(in.t_s[a] - target) < std::abs(in.t_s[b] - target);
    });
    return rows_in;
  };
  std::vector<std::size_t> events;
  for (std::size_t e : event_rows(in)) {
    if (in.t_s[e] >= t0 + 0.4 * span && in.t_s[e] <= t0 + 0.8 * span) events.push_back(e);
  }
  for (std::size_t e : nearest_first(events)) {
    if (fits(e)) {
      at_event = true;
      return e;
    }
  }
  std::vector<std::size_t> grid;
  for (int k = 0; k <= 8; ++k) {
    const double t = t0 + (0.4 + 0.05 * k) * span;
    grid.push_back(
        static_cast<std::size_t>(std::lower_bound(in.t_s.begin(), in.t_s.end(), t) - in.t_s.begin()));
  }
  for (std::size_t n : nearest_first(grid)) {
    if (fits(n)) {
      at_event = false;
      return n;
    }
  }
  fail(
      "{}: no split in 40-80 % of its duration trains on what it scores (at t = {:.3f} s {}); choose one "
      "with "
      "--split or give --validate runs",
      source, in.t_s[std::min(first, rows - 1)], split_lacks(run, std::min(first, rows - 1)));
}

Run truncate(const Run& run, std::size_t rows) {
  Run out = run;
  for (auto* v : {&out.inputs.t_s, &out.inputs.v_V, &out.inputs.clutch, &out.inputs.r_load_ohm}) v->resize(rows);
  for (auto* v : {&out.inputs.i_cmd_A, &out.inputs.T_cmd_Nm, &out.drive_torque}) {
    if (!v->empty()) v->resize(rows);
  }
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

model::DriveScale drive_scale(const model::Params& p, const std::vector<Run>& runs) {
  const model::DriveScale voltage = model::voltage_drive_scale(p);
  if (runs.empty() || drive_kind(runs.front()) == model::DriveKind::voltage) return voltage;
  double torque_Nm = 0.0;
  double speed_rad_s = 0.0;
  for (const Run& run : runs) {
    const bool current = drive_kind(run.inputs) == model::DriveKind::current;
    for (double u : drive_command(run.inputs)) {
      if (std::isfinite(u)) torque_Nm = std::max(torque_Nm, std::abs(current ? p.motor.Kt_Nm_A * u : u));
    }
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const double to_rad_s = rad_s_per_unit(run.outputs[o]);
      for (double y : run.measured[o]) {
        if (std::isfinite(y)) speed_rad_s = std::max(speed_rad_s, std::abs(y) * to_rad_s * run.gear_ratio);
      }
    }
  }
  return {torque_Nm > 0.0 ? k_command_headroom * torque_Nm : voltage.torque_Nm,
          speed_rad_s > 0.0 ? speed_rad_s : voltage.speed_rad_s};
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

double speed_resolution(const Run& run) {
  if (run.rpm_estimator) return run.rpm_estimator->rpm_per_count();
  double top = 0.0;
  for (std::size_t o = 0; o < run.outputs.size(); ++o) {
    if (run.outputs[o] != "rpm" && run.outputs[o] != "omega") continue;
    for (double y : run.measured[o]) {
      if (std::isfinite(y)) top = std::max(top, std::abs(y));
    }
  }
  return 2.0 * k_unstated_moving_share * top;
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
      if (std::string_view(name) == "rpm" && sr.run.rpm_estimator) {
        nf = rpm_noise_floor(part, transient, sr.run.rpm_estimator->window_s,
                             sr.run.rpm_estimator->counts_per_rev);
      } else if (std::string_view(name) == "rpm") {
        // No stated chain: the data's own estimate over the moving samples, in the data's unit
        // (the board's encoder resolution would class a small unit's every sample at rest).
        const double moving = 0.5 * speed_resolution(sr.run);
        std::vector<double> kept(part.begin(), part.end());
        for (double& sample : kept) {
          if (!(std::abs(sample) >= moving)) sample = k_nan;
        }
        nf = current_noise_floor(kept, transient, 0.0, 0.0);
        stated = false;
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
                         const model::Params& params, double split_fraction, bool split_given,
                         const DriveInput& drive) {
  if (train.empty()) fail("--train: no training file");
  GapData data;
  // The reports speak the data's unit: rad/s when every file measures omega and none rpm.
  const auto omega_only = [](const table::Table& t) { return t.has("omega") && !t.has("rpm"); };
  if (std::all_of(train.begin(), train.end(), omega_only) &&
      std::all_of(validate.begin(), validate.end(), omega_only)) {
    data.speed_unit = SpeedUnit{"rad/s", "rad_s", "omega", k_rad_s_per_rpm};
  }
  // make_run() drops the current samples at the rails of the run's stated chain.
  auto make = [&](const table::Table& measured) {
    const table::Table t = with_rpm(measured);
    return make_run(t, compared_outputs(t, drive), params, 50, drive);
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
    if (whole.inputs.t_s.size() < 100) {
      fail("{}: too short to split into training and validation parts (50 rows each)", t.source);
    }
    const std::size_t split = split_given ? split_row(whole.inputs, split_fraction, at_event)
                                          : covering_split(whole, t.source, split_fraction, at_event);
    if (split < 50 || whole.inputs.t_s.size() - split < 50) {
      fail("{}: too short to split into training and validation parts (50 rows each)", t.source);
    }
    const std::string lacks = split_lacks(whole, split);
    data.train.push_back(truncate(whole, split));
    const double t_split = whole.inputs.t_s[split];
    const double pct = 100.0 * (t_split - whole.inputs.t_s.front()) /
                       (whole.inputs.t_s.back() - whole.inputs.t_s.front());
    data.split_note = fmt::format(
        "single file split at t = {:.3f} s ({:.0f} % of its duration{}): rows before train, rows from there "
        "on "
        "validate (simulated from the start, scored after the split){}",
        t_split, pct, at_event ? ", at an input event" : "",
        lacks.empty() ? "" : fmt::format("; as --split asks, although {}", lacks));
    data.validate.push_back(scored(t, std::move(whole), split));
  } else {
    for (const auto& t : train) data.train.push_back(make(t));
    for (const auto& t : validate) data.validate.push_back(scored(t, make(t), 0));
  }
  return data;
}

}  // namespace mcg::fit
