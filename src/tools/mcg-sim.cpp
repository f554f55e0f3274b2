// mcg-sim: the motor-clutch-generator rig simulated on a table of inputs.
#include <iostream>

#include "cmd/sim.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Simulates the motor-clutch-generator rig on the input table read from stdin (t and v or duty,\n"
      "clutch, r_load; rpm_cmd for a closed loop) and writes one row per input row with omega, rpm,\n"
      "i, i_gen, v_gen and theta. See man mcg-sim.",
      "mcg-sim"};
  mcg::Diagnostics diag(std::cerr, app.get_name());
  mcg::cmd::Sim sim;
  return mcg::cmd::main_of(app, argc, argv, diag, sim);
}
