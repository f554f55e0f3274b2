// mcg-design subcommands: resolve the plant, the chain and the controller; design or analyse;
// write INI or CSV.
#include "design/run.hpp"
#include "common/edit_distance.hpp"

#include "design/rig.hpp"

#include "boardunits/controller.hpp"
#include "boardunits/plant_units.hpp"

#include "common/error.hpp"
#include "config/ini.hpp"
#include "linsys/parse.hpp"
#include "linsys/response.hpp"
#include "mcg/version.hpp"
#include "table/table.hpp"

#include <algorithm>
#include <iterator>
#include <string_view>
#include <cmath>
#include <numbers>
#include <optional>
#include <ostream>
#include <sstream>

namespace mcg::design {

using config::format_number;
using config::Ini;
using linsys::Domain;
using linsys::Poly;

namespace {

/// The report's identified plant, ω_internal/V_in in rad/s per V (Figure 16-1).
constexpr const char* k_report_plant = "16.557/((s/65+1)*(s/950+1))";

using Chain = boardunits::LoopChain;

struct Resolved {
  Ini ini;
  Tf raw;              ///< the plant as given
  std::string raw_where;
  bool chain = false;
  boardunits::PlantUnits units;  ///< what raw maps; physical units get the chain (converted to rad/s per V)
  Chain chain_values;
  bool hold = false;   ///< the continuous plant is sampled through a ZOH (the PWM)
  double dt_s = 0.0;   ///< controller sample period, 0 = continuous
  Setup setup;
};

std::optional<double> flag(double v) { return std::isnan(v) ? std::nullopt : std::optional<double>(v); }

std::vector<double> parse_list(const std::string& text, const std::string& where) {
  std::vector<double> out;
  std::string token;
  std::string normalised = text;
  std::replace(normalised.begin(), normalised.end(), ',', ' ');
  std::istringstream words(normalised);
  while (words >> token) {
    double v = 0.0;
    if (!table::parse_number(token, v) || !std::isfinite(v)) fail("{}: invalid number {}", where, quote(token));
    out.push_back(v);
  }
  if (out.empty()) fail("{}: empty coefficient list", where);
  return out;
}

Tf tf_from_lists(const std::vector<double>& num, const std::vector<double>& den, const std::string& where) {
  Tf g;
  g.num = linsys::trim(num);
  g.den = linsys::trim(den);
  if (g.den.empty()) fail("{}: the denominator is zero", where);
  linsys::check_degree(g, where);
  return g;
}

std::string origin_of(const Ini& ini, const char* section, const char* key) {
  const auto* e = ini.find(section, key);
  std::string where = e && !e->origin.empty() ? e->origin + ": " : std::string();
  return where + "[" + section + "] " + key;
}

double positive(const Ini& ini, const char* section, const char* key, std::optional<double> from_flag, const char* flag_name,
                double fallback) {
  if (from_flag) {
    if (!(*from_flag > 0.0) || !std::isfinite(*from_flag)) fail("{}: must be positive, got {}", flag_name, *from_flag);
    return *from_flag;
  }
  if (auto v = ini.number(section, key)) {
    if (!(*v > 0.0) || !std::isfinite(*v)) ini.reject(section, key, "must be positive");
    return *v;
  }
  return fallback;
}

using boardunits::PlantUnits;

bool is_design_command(const std::string& command) {
  for (const char* c : {"p", "pi", "pid", "lead", "lag", "rlocus-design", "tune"}) {
    if (command == c) return true;
  }
  return false;
}

constexpr const char* k_units_choices = "rpm/V, rad/s/V, rpm/duty, rad/s/duty or loop";

/// Every key a [plant] section may hold: those resolve() reads and those c2d and the designs
/// write (so that an output is an input again).
constexpr std::string_view k_plant_keys[] = {"tf",    "num",       "den",       "domain",     "maps",   "delay_s",
                                             "dt_s",  "hold",      "model",     "clutch",     "speed_rpm",
                                             "r_load_ohm", "method", "prewarp_rad_s"};
/// The sections mcg-design reads. Other tools' sections pass, but one a typing slip away from
/// these is an error: a misspelt [plnat] would otherwise leave the built-in plant analysed.
constexpr std::string_view k_design_sections[] = {"plant", "loop", "controller", "design"};

/// Unknown [plant] keys and near misses of mcg-design's sections are errors naming file:line.
void check_plant_names(const Ini& ini) {
  for (const auto* e : ini.entries("plant")) {
    if (std::find(std::begin(k_plant_keys), std::end(k_plant_keys), e->key) == std::end(k_plant_keys)) {
      ini.reject("plant", e->key, "unknown key (tf, num, den, domain, maps, delay_s, dt_s, hold, model, clutch, "
                                  "speed_rpm, r_load_ohm)");
    }
  }
  for (const std::string& section : ini.sections()) {
    for (const std::string_view known : k_design_sections) {
      if (section == known) break;
      const std::size_t d = edit_distance(section, known);
      if (d > 0 && d <= (known.size() >= 5 ? 2U : 1U)) {
        const auto entries = ini.entries(section);
        const std::string where = entries.empty() || entries.front()->origin.empty() ? std::string("config")
                                                                                     : entries.front()->origin;
        fail("{}: unknown section {} (did you mean [{}]?)", where, quote("[" + section + "]"), known);
      }
    }
  }
}

Resolved resolve(const Options& o) {
  Resolved r;
  r.ini = Ini::load_all(o.configs);
  const Ini& ini = r.ini;
  check_plant_names(ini);
  bool builtin = false;
  std::optional<Domain> domain;
  if (!o.plant.empty() || o.plant_given) {
    if (!o.num.empty() || !o.den.empty()) fail("--plant: give either --plant or --num/--den, not both");
    const linsys::ParsedTf p = linsys::parse_tf(o.plant, "--plant");
    r.raw = p.tf;
    domain = p.domain;
    r.raw_where = "--plant";
  } else if (!o.num.empty() || !o.den.empty()) {
    if (o.num.empty()) fail("--den: needs --num");
    if (o.den.empty()) fail("--num: needs --den");
    r.raw = tf_from_lists(parse_list(o.num, "--num"), parse_list(o.den, "--den"), "--den");
    r.raw_where = "--num/--den";
    if (o.domain == "z") domain = Domain::z;
  } else if (o.rig || ini.get("plant", "model") == std::optional<std::string>("rig")) {
    if (auto m = ini.get("plant", "model"); m && *m != "rig") ini.reject("plant", "model", "must be rig");
    int clutch = o.clutch;
    if (clutch < 0) {
      const double c = ini.number("plant", "clutch").value_or(2.0);
      if (c != 0.0 && c != 1.0 && c != 2.0) ini.reject("plant", "clutch", "must be 0, 1 or 2");
      clutch = static_cast<int>(c);
    }
    const std::optional<double> rpm = flag(o.speed_rpm) ? flag(o.speed_rpm) : ini.number("plant", "speed_rpm");
    if (!rpm) fail("--speed-rpm: required for the linearised rig (or speed_rpm in [plant])");
    const double r_load = flag(o.r_load_ohm).value_or(ini.number("plant", "r_load_ohm").value_or(INFINITY));
    r.raw = linearise_rig(model::from_ini(ini), clutch, rad_s_from_rpm(*rpm), r_load);
    r.raw_where = fmt::format("rig model linearised at clutch {}, {} rpm, r_load {} ohm", clutch,
                              format_number(*rpm), format_number(r_load));
    domain = Domain::s;
  } else if (auto text = ini.get("plant", "tf")) {
    r.raw_where = origin_of(ini, "plant", "tf");
    const linsys::ParsedTf p = linsys::parse_tf(*text, r.raw_where);
    r.raw = p.tf;
    domain = p.domain;
    // mcg-fit writes tf rounded for reading and num/den in full: from the same file, without a
    // delay in the text, the full coefficients are the plant (the units' conversion keeps them).
    const auto file_of = [&](const char* key) {
      const auto* e = ini.find("plant", key);
      const std::string origin = e ? e->origin : std::string();
      return origin.substr(0, origin.rfind(':'));
    };
    const auto num = ini.numbers("plant", "num");
    const auto den = ini.numbers("plant", "den");
    if (num && den && p.tf.delay_s == 0.0 && file_of("num") == file_of("tf") &&
        file_of("den") == file_of("tf")) {
      r.raw_where = origin_of(ini, "plant", "den");
      r.raw = tf_from_lists(*num, *den, r.raw_where);
    }
  } else if (ini.has("plant", "num") || ini.has("plant", "den")) {
    const auto num = ini.numbers("plant", "num");
    const auto den = ini.numbers("plant", "den");
    if (!num) ini.reject("plant", "den", "needs num in [plant] too");
    if (!den) ini.reject("plant", "num", "needs den in [plant] too");
    r.raw_where = origin_of(ini, "plant", "den");
    r.raw = tf_from_lists(*num, *den, r.raw_where);
  } else {
    r.raw = linsys::parse_tf(k_report_plant, "built-in plant").tf;
    r.raw_where = "built-in plant";
    builtin = true;
  }
  if (o.plant.empty() && o.num.empty()) {
    if (auto d = ini.get("plant", "domain")) {
      if (*d != "s" && *d != "z") ini.reject("plant", "domain", "must be s or z");
      if (domain && *domain != (*d == "s" ? Domain::s : Domain::z)) ini.reject("plant", "domain", "disagrees with the expression");
      domain = *d == "s" ? Domain::s : Domain::z;
    }
  }
  r.raw.domain = domain.value_or(Domain::s);

  // Delay: the flag adds to the text's exp(); the INI's delay_s applies to INI plants.
  if (auto d = flag(o.delay_s)) {
    if (!(*d >= 0.0) || !std::isfinite(*d)) fail("--delay: must be >= 0, got {}", *d);
    r.raw.delay_s += *d;
  } else if (o.plant.empty() && o.num.empty() && !builtin) {
    if (auto ini_delay = ini.number("plant", "delay_s")) {
      if (!(*ini_delay >= 0.0) || !std::isfinite(*ini_delay)) ini.reject("plant", "delay_s", "must be >= 0");
      r.raw.delay_s += *ini_delay;
    }
  }

  r.chain = o.loop || ini.has_section("loop") || builtin;
  // The plant's units: stated (--plant-units, [plant] maps), or implied by the chain (whose input is
  // rad/s per V). Physical units get the chain, converted to rad/s per V; loop units are designed on
  // as they are.
  const bool hand_plant = !o.plant.empty() || o.plant_given || !o.num.empty() || !o.den.empty();
  const bool ini_plant =
      !builtin && !hand_plant && !o.rig && ini.get("plant", "model") != std::optional<std::string>("rig");
  std::optional<PlantUnits> units;
  std::string units_where;
  if (!o.plant_units.empty()) {
    if (!hand_plant)
      fail(
          "--plant-units: states the units of --plant or --num/--den; an INI plant states its own ([plant] "
          "maps)");
    units = boardunits::parse_plant_units(o.plant_units);
    if (!units) {
      fail(
          "--plant-units: {} are units mcg-design does not know: give {} (encoder counts per sample per duty "
          "count)",
          quote(o.plant_units), k_units_choices);
    }
    units_where = "--plant-units";
  } else if (ini_plant) {
    if (const std::optional<std::string> maps = ini.get("plant", "maps")) {
      units = boardunits::parse_plant_units(*maps);
      if (!units) {
        ini.reject(
            "plant", "maps",
            fmt::format("{} are units mcg-design does not know: give v -> omega, v -> rpm, duty -> rpm, "
                        "duty -> omega or loop",
                        quote(*maps)));
      }
      units_where = origin_of(ini, "plant", "maps");
    } else if (!r.chain) {
      fail(
          "{}: the plant does not say what it maps: give maps = v -> omega (rad/s per V), v -> rpm, duty -> "
          "rpm "
          "(as mcg-fit tf writes it from the response; the loop chain is applied) or maps = loop (encoder "
          "counts "
          "per sample per duty count), or --loop",
          r.raw_where);
    }
  }
  if (units && units->loop && r.chain) {
    const std::string why = fmt::format(
        "the plant maps the loop already (counts per sample per duty count); {} would "
        "apply the loop chain twice",
        o.loop ? "--loop" : "its [loop] section");
    if (units_where == "--plant-units") fail("--plant-units: {}", why);
    ini.reject("plant", "maps", why);
  }
  if (units && !units->loop) r.chain = true;
  r.units = units.value_or(r.chain ? PlantUnits{} : PlantUnits{true});
  const std::optional<double> dt_flag = flag(o.dt_s);
  if (dt_flag && (!(*dt_flag > 0.0) || !std::isfinite(*dt_flag))) fail("--dt: must be positive, got {}", *dt_flag);
  std::optional<double> dt = dt_flag;
  for (const char* section : {"plant", "controller", "loop"}) {
    if (dt) break;
    if (auto v = ini.number(section, "dt_s")) {
      if (!(*v > 0.0) || !std::isfinite(*v)) ini.reject(section, "dt_s", "must be positive");
      dt = *v;
    }
  }
  if (!dt && r.chain) dt = Chain{}.dt_s;
  if (hand_plant && !units && !r.chain && dt && is_design_command(o.command)) {
    fail(
        "{}: the plant's units are not stated, and a sampled controller for the board depends on them: give "
        "--plant-units ({}) or --loop (rad/s per V)",
        r.raw_where, k_units_choices);
  }
  if (r.chain) {
    Chain& c = r.chain_values;
    c.pwm_full_counts = positive(ini, "loop", "pwm_full_counts", flag(o.pwm_full_counts), "--pwm-full-counts", c.pwm_full_counts);
    c.pwm_logic_v = positive(ini, "loop", "pwm_logic_v", flag(o.pwm_logic_v), "--pwm-logic-v", c.pwm_logic_v);
    c.hbridge_gain = positive(ini, "loop", "hbridge_gain", flag(o.hbridge_gain), "--hbridge-gain", c.hbridge_gain);
    c.counts_per_rev = positive(ini, "loop", "counts_per_rev", flag(o.counts_per_rev), "--counts-per-rev", c.counts_per_rev);
    c.dt_s = *dt;
  }
  if (r.raw.discrete()) {
    if (!dt) fail("{}: a z-domain plant needs its sample period (--dt, or dt_s in [plant])", r.raw_where);
    r.raw.dt_s = *dt;
    if (r.raw.delay_s > 0.0) r.raw = linsys::fold_delay(r.raw, r.raw_where);
  }
  if (!r.raw.proper()) {
    fail("{}: improper transfer function (numerator degree {} > denominator degree {})", r.raw_where,
         linsys::degree(r.raw.num), linsys::degree(r.raw.den));
  }
  const auto hold_text = ini.get("plant", "hold");
  if (hold_text && *hold_text != "zoh" && *hold_text != "none") ini.reject("plant", "hold", "must be zoh or none");
  r.hold = !r.raw.discrete() && (o.zoh || r.chain || (hold_text && *hold_text == "zoh"));
  if (r.hold && !dt) fail("--zoh: needs the sample period --dt");
  r.dt_s = dt.value_or(0.0);

  Tf g = r.raw;
  if (r.chain)
    g = linsys::scaled(g, r.chain_values.gain() * boardunits::omega_per_v_factor(r.units, r.chain_values));
  if (r.hold) g = linsys::c2d(g, r.dt_s, linsys::C2dMethod::zoh, 0.0, r.raw_where);
  r.setup.plant = g;
  r.setup.dt_s = r.dt_s;
  const std::string method = o.method.empty() ? ini.get("design", "method").value_or("tustin") : o.method;
  r.setup.method = linsys::parse_method(method, o.method.empty() ? origin_of(ini, "design", "method") : "--method");
  if (auto w = flag(o.prewarp_rad_s)) {
    if (!(*w > 0.0) || *w * r.dt_s >= k_pi) fail("--prewarp: must be in (0, pi/dt) rad/s, got {}", *w);
    r.setup.prewarp_rad_s = *w;
  }
  return r;
}

/// y[n] = −a1 y[n−1] − ... + b0 e[n] + b1 e[n−1] + ..., a normalised to a0 = 1.
void difference_coefficients(const Tf& cz, std::vector<double>& b, std::vector<double>& a) {
  const Poly den = linsys::trim(cz.den);
  const Poly num0 = linsys::trim(cz.num);
  Poly num(den.size(), 0.0);
  for (std::size_t i = 0; i < num0.size(); ++i) num[num.size() - num0.size() + i] = num0[i];
  b.clear();
  a.clear();
  for (std::size_t i = 0; i < den.size(); ++i) {
    b.push_back(num[i] / den[0]);
    a.push_back(den[i] / den[0]);
  }
  // A zero last coefficient is no term: b and a end where their last non-zero term does
  // (the board's PID: a = 1 -1 0 is a = 1 -1).
  while (b.size() > 1 && b.back() == 0.0) b.pop_back();
  while (a.size() > 1 && a.back() == 0.0) a.pop_back();
}

std::string difference_text(const std::vector<double>& b, const std::vector<double>& a) {
  std::string out = "y[n] =";
  bool first = true;
  auto term = [&](double c, const std::string& sym) {
    if (c == 0.0) return;
    const double m = std::abs(c);
    if (first) {
      out += c < 0.0 ? " -" : " ";
    } else {
      out += c < 0.0 ? " - " : " + ";
    }
    out += (m == 1.0 ? std::string() : format_number(m) + "*") + sym;
    first = false;
  };
  for (std::size_t k = 1; k < a.size(); ++k) term(-a[k], fmt::format("y[n-{}]", k));
  for (std::size_t k = 0; k < b.size(); ++k) term(b[k], k == 0 ? "e[n]" : fmt::format("e[n-{}]", k));
  if (first) out += " 0";
  return out;
}

Tf controller_from_coefficients(const std::vector<double>& b, const std::vector<double>& a, double dt_s) {
  const std::size_t n = std::max(a.size(), b.size());
  Poly num(n, 0.0);
  Poly den(n, 0.0);
  for (std::size_t i = 0; i < b.size(); ++i) num[i] = b[i];
  for (std::size_t i = 0; i < a.size(); ++i) den[i] = a[i];
  Tf c;
  c.domain = Domain::z;
  c.dt_s = dt_s;
  c.num = linsys::trim(num);
  c.den = linsys::trim(den);
  return linsys::cancel_origin(c);
}

std::string poles_text(const std::vector<Complex>& poles, bool imag) {
  std::vector<double> v;
  for (const Complex& p : poles) v.push_back(imag ? p.imag() : p.real());
  return linsys::list_text(v);
}

/// One Tf for the loop's product; a mixed loop (z controller, s plant) samples the plant
/// through a ZOH, which `note` records.
Tf single_loop(const std::vector<Tf>& factors, std::string* note) {
  Tf acc = factors.front();
  for (std::size_t i = 1; i < factors.size(); ++i) {
    Tf f = factors[i];
    if (acc.discrete() != f.discrete()) {
      if (f.discrete()) std::swap(acc, f);
      f = linsys::c2d(f, acc.dt_s, linsys::C2dMethod::zoh, 0.0, "plant");
      if (note) *note = "plant sampled through a zero-order hold for the closed loop";
    }
    acc = linsys::series(acc, f);
  }
  return acc;
}

void write_margins(Ini& ini, const std::string& section, const std::vector<Tf>& factors, double dt_s) {
  const linsys::Margins m = linsys::margins(factors);
  std::string note;
  const Tf loop = single_loop(factors, &note);
  bool padded = false;
  const auto poles = linsys::closed_loop_poles(loop, &padded);
  // With a continuous delay the verdict is K = 1's place in the stable ranges, whose boundary
  // gains are exact where the Padé poles are not (a day-long delay said "no" beside "gains in
  // (0, 1.0000005) are stable"); without one the poles decide, or refuse when rounding could.
  const auto ranges = linsys::stable_gain_ranges(loop);
  const bool stable = !loop.discrete() && loop.delay_s > 0.0
                          ? std::any_of(ranges.begin(), ranges.end(),
                                        [](const auto& g) { return g.k_low < 1.0 && 1.0 < g.k_high; })
                          : linsys::closed_loop_stable(loop);
  ini.set(section, "stable", stable ? "yes" : "no",
          padded ? "closed-loop poles with a [6/6] Pade delay" : (note.empty() ? "" : note));
  ini.set(section, "pm_deg", m.pm_deg, "phase margin nearest 0");
  ini.set(section, "wc_rad_s", m.pm_omega_rad_s, "gain crossover of that margin");
  ini.set(section, "gm", m.gm, "gain margin nearest 1, absolute");
  ini.set(section, "gm_db", 20.0 * std::log10(m.gm));
  ini.set(section, "w_gm_rad_s", m.gm_omega_rad_s, "phase crossover of that margin");
  ini.set(section, "dm_s", m.dm_s, "smallest delay margin");
  if (dt_s > 0.0) {
    ini.set(section, "dm_samples", m.dm_s / dt_s);
    ini.set(section, "ws_over_wc", 2.0 * k_pi / dt_s / m.pm_omega_rad_s, "D/A cost: sampling over crossover frequency");
  }
  double w_ms = 0.0;
  const double ms = peak_sensitivity(factors, &w_ms);
  ini.set(section, "ms", ms, "peak sensitivity max |1/(1+L)|");
  ini.set(section, "w_ms_rad_s", w_ms);
  ini.set(section, "gain_crossovers_rad_s", linsys::list_text(m.gain_crossovers_rad_s));
  ini.set(section, "phase_margins_deg", linsys::list_text(m.phase_margins_deg));
  ini.set(section, "delay_margins_s", linsys::list_text(m.delay_margins_s));
  ini.set(section, "phase_crossovers_rad_s", linsys::list_text(m.phase_crossovers_rad_s));
  std::vector<double> gm_db;
  for (double g : m.gain_margins) gm_db.push_back(20.0 * std::log10(g));
  ini.set(section, "gain_margins", linsys::list_text(m.gain_margins));
  ini.set(section, "gain_margins_db", linsys::list_text(gm_db));
  ini.set(section, "closed_loop_poles_re", poles_text(poles, false));
  ini.set(section, "closed_loop_poles_im", poles_text(poles, true));
  std::vector<double> lo;
  std::vector<double> hi;
  for (const auto& g : ranges) {
    lo.push_back(g.k_low);
    hi.push_back(g.k_high);
  }
  ini.set(section, "k_stable_low", linsys::list_text(lo), "a gain K on the loop is stable in (low, high)");
  ini.set(section, "k_stable_high", linsys::list_text(hi));
}

void echo_plant(Ini& ini, const Resolved& r) {
  ini.set("plant", "tf", linsys::tf_text(r.raw), r.raw_where);
  ini.set("plant", "domain", linsys::var_name(r.raw.domain));
  ini.set("plant", "maps", boardunits::units_text(r.units),
          r.chain ? boardunits::units_words(r.units) + "; [loop] is the chain around it"
                  : boardunits::units_words(r.units));
  if (r.raw.discrete()) ini.set("plant", "dt_s", r.raw.dt_s);
  ini.set("plant", "hold", r.hold ? "zoh" : "none", r.hold ? "the PWM holds the duty over each period" : "");
  if (r.chain) {
    const Chain& c = r.chain_values;
    ini.set("loop", "pwm_full_counts", c.pwm_full_counts, "duty counts at 100 %");
    ini.set("loop", "pwm_logic_v", c.pwm_logic_v, "V at 100 % duty");
    ini.set("loop", "hbridge_gain", c.hbridge_gain, "V/V");
    ini.set("loop", "counts_per_rev", c.counts_per_rev);
    ini.set("loop", "dt_s", c.dt_s, "s, counts summed over one period");
  }
}

Design run_design(const Options& o, const Setup& su) {
  auto need = [](double v, const char* name) {
    if (std::isnan(v)) fail("{}: required", name);
    return v;
  };
  if (o.command == "p") return design_p(su, need(o.pm_deg, "--pm"));
  if (o.command == "pi") {
    const double pm = need(o.pm_deg, "--pm");
    if (!std::isnan(o.zero_rad_s) && !std::isnan(o.wc_rad_s)) fail("--zero: give --zero or --wc, not both");
    if (!std::isnan(o.zero_rad_s)) return design_pi_zero(su, pm, o.zero_rad_s);
    if (!std::isnan(o.wc_rad_s)) return design_pi_crossover(su, pm, o.wc_rad_s);
    fail("--zero or --wc: required");
  }
  if (o.command == "pid" && o.pid_form == "board") {
    return design_pid_board(su, need(o.pm_deg, "--pm"), need(o.wc_rad_s, "--wc"), o.ti_over_td);
  }
  if (o.command == "pid") return design_pid(su, need(o.pm_deg, "--pm"), need(o.wc_rad_s, "--wc"), o.ti_over_td, o.n);
  if (o.command == "lead") return design_lead(su, need(o.pm_deg, "--pm"), need(o.wc_rad_s, "--wc"));
  if (o.command == "lag") return design_lag(su, need(o.pm_deg, "--pm"), need(o.k_dc, "--k-dc"), o.ratio);
  return tune(su, o.structure, o.limits);
}

void write_design(const Options& o, const Resolved& r, const Design& d, std::ostream& out,
                  const std::optional<RlocusResult>& rl) {
  Ini ini;
  const Setup& su = r.setup;
  ini.set("design", "kind", d.kind);
  for (const auto& [k, v] : d.params) ini.set("design", k, v);
  if (!d.cont.discrete()) {
    ini.set("design", "tf_s", linsys::tf_text(d.cont), "C(s)");
    ini.set("design", "num_s", linsys::list_text(linsys::trim(d.cont.num)));
    ini.set("design", "den_s", linsys::list_text(linsys::trim(d.cont.den)));
  }
  if (d.wc_rad_s > 0.0) ini.set("design", "wc_design_rad_s", d.wc_rad_s);
  if (rl) {
    ini.set("design", "omega_n_rad_s", rl->omega_n_rad_s);
    ini.set("design", "poles_re", poles_text(rl->poles, false));
    ini.set("design", "poles_im", poles_text(rl->poles, true));
  }
  if (o.command == "tune") {
    ini.set("design", "pm_min_deg", o.limits.pm_min_deg);
    ini.set("design", "gm_min_db", o.limits.gm_min_db);
    ini.set("design", "ms_max", o.limits.ms_max);
  }
  std::optional<Tf> cz;
  if (su.dt_s > 0.0) {
    cz = running_form(su, d.cont);
    ini.set("design", "dt_s", su.dt_s);
    if (d.cont.discrete()) {
      ini.set("design", "form", "board", "designed in z: backward differences, no derivative filter");
    } else {
      ini.set("design", "method", linsys::method_name(su.method));
    }
    if (!d.cont.discrete() && su.prewarp_rad_s > 0.0) ini.set("design", "prewarp_rad_s", su.prewarp_rad_s);
    ini.set("design", "tf_z", linsys::tf_text(*cz), "C(z)");
  }
  std::vector<double> b;
  std::vector<double> a;
  if (cz) {
    difference_coefficients(*cz, b, a);
    ini.set("design", "difference_equation", difference_text(b, a), "e in counts, y in duty counts");
  }
  write_margins(ini, "margins", loop_factors(su, d.cont), su.dt_s);
  if (cz) {
    const Chain& c = r.chain_values;
    const double full = r.chain ? c.pwm_full_counts : Chain{}.pwm_full_counts;
    const double cpr = r.chain ? c.counts_per_rev : Chain{}.counts_per_rev;
    ini.set("controller", "type", d.kind);
    ini.set("controller", "b", linsys::list_text(b), "numerator on e, b_0 first");
    ini.set("controller", "a", linsys::list_text(a), "denominator on y, a_0 first");
    ini.set("controller", "dt_s", su.dt_s, "s");
    ini.set("controller", "input_scale", cpr / 60.0 * su.dt_s, "counts per sample per rpm");
    ini.set("controller", "output", "duty_counts");
    ini.set("controller", "duty_full_scale", full, "duty counts at 100 %");
    // The board keeps its accumulator exact: the output is rounded, the state is not.
    ini.set("controller", "round_output", 0.0, "the board keeps an exact accumulator");

    boardunits::ControllerUnits units;
    units.input_scale = cpr / 60.0 * su.dt_s;
    units.duty_full_scale = full;
    units.dt_s = su.dt_s;
    if (const auto q = boardunits::board_fixed_point(b, a, units)) {
      const double lsb = std::ldexp(1.0, -q->coef_frac);
      ini.set("fixed_point", "mode", q->mode);
      ini.set("fixed_point", "coef_frac", static_cast<double>(q->coef_frac),
              fmt::format("F: c_q = round(c_board * 2^F), Q{}.{}", 15 - q->coef_frac, q->coef_frac));
      ini.set("fixed_point", "unit_factor", q->factor,
              fmt::format("c_board = c * ({}/2048) * (1000/{}) in 1/1000 duty per pulse/ms", format_number(cpr),
                          format_number(full)));
      static constexpr const char* k_names[] = {"b0", "b1", "b2"};
      for (std::size_t k = 0; k < q->regs.size(); ++k) {
        const double v = static_cast<double>(q->regs[k]);
        const std::string note = fmt::format("{} /1000 per pulse/ms", format_number(v * lsb));
        ini.set("fixed_point", q->mode == "p" ? std::string("kp") : std::string(k_names[k]), v, note);
      }
      ini.set("fixed_point", "acc_max", q->acc_max, "worst case 1000 * 2^(F+8) + 8191 * sum |c_q| <= 2^31 - 1");
      const Tf cq = controller_from_coefficients(q->b, q->a, su.dt_s);
      write_margins(ini, "margins_quantised", {cq, su.plant}, su.dt_s);
    }
  }
  echo_plant(ini, r);
  ini.write(out);
}

/// The controller for analysis commands, as it runs: --controller text or [controller] b/a.
std::optional<Tf> analysis_controller(const Options& o, const Resolved& r) {
  if (!o.controller.empty()) {
    linsys::ParsedTf p = linsys::parse_tf(o.controller, "--controller");
    Tf c = p.tf;
    c.domain = p.domain.value_or(Domain::s);
    if (!c.proper()) {
      fail("--controller: improper transfer function (numerator degree {} > denominator degree {})",
           linsys::degree(c.num), linsys::degree(c.den));
    }
    if (c.discrete()) {
      if (!(r.dt_s > 0.0)) fail("--controller: a z-domain controller needs --dt");
      c.dt_s = r.dt_s;
      return linsys::fold_delay(c, "--controller");
    }
    if (r.dt_s > 0.0) return running_form(r.setup, c);
    if (r.setup.plant.discrete()) fail("--controller: a continuous controller on a sampled plant needs --dt");
    return c;
  }
  if (const auto c = boardunits::controller_from_ini(r.ini)) return controller_from_coefficients(c->b, c->a, c->dt_s);
  return std::nullopt;
}

std::vector<Tf> analysis_factors(const Options& o, const Resolved& r) {
  const std::optional<Tf> c = analysis_controller(o, r);
  if (!c) return {r.setup.plant};
  return {*c, r.setup.plant};
}

void plot_range(const Options& o, const std::vector<Tf>& factors, double& lo, double& hi) {
  lo = INFINITY;
  hi = 0.0;
  double dt = 0.0;
  for (const Tf& f : factors) {
    const linsys::FreqEval fe(f);
    for (double c : fe.corner_frequencies()) {
      lo = std::min(lo, c / 100.0);
      hi = std::max(hi, c * 100.0);
    }
    if (f.discrete()) dt = dt == 0.0 ? f.dt_s : std::min(dt, f.dt_s);
  }
  if (!std::isfinite(lo)) {
    lo = 0.01;
    hi = 1e4;
  }
  if (dt > 0.0) hi = std::min(hi, k_pi / dt);
  if (lo >= hi) lo = hi / 1e4;
  if (!std::isnan(o.f_min_hz)) lo = 2.0 * k_pi * o.f_min_hz;
  if (!std::isnan(o.f_max_hz)) hi = 2.0 * k_pi * o.f_max_hz;
  if (!(lo > 0.0) || !(hi > lo)) fail("--f-min/--f-max: need 0 < f-min < f-max");
}

void write_frequency(const Options& o, const std::vector<Tf>& factors, std::ostream& out, bool nyquist) {
  double lo = 0.0;
  double hi = 0.0;
  plot_range(o, factors, lo, hi);
  const int points = o.points > 0 ? o.points : 500;
  const linsys::LoopEval le(factors);
  table::Writer w(out);
  w.meta("source", std::string("mcg-design ") + k_version);
  std::string loop;
  for (const Tf& f : factors) loop += (loop.empty() ? "" : " * ") + linsys::tf_text(f);
  w.meta("loop", loop);
  if (nyquist) {
    w.header({"f_hz", "re", "im"});
  } else {
    w.header({"f_hz", "mag_db", "phase_deg"});
  }
  for (double x : linsys::log_grid(lo, hi, std::max(points, 2))) {
    if (nyquist) {
      const Complex v = le.value(x);
      w.row({x / (2.0 * k_pi), v.real(), v.imag()});
    } else {
      w.row({x / (2.0 * k_pi), le.log_mag(x) * 20.0 / std::log(10.0), le.phase_rad(x) * 180.0 / k_pi});
    }
  }
  w.finish();
}

void write_rlocus(const Options& o, const std::vector<Tf>& factors, std::ostream& out) {
  std::string note;
  Tf loop = single_loop(factors, &note);
  if (loop.discrete()) loop = linsys::fold_delay(loop, "loop");
  if (!loop.discrete() && loop.delay_s > 0.0) {
    loop.delay_s = 0.0;
    loop = linsys::series(loop, linsys::pade(single_loop(factors, nullptr).delay_s, 6));
    note = "delay as its [6/6] Pade approximant";
  }
  const auto ranges = linsys::stable_gain_ranges(loop);
  const auto bounds = linsys::boundary_gains(loop);
  double k_max = o.k_max;
  if (std::isnan(k_max)) k_max = bounds.empty() ? 100.0 : 3.0 * bounds.back();
  if (!(k_max > 0.0)) fail("--k-max: must be positive");
  const int points = o.points > 0 ? o.points : 400;
  std::vector<double> ks{0.0};
  for (double k : linsys::log_grid(k_max * 1e-4, k_max, std::max(points, 2))) ks.push_back(k);
  for (double k : bounds) {
    if (k <= k_max) ks.push_back(k);
  }
  std::sort(ks.begin(), ks.end());
  table::Writer w(out);
  w.meta("source", std::string("mcg-design ") + k_version);
  w.meta("loop", linsys::tf_text(loop));
  if (!note.empty()) w.meta("note", note);
  for (const auto& g : ranges) w.meta("k_stable", fmt::format("{} .. {}", format_number(g.k_low), format_number(g.k_high)));
  w.meta("boundary", loop.discrete() ? "unit circle" : "imaginary axis");
  // n − m branches leave for infinity along rays from the centroid (Σp − Σz)/(n − m) at
  // (2q + 1)·180/(n − m) degrees.
  const std::vector<Complex> poles = linsys::roots(linsys::trim(loop.den));
  const std::vector<Complex> zeros = linsys::roots(linsys::trim(loop.num));
  if (poles.size() > zeros.size()) {
    const double excess = static_cast<double>(poles.size() - zeros.size());
    double centre = 0.0;
    for (const Complex& p : poles) centre += p.real();
    for (const Complex& z : zeros) centre -= z.real();
    std::string angles;
    for (std::size_t q = 0; q < poles.size() - zeros.size(); ++q) {
      angles += (angles.empty() ? "" : " ") + format_number((2.0 * static_cast<double>(q) + 1.0) * 180.0 / excess);
    }
    w.meta("asymptote_centre", format_number(centre / excess));
    w.meta("asymptote_angles_deg", angles);
  }
  w.header({"k", "branch", "re", "im"});
  std::vector<Complex> prev;
  for (double k : ks) {
    std::vector<Complex> p = linsys::roots(linsys::add(loop.den, linsys::scale(loop.num, k)));
    if (!prev.empty() && p.size() == prev.size()) {
      // Keep branches continuous: each previous pole takes its nearest new one.
      std::vector<Complex> ordered(prev.size());
      std::vector<bool> used(p.size(), false);
      for (std::size_t i = 0; i < prev.size(); ++i) {
        std::size_t best = 0;
        double best_d = INFINITY;
        for (std::size_t j = 0; j < p.size(); ++j) {
          if (!used[j] && std::abs(p[j] - prev[i]) < best_d) {
            best_d = std::abs(p[j] - prev[i]);
            best = j;
          }
        }
        used[best] = true;
        ordered[i] = p[best];
      }
      p = ordered;
    }
    for (std::size_t i = 0; i < p.size(); ++i) w.row({k, static_cast<double>(i + 1), p[i].real(), p[i].imag()});
    prev = p;
  }
  w.finish();
}

linsys::StepLimits step_limits(const Options& o) {
  linsys::StepLimits lim;
  if (!o.rise_pct.empty()) {
    const std::vector<double> v = parse_list(o.rise_pct, "--rise");
    if (v.size() != 2 || !(v[0] >= 0.0 && v[0] < v[1] && v[1] <= 100.0)) {
      fail("--rise: expected LOW,HIGH with 0 <= LOW < HIGH <= 100 (percent), got {}", quote(o.rise_pct));
    }
    lim.rise_low = v[0] / 100.0;
    lim.rise_high = v[1] / 100.0;
  }
  if (!std::isnan(o.settling_pct)) lim.settling = o.settling_pct / 100.0;
  return lim;
}

void write_step(const Options& o, const Resolved& r, std::ostream& out) {
  const std::optional<Tf> c = analysis_controller(o, r);
  Tf plant = r.setup.plant;
  std::string note;
  if (c && c->discrete() && !plant.discrete()) {
    plant = linsys::c2d(plant, c->dt_s, linsys::C2dMethod::zoh, 0.0, r.raw_where);
    note = "plant sampled through a zero-order hold";
  }
  const double t_end = std::isnan(o.t_end_s) ? 0.0 : o.t_end_s;
  if (!std::isnan(o.t_end_s) && !(o.t_end_s > 0.0)) fail("--t-end: must be positive");
  const linsys::StepLimits lim = step_limits(o);
  const linsys::StepResponse s =
      linsys::step_response(plant, c, t_end, o.points > 0 ? o.points : 2000, o.open_loop);
  const linsys::StepMetrics m = linsys::step_info(s, 1.0, lim);
  std::vector<std::pair<std::string, double>> metrics{
      {"final_value", m.final_value},   {"rise_time_s", m.rise_time_s},       {"transient_time_s", m.transient_time_s},
      {"settling_time_s", m.settling_time_s}, {"settling_min", m.settling_min}, {"settling_max", m.settling_max},
      {"overshoot_pct", m.overshoot_pct}, {"undershoot_pct", m.undershoot_pct}, {"peak", m.peak},
      {"peak_time_s", m.peak_time_s}};
  if (!o.open_loop) metrics.emplace_back("steady_state_error", m.steady_state_error);
  const std::string loop_kind = o.open_loop ? "open" : "closed";
  const std::string levels = fmt::format("rise {}-{} %, settling {} %", format_number(100.0 * lim.rise_low),
                                         format_number(100.0 * lim.rise_high), format_number(100.0 * lim.settling));
  const char* timing = s.sampled ? "at the sample instants" : "interpolated between samples";
  if (o.metrics) {
    Ini ini;
    ini.set("step", "loop", loop_kind);
    for (const auto& [k, v] : metrics) ini.set("step", k, v);
    ini.set("step", "levels", levels);
    ini.set("step", "times", timing);
    if (!note.empty()) ini.set("step", "note", note);
    if (!s.note.empty()) ini.set("step", "simulation", s.note);
    ini.write(out);
    return;
  }
  table::Writer w(out);
  w.meta("source", std::string("mcg-design ") + k_version);
  w.meta("loop", linsys::tf_text(c ? linsys::series(*c, plant) : plant));
  w.meta("step", loop_kind);
  if (!note.empty()) w.meta("note", note);
  if (!s.note.empty()) w.meta("simulation", s.note);
  for (const auto& [k, v] : metrics) w.meta(k, format_number(v));
  w.meta("levels", levels);
  w.meta("times", timing);
  if (o.open_loop) {
    w.header({"t", "r", "y", "u"});
    for (std::size_t k = 0; k < s.t_s.size(); ++k) w.row({s.t_s[k], 1.0, s.y[k], s.u[k]});
  } else {
    w.header({"t", "r", "y", "e", "u"});
    for (std::size_t k = 0; k < s.t_s.size(); ++k) w.row({s.t_s[k], 1.0, s.y[k], 1.0 - s.y[k], s.u[k]});
  }
  w.finish();
}

void write_c2d(const Options& o, const Resolved& r, std::ostream& out) {
  if (r.raw.discrete()) fail("{}: the plant is already discrete", r.raw_where);
  if (!(r.dt_s > 0.0)) fail("--dt: required");
  const linsys::C2dMethod method =
      o.method.empty() ? linsys::C2dMethod::zoh : linsys::parse_method(o.method, "--method");
  const double prewarp = std::isnan(o.prewarp_rad_s) ? 0.0 : o.prewarp_rad_s;
  Tf g = r.raw;
  if (r.chain)
    g = linsys::scaled(g, r.chain_values.gain() * boardunits::omega_per_v_factor(r.units, r.chain_values));
  const Tf h = linsys::c2d(g, r.dt_s, method, prewarp, r.raw_where);
  Ini ini;
  ini.set("plant", "tf", linsys::tf_text(h), fmt::format("{} of {}", linsys::method_name(method), linsys::tf_text(g)));
  ini.set("plant", "domain", "z");
  ini.set("plant", "dt_s", r.dt_s);
  ini.set("plant", "num", linsys::list_text(linsys::trim(h.num)));
  ini.set("plant", "den", linsys::list_text(linsys::trim(h.den)));
  ini.set("plant", "method", linsys::method_name(method));
  if (prewarp > 0.0) ini.set("plant", "prewarp_rad_s", prewarp);
  ini.write(out);
}

void write_loop(const Resolved& r, std::ostream& out) {
  const Chain& c = r.chain_values;
  Ini ini;
  ini.set("loop", "pwm_full_counts", c.pwm_full_counts, "duty counts at 100 %");
  ini.set("loop", "pwm_logic_v", c.pwm_logic_v, "V at 100 % duty");
  ini.set("loop", "pwm_v_per_count", c.pwm_v_per_count(), "PWM gain, V per duty count (report: .00542)");
  ini.set("loop", "hbridge_gain", c.hbridge_gain, "V/V (report: 4 = 20 V / 5 V)");
  ini.set("loop", "counts_per_rev", c.counts_per_rev);
  ini.set("loop", "encoder_counts_per_rad", c.counts_per_rad(), "report: 81.5");
  ini.set("loop", "dt_s", c.dt_s, "software conversion: counts summed over one period");
  ini.set("loop", "chain_gain", c.gain(), "counts per sample per (rad/s) per duty count, without the plant");
  const double g0 = r.raw.dc_gain();
  ini.set("loop", "plant_dc_gain", g0, "rad/s per V");
  ini.set("loop", "forward_gain", c.pwm_v_per_count() * c.hbridge_gain * g0, "rad/s per duty count (report: 0.3589)");
  ini.set("loop", "feedback_gain", c.counts_per_rad() * c.dt_s, "counts per sample per rad/s (report: 81.5*.001)");
  ini.set("loop", "loop_dc_gain", c.gain() * g0, "report's third-order fit: 0.0146");
  Tf cont = linsys::scaled(r.raw, c.gain());
  ini.set("loop", "tf_s", linsys::tf_text(cont), "chain x plant, without the hold");
  const Tf& z = r.setup.plant;
  ini.set("loop", "tf_z", linsys::tf_text(z), "with the PWM as a zero-order hold");
  ini.set("loop", "num_z", linsys::list_text(linsys::trim(z.num)));
  ini.set("loop", "den_z", linsys::list_text(linsys::trim(z.den)));
  write_margins(ini, "margins", {z}, r.dt_s);
  ini.write(out);
}

}  // namespace

void run(const Options& o, std::ostream& out) {
  Options opts = o;
  if (opts.command == "loop") opts.loop = true;
  const Resolved r = resolve(opts);
  const std::string& cmd = opts.command;
  if (cmd == "margins") {
    Ini ini;
    const std::vector<Tf> f = analysis_factors(opts, r);
    for (const Tf& x : f) {
      if (!x.proper()) fail("margins need a proper loop");
    }
    write_margins(ini, "margins", f, r.dt_s);
    ini.write(out);
    return;
  }
  if (cmd == "bode" || cmd == "nyquist") return write_frequency(opts, analysis_factors(opts, r), out, cmd == "nyquist");
  if (cmd == "rlocus") return write_rlocus(opts, analysis_factors(opts, r), out);
  if (cmd == "step") return write_step(opts, r, out);
  if (cmd == "c2d") return write_c2d(opts, r, out);
  if (cmd == "loop") return write_loop(r, out);
  if (cmd == "rlocus-design") {
    if (std::isnan(opts.zeta)) fail("--zeta: required");
    const RlocusResult rl = design_rlocus(r.setup, opts.zeta);
    return write_design(opts, r, rl.design, out, rl);
  }
  const Design d = run_design(opts, r.setup);
  write_design(opts, r, d, out, std::nullopt);
}

}  // namespace mcg::design
