// The sim-to-real gap diagnosis (see gap.hpp for the method).
#include "fit/gap.hpp"

#include "common/error.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "table/table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <complex>
#include <fstream>
#include <mutex>
#include <numbers>
#include <ostream>
#include <thread>

namespace mcg::fit {

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

/// The nominal parameters a refit moves: the scale factors of the param_mismatch effect.
/// L is left alone: at 1 kHz sampling the 1 ms electrical time constant barely shows.
const std::vector<std::string>& mismatch_scales() {
  static const std::vector<std::string> names = {"Kt_scale",     "J_scale",       "coulomb_scale",
                                                 "static_scale", "viscous_scale", "R_scale"};
  return names;
}

/// How one catalog effect is fitted: the parameters set free and a coarse grid of
/// starting points (the best grid point on the training cost starts the fit).
struct EffectPlan {
  std::string name;
  std::vector<std::string> free;                  ///< effect parameter keys fitted
  std::vector<std::vector<double>> grid;          ///< per free key, starting values tried
};

const std::vector<EffectPlan>& effect_plans() {
  static const std::vector<EffectPlan> plans = {
      {"stribeck", {"v_s_rad_s", "shape_exp"}, {{2.0, 5.0, 12.0, 30.0, 80.0}, {1.5}}},
      {"dead_time", {"tau_d_s"}, {{0.0005, 0.001, 0.002, 0.004, 0.008, 0.016}}},
      {"supply_sag", {"R_s_ohm"}, {{0.3, 1.0, 3.0}}},
      {"hbridge", {"R_on_ohm", "deadband"}, {{0.1, 0.5}, {0.005, 0.02, 0.06}}},
      {"brush_drop", {"V_b_V"}, {{0.2, 0.5, 1.0, 2.0}}},
      {"clutch_compliance", {"k_Nm_per_rad", "zeta"}, {{0.01, 0.03, 0.1, 0.3, 1.0}, {0.03, 0.1, 0.3}}},
      {"clutch_engage_lag", {"T_max_Nm", "tau_s"}, {{0.01, 0.05, 0.2}, {0.005, 0.03, 0.1}}},
      {"cogging",
       {"T_c_Nm", "phase_rad"},
       {{0.0006, 0.001, 0.0016, 0.0025}, {-2.75, -1.96, -1.18, -0.39, 0.39, 1.18, 1.96, 2.75}}},
      {"thermal", {"R_th_K_W", "tau_th_s"}, {{5.0, 20.0, 60.0}, {5.0, 60.0}}},
  };
  return plans;
}

const EffectPlan* find_plan(std::string_view name) {
  for (const auto& p : effect_plans()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------
// Metadata of the current measurement

/// Reads the number that follows `key` in `text` ("noise sigma 0.003 A" with key "sigma").
std::optional<double> number_after(std::string_view text, std::string_view key) {
  const auto at = text.find(key);
  if (at == std::string_view::npos) return std::nullopt;
  std::string_view rest = text.substr(at + key.size());
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  std::size_t len = 0;
  while (len < rest.size() && (std::isdigit(static_cast<unsigned char>(rest[len])) != 0 || rest[len] == '.' ||
                               rest[len] == '-' || rest[len] == 'e')) {
    ++len;
  }
  double v = 0.0;
  if (len == 0 || !table::parse_number(rest.substr(0, len), v)) return std::nullopt;
  return v;
}

/// Reads the number that precedes `key` ("10-bit" with key "-bit", "1 ohm shunt" with " ohm shunt").
std::optional<double> number_before(std::string_view text, std::string_view key) {
  const auto at = text.find(key);
  if (at == std::string_view::npos) return std::nullopt;
  std::size_t begin = at;
  while (begin > 0 && (std::isdigit(static_cast<unsigned char>(text[begin - 1])) != 0 || text[begin - 1] == '.')) {
    --begin;
  }
  double v = 0.0;
  if (begin == at || !table::parse_number(text.substr(begin, at - begin), v)) return std::nullopt;
  return v;
}

struct CurrentChain {
  double step_A = k_nan;
  double sigma_A = k_nan;
  double rail_low_A = -std::numeric_limits<double>::infinity();
  double rail_high_A = std::numeric_limits<double>::infinity();
};

/// "1 ohm shunt, 10-bit ADC over 0-5 V with 2.5 V mid-scale offset (range -2.5..2.495 A,
/// saturates), nominal noise sigma 0.003 A": step = span / 2^bits / shunt, the rails, sigma.
CurrentChain parse_current_chain(const table::Metadata& meta) {
  CurrentChain c;
  const auto text = meta.get("i_measurement");
  if (!text) return c;
  const std::string_view s = *text;
  if (auto sigma = number_after(s, "sigma")) c.sigma_A = *sigma;
  const auto bits = number_before(s, "-bit");
  const auto shunt = number_before(s, " ohm shunt");
  const auto over = s.find("ADC over ");
  if (bits && over != std::string_view::npos) {
    std::string_view span = s.substr(over + 9);
    const auto dash = span.find('-');
    const auto volt = span.find(" V");
    double lo = 0.0;
    double hi = 0.0;
    if (dash != std::string_view::npos && volt != std::string_view::npos && dash < volt &&
        table::parse_number(span.substr(0, dash), lo) && table::parse_number(span.substr(dash + 1, volt - dash - 1), hi)) {
      c.step_A = (hi - lo) / std::pow(2.0, *bits) / shunt.value_or(1.0);
    }
  }
  const auto range = s.find("range ");
  if (range != std::string_view::npos) {
    std::string_view r = s.substr(range + 6);
    const auto dots = r.find("..");
    const auto unit = r.find(" A");
    double lo = 0.0;
    double hi = 0.0;
    if (dots != std::string_view::npos && unit != std::string_view::npos && dots < unit &&
        table::parse_number(r.substr(0, dots), lo) && table::parse_number(r.substr(dots + 2, unit - dots - 2), hi)) {
      c.rail_low_A = lo;
      c.rail_high_A = hi;
    }
  }
  return c;
}

/// Marks current samples at (or within a tenth of an ADC step of) the rails as not measured.
void drop_saturated_current(Run& run, const CurrentChain& chain) {
  const auto it = std::find(run.outputs.begin(), run.outputs.end(), "i");
  if (it == run.outputs.end() || !std::isfinite(chain.rail_high_A)) return;
  const double margin = std::isfinite(chain.step_A) ? 0.1 * chain.step_A : 1e-6;
  auto& y = run.measured[static_cast<std::size_t>(it - run.outputs.begin())];
  for (double& v : y) {
    if (v >= chain.rail_high_A - margin || v <= chain.rail_low_A + margin) v = k_nan;
  }
}

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

// ---------------------------------------------------------------------------------------
// Scoring

/// Index of output `name` in `floors`, or npos.
std::size_t floor_index(const std::vector<OutputFloor>& floors, const std::string& name) {
  for (std::size_t k = 0; k < floors.size(); ++k) {
    if (floors[k].output == name) return k;
  }
  return std::string::npos;
}

/// Validation evaluation of one model: per run, per output (in the run's order) the
/// simulated series, and per floor output the pooled squared error and count.
struct Evaluation {
  std::vector<std::vector<std::vector<double>>> simulated;
  std::vector<double> sum_sq;
  std::vector<std::size_t> count;
  double score = 0.0;
  std::vector<double> rms;
};

Evaluation evaluate(const model::Model& model, const GapData& data, const std::vector<OutputFloor>& floors) {
  Evaluation ev;
  ev.sum_sq.assign(floors.size(), 0.0);
  ev.count.assign(floors.size(), 0);
  for (const ScoredRun& sr : data.validate) {
    auto sim = simulate_as_measured(model, sr.run);
    for (std::size_t o = 0; o < sr.run.outputs.size(); ++o) {
      const std::size_t f = floor_index(floors, sr.run.outputs[o]);
      if (f == std::string::npos) continue;
      const auto& y = sr.run.measured[o];
      for (std::size_t n = sr.first_scored; n < y.size(); ++n) {
        const double r = y[n] - sim[o][n];
        if (!std::isfinite(r)) continue;
        ev.sum_sq[f] += r * r;
        ++ev.count[f];
      }
    }
    ev.simulated.push_back(std::move(sim));
  }
  for (std::size_t f = 0; f < floors.size(); ++f) {
    const double mse = ev.count[f] > 0 ? ev.sum_sq[f] / static_cast<double>(ev.count[f]) : k_nan;
    ev.rms.push_back(std::sqrt(mse));
    if (ev.count[f] > 0) ev.score += mse / (floors[f].floor * floors[f].floor);
  }
  return ev;
}

/// The fit objective on the training runs (sum over runs and outputs of the squared NRMSE),
/// used to pick a starting point on a grid.
double training_cost(const model::Model& model, const std::vector<Run>& runs) {
  double cost = 0.0;
  for (const Run& run : runs) {
    const auto sim = simulate_as_measured(model, run);
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const auto& y = run.measured[o];
      double mean = 0.0;
      std::size_t count = 0;
      for (double v : y) {
        if (std::isfinite(v)) {
          mean += v;
          ++count;
        }
      }
      if (count < 2) continue;
      mean /= static_cast<double>(count);
      double err = 0.0;
      double spread = 0.0;
      for (std::size_t n = 0; n < y.size(); ++n) {
        if (!std::isfinite(y[n])) continue;
        err += (sim[o][n] - y[n]) * (sim[o][n] - y[n]);
        spread += (y[n] - mean) * (y[n] - mean);
      }
      if (spread > 0.0) cost += err / spread;
    }
  }
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
}

double training_rms_rpm(const model::Model& model, const std::vector<Run>& runs) {
  double sq = 0.0;
  std::size_t count = 0;
  for (const Run& run : runs) {
    const auto it = std::find(run.outputs.begin(), run.outputs.end(), "rpm");
    if (it == run.outputs.end()) continue;
    const auto o = static_cast<std::size_t>(it - run.outputs.begin());
    const auto sim = simulate_as_measured(model, run);
    for (std::size_t n = 0; n < run.measured[o].size(); ++n) {
      const double r = run.measured[o][n] - sim[o][n];
      if (std::isfinite(r)) {
        sq += r * r;
        ++count;
      }
    }
  }
  return count > 0 ? std::sqrt(sq / static_cast<double>(count)) : k_nan;
}

// ---------------------------------------------------------------------------------------
// Candidates

/// Why an effect cannot be identified from the training runs (empty: it can).
std::string not_excited(std::string_view effect, const std::vector<Run>& runs) {
  bool engaged = false;
  bool engages = false;
  for (const Run& run : runs) {
    const auto& c = run.inputs.clutch;
    for (std::size_t n = 0; n < c.size(); ++n) {
      if (c[n] == 2.0) engaged = true;
      if (n > 0 && c[n] == 2.0 && c[n - 1] != 2.0) engages = true;
    }
  }
  if (effect == "clutch_compliance" && !engaged) return "not excited: clutch never engaged in training";
  if (effect == "clutch_engage_lag" && !engages) return "not excited: no engagement in training";
  return {};
}

struct Job {
  std::string name;
  std::vector<std::string> effects;
  model::Model start;       ///< effects present with starting values (grid applied later)
  std::vector<std::string> free;
  std::vector<std::string> grid_effects;  ///< effects whose plan grid is searched before the fit
  int evaluations_per_parameter = 10;     ///< simulation budget per free parameter (and one)
  std::vector<std::string> stage1_free;   ///< fitted alone first (the added effect's parameters)
  std::vector<model::Model> other_starts; ///< further nominal models the grid is searched on
};

void add_effect(model::Model& m, std::string_view name) {
  if (m.effect(name) == nullptr) m.effects.push_back(model::default_effect(name));
}

/// The scale of param_mismatch that moves a nominal parameter (empty: none does).
std::string scale_of(std::string_view name) {
  if (name == "motor.R_ohm") return "R_scale";
  if (name == "motor.J_kg_m2") return "J_scale";
  if (name == "motor.Kt_Nm_A" || name == "motor.Ke_V_s_rad") return "Kt_scale";
  if (name.ends_with(".Tc_Nm")) return "coulomb_scale";
  if (name.ends_with(".Ts_Nm")) return "static_scale";
  if (name.find(".visc") != std::string_view::npos) return "viscous_scale";
  return {};
}

std::vector<std::string> mismatch_free(const std::vector<std::string>& fixed) {
  std::vector<std::string> free;
  for (const auto& s : mismatch_scales()) {
    if (std::none_of(fixed.begin(), fixed.end(), [&](const std::string& f) { return scale_of(f) == s; })) {
      free.push_back("param_mismatch." + s);
    }
  }
  if (free.empty()) fail("--fix pins every parameter the refit moves");
  return free;
}

/// Searches the effect's grid (the cartesian product of its starting values) on the
/// training cost and leaves the best point in `m`.
/// Searches the effect's grid (the cartesian product of its starting values, on each of the
/// `bases`) on the training cost and returns the best point.
model::Model grid_start(const std::vector<model::Model>& bases, const EffectPlan& plan, const std::vector<Run>& runs,
                        const std::vector<double>& cogging_n) {
  std::vector<std::vector<double>> axes = plan.grid;
  std::vector<std::string> keys = plan.free;
  if (plan.name == "cogging" && !cogging_n.empty()) {
    keys.push_back("N_per_rev");
    axes.push_back(cogging_n);
  }
  std::size_t points = 1;
  for (const auto& a : axes) points *= a.size();
  double best = std::numeric_limits<double>::infinity();
  model::Model best_model = bases.front();
  for (const model::Model& base : bases) {
    for (std::size_t p = 0; p < points; ++p) {
      model::Model trial = base;
      std::size_t rest = p;
      for (std::size_t k = 0; k < keys.size(); ++k) {
        model::set_parameter(trial, plan.name + "." + keys[k], axes[k][rest % axes[k].size()]);
        rest /= axes[k].size();
      }
      const double cost = training_cost(trial, runs);
      if (cost < best) {
        best = cost;
        best_model = std::move(trial);
      }
    }
  }
  return best_model;
}

GapCandidate run_job(const Job& job, const GapData& data, const std::vector<OutputFloor>& floors,
                     const GapSettings& settings, unsigned jacobian_threads, const std::vector<double>& cogging_n) {
  GapCandidate c;
  c.name = job.name;
  c.effects = job.effects;
  model::Model start = job.start;
  if (job.grid_effects.empty() && !job.other_starts.empty()) {
    double best = training_cost(start, data.train);
    for (const model::Model& other : job.other_starts) {
      const double cost = training_cost(other, data.train);
      if (cost < best) {
        best = cost;
        start = other;
      }
    }
  }
  for (const auto& e : job.grid_effects) {
    if (const EffectPlan* plan = find_plan(e)) {
      std::vector<model::Model> bases{start};
      for (model::Model other : job.other_starts) {
        add_effect(other, e);
        bases.push_back(std::move(other));
      }
      start = grid_start(bases, *plan, data.train, cogging_n);
    }
  }
  FitProblem problem;
  problem.runs = data.train;
  problem.nls.threads = jacobian_threads;
  problem.nls.xtol = 1e-4;
  problem.nls.ftol = 1e-5;
  problem.nls.check_smoothness = false;
  problem.bounds = settings.bounds;
  auto budget = [&](std::size_t free) {
    return settings.max_evaluations > 0 ? settings.max_evaluations
                                        : job.evaluations_per_parameter * static_cast<int>(free + 1);
  };
  // Stage 1: the added effect alone on the refitted nominal model (cheap, and it brings the
  // effect into its basin before the nominal parameters may move to absorb it).
  if (!job.stage1_free.empty()) {
    problem.model = start;
    problem.free = job.stage1_free;
    problem.nls.max_evaluations = budget(job.stage1_free.size());
    start = fit_model(problem).model;
  }
  problem.model = start;
  problem.free = job.free;
  problem.nls.max_evaluations = budget(job.free.size());
  const FitResult fit = fit_model(problem);
  c.model = fit.model;
  c.free = job.free;
  for (Eigen::Index k = 0; k < fit.nls.values.size(); ++k) {
    c.values.push_back(fit.nls.values[k]);
    c.std_errors.push_back(fit.nls.std_errors[k]);
  }
  for (const auto& e : job.effects) {
    if (const EffectPlan* plan = find_plan(e)) c.added_parameters += plan->free.size();
  }
  c.status = fit.nls.converged ? "fitted" : "fitted, budget spent";
  c.evaluated = true;
  const Evaluation ev = evaluate(c.model, data, floors);
  c.score = ev.score;
  c.rms = ev.rms;
  c.train_rms_rpm = training_rms_rpm(c.model, data.train);
  return c;
}

/// Runs the jobs on `threads` workers; each result lands at its job's index.
std::vector<GapCandidate> run_jobs(const std::vector<Job>& jobs, const GapData& data,
                                   const std::vector<OutputFloor>& floors, const GapSettings& settings,
                                   unsigned threads, const std::vector<double>& cogging_n, std::size_t& done,
                                   std::size_t total) {
  std::vector<GapCandidate> out(jobs.size());
  std::atomic<std::size_t> next{0};
  std::mutex mutex;
  std::exception_ptr error;
  const unsigned workers = std::max(1U, std::min<unsigned>(threads, static_cast<unsigned>(jobs.size())));
  const unsigned jac_threads = std::max(1U, threads / workers);
  auto work = [&] {
    while (true) {
      const std::size_t k = next.fetch_add(1);
      if (k >= jobs.size()) return;
      try {
        out[k] = run_job(jobs[k], data, floors, settings, jac_threads, cogging_n);
      } catch (const Error& e) {
        // A candidate the data cannot fit is reported as such; the others go on.
        GapCandidate& c = out[k];
        c.name = jobs[k].name;
        c.effects = jobs[k].effects;
        c.model = jobs[k].start;
        c.status = fmt::format("fit failed: {}", e.what());
        c.score = k_nan;
        c.rms.assign(floors.size(), k_nan);
        c.train_rms_rpm = k_nan;
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
        return;
      }
      std::lock_guard lock(mutex);
      ++done;
      if (settings.progress) settings.progress(fmt::format("fitted {} ({}/{})", jobs[k].name, done, total));
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return out;
}

std::size_t validation_count(const GapData& data) {
  std::size_t n = 0;
  for (const ScoredRun& sr : data.validate) n += sr.run.inputs.t_s.size() - sr.first_scored;
  return n;
}

/// score_ref - score > max(k_abs, k_rel (score_ref - outputs)).
bool improves(double score, double score_ref, std::size_t outputs) {
  const double gap = score_ref - static_cast<double>(outputs);
  return score_ref - score > std::max(k_gap_abs_threshold, k_gap_rel_threshold * gap);
}

// ---------------------------------------------------------------------------------------
// Pooled residual analysis

std::vector<RegimeStat> pool(const std::vector<std::vector<RegimeStat>>& parts) {
  if (parts.empty()) return {};
  std::vector<RegimeStat> out = parts.front();
  std::vector<double> sum_sq(out.size(), 0.0);
  for (auto& s : out) s.samples = 0;
  for (const auto& part : parts) {
    assert(part.size() == out.size());
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
std::vector<std::vector<double>> residual_series(const GapData& data,
                                                 const std::vector<std::vector<std::vector<double>>>& simulated,
                                                 const std::string& name) {
  std::vector<std::vector<double>> out;
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const ScoredRun& sr = data.validate[r];
    std::vector<double> res(sr.run.inputs.t_s.size(), k_nan);
    const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), name);
    if (it != sr.run.outputs.end()) {
      const auto o = static_cast<std::size_t>(it - sr.run.outputs.begin());
      for (std::size_t n = sr.first_scored; n < res.size(); ++n) res[n] = sr.run.measured[o][n] - simulated[r][o][n];
    }
    out.push_back(std::move(res));
  }
  return out;
}

double rpm_resolution(const Run& run) {
  const RpmEstimator est = run.rpm_estimator.value_or(RpmEstimator{});
  return 60.0 / (est.window_s * est.counts_per_rev);
}

std::vector<double> measured_rpm(const Run& run) {
  const auto it = std::find(run.outputs.begin(), run.outputs.end(), "rpm");
  if (it == run.outputs.end()) return std::vector<double>(run.inputs.t_s.size(), k_nan);
  return run.measured[static_cast<std::size_t>(it - run.outputs.begin())];
}

void analyse(const GapData& data, const std::vector<std::vector<std::vector<double>>>& simulated,
             std::vector<RegimeStat>& regimes, std::vector<RegimeStat>& bands, std::vector<RegimeStat>& current,
             Whiteness& white) {
  const auto rpm_res = residual_series(data, simulated, "rpm");
  const auto i_res = residual_series(data, simulated, "i");
  std::vector<std::vector<RegimeStat>> reg, band, cur;
  std::vector<double> joined_r;
  std::vector<double> joined_u;
  std::size_t max_lag = 50;
  std::size_t first_lag = 1;
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const Run& run = data.validate[r].run;
    const std::vector<double> rpm = measured_rpm(run);
    const RegimeContext ctx{&run.inputs, rpm, rpm_resolution(run)};
    reg.push_back(regime_breakdown(ctx, rpm_res[r]));
    cur.push_back(regime_breakdown(ctx, i_res[r]));
    std::vector<double> dt;
    for (std::size_t n = 1; n < run.inputs.t_s.size(); ++n) dt.push_back(run.inputs.t_s[n] - run.inputs.t_s[n - 1]);
    std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
    const double dt_s = dt[dt.size() / 2];
    band.push_back(band_breakdown(rpm_res[r], dt_s));
    if (run.rpm_estimator) {
      first_lag = std::max(first_lag, static_cast<std::size_t>(std::lround(run.rpm_estimator->window_s / dt_s)) + 1);
    }
    joined_r.insert(joined_r.end(), rpm_res[r].begin(), rpm_res[r].end());
    joined_u.insert(joined_u.end(), run.inputs.v_V.begin(), run.inputs.v_V.end());
    joined_r.insert(joined_r.end(), max_lag, k_nan);
    joined_u.insert(joined_u.end(), max_lag, k_nan);
  }
  regimes = pool(reg);
  bands = pool(band);
  current = pool(cur);
  white = whiteness(joined_r, joined_u, max_lag, first_lag);
}

}  // namespace

// ---------------------------------------------------------------------------------------

std::vector<double> cogging_orders(const model::Model& model, const std::vector<Run>& runs, std::size_t keep) {
  std::vector<double> power(k_max_cogging_order + 1, 0.0);
  for (const Run& run : runs) {
    const auto it = std::find(run.outputs.begin(), run.outputs.end(), "rpm");
    if (it == run.outputs.end()) continue;
    const auto o = static_cast<std::size_t>(it - run.outputs.begin());
    const auto& y = run.measured[o];
    const auto sim = simulate_as_measured(model, run);
    // The measured angle: the trapezoidal integral of the measured speed.
    std::vector<std::complex<double>> acc(k_max_cogging_order + 1, {0.0, 0.0});
    double theta = 0.0;
    for (std::size_t n = 1; n < y.size(); ++n) {
      const double dt = run.inputs.t_s[n] - run.inputs.t_s[n - 1];
      if (std::isfinite(y[n]) && std::isfinite(y[n - 1])) theta += 0.5 * (y[n] + y[n - 1]) * dt * std::numbers::pi / 30.0;
      const double r = y[n] - sim[o][n];
      if (!std::isfinite(r) || y[n] == 0.0) continue;
      for (std::size_t order = 2; order <= k_max_cogging_order; ++order) {
        acc[order] += r * std::polar(1.0, -static_cast<double>(order) * theta);
      }
    }
    for (std::size_t order = 2; order <= k_max_cogging_order; ++order) power[order] += std::norm(acc[order]);
  }
  std::vector<double> orders;
  for (std::size_t order = 2; order <= k_max_cogging_order; ++order) orders.push_back(static_cast<double>(order));
  std::stable_sort(orders.begin(), orders.end(), [&](double a, double b) {
    return power[static_cast<std::size_t>(a)] > power[static_cast<std::size_t>(b)];
  });
  orders.resize(std::min(keep, orders.size()));
  return orders;
}

GapData prepare_gap_data(const std::vector<table::Table>& train, const std::vector<table::Table>& validate,
                         const model::Params& params, double split_fraction) {
  if (train.empty()) fail("--train: no training file");
  GapData data;
  auto make = [&](const table::Table& measured) {
    const table::Table t = with_rpm(measured);
    Run run = make_run(t, compared_outputs(t), params);
    drop_saturated_current(run, parse_current_chain(t.meta));
    return run;
  };
  auto scored = [&](const table::Table& t, Run run, std::size_t first) {
    ScoredRun sr{std::move(run), first};
    const CurrentChain chain = parse_current_chain(t.meta);
    sr.i_step_A = chain.step_A;
    sr.i_sigma_A = chain.sigma_A;
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

GapReport diagnose_gap(const model::Model& model, const GapData& data, const GapSettings& settings) {
  assert(!data.train.empty() && !data.validate.empty());
  const unsigned threads = settings.threads > 0 ? settings.threads : std::max(1U, std::thread::hardware_concurrency());
  GapReport report;
  report.split_note = data.split_note;
  report.validation_samples = validation_count(data);

  // Noise floors of the compared outputs, pooled over the validation runs (scored rows).
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
    of.floor = stated && of.noise.chain > 0.0 ? of.noise.chain : of.noise.data;
    // Noise-free data (a simulation without a measurement chain) still needs a scale:
    // 0.1 % of the signal's RMS.
    of.floor = std::max(of.floor, 1e-3 * std::sqrt(signal_sq / static_cast<double>(rows)));
    if (of.floor > 0.0) report.floors.push_back(of);
  }
  if (report.floors.empty()) fail("no noise floor: the validation runs measure neither rpm nor i with any noise");
  const std::size_t outputs = report.floors.size();
  const auto n_val = static_cast<double>(report.validation_samples * outputs);
  auto fpe = [&](double score, std::size_t k) {
    const auto kk = static_cast<double>(k);
    return std::isfinite(score) && kk < n_val ? score * (n_val + kk) / (n_val - kk)
                                             : std::numeric_limits<double>::infinity();
  };

  // Before: the model as given.
  const Evaluation before = evaluate(model, data, report.floors);
  GapCandidate none;
  none.name = "none";
  none.status = "as given";
  none.model = model;
  none.score = before.score;
  none.fpe = before.score;
  none.rms = before.rms;
  none.train_rms_rpm = training_rms_rpm(model, data.train);
  none.evaluated = true;
  const bool gap = improves(static_cast<double>(outputs), before.score, outputs);

  std::size_t done = 0;
  std::size_t total = 2 + effect_plans().size() + settings.pair_effects * (settings.pair_effects - 1) / 2;

  // The refit of the nominal parameters, warm start of every effect candidate.
  model::Model base = model;
  add_effect(base, "param_mismatch");
  Job pm_job{"param_mismatch", {}, base, mismatch_free(settings.fixed), {}, 20, {}, {}};
  if (settings.progress) settings.progress("fitting param_mismatch (nominal parameters)");
  std::vector<GapCandidate> pm_result = run_jobs({pm_job}, data, report.floors, settings, threads, {}, done, total);
  GapCandidate pm = std::move(pm_result.front());
  pm.fpe = fpe(pm.score, pm.free.size());

  // Single effects.
  std::vector<Job> jobs;
  std::vector<GapCandidate> skipped;
  const std::vector<double> cogging_n = cogging_orders(pm.model, data.train, 2);
  for (const EffectPlan& plan : effect_plans()) {
    if (model.effect(plan.name) != nullptr) continue;
    const std::string why = not_excited(plan.name, data.train);
    if (!why.empty()) {
      GapCandidate c;
      c.name = plan.name;
      c.effects = {plan.name};
      c.status = why;
      c.score = k_nan;
      c.fpe = std::numeric_limits<double>::infinity();
      c.rms.assign(outputs, k_nan);
      c.train_rms_rpm = k_nan;
      skipped.push_back(std::move(c));
      ++done;
      continue;
    }
    Job job{plan.name, {plan.name}, pm.model, mismatch_free(settings.fixed), {plan.name}, 15, {}, {base}};
    add_effect(job.start, plan.name);
    for (const auto& key : plan.free) {
      job.free.push_back(plan.name + "." + key);
      job.stage1_free.push_back(plan.name + "." + key);
    }
    jobs.push_back(std::move(job));
  }
  std::vector<GapCandidate> singles = run_jobs(jobs, data, report.floors, settings, threads, cogging_n, done, total);

  // The refit must not lose to an effect fit that merely found better nominal values: when
  // some candidate's nominal scales alone fit the training runs better, refit from there.
  {
    model::Model start = pm.model;
    const double pm_cost = training_cost(pm.model, data.train);
    double best = pm_cost;
    for (const auto& c : singles) {
      if (!c.evaluated) continue;
      model::Model trial = pm.model;
      *std::find_if(trial.effects.begin(), trial.effects.end(), [](const auto& e) { return e.name == "param_mismatch"; }) =
          *c.model.effect("param_mismatch");
      const double cost = training_cost(trial, data.train);
      if (cost < best) {
        best = cost;
        start = trial;
      }
    }
    if (best < pm_cost) {
      if (settings.progress) settings.progress("refitting param_mismatch from a better start");
      ++total;
      Job again{"param_mismatch", {}, start, mismatch_free(settings.fixed), {}, 10, {}, {}};
      GapCandidate refit = std::move(run_jobs({again}, data, report.floors, settings, threads, {}, done, total).front());
      refit.fpe = fpe(refit.score, refit.free.size());
      if (refit.evaluated && training_cost(refit.model, data.train) < pm_cost) pm = std::move(refit);
    }
  }
  const double ref_score = std::min(before.score, pm.score);
  for (auto& c : singles) {
    c.fpe = fpe(c.score, c.free.size());
    c.significant = gap && improves(c.score, ref_score, outputs);
  }
  std::sort(singles.begin(), singles.end(), [](const auto& a, const auto& b) { return a.fpe < b.fpe; });

  // Pairs of the strongest significant effects, each started from the better single fit
  // with the other effect's fitted values.
  std::vector<const GapCandidate*> strong;
  for (const auto& c : singles) {
    if (c.significant && strong.size() < settings.pair_effects) strong.push_back(&c);
  }
  std::vector<Job> pair_jobs;
  for (std::size_t a = 0; a < strong.size(); ++a) {
    for (std::size_t b = a + 1; b < strong.size(); ++b) {
      const GapCandidate& first = *strong[a];
      const GapCandidate& second = *strong[b];
      // Named in catalog order, so that a pair reads the same whichever single fitted better.
      const bool in_order = find_plan(first.name) < find_plan(second.name);
      const std::string name = in_order ? first.name + "+" + second.name : second.name + "+" + first.name;
      // Started from the better single's model with the other effect added, or from the
      // model as given with both effects at their single-fit values.
      Job job{name, {first.name, second.name}, first.model, first.free, {}, 10, {}, {base}};
      job.start.effects.push_back(*second.model.effect(second.name));
      job.other_starts.front().effects.push_back(*first.model.effect(first.name));
      job.other_starts.front().effects.push_back(*second.model.effect(second.name));
      for (const GapCandidate* single : {&first, &second}) {
        for (const auto& key : find_plan(single->name)->free) job.stage1_free.push_back(single->name + "." + key);
      }
      for (const auto& key : find_plan(second.name)->free) job.free.push_back(second.name + "." + key);
      pair_jobs.push_back(std::move(job));
    }
  }
  total = done + pair_jobs.size();
  std::vector<GapCandidate> pairs = run_jobs(pair_jobs, data, report.floors, settings, threads, cogging_n, done, total);
  const GapCandidate* best_single = strong.empty() ? nullptr : strong.front();
  for (auto& c : pairs) {
    c.fpe = fpe(c.score, c.free.size());
    c.significant = best_single != nullptr && improves(c.score, best_single->score, outputs) &&
                    improves(c.score, ref_score, outputs);
  }
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) { return a.fpe < b.fpe; });

