// CSV tables per the data contract (man/mcg-csv.5): metadata, header, rows of numbers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/line_reader.hpp"

namespace mcg::table {

/// The widest header a table may have; a wider one is a one-line error (mcg-csv(5), LIMITS).
/// Lines are at most k_max_line_bytes (common/line_reader.hpp).
inline constexpr std::size_t k_max_columns = 10000;

/// The "# key: value" lines that precede the header, kept in order and passed on.
class Metadata {
 public:
  using Entry = std::pair<std::string, std::string>;

  /// Value of the first entry named `key`, if any.
  std::optional<std::string> get(std::string_view key) const;
  /// Replaces the value of `key` if present, else appends it.
  void set(std::string_view key, std::string_view value);
  /// Removes every entry named `key`.
  void erase(std::string_view key);
  const std::vector<Entry>& entries() const { return m_entries; }
  bool empty() const { return m_entries.empty(); }
  /// Notes that `key` was read from line `line` of its source (the Reader does).
  void note_line(std::string_view key, std::size_t line);
  /// "<source>:<line>" of `key` when read from a source, else "<source>" (for messages).
  std::string where(std::string_view source, std::string_view key) const;

 private:
  struct Hash {
    using is_transparent = void;
    std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
  };
  std::vector<Entry> m_entries;
  /// Position of each key in m_entries (keys are unique there): a lookup costs the same for
  /// the 100000th line of metadata as for the first.
  std::unordered_map<std::string, std::size_t, Hash, std::equal_to<>> m_index;
  /// The line each key was read from (note_line()), for where().
  std::unordered_map<std::string, std::size_t, Hash, std::equal_to<>> m_lines;
};

/// Parses one field: decimal or exponent form, inf, -inf, nan (any case); an empty field
/// (after trimming blanks) is "not measured" and reads as NaN. Returns false if malformed.
bool parse_number(std::string_view text, double& value);

/// Streaming reader: metadata and header on construction, then one row per next(). It reads
/// what the input has (a pipe's rows are handed on as they come, read(2) as it were), in time
/// linear in the input. Every error is an mcg::Error naming the source, the line and, for a
/// field, the column and the text: "<stdin>:12: column 'rpm': invalid number '3a'".
class Reader {
 public:
  Reader(std::istream& in, std::string source);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const Metadata& metadata() const { return m_meta; }
  const std::vector<std::string>& columns() const { return m_columns; }
  const std::string& source() const { return m_lines.source(); }
  std::optional<std::size_t> find(std::string_view name) const;
  /// Index of column `name`; throws "<src>: missing column 'v' (has: t,rpm)".
  std::size_t require(std::string_view name) const;

  /// Reads the next row; false at the end of input.
  bool next();
  const std::vector<double>& row() const { return m_row; }
  double operator[](std::size_t column) const { return m_row[column]; }
  /// 1-based line number of the current row (or of the header before the first next()).
  std::size_t line() const { return m_lines.line(); }
  /// The input not read yet as whole lines, at least `bytes` of them unless the input ends
  /// first, into `out` (its storage reused); false at the end, or before a line longer than
  /// k_max_line_bytes (then overlong()). read() parses them on every core and counts their
  /// lines itself: line() does not move.
  bool take_lines(std::string& out, std::size_t bytes) { return m_lines.take(out, bytes); }
  bool overlong() const { return m_lines.overlong(); }

 private:
  LineReader m_lines;
  Metadata m_meta;
  std::vector<std::string> m_columns;
  std::vector<double> m_row;
};

/// A whole table in memory, column-major.
struct Table {
  std::string source;
  Metadata meta;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  /// Line number of row 0 in the source (for error messages about rows).
  std::size_t first_line = 1;

  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  std::optional<std::size_t> find(std::string_view name) const;
  bool has(std::string_view name) const { return find(name).has_value(); }
  /// Column `name`; throws "<src>: missing column 'name' (has: ...)".
  const std::vector<double>& col(std::string_view name) const;
  std::vector<double>& col(std::string_view name);
  /// Adds (or replaces) a column; its length must equal rows() unless the table is empty.
  std::vector<double>& set(std::string_view name, std::vector<double> values);
  std::size_t line_of(std::size_t row) const { return first_line + row; }
};

/// Reads a whole table. Throws on an input with no header line. A large input is parsed on
/// every core, with the same errors (the first bad line of the input) as the Reader's.
Table read(std::istream& in, std::string source);
/// Reads the file at `path` ("-" = stdin).
Table read_path(const std::string& path);

/// Throws unless column `name` is finite and strictly increasing, naming the first bad line.
void require_increasing(const Table& table, std::string_view name);
/// Throws unless every value of column `name` is finite, naming the first bad line.
void require_finite(const Table& table, std::string_view name);

/// The rows at the start of the table in which one of `names` is unmeasured (NaN), such as a
/// capture's first rows while the board's speed estimator fills its window, and which of the
/// columns were; a table with no measured row throws, naming the columns.
struct LeadingUnmeasured {
  std::size_t rows = 0;
  std::vector<std::string> columns;
};
LeadingUnmeasured leading_unmeasured(const Table& table, const std::vector<std::string>& names);
/// The table from row `first` on; its lines keep their numbers in messages.
Table drop_leading(const Table& table, std::size_t first);
/// One line for a note on what was skipped: "<src>: skipped the first 5 rows (lines 9-13): 'rpm' not
/// measured yet (the speed estimator's warm-up)".
std::string skipped_note(const Table& table, const LeadingUnmeasured& skipped);

/// Buffered writer. Numbers use `digits` significant digits (default 10), inf/-inf/nan
/// as the contract spells them. Writes in large blocks; a closed pipe throws
/// mcg::BrokenPipe, any other failure mcg::Error.
class Writer {
 public:
  explicit Writer(std::ostream& out, std::string dest = "<stdout>");
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void metadata(const Metadata& meta);
  void meta(std::string_view key, std::string_view value);
  void header(const std::vector<std::string>& names);
  /// Significant digits for one column (after header()), 1..17.
  void set_digits(std::size_t column, int digits);
  void set_digits(std::string_view name, int digits);
  void row(std::span<const double> values);
  void row(std::initializer_list<double> values) {
    row(std::span<const double>(values.begin(), values.size()));
  }
  /// A row of cells already written as text (a report's names and numbers side by side), each as
  /// it is: one line and no comma (a comma in a cell would shift every column after it).
  void text_row(const std::vector<std::string>& cells);
  /// Flushes to the stream and checks it; call before the end of a successful run.
  void finish();

 private:
  void flush_if_full();
  void flush();
  /// Where the next `bytes` bytes go (the buffer grown if it must be; written rows are never
  /// cleared, so no row pays for filling its room first).
  char* room(std::size_t bytes);
  void append(std::string_view text);

  std::ostream& m_out;
  std::string m_dest;
  std::string m_buffer;  ///< its first m_used bytes wait to be written
  std::size_t m_used = 0;
  /// A column's last number and its text: a value that repeats (an input passed on, a shaft
  /// at rest) is copied, not formatted again.
  struct Cell {
    std::uint64_t bits = 0;
    std::size_t size = 0;  ///< 0: nothing written yet with the column's digits
    std::array<char, 32> text{};
  };

  std::vector<std::string> m_names;
  std::vector<int> m_digits;
  std::vector<Cell> m_cells;
};

/// Writes a whole table (metadata, header, rows).
void write(std::ostream& out, const Table& table, int digits = 10);

}  // namespace mcg::table
