// mcg-design speed: every subcommand on the report's loops, through the same command the tool
// runs (output to a string). The goal is well under 50 ms per command.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cmd/design/analysis.hpp"
#include "cmd/design/methods.hpp"
#include "cmd/design/plant.hpp"

namespace {

constexpr const char* k_third_order = "0.0146/((s/60+1)*(s/850+1)*(s/1800+1))";

/// The options a case gives, as on the command line.
struct Options {
  std::string command;
  std::string plant;
  std::string plant_units;
  std::string controller;
  double dt_s = NAN;
  double pm_deg = NAN;
  double zero_rad_s = NAN;
  double wc_rad_s = NAN;
  double k_dc = NAN;
  double zeta = NAN;
};

struct Case {
  const char* name;
  Options options;
};

/// The tool's command for `o`, its options set.
std::unique_ptr<mcg::cmd::Command> command_of(const Options& o) {
  mcg::design::PlantOptions plant;
  plant.plant = o.plant;
  plant.plant_units = o.plant_units;
  plant.dt_s = o.dt_s;
  const auto with = [&](auto command, auto set) {
    auto c = std::make_unique<decltype(command)>(command);
    c->options.plant = plant;
    set(c->options);
    return std::unique_ptr<mcg::cmd::Command>(std::move(c));
  };
  const auto none = [](auto&) {};
  const auto controller = [&](auto& x) { x.controller = o.controller; };
  if (o.command == "p") return with(mcg::cmd::DesignP{}, [&](auto& x) { x.pm_deg = o.pm_deg; });
  if (o.command == "pi") {
    return with(mcg::cmd::DesignPi{}, [&](auto& x) {
      x.pm_deg = o.pm_deg;
      x.zero_rad_s = o.zero_rad_s;
      x.wc_rad_s = o.wc_rad_s;
    });
  }
  if (o.command == "pid") {
    return with(mcg::cmd::DesignPid{}, [&](auto& x) {
      x.pm_deg = o.pm_deg;
      x.wc_rad_s = o.wc_rad_s;
    });
  }
  if (o.command == "lead") {
    return with(mcg::cmd::DesignLead{}, [&](auto& x) {
      x.pm_deg = o.pm_deg;
      x.wc_rad_s = o.wc_rad_s;
    });
  }
  if (o.command == "lag") {
    return with(mcg::cmd::DesignLag{}, [&](auto& x) {
      x.pm_deg = o.pm_deg;
      x.k_dc = o.k_dc;
    });
  }
  if (o.command == "rlocus-design") return with(mcg::cmd::DesignRlocus{}, [&](auto& x) { x.zeta = o.zeta; });
  if (o.command == "tune") return with(mcg::cmd::DesignTune{}, none);
  if (o.command == "margins") return with(mcg::cmd::Margins{}, controller);
  if (o.command == "bode") return with(mcg::cmd::Bode{false}, controller);
  if (o.command == "nyquist") return with(mcg::cmd::Bode{true}, controller);
  if (o.command == "rlocus") return with(mcg::cmd::Rlocus{}, controller);
  if (o.command == "step") return with(mcg::cmd::Step{}, controller);
  if (o.command == "c2d") return with(mcg::cmd::C2d{}, none);
  return with(mcg::cmd::Loop{}, none);
}

std::vector<Case> cases() {
  auto base = [](const char* command, const char* plant) {
    Options o;
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
      const std::shared_ptr<mcg::cmd::Command> command = command_of(options);
      std::istringstream in;
      std::ostringstream err;
      mcg::Diagnostics diag(err, "mcg-design");
      for (auto _ : state) {
        std::ostringstream out;
        mcg::cmd::Io io{in, out, diag, "mcg-design"};
        command->run(io);
        benchmark::DoNotOptimize(out.str().size());
      }
    })->Unit(benchmark::kMillisecond);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
