// Builds mcg-sim(1) from its source page: the line `.\" @EFFECTS@` becomes the effect
// catalog's entries, so the page and `mcg-sim --list-effects` have one owner.
// Usage: mcg_effects_page SOURCE_PAGE OUTPUT_PAGE
#include <fstream>
#include <iostream>
#include <string>

#include "model/model.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: mcg_effects_page SOURCE_PAGE OUTPUT_PAGE\n";
    return 2;
  }
  std::ifstream in(argv[1]);
  std::ofstream out(argv[2]);
  if (!in || !out) {
    std::cerr << "mcg_effects_page: cannot open " << (in ? argv[2] : argv[1]) << "\n";
    return 1;
  }
  int markers = 0;
  for (std::string line; std::getline(in, line);) {
    if (line == ".\\\" @EFFECTS@") {
      mcg::model::write_effect_catalog_roff(out);
      ++markers;
    } else {
      out << line << '\n';
    }
  }
  if (markers != 1) {
    std::cerr << "mcg_effects_page: " << argv[1] << ": expected one @EFFECTS@ line, found " << markers
              << "\n";
    return 1;
  }
  return out.good() ? 0 : 1;
}
