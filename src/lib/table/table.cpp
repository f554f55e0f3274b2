// CSV reader and writer per the data contract.
#include "table/table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <istream>
#include <limits>
#include <ostream>
#include <unordered_set>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/text.hpp"
#include "common/tool.hpp"

namespace mcg::table {

namespace {

constexpr std::size_t k_write_block = 1 << 18;
constexpr int k_default_digits = 10;

/// Exact powers of ten (every one up to 1e22 is a double); format_general scales by up to 1e18
/// (15 digits of a value from 1e-4).
constexpr std::array<double, 23> k_pow10{1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                         1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                         1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

constexpr std::string_view k_digit_pairs =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839404142434445464748495051"
    "525354555657585960616263646566676869707172737475767778798081828384858687888990919293949596979899";

/// Writes the `count` lowest decimal digits of v, zero-padded, so that they end at `end`.
void put_digits(char* end, std::uint32_t v, int count) {
  for (; count >= 2; count -= 2) {  // two digits a division
    const std::size_t pair = v % 100U;
    v /= 100U;
    end -= 2;
    std::copy_n(k_digit_pairs.data() + 2 * pair, 2, end);
  }
  if (count == 1) end[-1] = static_cast<char>('0' + v);
}

/// Writes the `count` lowest decimal digits of n (count <= 17), zero-padded, ending at `end`.
void put_digits64(char* end, std::uint64_t n, int count) {
  for (; count > 8; count -= 8, end -= 8, n /= 100000000U)
    put_digits(end, static_cast<std::uint32_t>(n % 100000000U), 8);
  put_digits(end, static_cast<std::uint32_t>(n), count);
}

/// Writes v (finite, not zero) as printf's "%.{digits}g" (general, trailing zeros dropped), the
/// same characters as std::to_chars(general, digits). Values printed in fixed notation with at
/// most 15 digits take a fast path: v scaled by an exact power of ten to a `digits`-digit integer,
/// rounded, and printed. The scaling rounds once, and rounding is monotone, so the scaled value
/// lies on the same side of each half as the exact one, or on the half itself (below 2^52 every
/// half is a double): that tie, and everything else, goes to Ryu printf (std::to_chars). Twice as
/// fast on a simulator's columns.
char* format_general(char* p, double v, int digits) {
  const double a = std::fabs(v);
  // An integer of at most `digits` digits prints as itself (a clutch state, a voltage level); below
  // 1e9 the conversion to 32 bits is exact for it and truncates anything else.
  if (a < 1e9 && a < k_pow10[static_cast<std::size_t>(digits)] &&
      static_cast<double>(static_cast<std::uint32_t>(a)) == a) {
    auto n = static_cast<std::uint32_t>(a);
    int count = 1;
    while (count < 9 && n >= static_cast<std::uint32_t>(k_pow10[static_cast<std::size_t>(count)])) ++count;
    if (v < 0) *p++ = '-';
    put_digits(p + count, n, count);
    return p + count;
  }
  if (digits <= 15 && a >= 1e-4 && a < 1e15) {
    // x = floor(log10(a)), maybe one off at a power of ten: the range checks below catch that.
    // From the binary exponent e (2^e <= a < 2^(e+1)): floor(e log10(2)) is x or x - 1.
    const int e = static_cast<int>((std::bit_cast<std::uint64_t>(a) >> 52) & 0x7ffU) - 1023;
    int x = (e * 1233) >> 12;
    if (x >= 0) {
      if (x < 14 && a >= k_pow10[static_cast<std::size_t>(x + 1)]) ++x;
    } else {
      if (x < -4) x = -4;
      if (x < -1 && a * k_pow10[static_cast<std::size_t>(-x - 1)] >= 1.0) ++x;
    }
    const int k = digits - 1 - x;
    const double s =
        k >= 0 ? a * k_pow10[static_cast<std::size_t>(k)] : a / k_pow10[static_cast<std::size_t>(-k)];
    // s < 10^15 < 2^53: the conversion truncates, the floor of a positive s, and is exact.
    const auto whole = static_cast<std::uint64_t>(s);
    const double frac = s - static_cast<double>(whole);
    if (frac != 0.5) {
      auto n = whole + (frac > 0.5 ? 1U : 0U);
      const auto top = static_cast<std::uint64_t>(k_pow10[static_cast<std::size_t>(digits)]);
      if (n == top) {  // 9.99...95 rounded up to the next power of ten
        n /= 10;
        ++x;
      }
      if (n >= top / 10 && n < top && x < digits && x >= -4) {
        // The digits without their trailing zeros (n > 0), printed in place.
        int nd = digits;
        while (n % 10U == 0) {
          n /= 10U;
          --nd;
        }
        if (v < 0) *p++ = '-';
        if (x < 0) {
          *p++ = '0';
          *p++ = '.';
          p = std::fill_n(p, -x - 1, '0');
          put_digits64(p + nd, n, nd);
          return p + nd;
        }
        if (nd <= x + 1) {
          put_digits64(p + nd, n, nd);
          return std::fill_n(p + nd, x + 1 - nd, '0');
        }
        // One place to the right, then the integer part moved back over the point's place.
        put_digits64(p + 1 + nd, n, nd);
        for (int d = 0; d <= x; ++d) p[d] = p[d + 1];
        p[x + 1] = '.';
        return p + 1 + nd;
      }
    }
  }
  return std::to_chars(p, p + 25, v, std::chars_format::general, digits).ptr;
}

/// Shortens a field for an error message so one line stays one readable line.
/// The header's names for a message, each through printable(); a long header is cut after
/// 16 names with the count of the rest.
std::string column_list(const std::vector<std::string>& names) {
  constexpr std::size_t k_max_names = 16;
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < k_max_names; ++i) {
    if (!out.empty()) out += ',';
    out += printable(names[i]);
  }
  if (names.size() > k_max_names) out += fmt::format(",... ({} columns)", names.size());
  return out;
}

}  // namespace

std::optional<std::string> Metadata::get(std::string_view key) const {
  const auto it = m_index.find(key);
  if (it == m_index.end()) return std::nullopt;
  return m_entries[it->second].second;
}

void Metadata::set(std::string_view key, std::string_view value) {
  const auto [it, added] = m_index.try_emplace(std::string(key), m_entries.size());
  if (!added) {
    m_entries[it->second].second = value;
    return;
  }
  m_entries.emplace_back(std::string(key), std::string(value));
}

void Metadata::erase(std::string_view key) {
  if (const auto line = m_lines.find(key); line != m_lines.end()) m_lines.erase(line);
  const auto it = m_index.find(key);
  if (it == m_index.end()) return;
  const std::size_t at = it->second;
  m_entries.erase(m_entries.begin() + static_cast<std::ptrdiff_t>(at));
  m_index.erase(it);
  for (auto& entry : m_index) {
    if (entry.second > at) --entry.second;
  }
}

void Metadata::note_line(std::string_view key, std::size_t line) {
  if (const auto it = m_lines.find(key); it != m_lines.end()) {
    it->second = line;
  } else {
    m_lines.emplace(key, line);
  }
}

std::string Metadata::where(std::string_view source, std::string_view key) const {
  const auto it = m_lines.find(key);
  return it == m_lines.end() ? std::string(source) : fmt::format("{}:{}", source, it->second);
}

namespace {

/// Reads the plain decimal, -?[0-9]+(.[0-9]+)?, at the start of [first, last) when it has at most
/// 19 digits, its integer m (the digits without the point) is at most 2^53 and its fraction has at
/// most 22 digits: then m and 10^f are exact doubles and m / 10^f, one rounding, is the correctly
/// rounded value (Clinger's fast path), the value std::from_chars gives. Returns the end of the
/// number, or nullptr for anything else, which from_chars reads. Three times as fast on a
/// simulator's columns.
const char* scan_decimal(const char* first, const char* last, double& value) {
  if (first == last) return nullptr;
  const bool negative = *first == '-';
  const char* p = first + (negative ? 1 : 0);
  std::uint64_t m = 0;
  int digits = 0;
  const char* int_start = p;
  for (; p < last && *p >= '0' && *p <= '9'; ++p, ++digits)
    m = m * 10U + static_cast<std::uint64_t>(*p - '0');
  if (p == int_start) return nullptr;
  int frac = 0;
  if (p < last && *p == '.') {
    const char* frac_start = ++p;
    for (; p < last && *p >= '0' && *p <= '9'; ++p, ++digits)
      m = m * 10U + static_cast<std::uint64_t>(*p - '0');
    frac = static_cast<int>(p - frac_start);
    if (frac == 0) return nullptr;
  }
  if (digits > 19 || frac > 22 || m > (std::uint64_t{1} << 53)) return nullptr;
  const double x = static_cast<double>(m) / k_pow10[static_cast<std::size_t>(frac)];
  value = negative ? -x : x;
  return p;
}

}  // namespace

bool parse_number(std::string_view text, double& value) {
  text = trim_line(text);
  if (text.empty()) {
    value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (scan_decimal(first, last, value) == last) return true;
  if (*first == '+') ++first;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc() && ptr == last) return true;
  if (ec == std::errc::result_out_of_range && ptr == last) {
    // Overflow reads as +-inf and underflow as 0, as strtod does; the text was a number.
    value = std::strtod(std::string(text).c_str(), nullptr);
    return true;
  }
  return false;
}

namespace {

/// Parses data line `line` (its '\r' removed) into `row` (one value a column); false with the
/// message for "source:line: " in `error` when it is no row of this header.
bool parse_line(std::string_view line, const std::vector<std::string>& columns, double* row,
                std::string& error) {
  // A row of plain decimals (what the tools write) is read in one pass, each field as
  // parse_number reads it; any other line, and every error, takes the field-by-field path.
  const char* p = line.data();
  const char* const last = p + line.size();
  std::size_t read = 0;
  while (read < columns.size() && (p = scan_decimal(p, last, row[read])) != nullptr) {
    if (++read == columns.size()) {
      if (p == last) return true;
    } else if (p != last && *p == ',') {
      ++p;
    } else {
      break;
    }
  }
  const std::string_view t = trim_line(line);
  if (!t.empty() && t.front() == '#') {
    error = "metadata line after the header";
    return false;
  }
  if (t.empty() && columns.size() > 1) {
    error = fmt::format("empty line, the header has {} columns", columns.size());
    return false;
  }
  std::size_t column = 0;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    const std::string_view field =
        line.substr(start, comma == std::string_view::npos ? line.npos : comma - start);
    if (column >= columns.size()) {
      error = fmt::format("more fields than the {} columns of the header", columns.size());
      return false;
    }
    if (!parse_number(field, row[column])) {
      error = fmt::format("column {}: invalid number {}", quote(columns[column]), quote(trim_line(field)));
      return false;
    }
    ++column;
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (column != columns.size()) {
    error =
        fmt::format("{} field{}, the header has {} columns", column, column == 1 ? "" : "s", columns.size());
    return false;
  }
  return true;
}

/// A part of a table's text (whole lines) and its rows, parsed on a core of its own.
struct Part {
  std::string text;
  std::vector<std::vector<double>> columns;  ///< its rows, column-major
  std::size_t lines = 0;
  std::size_t bad_line = 0;  ///< 1-based within the part; 0: every line parsed
  std::string error;
};

/// Parses `part.text` into `part.columns`; stops at its first bad line.
void parse_part(Part& part, const std::vector<std::string>& names) {
  const std::string_view text = part.text;
  part.lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) +
               (!text.empty() && text.back() != '\n' ? 1 : 0);
  part.columns.resize(names.size());
  for (auto& c : part.columns) c.resize(part.lines);
  part.bad_line = 0;
  std::vector<double> row(names.size());
  std::string_view rest = text;
  for (std::size_t k = 0; k < part.lines; ++k) {
    const auto nl = rest.find('\n');
    std::string_view line = rest.substr(0, nl);
    rest.remove_prefix(nl == std::string_view::npos ? rest.size() : nl + 1);
    if (line.size() > k_max_line_bytes) {
      part.error = line_too_long();
      part.bad_line = k + 1;
      return;
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!parse_line(line, names, row.data(), part.error)) {
      part.bad_line = k + 1;
      return;
    }
    for (std::size_t c = 0; c < row.size(); ++c) part.columns[c][k] = row[c];
  }
}

}  // namespace

