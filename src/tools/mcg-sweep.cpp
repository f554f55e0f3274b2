// mcg-sweep: excitation tables (step, staircase, chirp, multisine, prbs, aprbs) and the
// frequency response between two columns of a table (bode).
#include <iostream>

#include "cmd/sweep/bode.hpp"
#include "cmd/sweep/generate.hpp"

int main(int argc, char** argv) {
  using mcg::signal::Generator;
  CLI::App app{"Excitation tables for mcg-sim or the board, and frequency responses of measured tables.",
               "mcg-sweep"};
  mcg::Diagnostics diag(std::cerr, app.get_name());
  mcg::cmd::SweepGenerate step(Generator::step);
  mcg::cmd::SweepGenerate staircase(Generator::staircase);
  mcg::cmd::SweepGenerate chirp(Generator::chirp);
  mcg::cmd::SweepGenerate multisine(Generator::multisine);
  mcg::cmd::SweepGenerate prbs(Generator::prbs);
  mcg::cmd::SweepGenerate aprbs(Generator::aprbs);
  mcg::cmd::SweepBode bode;
  return mcg::cmd::main_of(app, argc, argv, diag,
                           {&step, &staircase, &chirp, &multisine, &prbs, &aprbs, &bode});
}
