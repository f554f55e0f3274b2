// The gap diagnosis' decision: when a candidate is significant, how candidates rank, and
// the verdict with its one-sentence reason.
#include "fit/gap_parts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include "common/demand.hpp"
#include <cmath>
#include <limits>

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
  std::vector<GapCandidate>& pairs = candidates.pairs;
  std::vector<GapCandidate>& skipped = candidates.skipped;
  const GapCandidate* best_single = nullptr;
  for (const auto& c : singles) {
    if (c.name == candidates.best_single) best_single = &c;
  }
  const double before_score = none.score;
  // The decision.
  pm.significant = gap && improves(pm.score, before_score, outputs);
  std::string diagnosis = "none";
  if (!gap) {
    report.reason = fmt::format("the model as given matches the validation runs within the noise (score {:.2f} for "
                                "{} output{}, noise alone gives about {})",
                                before_score, outputs, outputs > 1 ? "s" : "", outputs);
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
  MCG_DEMAND(it != all.end());
  std::rotate(all.begin(), it, it + 1);
  if (diagnosis == "none") all.front().significant = false;
  report.candidates = std::move(all);
  report.diagnosis = diagnosis;
}

}  // namespace mcg::fit::gap_detail
