// What every mcg-design subcommand shares: the plant and chain options and their resolution.
#pragma once

#include <string>
#include <utility>

#include "cmd/command.hpp"
#include "design/run.hpp"

namespace mcg::cmd {

/// A subcommand of mcg-design: its name and help, the plant options on its command line.
class PlantCommand : public Command {
 public:
  PlantCommand(std::string name, std::string help) : m_name(std::move(name)), m_help(std::move(help)) {}
  std::string name() const override { return m_name; }
  std::string help() const override { return m_help; }

 protected:
  /// Adds the plant and chain options (--config, --plant, ..., --counts-per-rev) to `app`.
  void define_plant(CLI::App& app, design::PlantOptions& plant);
  /// design::resolve on `plant`, with plant_given from the command line.
  design::ResolvedPlant resolve(design::PlantOptions& plant, bool designs) const;

 private:
  std::string m_name;
  std::string m_help;
  CLI::App* m_app = nullptr;
};

}  // namespace mcg::cmd
