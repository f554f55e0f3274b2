// mcg-fit: parameters from measured runs: friction, transfer function, grey-box model.
#include <iostream>

#include "cmd/fit/friction.hpp"
#include "cmd/fit/gap.hpp"
#include "cmd/fit/model.hpp"
#include "cmd/fit/tf.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Identify the rig from measured runs: friction, a transfer function, the nonlinear model.",
               "mcg-fit"};
  mcg::Diagnostics diag(std::cerr, app.get_name());
  mcg::cmd::FitFriction friction;
  mcg::cmd::FitTf tf;
  mcg::cmd::FitModel model;
  mcg::cmd::FitGap gap;
  return mcg::cmd::main_of(app, argc, argv, diag, {&friction, &tf, &model, &gap});
}
