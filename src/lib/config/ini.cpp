// INI parameter sets.
#include "config/ini.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <istream>
#include <ostream>
#include <sstream>

#include "common/error.hpp"
#include "common/line_reader.hpp"
#include "common/quote.hpp"
#include "common/text.hpp"
#include "table/table.hpp"

namespace mcg::config {

namespace {

/// Strips a trailing "; comment" or "# comment" that follows a blank.
std::string_view strip_comment(std::string_view s) {
  for (std::size_t i = 1; i < s.size(); ++i) {
    if ((s[i] == ';' || s[i] == '#') && (s[i - 1] == ' ' || s[i - 1] == '\t')) return s.substr(0, i);
  }
  return s;
}

std::string index_key(std::string_view section, std::string_view key) {
  return fmt::format("{}:{}{}", section.size(), section, key);
}

}  // namespace

void Ini::add(Entry entry) {
  m_index.emplace(index_key(entry.section, entry.key), m_entries.size());
  auto [it, added] = m_by_section.try_emplace(entry.section);
  if (added) m_sections.push_back(entry.section);
  it->second.push_back(m_entries.size());
  m_entries.push_back(std::move(entry));
}

const std::size_t* Ini::index_of(std::string_view section, std::string_view key) const {
  const auto it = m_index.find(index_key(section, key));
  return it == m_index.end() ? nullptr : &it->second;
}

Ini Ini::parse(std::istream& in, const std::string& source) {
  Ini ini;
  std::string section;
  LineReader lines(in, source);
  std::string_view raw;
  while (lines.next(raw)) {
    const std::size_t line_no = lines.line();
    std::string_view line = trim_line(raw);
    if (line.empty() || line.front() == ';' || line.front() == '#') continue;
    if (line.front() == '[') {
      const auto close = line.find(']');
      if (close == std::string_view::npos) fail("{}:{}: section header without ']'", source, line_no);
      if (!trim_line(strip_comment(line.substr(close + 1))).empty()) {
        fail("{}:{}: text after the section header", source, line_no);
      }
      section = std::string(trim_line(line.substr(1, close - 1)));
      if (section.empty()) fail("{}:{}: empty section name", source, line_no);
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string_view::npos) fail("{}:{}: expected 'key = value', found {}", source, line_no, quote(line));
    const std::string_view key = trim_line(line.substr(0, eq));
    if (key.empty()) fail("{}:{}: empty key", source, line_no);
    const std::string_view value = trim_line(strip_comment(line.substr(eq + 1)));
    const std::string origin = fmt::format("{}:{}", source, line_no);
    if (const std::size_t* first = ini.index_of(section, key)) {
      fail("{}: [{}] {}: given twice (first at {})", origin, printable(section), printable(key),
           ini.m_entries[*first].origin);
    }
    ini.add(Entry{section, std::string(key), std::string(value), origin, {}});
  }
  return ini;
}

Ini Ini::load(const std::string& path) {
  if (path == "-") return parse(std::cin, "<stdin>");
  std::ifstream in(path);
  if (!in) fail("{}: cannot open: {}", printable_name(path), std::strerror(errno));
  return parse(in, printable_name(path));
}

Ini Ini::load_all(const std::vector<std::string>& paths) {
  Ini ini;
  for (const auto& p : paths) ini.merge(load(p));
  return ini;
}

void Ini::merge(const Ini& later) {
  for (const auto& e : later.m_entries) {
    if (const std::size_t* at = index_of(e.section, e.key)) {
      m_entries[*at] = e;
    } else {
      add(e);
    }
  }
}

const Ini::Entry* Ini::find(std::string_view section, std::string_view key) const {
  const std::size_t* at = index_of(section, key);
  return at == nullptr ? nullptr : &m_entries[*at];
}

bool Ini::has(std::string_view section, std::string_view key) const { return find(section, key) != nullptr; }

bool Ini::has_section(std::string_view section) const { return m_by_section.contains(std::string(section)); }

std::optional<std::string> Ini::get(std::string_view section, std::string_view key) const {
  if (const Entry* e = find(section, key)) return e->value;
  return std::nullopt;
}

void Ini::reject(std::string_view section, std::string_view key, std::string_view what) const {
  const Entry* e = find(section, key);
  const std::string where = e && !e->origin.empty() ? e->origin + ": " : std::string();
  fail("{}[{}] {}: {}", where, printable(section), printable(key), what);
}

std::optional<double> Ini::number(std::string_view section, std::string_view key) const {
  const Entry* e = find(section, key);
  if (!e) return std::nullopt;
  double v = 0;
  if (e->value.empty() || !table::parse_number(e->value, v)) {
    reject(section, key, fmt::format("invalid number {}", quote(e->value)));
  }
  return v;
}

double Ini::number_or(std::string_view section, std::string_view key, double fallback) const {
  return number(section, key).value_or(fallback);
}

std::optional<std::vector<double>> Ini::numbers(std::string_view section, std::string_view key) const {
  const Entry* e = find(section, key);
  if (!e) return std::nullopt;
  std::vector<double> out;
  std::string_view rest = e->value;
  while (true) {
    const auto sep = rest.find_first_of(" \t,");
    const std::string_view tok = rest.substr(0, sep);
    if (!tok.empty()) {
      double v = 0;
      if (!table::parse_number(tok, v)) reject(section, key, fmt::format("invalid number {}", quote(tok)));
      out.push_back(v);
    }
    if (sep == std::string_view::npos) break;
    rest.remove_prefix(sep + 1);
  }
  return out;
}

void Ini::set(std::string_view section, std::string_view key, std::string_view value, std::string_view comment) {
  if (const std::size_t* at = index_of(section, key)) {
    Entry& e = m_entries[*at];
    e.value = value;
    e.origin.clear();
    e.comment = comment;
    return;
  }
  add(Entry{std::string(section), std::string(key), std::string(value), {}, std::string(comment)});
}

void Ini::set(std::string_view section, std::string_view key, double value, std::string_view comment) {
  set(section, key, format_number(value), comment);
}

std::vector<std::string> Ini::sections() const { return m_sections; }

std::vector<const Ini::Entry*> Ini::entries(std::string_view section) const {
  std::vector<const Entry*> out;
  const auto it = m_by_section.find(std::string(section));
  if (it == m_by_section.end()) return out;
  out.reserve(it->second.size());
  for (const std::size_t at : it->second) out.push_back(&m_entries[at]);
  return out;
}

void Ini::write(std::ostream& out) const {
  bool first = true;
  for (const auto& section : m_sections) {
    if (!section.empty()) {
      if (!first) out << '\n';
      out << '[' << section << "]\n";
    }
    first = false;
    for (const Entry* e : entries(section)) {
      out << e->key << " = " << e->value;
      if (!e->comment.empty()) out << "  ; " << e->comment;
      out << '\n';
    }
  }
}

std::string Ini::str() const {
  std::ostringstream os;
  write(os);
  return os.str();
}

std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return fmt::format("{}", without_negative_zero(value));
}

}  // namespace mcg::config
