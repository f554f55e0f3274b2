// mcg-sweep: excitation tables for mcg-sim or the board, and frequency responses of tables.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/diagnostics.hpp"

namespace mcg::table {
struct Table;
}

namespace mcg::signal {

enum class Generator { step, staircase, chirp, multisine, prbs, aprbs };

/// Options of the generator subcommands. Each generator writes
///   t, <column> = bias + x(t), clutch, r_load
/// at t = k dt for k = 0 .. floor(duration / dt) - 1, with metadata describing the excitation.
struct GeneratorOptions {
  std::string column = "v";  ///< v (V), duty (1) or rpm_cmd (rev/min)
  double bias = 0.0;         ///< added to every sample, in the column's unit
  double dt_s = 0.001;
  std::optional<double> duration_s;  ///< default per generator (see default_duration_s)
  double clutch = 2.0;               ///< 0, 1 or 2 until the first --clutch-schedule change (2, as mcg-sim)
  std::string clutch_schedule;       ///< "1@0,2@1.5"
  double r_load_ohm = std::numeric_limits<double>::infinity();
  std::string r_load_schedule;  ///< "inf@0,5.6@2"
  std::uint64_t seed = 1;

  double level = 1.0;  ///< step: level after --at
  double at_s = 0.0;
  std::string then;  ///< step: further steps "6@0.5,0@0.8"

  double amp = 1.0;           ///< staircase, chirp, multisine (peak), prbs, aprbs amplitude
  int steps = 5;              ///< staircase: levels per side
  double hold_s = 1.0;        ///< staircase: time on each level
  double settle_s = 2.0;      ///< chirp: bias held this long before and after the sweep
  double f0_hz = 0.5;         ///< chirp, multisine band
  double f1_hz = 200.0;
  std::string spacing;        ///< "linear" or "log"; default linear (chirp), log (multisine)
  int lines = 20;             ///< multisine: number of lines
  std::optional<double> period_s;  ///< multisine period; default 1/f0
  std::string phases = "schroeder";  ///< multisine: schroeder, random (--seed), zero
  int order = 10;             ///< prbs/aprbs register length
  std::optional<double> clock_s;  ///< prbs/aprbs bit time; default dt
  std::string tool;               ///< the tool's name, for the table's source metadata
};

/// Writes the excitation table. Throws mcg::Error for inconsistent options (a band above
/// Nyquist, a clock that is not a whole number of samples, a schedule out of order, ...).
void generate(Generator generator, const GeneratorOptions& options, std::ostream& out);

enum class BodeMethod { automatic, welch, lines };

/// Options of `mcg-sweep bode`.
struct BodeOptions {
  std::string input = "-";
  std::string in_column;   ///< empty: the board's `# excitation:` line's column, else v
  std::string out_column;  ///< empty: omega, else rpm when the table has rpm and no omega
  BodeMethod method = BodeMethod::automatic;
  std::size_t segment = 0;  ///< Welch segment in samples; 0 = default_segment()
  double overlap = 0.5;
  std::string lines_hz;  ///< multisine lines "1,2,5" (Hz); default from the metadata
  std::optional<double> period_s;
  std::optional<double> f_min_hz;
  std::optional<double> f_max_hz;
  std::string tool;  ///< the tool's name, for the response's source metadata
};

/// Reads the table, estimates the response from in_column to out_column and writes
/// f_hz, mag_db, phase_deg, coherence. Uneven sampling is resampled by linear interpolation
/// with one warning on `diag`; leading rows not measured yet are skipped with a note.
void bode(const BodeOptions& options, std::ostream& out, Diagnostics& diag);
/// bode() of a table already read (options.input unused).
void bode(const table::Table& table, const BodeOptions& options, std::ostream& out, Diagnostics& diag);

}  // namespace mcg::signal
