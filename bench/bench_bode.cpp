// Frequency-response speed on one million samples (goal: under 0.5 s for `mcg-sweep bode`):
// the Welch H1 estimator alone at two segment lengths, the multisine line estimator, and the
// whole tool path (CSV parse of t,v,omega + estimate + CSV write).
#include "signal/excitation.hpp"
#include "signal/spectrum.hpp"
#include "signal/sweep.hpp"
#include "table/table.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

constexpr std::size_t k_samples = 1000000;
constexpr double k_dt_s = 0.001;

// A first-order lag with a delay, y_k = 0.9 y_{k-1} + 0.1 x_{k-3}: the plant's shape.
std::vector<double> plant(const std::vector<double>& x) {
  std::vector<double> y(x.size(), 0.0);
  for (std::size_t k = 1; k < x.size(); ++k) y[k] = 0.9 * y[k - 1] + 0.1 * (k >= 3 ? x[k - 3] : 0.0);
  return y;
}

const std::vector<double>& chirp_input() {
  static const std::vector<double> x = [] {
    const auto t = mcg::signal::time_grid(k_dt_s, static_cast<double>(k_samples) * k_dt_s);
    return mcg::signal::chirp_signal(t, 2.0, 0.5, 200.0, static_cast<double>(t.size()) * k_dt_s,
                                     mcg::signal::ChirpSpacing::linear);
  }();
  return x;
}

void BM_WelchH1(benchmark::State& state) {
  const auto& x = chirp_input();
  const auto y = plant(x);
  const auto segment = static_cast<std::size_t>(state.range(0));
  for (auto _ : state) {
    auto r = mcg::signal::welch_h1(x, y, k_dt_s, segment, 0.5);
    benchmark::DoNotOptimize(r.h.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(k_samples));
}
BENCHMARK(BM_WelchH1)->Arg(4096)->Arg(65536)->Unit(benchmark::kMillisecond);

void BM_LineResponse(benchmark::State& state) {
  const std::size_t period = 2000;
  const auto harmonics = mcg::signal::multisine_harmonics(0.5, 200, 30, 2.0, mcg::signal::ChirpSpacing::log);
  const auto x = mcg::signal::multisine_signal(k_samples, 2.0, period, harmonics,
                                               mcg::signal::schroeder_phases(harmonics.size()));
  const auto y = plant(x);
  for (auto _ : state) {
    auto r = mcg::signal::line_response(x, y, k_dt_s, period, harmonics);
    benchmark::DoNotOptimize(r.h.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(k_samples));
}
BENCHMARK(BM_LineResponse)->Unit(benchmark::kMillisecond);

// The tool's whole path, reading the table from a file as `mcg-sweep bode FILE` does.
void BM_BodeTool(benchmark::State& state) {
  const auto& x = chirp_input();
  const auto y = plant(x);
  const std::string path = "/tmp/mcg-bench-bode-" + std::to_string(::getpid()) + ".csv";
  {
    std::ofstream file(path);
    mcg::table::Writer w(file);
    w.meta("sample_period", "0.001");
    w.header({"t", "v", "omega"});
    for (std::size_t k = 0; k < x.size(); ++k) w.row({static_cast<double>(k) * k_dt_s, 6.0 + x[k], y[k]});
    w.finish();
  }
  mcg::signal::BodeOptions options;
  options.input = path;
  for (auto _ : state) {
    std::ostringstream out;
    std::ostringstream warn;
    mcg::Diagnostics diag(warn, "bode");
    mcg::signal::bode(options, out, diag);
    benchmark::DoNotOptimize(out.str().data());
  }
  std::remove(path.c_str());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(k_samples));
}
BENCHMARK(BM_BodeTool)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
