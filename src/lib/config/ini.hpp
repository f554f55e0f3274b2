// INI parameter sets: "key = value" under "[section]", the named numbers tools exchange.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace mcg::config {

/// An INI document. Comments start with ';' or '#' (whole lines, or after a blank inside a
/// line); keys before any [section] belong to section "". Each value remembers where it
/// came from, so errors read "plant.ini:7: [plant] num: invalid number 'x'".
/// Several files merge in order, later ones winning (--config a.ini --config b.ini).
/// Lines are at most k_max_line_bytes (common/line_reader.hpp); reading, lookups and writing
/// take time linear in the number of keys.
class Ini {
 public:
  struct Entry {
    std::string section;
    std::string key;
    std::string value;
    std::string origin;  ///< "file:line", or "" for values set in code
    std::string comment; ///< written after the value as "; comment"
  };

  static Ini parse(std::istream& in, const std::string& source);
  static Ini load(const std::string& path);
  /// Loads and merges every file in order; an empty list gives an empty document.
  static Ini load_all(const std::vector<std::string>& paths);

  void merge(const Ini& later);
  bool has(std::string_view section, std::string_view key) const;
  bool has_section(std::string_view section) const;
  const Entry* find(std::string_view section, std::string_view key) const;
  std::optional<std::string> get(std::string_view section, std::string_view key) const;
  /// The value as a number (inf/nan accepted), or nullopt if absent; throws if malformed.
  std::optional<double> number(std::string_view section, std::string_view key) const;
  double number_or(std::string_view section, std::string_view key, double fallback) const;
  /// A whitespace- or comma-separated list of numbers, or nullopt if absent.
  std::optional<std::vector<double>> numbers(std::string_view section, std::string_view key) const;
  /// Throws "<origin>: [section] key: <what>" for a value that is present but wrong.
  [[noreturn]] void reject(std::string_view section, std::string_view key, std::string_view what) const;

  void set(std::string_view section, std::string_view key, std::string_view value, std::string_view comment = {});
  void set(std::string_view section, std::string_view key, double value, std::string_view comment = {});
  /// Sections in first-seen order.
  std::vector<std::string> sections() const;
  std::vector<const Entry*> entries(std::string_view section) const;
  const std::vector<Entry>& all() const { return m_entries; }

  void write(std::ostream& out) const;
  std::string str() const;

 private:
  /// Appends an entry whose (section, key) is new.
  void add(Entry entry);
  /// Index into m_entries of (section, key), or none.
  const std::size_t* index_of(std::string_view section, std::string_view key) const;

  std::vector<Entry> m_entries;
  /// (section, key) -> position in m_entries; the key is the section's length, ':', the
  /// section and the key, which no two different pairs share.
  std::unordered_map<std::string, std::size_t> m_index;
  /// Sections in first-seen order, and the positions of each one's entries in order.
  std::vector<std::string> m_sections;
  std::unordered_map<std::string, std::vector<std::size_t>> m_by_section;
};

/// Formats a double for INI/CSV text: shortest form that reads back exactly.
std::string format_number(double value);

/// `value`, a zero reached from below made 0: every number the tools write goes through it
/// (-0 reads as a negative number).
inline double without_negative_zero(double value) { return value == 0.0 ? 0.0 : value; }

}  // namespace mcg::config