Reader::Reader(std::istream& in, std::string source) : m_lines(in, std::move(source)) {
  const std::string& src = m_lines.source();
  std::string_view line;
  while (true) {
    if (!m_lines.next(line)) fail("{}: empty input: no header line", src);
    const std::string_view t = trim_line(line);
    if (t.empty()) continue;
    if (t.front() != '#') break;
    std::string_view body = trim_line(t.substr(1));
    const auto colon = body.find(':');
    const std::string_view key = colon == std::string_view::npos ? body : trim_line(body.substr(0, colon));
    m_meta.set(key, colon == std::string_view::npos ? std::string_view() : trim_line(body.substr(colon + 1)));
    m_meta.note_line(key, m_lines.line());
  }
  const std::size_t at = m_lines.line();
  // The names seen, as views into the header line (it stays put until the next read).
  std::unordered_set<std::string_view> seen;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    const std::string_view name =
        trim_line(line.substr(start, comma == std::string_view::npos ? line.npos : comma - start));
    if (m_columns.size() == k_max_columns) {
      fail("{}:{}: header: more than {} columns", src, at, k_max_columns);
    }
    if (name.empty()) fail("{}:{}: header: empty column name (column {})", src, at, m_columns.size() + 1);
    // A name is written back as it is read (Writer::header): no control character fits a line.
    if (std::any_of(name.begin(), name.end(),
                    [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; })) {
      fail("{}:{}: header: column name {} holds a control character", src, at, quote(name));
    }
    if (!seen.insert(name).second) fail("{}:{}: header: duplicate column {}", src, at, quote(name));
    double probe = 0;
    if (parse_number(name, probe)) {
      fail("{}:{}: header: expected column names, found the number {}", src, at, quote(name));
    }
    m_columns.emplace_back(name);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  m_row.resize(m_columns.size());
}

