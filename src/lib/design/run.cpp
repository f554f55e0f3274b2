// The services of mcg-design's commands: the plant, the chain and the controller resolved from
// the options and INI files; a design and the margins written as INI.
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
using Chain = boardunits::LoopChain;

namespace {

/// The report's identified plant, ω_internal/V_in in rad/s per V (Figure 16-1).
constexpr const char* k_report_plant = "16.557/((s/65+1)*(s/950+1))";

std::optional<double> flag(double v) { return std::isnan(v) ? std::nullopt : std::optional<double>(v); }

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

/// The plant as given (--plant, --num/--den, the linearised rig, [plant] tf or num/den, or the
/// report's) and its domain, into r.raw and r.raw_where. Returns true for the built-in plant.
bool read_plant(const PlantOptions& o, ResolvedPlant& r) {
  const Ini& ini = r.ini;
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
  return builtin;
}

/// The plant's units: stated (--plant-units, [plant] maps), or implied by the chain (whose input is
/// rad/s per V). Physical units get the chain, converted to rad/s per V; loop units are designed on
/// as they are.
/// A plant mapping the loop already refuses a second chain.
std::optional<PlantUnits> stated_units(const PlantOptions& o, const ResolvedPlant& r, bool builtin,
                                       bool hand_plant) {
  const Ini& ini = r.ini;
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
  return units;
}

}  // namespace

std::vector<double> parse_list(const std::string& text, const std::string& where) {
  std::vector<double> out;
  std::string token;
  std::string normalised = text;
  std::replace(normalised.begin(), normalised.end(), ',', ' ');
  std::istringstream words(normalised);
  while (words >> token) {
    double v = 0.0;
    if (!table::parse_number(token, v) || !std::isfinite(v))
      fail("{}: invalid number {}", where, quote(token));
    out.push_back(v);
  }
  if (out.empty()) fail("{}: empty coefficient list", where);
  return out;
}

ResolvedPlant resolve(const PlantOptions& o, bool designs) {
  ResolvedPlant r;
  r.ini = Ini::load_all(o.configs);
  const Ini& ini = r.ini;
  check_plant_names(ini);
  const bool builtin = read_plant(o, r);

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
  const bool hand_plant = !o.plant.empty() || o.plant_given || !o.num.empty() || !o.den.empty();
  const std::optional<PlantUnits> units = stated_units(o, r, builtin, hand_plant);
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
  if (hand_plant && !units && !r.chain && dt && designs) {
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

namespace {

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

void echo_plant(Ini& ini, const ResolvedPlant& r) {
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

}  // namespace

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

void write_design(const ResolvedPlant& r, const Design& d, std::ostream& out,
                  const std::optional<RlocusResult>& rl, const TuneLimits* limits) {
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
  if (limits != nullptr) {
    ini.set("design", "pm_min_deg", limits->pm_min_deg);
    ini.set("design", "gm_min_db", limits->gm_min_db);
    ini.set("design", "ms_max", limits->ms_max);
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
    boardunits::Controller controller;
    controller.type = d.kind;
    controller.b = b;
    controller.a = a;
    controller.dt_s = su.dt_s;
    controller.input_scale = cpr / 60.0 * su.dt_s;
    controller.duty_full_scale = full;
    // The board keeps its accumulator exact: the output is rounded, the state is not.
    controller.round_output = false;
    boardunits::controller_to_ini(controller, ini);
    if (const auto q = boardunits::board_fixed_point(b, a, controller.units())) {
      boardunits::fixed_point_to_ini(*q, cpr, full, ini);
      const Tf cq = controller_from_coefficients(q->b, q->a, su.dt_s);
      write_margins(ini, "margins_quantised", {cq, su.plant}, su.dt_s);
    }
  }
  echo_plant(ini, r);
  ini.write(out);
}

std::optional<Tf> analysis_controller(const std::string& controller, const ResolvedPlant& r) {
  if (!controller.empty()) {
    linsys::ParsedTf p = linsys::parse_tf(controller, "--controller");
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

std::vector<Tf> analysis_factors(const std::string& controller, const ResolvedPlant& r) {
  const std::optional<Tf> c = analysis_controller(controller, r);
  if (!c) return {r.setup.plant};
  return {*c, r.setup.plant};
}

}  // namespace mcg::design
