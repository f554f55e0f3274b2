// The joint refit of the discrepancy's shaft terms with the nominal scales and the catalog
// effects of the model they accompany (see discrepancy_parts.hpp). The weak form fits each
// term against the model as given; refitted together on the simulated runs, a term and a
// nominal scale that share a shape (a constant torque and the Coulomb scale, a current-scaled
// torque and Kt) settle where the runs put them, not where the model as given left them.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "fit/discrepancy_parts.hpp"
#include "fit/gap_parts.hpp"
#include "fit/nls.hpp"

namespace mcg::fit::discrepancy_detail {

namespace {

/// Residual evaluations per free parameter the refit may spend (it starts near the optimum).
constexpr int k_joint_evaluations_per_parameter = 12;

}  // namespace

JointFit joint_refit(const model::Model& model, std::size_t first_term, const std::vector<bool>& phased,
                     const GapData& data, const std::function<bool()>& stop) {
  MCG_DEMAND(first_term <= model.shaft_terms.size() &&
             phased.size() == model.shaft_terms.size() - first_term);
  model::Model start = model;
  if (!start.effect("param_mismatch")) start.effects.push_back(model::default_effect("param_mismatch"));
  std::vector<std::string> effects;
  for (const model::Effect& e : model.effects) effects.push_back(e.name);
  std::vector<std::string> nominal = gap_detail::mismatch_free({}, model.params, data.train, effects);
  for (const model::Effect& e : model.effects) {
    const model::EffectSpec* spec = model::find_effect(e.name);
    if (spec == nullptr || e.name == "param_mismatch") continue;
    for (const std::string& key : gap_detail::fitted_keys(*spec, data.train)) {
      if (key != spec->plan.angle_order_key) nominal.push_back(e.name + "." + key);
    }
  }
  // Parameters: the nominal ones (by name, within their bounds), then per term its coefficient
  // and, for a harmonic, its phase.
  std::vector<ParameterSpec> specs;
  std::vector<std::pair<double, double>> bounds;
  const std::vector<model::ParamInfo> infos = model::parameters(start);
  for (const std::string& name : nominal) {
    const auto info = std::find_if(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; });
    MCG_DEMAND(info != infos.end());
    specs.push_back({name, info->value, Transform::linear, std::max(std::abs(info->value), 1e-3)});
    // The reference's own value stays within reach: a diagnosis may hold a scale beyond its
    // default range (widen_diagnosis_scales(), or the user's [bounds]).
    bounds.emplace_back(std::min(info->lower, info->value), std::max(info->upper, info->value));
  }
  const std::size_t n_nominal = specs.size();
  for (std::size_t s = first_term; s < start.shaft_terms.size(); ++s) {
    const model::ShaftTerm& t = start.shaft_terms[s];
    specs.push_back({fmt::format("term{}", s - first_term), t.k[3], Transform::linear, std::abs(t.k[3])});
    if (phased[s - first_term])
      specs.push_back({fmt::format("phase{}", s - first_term), t.k[1], Transform::linear, 0.1});
  }
  auto model_at = [&](const Eigen::VectorXd& p) {
    model::Model m = start;
    for (std::size_t j = 0; j < n_nominal; ++j) {
      set_parameter(m, nominal[j],
                    std::clamp(p[static_cast<Eigen::Index>(j)], bounds[j].first, bounds[j].second));
    }
    auto j = static_cast<Eigen::Index>(n_nominal);
    for (std::size_t s = first_term; s < m.shaft_terms.size(); ++s) {
      m.shaft_terms[s].k[3] = p[j++];
      if (phased[s - first_term]) m.shaft_terms[s].k[1] = p[j++];
    }
    return m;
  };
  // The training runs' outputs, each divided by its spread about its mean (training_cost's
  // weighting: the sum of squares is the sum of the squared NRMSEs).
  struct Series {
    std::size_t run, output;
    double spread;
  };
  std::vector<Series> series;
  std::size_t count = 0;
  for (std::size_t r = 0; r < data.train.size(); ++r) {
    for (std::size_t o = 0; o < data.train[r].outputs.size(); ++o) {
      const auto& y = data.train[r].measured[o];
      double mean = 0.0;
      std::size_t finite = 0;
      for (double v : y) {
        if (std::isfinite(v)) {
          mean += v;
          ++finite;
        }
      }
      if (finite < 2) continue;
      mean /= static_cast<double>(finite);
      double spread = 0.0;
      for (double v : y) {
        if (std::isfinite(v)) spread += (v - mean) * (v - mean);
      }
      if (!(spread > 0.0)) continue;
      series.push_back({r, o, std::sqrt(spread)});
      count += finite;
    }
  }
  if (count <= specs.size()) fail("too few training samples for the joint refit");
  const ResidualFunction residuals = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    const model::Model m = model_at(p);
    Eigen::Index k = 0;
    std::size_t last_run = data.train.size();
    std::vector<std::vector<double>> sim;
    for (const Series& s : series) {
      const Run& run = data.train[s.run];
      if (s.run != last_run) {
        sim = simulate_as_measured(m, run);
        last_run = s.run;
      }
      const auto& y = run.measured[s.output];
      for (std::size_t n = 0; n < y.size(); ++n) {
        if (std::isfinite(y[n])) r[k++] = (y[n] - sim[s.output][n]) / s.spread;
      }
    }
  };
  NlsOptions options;
  options.max_evaluations = k_joint_evaluations_per_parameter * static_cast<int>(specs.size() + 1);
  options.check_smoothness = false;
  options.stop = stop;
  const NlsResult fit = least_squares(specs, count, residuals, options);
  JointFit out;
  out.model = model_at(fit.values);
  out.converged = fit.converged;
  for (std::size_t j = 0; j < n_nominal; ++j) {
    out.nominal.emplace_back(nominal[j], get_parameter(out.model, nominal[j]));
  }
  auto j = static_cast<Eigen::Index>(n_nominal);
  for (std::size_t s = first_term; s < start.shaft_terms.size(); ++s) {
    out.coefficient.push_back(fit.values[j]);
    out.coefficient_se.push_back(fit.std_errors[j++]);
    const bool has_phase = phased[s - first_term];
    out.phase.push_back(has_phase ? fit.values[j] : std::nan(""));
    out.phase_se.push_back(has_phase ? fit.std_errors[j++] : std::nan(""));
  }
  return out;
}

}  // namespace mcg::fit::discrepancy_detail