Reader::~Reader() = default;

bool Reader::next() {
  std::string_view text;
  if (!m_lines.next(text)) return false;
  std::string error;
  if (!parse_line(text, m_columns, m_row.data(), error)) fail("{}:{}: {}", source(), line(), error);
  return true;
}

std::optional<std::size_t> Reader::find(std::string_view name) const {
  const auto it = std::find(m_columns.begin(), m_columns.end(), name);
  if (it == m_columns.end()) return std::nullopt;
  return static_cast<std::size_t>(it - m_columns.begin());
}

std::size_t Reader::require(std::string_view name) const {
  if (auto i = find(name)) return *i;
  fail("{}: missing column {} (has: {})", source(), quote(name), column_list(m_columns));
}

std::optional<std::size_t> Table::find(std::string_view name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<std::size_t>(it - names.begin());
}

const std::vector<double>& Table::col(std::string_view name) const {
  if (auto i = find(name)) return columns[*i];
  fail("{}: missing column {} (has: {})", source, quote(name), column_list(names));
}

std::vector<double>& Table::col(std::string_view name) {
  return const_cast<std::vector<double>&>(std::as_const(*this).col(name));
}

std::vector<double>& Table::set(std::string_view name, std::vector<double> values) {
  MCG_DEMAND(names.empty() || values.size() == rows());
  if (auto i = find(name)) {
    columns[*i] = std::move(values);
    return columns[*i];
  }
  names.emplace_back(name);
  columns.push_back(std::move(values));
  return columns.back();
}