  // The decision.
  pm.significant = gap && improves(pm.score, before.score, outputs);
  std::string diagnosis = "none";
  if (!gap) {
    report.reason = fmt::format("the model as given matches the validation runs within the noise (score {:.2f} for "
                                "{} output{}, noise alone gives about {})",
                                before.score, outputs, outputs > 1 ? "s" : "", outputs);
  } else if (!pairs.empty() && pairs.front().significant) {
    diagnosis = pairs.front().name;
    report.reason = fmt::format("both effects together close significantly more of the gap than {} alone",
                                best_single->name);
  } else if (best_single != nullptr) {
    diagnosis = best_single->name;
    report.reason = fmt::format("{} closes significantly more of the gap than refitting the nominal parameters",
                                diagnosis);
  } else if (pm.significant) {
    diagnosis = "param_mismatch";
    report.reason = "refitting the nominal parameters closes the gap; no effect adds to it beyond the noise";
  } else {
    report.reason = "the model misses by more than the noise, but no candidate closes a significant part of the gap";
  }
  none.significant = false;

  std::vector<GapCandidate> all;
  all.push_back(std::move(none));
  all.push_back(std::move(pm));
  for (auto& c : singles) all.push_back(std::move(c));
  for (auto& c : pairs) all.push_back(std::move(c));
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.fpe < b.fpe; });
  for (auto& c : skipped) all.push_back(std::move(c));
  const auto it = std::find_if(all.begin(), all.end(), [&](const auto& c) { return c.name == diagnosis; });
  assert(it != all.end());
  std::rotate(all.begin(), it, it + 1);
  if (diagnosis == "none") all.front().significant = false;
  report.candidates = std::move(all);
  report.diagnosis = diagnosis;

  report.simulated_before = before.simulated;
  const Evaluation after = evaluate(report.candidates.front().model, data, report.floors);
  report.simulated_after = after.simulated;
  analyse(data, report.simulated_before, report.regimes_before, report.bands_before, report.current_regimes_before,
          report.white_before);
  analyse(data, report.simulated_after, report.regimes_after, report.bands_after, report.current_regimes_after,
          report.white_after);
  return report;
}

