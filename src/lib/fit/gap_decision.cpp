// The gap diagnosis' decision: when a candidate is significant, how candidates rank, and
// the verdict with its one-sentence reason.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/demand.hpp"
#include "fit/gap_parts.hpp"

namespace mcg::fit {

bool GapCandidate::determined() const {
  const auto loose = [&](const std::string& key) {
    const auto it = std::find(free.begin(), free.end(), key);
    if (it == free.end()) return true;
    const auto k = static_cast<std::size_t>(it - free.begin());
    return k >= std::min(values.size(), std::min(std_errors.size(), free.size())) ||
           !(std_errors[k] <= k_gap_max_relative_error * std::abs(values[k]));
  };
  return std::none_of(flags.begin(), flags.end(), [&](const FitFlag& f) {
    const bool effect = std::any_of(f.names.begin(), f.names.end(), [](const std::string& n) {
      return !n.starts_with("param_mismatch.");
    });
    switch (f.kind) {
      case FitFlag::Kind::impossible:
        return true;
      case FitFlag::Kind::at_bound:
        return false;
      case FitFlag::Kind::correlated:
        return effect && std::any_of(f.names.begin(), f.names.end(), loose);
      case FitFlag::Kind::undetermined:
      case FitFlag::Kind::too_precise:
        return effect;
    }
    return true;
  });
}

}  // namespace mcg::fit