Table read(std::istream& in, std::string source) {
  Reader reader(in, source);
  Table table;
  table.source = std::move(source);
  table.meta = reader.metadata();
  table.names = reader.columns();
  table.columns.resize(table.names.size());
  table.first_line = reader.line() + 1;
  // Parts of 4 MiB of whole lines, one a core, parsed side by side and appended in order; the
  // first bad line of the input is the one reported, as the Reader reports it. The parts'
  // buffers grow with what comes and are reused, so the memory is the table's and at most a
  // part a core: a small input costs a small buffer.
  constexpr std::size_t k_part_bytes = std::size_t{4} << 20;
  std::vector<Part> parts(parallel::worker_count(0, 64));
  for (bool more = true; more;) {
    std::size_t filled = 0;
    while (filled < parts.size() && (more = reader.take_lines(parts[filled].text, k_part_bytes))) ++filled;
    parallel::for_each(filled, 0, [&](std::size_t k) { parse_part(parts[k], table.names); });
    for (std::size_t k = 0; k < filled; ++k) {
      const Part& p = parts[k];
      if (p.bad_line != 0)
        fail("{}:{}: {}", table.source, table.line_of(table.rows()) + p.bad_line - 1, p.error);
      for (std::size_t c = 0; c < table.columns.size(); ++c) {
        table.columns[c].insert(table.columns[c].end(), p.columns[c].begin(), p.columns[c].end());
      }
    }
  }
  if (reader.overlong()) fail("{}:{}: {}", table.source, table.line_of(table.rows()), line_too_long());
  return table;
}