namespace {

double at_or_nan(const std::vector<double>& v, std::size_t k) { return k < v.size() ? v[k] : k_nan; }

/// sqrt(max(0, rms^2 - floor^2)): the part of an RMS above the noise.
double above_noise(double rms, double floor) {
  return std::isfinite(rms) ? std::sqrt(std::max(0.0, rms * rms - floor * floor)) : k_nan;
}

std::string number(double v, int digits = 4) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:.{}g}", v, digits);
}

/// "stribeck.v_s_rad_s=7.9+-0.4 ..." for the added effects first, then the nominal scales.
std::string params_text(const GapCandidate& c) {
  std::vector<std::string> effect_part;
  std::vector<std::string> nominal_part;
  for (std::size_t k = 0; k < c.free.size(); ++k) {
    const std::string item = fmt::format("{}={}+-{}", c.free[k], number(c.values[k]), number(c.std_errors[k], 2));
    (c.free[k].rfind("param_mismatch.", 0) == 0 ? nominal_part : effect_part).push_back(item);
  }
  if (const model::Effect* cog = c.model.effect("cogging"); cog != nullptr && c.evaluated &&
                                                             std::find(c.effects.begin(), c.effects.end(), "cogging") !=
                                                                 c.effects.end()) {
    effect_part.push_back(fmt::format("cogging.N_per_rev={}", number(cog->get("N_per_rev"))));
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
                        const std::vector<RegimeStat>& after, const char* unit, int digits) {
  out << fmt::format("{}\n  {:<22} {:>8} {:>12} {:>7} {:>12} {:>7}\n", title, "regime", "samples",
                     fmt::format("before {}", unit), "share", fmt::format("after {}", unit), "share");
  for (std::size_t k = 0; k < before.size() && k < after.size(); ++k) {
    const auto& b = before[k];
    const auto& a = after[k];
    if (b.samples == 0) continue;
    out << fmt::format("  {:<22} {:>8} {:>12.{}f} {:>6.1f}% {:>12.{}f} {:>6.1f}%\n", b.group + " " + b.regime, b.samples,
                       b.rms, digits, 100.0 * b.share, a.rms, digits, 100.0 * a.share);
  }
}

}  // namespace