namespace mcg::fit::gap_detail {

bool improves(double score, double score_ref, std::size_t outputs) {
  const double gap = score_ref - static_cast<double>(outputs);
  return score_ref - score > std::max(k_gap_abs_threshold, k_gap_rel_threshold * gap);
}

double fpe(double score, std::size_t k, double samples) {
  const auto kk = static_cast<double>(k);
  return std::isfinite(score) && kk < samples ? score * (samples + kk) / (samples - kk)
                                              : std::numeric_limits<double>::infinity();
}

void decide(Candidates candidates, bool gap, std::size_t outputs, GapReport& report) {
  GapCandidate& none = candidates.none;
  GapCandidate& pm = candidates.pm;
  std::vector<GapCandidate>& singles = candidates.singles;
  std::vector<GapCandidate>& mixtures = candidates.mixtures;
  std::vector<GapCandidate>& skipped = candidates.skipped;
  // A candidate whose parameters the data do not determine cannot be the diagnosis: the
  // search does not call it significant, and the choice here skips it all the same.
  const GapCandidate* best_single = nullptr;
  for (const auto& c : singles) {
    if (c.name == candidates.best_single && c.determined()) best_single = &c;
  }
  if (best_single == nullptr) {
    for (const auto& c : singles) {
      if (c.significant && c.determined() && (best_single == nullptr || c.fpe < best_single->fpe)) best_single = &c;
    }
  }
  const GapCandidate* best_mixture = nullptr;
  for (const auto& c : mixtures) {
    if (c.name == candidates.best_mixture && c.determined() && best_single != nullptr) best_mixture = &c;
  }
  const double before_score = none.score;
  const double excess = before_score - static_cast<double>(outputs);
  // The share of the excess over the noise that the model as given leaves and `c` removes.
  auto removed = [&](const GapCandidate& c) {
    return excess > 0.0 ? (before_score - c.score) / excess : 0.0;
  };
  for (std::vector<GapCandidate>* group : {&singles, &mixtures}) {
    for (auto& c : *group) c.significant = c.significant && c.determined();
  }
  // The decision.
  pm.significant = gap && pm.determined() && improves(pm.score, before_score, outputs);
  std::string diagnosis = "none";
  const GapCandidate* chosen = nullptr;
  if (!gap) {
    report.reason = fmt::format(
        "the model as given matches the validation runs within the noise (score {:.2f} for "
        "{} output{}, noise alone gives about {})",
        before_score, outputs, outputs > 1 ? "s" : "", outputs);
  } else if (best_mixture != nullptr) {
    chosen = best_mixture;
    report.reason = fmt::format(
        "the {} effects together close significantly more of the gap than {} alone, each "
        "added one significant against the model it extends",
        chosen->effects.size(), best_single->name);
  } else if (best_single != nullptr) {
    chosen = best_single;
    report.reason = fmt::format(
        "{} closes significantly more of the gap than refitting the nominal parameters", best_single->name);
  } else if (pm.significant) {
    chosen = &pm;
    report.reason = "refitting the nominal parameters closes the gap; no effect adds to it beyond the noise";
  }
  // A small excess that no candidate predicts the held-out runs better than is no missing
  // effect: every candidate fitted to the training runs scores worse on the validation runs.
  const auto better = [&](const GapCandidate& c) { return c.evaluated && c.score < before_score; };
  const bool none_better = !better(pm) && std::none_of(singles.begin(), singles.end(), better) &&
                           std::none_of(mixtures.begin(), mixtures.end(), better);
  if (gap && chosen == nullptr && none_better &&
      before_score <= (1.0 + k_gap_small_excess) * static_cast<double>(outputs)) {
    report.reason = fmt::format(
        "the model as given misses the validation runs by a little more than the noise (score {:.2f} for {} "
        "output{}, noise alone gives about {}), but no candidate, not even a refit of its nominal "
        "parameters, "
        "predicts them better: no effect is missing",
        before_score, outputs, outputs > 1 ? "s" : "", outputs);
    gap = false;
  }
  // Accepted only when it explains the gap: near the noise, or most of the excess removed.
  const bool near_noise =
      chosen != nullptr && chosen->score <= (1.0 + k_gap_near_noise) * static_cast<double>(outputs);
  if (chosen != nullptr && (near_noise || removed(*chosen) >= k_gap_explained_share)) {
    diagnosis = chosen->name;
  } else if (gap) {
    diagnosis = "unexplained";
    // The best candidate by FPE stands for what the catalog can do; its residual is analysed.
    const GapCandidate* best = chosen;
    for (const std::vector<GapCandidate>* group : {&singles, &mixtures}) {
      for (const auto& c : *group) {
        if (c.evaluated && std::isfinite(c.fpe) && (best == nullptr || c.fpe < best->fpe)) best = &c;
      }
    }
    if (best == nullptr || !(best->fpe < none.fpe)) best = pm.evaluated && pm.fpe < none.fpe ? &pm : &none;
    GapCandidate u = *best;
    u.name = "unexplained";
    u.effects.clear();
    u.significant = false;
    u.status = fmt::format("best candidate {} removes {:.0f} % of the score above the noise", best->name,
                           100.0 * removed(*best));
    report.reason = fmt::format(
        "no candidate explains the gap: the best, {}, leaves a validation score of {:.2f} against about {} "
        "for "
        "noise alone and removes {:.0f} % of the excess (accepted: within {:.0f} % of the noise, or {:.0f} % "
        "removed)",
        best->name, best->score, outputs, 100.0 * removed(*best), 100.0 * k_gap_near_noise,
        100.0 * k_gap_explained_share);
    report.candidates.push_back(std::move(u));
  }
  none.significant = false;
  // A candidate that would have scored better than the verdict but whose parameters the data
  // do not determine was set aside: say so, it is what a user would otherwise read as the answer.
  {
    const GapCandidate* verdict = diagnosis == "unexplained" ? nullptr : chosen;
    const GapCandidate* aside = nullptr;
    for (const std::vector<GapCandidate>* group : {&singles, &mixtures}) {
      for (const auto& c : *group) {
        if (c.evaluated && !c.determined() && std::isfinite(c.fpe) &&
            (verdict == nullptr || c.fpe < verdict->fpe) && (aside == nullptr || c.fpe < aside->fpe)) {
          aside = &c;
        }
      }
    }
    if (!pm.determined() && pm.evaluated && std::isfinite(pm.fpe) && (verdict == nullptr || pm.fpe < verdict->fpe) &&
        (aside == nullptr || pm.fpe < aside->fpe)) {
      aside = &pm;
    }
    if (aside != nullptr) {
      report.reason += fmt::format(
          "; {} scores better but was set aside: the data do not determine its parameters (see its flags)",
          aside->name);
    }
  }

  const auto cut = [](const GapCandidate& c) { return c.status.starts_with(k_out_of_time); };
  report.partial = cut(pm) || std::any_of(singles.begin(), singles.end(), cut) ||
                   std::any_of(mixtures.begin(), mixtures.end(), cut);
  if (report.partial) {
    report.reason +=
        "; PARTIAL: the time budget cut the search short, the candidates marked so are unfinished";
  }
  std::vector<GapCandidate> all;
  if (diagnosis == "unexplained") {
    all.push_back(std::move(report.candidates.back()));
    report.candidates.clear();
  }
  all.push_back(std::move(none));
  all.push_back(std::move(pm));
  for (auto& c : singles) all.push_back(std::move(c));
  for (auto& c : mixtures) all.push_back(std::move(c));
  const auto ranked = all.begin() + (diagnosis == "unexplained" ? 1 : 0);
  std::stable_sort(ranked, all.end(), [](const auto& a, const auto& b) { return a.fpe < b.fpe; });
  for (auto& c : skipped) all.push_back(std::move(c));
  const auto it = std::find_if(all.begin(), all.end(), [&](const auto& c) { return c.name == diagnosis; });
  MCG_DEMAND(it != all.end());
  std::rotate(all.begin(), it, it + 1);
  if (diagnosis == "none") all.front().significant = false;
  report.candidates = std::move(all);
  report.diagnosis = diagnosis;
}

}  // namespace mcg::fit::gap_detail