Table read_path(const std::string& path) { return read(open_input(path), input_name(path)); }

void require_finite(const Table& table, std::string_view name) {
  const auto& v = table.col(name);
  for (std::size_t r = 0; r < v.size(); ++r) {
    if (!std::isfinite(v[r])) {
      fail("{}:{}: column {}: {} is not allowed here", table.source, table.line_of(r), quote(name),
           std::isnan(v[r]) ? "an unmeasured value (nan or empty)" : "an infinite value");
    }
  }
}

LeadingUnmeasured leading_unmeasured(const Table& table, const std::vector<std::string>& names) {
  LeadingUnmeasured out;
  std::vector<const std::vector<double>*> cols;
  for (const auto& name : names) cols.push_back(&table.col(name));
  const auto unmeasured = [&](std::size_t r) {
    return std::any_of(cols.begin(), cols.end(), [r](const auto* c) { return std::isnan((*c)[r]); });
  };
  while (out.rows < table.rows() && unmeasured(out.rows)) ++out.rows;
  for (std::size_t k = 0; k < names.size() && out.rows > 0; ++k) {
    const auto& c = *cols[k];
    if (std::any_of(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(out.rows),
                    [](double x) { return std::isnan(x); })) {
      out.columns.push_back(names[k]);
    }
  }
  if (out.rows > 0 && out.rows == table.rows()) {
    std::string which;
    for (const auto& c : out.columns) which += (which.empty() ? "" : ", ") + quote(c);
    fail("{}: no row has {} measured", table.source, which);
  }
  return out;
}

Table drop_leading(const Table& table, std::size_t first) {
  MCG_DEMAND(first <= table.rows());
  Table out;
  out.source = table.source;
  out.meta = table.meta;
  out.names = table.names;
  out.first_line = table.first_line + first;
  for (const auto& c : table.columns)
    out.columns.emplace_back(c.begin() + static_cast<std::ptrdiff_t>(first), c.end());
  return out;
}

std::string skipped_note(const Table& table, const LeadingUnmeasured& skipped) {
  std::string which;
  for (const auto& c : skipped.columns) which += (which.empty() ? "" : ", ") + quote(c);
  const bool speed = std::any_of(skipped.columns.begin(), skipped.columns.end(),
                                 [](const std::string& c) { return c.rfind("rpm", 0) == 0 || c == "omega"; });
  return fmt::format("{}: skipped the first {} row{} (line{} {}{}): {} not measured yet{}", table.source,
                     skipped.rows, skipped.rows == 1 ? "" : "s", skipped.rows == 1 ? "" : "s",
                     table.line_of(0),
                     skipped.rows == 1 ? std::string() : fmt::format("-{}", table.line_of(skipped.rows - 1)),
                     which, speed ? " (the speed estimator's warm-up)" : "");
}

void require_increasing(const Table& table, std::string_view name) {
  require_finite(table, name);
  const auto& v = table.col(name);
  for (std::size_t r = 1; r < v.size(); ++r) {
    if (!(v[r] > v[r - 1])) {
      fail("{}:{}: column {}: {} does not increase (previous row: {})", table.source, table.line_of(r),
           quote(name), fmt::format("{:.10g}", v[r]), fmt::format("{:.10g}", v[r - 1]));
    }
  }
}

Writer::Writer(std::ostream& out, std::string dest) : m_out(out), m_dest(std::move(dest)) {
  m_buffer.resize(k_write_block + 4096);
}

Writer::~Writer() {
  if (m_used > 0 && m_out) m_out.write(m_buffer.data(), static_cast<std::streamsize>(m_used));
}

char* Writer::room(std::size_t bytes) {
  if (m_buffer.size() - m_used < bytes) m_buffer.resize(m_used + bytes);
  return m_buffer.data() + m_used;
}

void Writer::append(std::string_view text) {
  std::copy_n(text.data(), text.size(), room(text.size()));
  m_used += text.size();
}

void Writer::metadata(const Metadata& meta) {
  for (const auto& [k, v] : meta.entries()) this->meta(k, v);
}