void write_gap_csv(std::ostream& out, const GapReport& report) {
  const Summary s = summary_of(report);
  const GapCandidate& none = *std::find_if(report.candidates.begin(), report.candidates.end(),
                                           [](const auto& c) { return c.name == "none"; });
  const double before_rpm = at_or_nan(none.rms, s.rpm);
  const double before_i = at_or_nan(none.rms, s.i);
  out << "# source: mcg-fit gap\n";
  out << "# diagnosis: " << report.diagnosis << "\n";
  if (!report.split_note.empty()) out << "# split: " << report.split_note << "\n";
  for (const auto& f : report.floors) {
    out << fmt::format("# noise_floor_{}: {} (measurement chain {}, from the data {})\n", f.output, number(f.floor),
                       number(f.noise.chain), number(f.noise.data));
  }
  out << "# validation_samples: " << report.validation_samples << "\n";
  out << "effect,rms_before_rpm,rms_after_rpm,shrink_pct,gap_before_rpm,gap_after_rpm,gap_shrink_pct,"
         "rms_before_i_A,rms_after_i_A,train_rms_rpm,score,fpe,n_params,n_added,params,significant,status\n";
  for (const auto& c : report.candidates) {
    const double after_rpm = at_or_nan(c.rms, s.rpm);
    const double gap_before = above_noise(before_rpm, s.floor_rpm);
    const double gap_after = above_noise(after_rpm, s.floor_rpm);
    const double shrink = 100.0 * (before_rpm - after_rpm) / before_rpm;
    const double gap_shrink = gap_before > 0.0 ? 100.0 * (gap_before - gap_after) / gap_before : k_nan;
    out << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", c.name, number(before_rpm, 6),
                       number(after_rpm, 6), number(shrink, 4), number(gap_before, 6), number(gap_after, 6),
                       number(gap_shrink, 4), number(before_i, 6), number(at_or_nan(c.rms, s.i), 6),
                       number(c.train_rms_rpm, 6),
                       number(c.score, 6), number(c.fpe, 6), c.free.size(), c.added_parameters, params_text(c),
                       c.significant ? 1 : 0, c.status);
  }
}

