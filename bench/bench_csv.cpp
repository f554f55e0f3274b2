// CSV throughput: parse and write of a simulator-shaped table (goal: >= 100 MB/s each, one core).
#include "table/table.hpp"

#include <benchmark/benchmark.h>

#include <sstream>
#include <string>

namespace {

constexpr std::size_t k_rows = 200000;

std::string make_csv() {
  std::ostringstream out;
  mcg::table::Writer w(out);
  w.meta("source", "bench_csv");
  w.header({"t", "v", "clutch", "r_load", "rpm", "i", "v_gen"});
  for (std::size_t n = 0; n < k_rows; ++n) {
    const double t = 0.001 * static_cast<double>(n);
    w.row({t, 12.0 * (n % 1000 < 500), 2, 5.6, 1234.5678 + t, 0.123456 - t * 1e-3, 3.14159 * t});
  }
  w.finish();
  return out.str();
}

void BM_CsvParse(benchmark::State& state) {
  const std::string text = make_csv();
  for (auto _ : state) {
    std::istringstream in(text);
    mcg::table::Reader r(in, "bench");
    double sum = 0;
    while (r.next()) sum += r[4];
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(text.size()));
}
BENCHMARK(BM_CsvParse)->Unit(benchmark::kMillisecond);

// A three-row file, as a fuzzer or a short script feeds it: the cost is the reader's set-up.
void BM_CsvParseSmall(benchmark::State& state) {
  const std::string text = "# source: bench_csv\nt,v,rpm\n0,12,0\n0.001,12,1.5\n0.002,12,3\n";
  for (auto _ : state) {
    std::istringstream in(text);
    mcg::table::Reader r(in, "bench");
    double sum = 0;
    while (r.next()) sum += r[2];
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_CsvParseSmall);

// The same file through table::read, the whole-table reader every batch tool and the fuzz
// harnesses use: its buffers must be sized to the input, not to the parts of a large one.
void BM_CsvReadSmall(benchmark::State& state) {
  const std::string text = "# source: bench_csv\nt,v,rpm\n0,12,0\n0.001,12,1.5\n0.002,12,3\n";
  for (auto _ : state) {
    std::istringstream in(text);
    const mcg::table::Table t = mcg::table::read(in, "bench");
    benchmark::DoNotOptimize(t.columns.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_CsvReadSmall);

void BM_CsvWrite(benchmark::State& state) {
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string text = make_csv();
    bytes = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(bytes));
}
BENCHMARK(BM_CsvWrite)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
