// mcg-design: exact controller design, discretisation and loop analysis, down to fixed point.
#include <iostream>

#include "cmd/design/analysis.hpp"
#include "cmd/design/methods.hpp"
#include "cmd/design/plant.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Designs controllers exactly (P, PI, PID, lead, lag, root locus, robust tuning), discretises them,\n"
      "analyses loops (margins, Bode, Nyquist, root locus, step) and writes the fixed-point coefficients\n"
      "the firmware runs. Designs and numbers are INI, series are CSV. See man mcg-design.",
      "mcg-design"};
  mcg::Diagnostics diag(std::cerr, app.get_name());
  mcg::cmd::DesignP p;
  mcg::cmd::DesignPi pi;
  mcg::cmd::DesignPid pid;
  mcg::cmd::DesignLead lead;
  mcg::cmd::DesignLag lag;
  mcg::cmd::DesignRlocus rlocus_design;
  mcg::cmd::DesignTune tune;
  mcg::cmd::Margins margins;
  mcg::cmd::Bode bode(false);
  mcg::cmd::Bode nyquist(true);
  mcg::cmd::Rlocus rlocus;
  mcg::cmd::Step step;
  mcg::cmd::C2d c2d;
  mcg::cmd::Loop loop;
  return mcg::cmd::main_of(app, argc, argv, diag,
                           {&p, &pi, &pid, &lead, &lag, &rlocus_design, &tune, &margins, &bode, &nyquist,
                            &rlocus, &step, &c2d, &loop});
}