void write_gap_text(std::ostream& out, const GapReport& report) {
  const Summary s = summary_of(report);
  const GapCandidate& diag = report.candidates.front();
  const GapCandidate& none = *std::find_if(report.candidates.begin(), report.candidates.end(),
                                           [](const auto& c) { return c.name == "none"; });
  out << fmt::format("diagnosis: {}\n  {}.\n", report.diagnosis, report.reason);
  if (!report.split_note.empty()) out << "split: " << report.split_note << "\n";
  for (const auto& f : report.floors) {
    const char* unit = f.output == "rpm" ? "rpm" : "A";
    out << fmt::format("noise floor {}: {} {} (measurement chain {}, estimated from the data {})\n", f.output,
                       number(f.floor), unit, number(f.noise.chain), number(f.noise.data));
  }
  if (s.rpm != std::string::npos) {
    const double b = none.rms[s.rpm];
    const double a = diag.rms[s.rpm];
    out << fmt::format("validation rpm RMS: {:.2f} -> {:.2f} rpm ({:.0f} % less); above the noise {:.2f} -> {:.2f} rpm\n",
                       b, a, 100.0 * (b - a) / b, above_noise(b, s.floor_rpm), above_noise(a, s.floor_rpm));
  }
  if (s.i != std::string::npos) {
    out << fmt::format("validation i RMS: {:.4f} -> {:.4f} A\n", none.rms[s.i], diag.rms[s.i]);
  }
  if (!diag.free.empty()) out << "fitted parameters (+- one standard error): " << params_text(diag) << "\n";
  out << "\ncandidates, diagnosis first (score = validation MSE in noise units summed over outputs; FPE ranks):\n";
  out << fmt::format("  {:<32} {:>10} {:>10} {:>9} {:>3}  {}\n", "effect", "rms rpm", "score", "fpe", "sig", "status");
  for (const auto& c : report.candidates) {
    out << fmt::format("  {:<32} {:>10} {:>10} {:>9} {:>3}  {}\n", c.name, number(at_or_nan(c.rms, s.rpm)),
                       number(c.score), number(c.fpe), c.significant ? "yes" : "no", c.status);
  }
  out << "\n";
  if (s.rpm != std::string::npos) {
    write_regime_table(out, "where the speed gap lies (validation residual rpm, before and after):",
                       report.regimes_before, report.regimes_after, "rpm", 2);
    write_regime_table(out, "by frequency band:", report.bands_before, report.bands_after, "rpm", 2);
  }
  if (s.i != std::string::npos) {
    write_regime_table(out, "where the current gap lies (validation residual i):", report.current_regimes_before,
                       report.current_regimes_after, "A", 4);
  }
  auto checks = [&](const char* label, const Whiteness& w) {
    out << fmt::format("  {}: autocorrelation Q = {:.0f} (99 % limit {:.0f}, {}; largest {:.3f} at lag {}), "
                       "cross-correlation with v Q = {:.0f} (limit {:.0f}, {}; largest {:.3f} at lag {})\n",
                       label, w.q_auto, w.q_auto_limit, w.white() ? "white" : "not white", w.max_auto,
                       w.max_auto_lag, w.q_cross, w.q_cross_limit, w.independent() ? "independent" : "correlated",
                       w.max_cross, w.max_cross_lag);
  };
  out << fmt::format("residual checks (speed; whiteness from lag {}, past the estimator window, to 50 samples):\n",
                     report.white_before.first_lag);
  checks("before", report.white_before);
  checks("after ", report.white_after);
}

