// The design subcommands: the plant resolved, the method solved, the design written.
#include "cmd/design/methods.hpp"

#include <limits>

#include "common/error.hpp"
#include "common/range.hpp"

namespace mcg::cmd {

namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();

/// A target the method cannot do without. When several are missing, the last one of the method's
/// signature is named (as the tool always has).
double need(double v, const char* name) {
  if (std::isnan(v)) fail("{}: required", name);
  return v;
}

void add_pm(CLI::App& app, double& pm_deg) {
  app.add_option("--pm", pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
}

void add_wc(CLI::App& app, double& wc_rad_s) {
  app.add_option("--wc", wc_rad_s, "crossover frequency, rad/s")->check(mcg::Range(1e-12, k_inf));
}

}  // namespace

void DesignP::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_pm(app, options.pm_deg);
}

int DesignP::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  design::write_design(r, design::design_p(r.setup, need(options.pm_deg, "--pm")), io.out);
  return 0;
}

void DesignPi::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_pm(app, options.pm_deg);
  app.add_option("--zero", options.zero_rad_s, "PI zero Ki/Kp, rad/s")->check(mcg::Range(1e-12, k_inf));
  add_wc(app, options.wc_rad_s);
}

int DesignPi::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  const double pm = need(options.pm_deg, "--pm");
  const bool zero = !std::isnan(options.zero_rad_s);
  const bool wc = !std::isnan(options.wc_rad_s);
  if (zero && wc) fail("--zero: give --zero or --wc, not both");
  if (!zero && !wc) fail("--zero or --wc: required");
  design::write_design(r,
                       zero ? design::design_pi_zero(r.setup, pm, options.zero_rad_s)
                            : design::design_pi_crossover(r.setup, pm, options.wc_rad_s),
                       io.out);
  return 0;
}

void DesignPid::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_pm(app, options.pm_deg);
  add_wc(app, options.wc_rad_s);
  app.add_option("--ti-td", options.ti_over_td, "Ti/Td")->check(mcg::Range(1e-6, 1e6))->capture_default_str();
  app.add_option("--n", options.n, "derivative filter: pole at N/Td (--form filtered)")
      ->check(mcg::Range(1e-6, 1e6))
      ->capture_default_str();
  app.add_option(
         "--form", options.form,
         "filtered: C(s) with the derivative filter, discretised by --method; board: the board's PID, "
         "designed in z (backward differences, no filter; needs --dt)")
      ->check(CLI::IsMember({"filtered", "board"}))
      ->capture_default_str();
}

int DesignPid::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  const double wc = need(options.wc_rad_s, "--wc");
  const double pm = need(options.pm_deg, "--pm");
  design::write_design(r,
                       options.form == "board"
                           ? design::design_pid_board(r.setup, pm, wc, options.ti_over_td)
                           : design::design_pid(r.setup, pm, wc, options.ti_over_td, options.n),
                       io.out);
  return 0;
}

void DesignLead::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_pm(app, options.pm_deg);
  add_wc(app, options.wc_rad_s);
}

int DesignLead::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  const double wc = need(options.wc_rad_s, "--wc");
  design::write_design(r, design::design_lead(r.setup, need(options.pm_deg, "--pm"), wc), io.out);
  return 0;
}

void DesignLag::define(CLI::App& app) {
  define_plant(app, options.plant);
  add_pm(app, options.pm_deg);
  app.add_option("--k-dc", options.k_dc, "controller DC gain")->check(mcg::Range(1e-12, k_inf));
  app.add_option("--ratio", options.ratio, "zero at wc/ratio")
      ->check(mcg::Range(1.0, 1e6))
      ->capture_default_str();
}

int DesignLag::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  const double k_dc = need(options.k_dc, "--k-dc");
  design::write_design(r, design::design_lag(r.setup, need(options.pm_deg, "--pm"), k_dc, options.ratio),
                       io.out);
  return 0;
}

void DesignRlocus::define(CLI::App& app) {
  define_plant(app, options.plant);
  app.add_option("--zeta", options.zeta, "damping ratio, 0..1")->check(mcg::Range(0.0, 1.0));
}

int DesignRlocus::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  if (std::isnan(options.zeta)) fail("--zeta: required");
  const design::RlocusResult rl = design::design_rlocus(r.setup, options.zeta);
  design::write_design(r, rl.design, io.out, rl);
  return 0;
}

void DesignTune::define(CLI::App& app) {
  define_plant(app, options.plant);
  app.add_option("--structure", options.structure, "p or pi")
      ->check(CLI::IsMember({"p", "pi"}))
      ->capture_default_str();
  app.add_option("--pm-min", options.limits.pm_min_deg, "least phase margin, degrees")
      ->check(mcg::Range(0.0, 180.0))
      ->capture_default_str();
  app.add_option("--gm-min", options.limits.gm_min_db, "least gain margin, dB")
      ->check(mcg::Range(0.0, 200.0))
      ->capture_default_str();
  app.add_option("--ms-max", options.limits.ms_max, "largest peak sensitivity")
      ->check(mcg::Range(1.0, 100.0))
      ->capture_default_str();
}

int DesignTune::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, true);
  design::write_design(r, design::tune(r.setup, options.structure, options.limits), io.out, std::nullopt,
                       &options.limits);
  return 0;
}

}  // namespace mcg::cmd
