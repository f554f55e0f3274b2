// mcg-design speed: every subcommand on the report's loops, through the same library call the
// tool makes (output to a string). The goal is well under 50 ms per command.
#include <benchmark/benchmark.h>

#include <sstream>
#include <string>
#include <vector>

#include "design/run.hpp"

namespace {

constexpr const char* k_third_order = "0.0146/((s/60+1)*(s/850+1)*(s/1800+1))";

struct Case {
  const char* name;
  mcg::design::Options options;
};

std::vector<Case> cases() {
  auto base = [](const char* command, const char* plant) {
    mcg::design::Options o;
    o.command = command;
    o.plant = plant;
    return o;
  };
  std::vector<Case> out;
  {
    auto o = base("p", k_third_order);
    o.pm_deg = 55.0;
    out.push_back({"p/report-third-order", o});
  }
  {
    auto o = base("pi", k_third_order);
    o.pm_deg = 50.0;
    o.zero_rad_s = 500.0;
    o.dt_s = 0.001;
    o.plant_units = "loop";
    out.push_back({"pi/report-zero-500-tustin-fixed-point", o});
  }
  {
    auto o = base("pi", "");
    o.pm_deg = 50.0;
    o.wc_rad_s = 50.0;
    out.push_back({"pi/zoh-loop-crossover", o});
  }
  {
    auto o = base("pid", k_third_order);
    o.pm_deg = 50.0;
    o.wc_rad_s = 300.0;
    out.push_back({"pid/third-order", o});
  }
  {
    auto o = base("lead", k_third_order);
    o.pm_deg = 50.0;
    o.wc_rad_s = 600.0;
    o.dt_s = 0.001;
    o.plant_units = "loop";
    out.push_back({"lead/third-order-tustin", o});
  }
  {
    auto o = base("lag", k_third_order);
    o.pm_deg = 50.0;
    o.k_dc = 2000.0;
    out.push_back({"lag/third-order", o});
  }
  {
    auto o = base("rlocus-design", "");
    o.zeta = 0.7;
    out.push_back({"rlocus-design/zoh-loop", o});
  }
  {
    auto o = base("tune", k_third_order);
    out.push_back({"tune/pi-third-order", o});
  }
  {
    auto o = base("tune", "");
    out.push_back({"tune/pi-zoh-loop", o});
  }
  {
    auto o = base("margins", k_third_order);
    o.controller = "4658*(s/500+1)/s";
    out.push_back({"margins/report-pi", o});
  }
  {
    auto o = base("margins", "16.557*exp(-0.002*s)/((s/65+1)*(s/950+1))");
    o.controller = "0.05";
    out.push_back({"margins/delay", o});
  }
  out.push_back({"bode/zoh-loop", base("bode", "")});
  out.push_back({"nyquist/zoh-loop", base("nyquist", "")});
  out.push_back({"rlocus/zoh-loop", base("rlocus", "")});
  {
    auto o = base("step", k_third_order);
    o.controller = "4658*(s/500+1)/s";
    out.push_back({"step/report-pi", o});
  }
  {
    auto o = base("c2d", k_third_order);
    o.dt_s = 0.001;
    out.push_back({"c2d/zoh", o});
  }
  out.push_back({"loop/report", base("loop", "")});
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  for (const Case& c : cases()) {
    benchmark::RegisterBenchmark(c.name, [options = c.options](benchmark::State& state) {
      for (auto _ : state) {
        std::ostringstream out;
        mcg::design::run(options, out);
        benchmark::DoNotOptimize(out.str().size());
      }
    })->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