void write_gap_residuals(std::ostream& out, const GapReport& report, const GapData& data) {
  table::Writer w(out);
  w.meta("source", "mcg-fit gap");
  w.meta("diagnosis", report.diagnosis);
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    w.meta(fmt::format("run_{}", r + 1), data.validate[r].run.source);
  }
  std::vector<std::string> names = {"run", "t", "v", "clutch", "r_load", "transient"};
  for (const auto& f : report.floors) {
    for (const char* suffix : {"", "_before", "_after", "_res_before", "_res_after"}) names.push_back(f.output + suffix);
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
      row[2] = in.v_V[n];
      row[3] = in.clutch[n];
      row[4] = in.r_load_ohm[n];
      row[5] = transient[n] ? 1.0 : 0.0;
      std::size_t k = 6;
      for (const auto& f : report.floors) {
        const auto it = std::find(sr.run.outputs.begin(), sr.run.outputs.end(), f.output);
        const bool has = it != sr.run.outputs.end();
        const auto o = static_cast<std::size_t>(it - sr.run.outputs.begin());
        const double y = has ? sr.run.measured[o][n] : k_nan;
        const double b = has ? report.simulated_before[r][o][n] : k_nan;
        const double a = has ? report.simulated_after[r][o][n] : k_nan;
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
    if (!file) fail("--residuals: cannot open '{}' for writing", options.residuals);
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