void Writer::meta(std::string_view key, std::string_view value) {
  // One line each: a value that names a file quotes it (printable()), input cannot hold a newline.
  MCG_DEMAND(key.find('\n') == std::string_view::npos && value.find('\n') == std::string_view::npos);
  append("# ");
  append(key);
  if (!value.empty()) {
    append(": ");
    append(value);
  }
  append("\n");
  flush_if_full();
}

void Writer::header(const std::vector<std::string>& names) {
  m_names = names;
  m_digits.assign(names.size(), k_default_digits);
  m_cells.assign(names.size(), Cell{});
  // Every name, as it is: column_list() is the shortened form for messages.
  for (std::size_t c = 0; c < names.size(); ++c) {
    MCG_DEMAND(names[c].find_first_of(",\n\r") == std::string::npos);
    if (c) append(",");
    append(names[c]);
  }
  append("\n");
  flush_if_full();
}

void Writer::set_digits(std::size_t column, int digits) {
  MCG_DEMAND(column < m_digits.size() && digits >= 1 && digits <= 17);
  m_digits[column] = digits;
  m_cells[column] = Cell{};
}

void Writer::set_digits(std::string_view name, int digits) {
  const auto it = std::find(m_names.begin(), m_names.end(), name);
  MCG_DEMAND(it != m_names.end());
  set_digits(static_cast<std::size_t>(it - m_names.begin()), digits);
}

void Writer::row(std::span<const double> values) {
  MCG_DEMAND(values.size() == m_names.size());
  // Formatted straight into the buffer's tail, as printf's "%.Ng" (format_general): at most 25
  // characters a number ("%.17g" of a negative subnormal) and a separator each. A field is kept
  // and copied as a whole Cell, so each has a Cell's room.
  constexpr std::size_t k_field_room = std::tuple_size_v<decltype(Cell::text)>;
  char* const start = room(values.size() * k_field_room + 1);
  char* p = start;
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (c) *p++ = ',';
    const double v = values[c];
    Cell& cell = m_cells[c];
    const auto bits = std::bit_cast<std::uint64_t>(v);
    if (cell.size != 0 && cell.bits == bits) {
      std::memcpy(p, cell.text.data(), cell.text.size());
      p += cell.size;
      continue;
    }
    char* const field = p;
    if (std::isnan(v)) {
      p = std::copy_n("nan", 3, p);
    } else if (std::isinf(v)) {
      p = v > 0 ? std::copy_n("inf", 3, p) : std::copy_n("-inf", 4, p);
    } else if (v == 0) {
      *p++ = '0';
    } else {
      p = format_general(p, v, m_digits[c]);
    }
    cell.bits = bits;
    cell.size = static_cast<std::size_t>(p - field);
    std::memcpy(cell.text.data(), field, cell.text.size());
  }
  *p++ = '\n';
  m_used += static_cast<std::size_t>(p - start);
  flush_if_full();
}

void Writer::text_row(const std::vector<std::string>& cells) {
  MCG_DEMAND(cells.size() == m_names.size());
  for (std::size_t c = 0; c < cells.size(); ++c) {
    MCG_DEMAND(cells[c].find_first_of("\n\r,") == std::string::npos);
    if (c) append(",");
    append(cells[c]);
  }
  append("\n");
  flush_if_full();
}

void Writer::flush_if_full() {
  if (m_used >= k_write_block) flush();
}

void Writer::flush() {
  if (m_used == 0) return;
  errno = 0;
  m_out.write(m_buffer.data(), static_cast<std::streamsize>(m_used));
  m_used = 0;
  if (!m_out) {
    if (errno == EPIPE) throw BrokenPipe();
    fail("writing {}: {}", m_dest, errno ? std::strerror(errno) : "write failed");
  }
}

void Writer::finish() {
  flush();
  errno = 0;
  m_out.flush();
  if (!m_out) {
    if (errno == EPIPE) throw BrokenPipe();
    fail("writing {}: {}", m_dest, errno ? std::strerror(errno) : "write failed");
  }
}

void write(std::ostream& out, const Table& table, int digits) {
  Writer w(out);
  w.metadata(table.meta);
  w.header(table.names);
  for (std::size_t c = 0; c < table.names.size(); ++c) w.set_digits(c, digits);
  std::vector<double> row(table.names.size());
  for (std::size_t r = 0; r < table.rows(); ++r) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = table.columns[c][r];
    w.row(row);
  }
  w.finish();
}

}  // namespace mcg::table
