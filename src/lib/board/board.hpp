// The emulated board: the firmware's portable core (host board layer) driving the plant model.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "board/core.hpp"         // FirmwareCore
#include "common/diagnostics.hpp"
#include "boardunits/chain.hpp"  // k_load_resistor_ohm
#include "model/model.hpp"  // Model, Plant, State

namespace mcg::board {

/// What the emulated board is wired to.
struct BoardOptions {
  model::Model model;               ///< the rig (mcg-sim's --config)
  double r_load_ohm =
      boardunits::k_load_resistor_ohm;  ///< resistor the load relay puts across the generator, ohm
  std::uint32_t baud = 9600;        ///< serial line rate; 0 = unlimited
  double max_step_s = 1e-3;         ///< the plant's largest integration step (model::SimOptions)
};

/// One board per process (the core keeps its state in globals, as on the 8051): a second
/// instance while one lives is a programming error (MCG_DEMAND).
///
/// Per 1 ms tick: the core's PWM duty d (1/1000) drives the plant with v = d / 1000 * supply_V
/// for 1 ms; the clutch output selects clutch state 2 (engaged) or 1 (attached, disengaged);
/// the load relay puts r_load_ohm across the generator or leaves it open. The encoder input
/// counts |floor(theta N / 2 pi) - previous| pulses (N = MCG_COUNTS_PER_REV; no direction,
/// as the 80C515's counter input) and feeds them to the next tick.
class EmulatedBoard {
 public:
  explicit EmulatedBoard(const BoardOptions& options);
  ~EmulatedBoard();
  EmulatedBoard(const EmulatedBoard&) = delete;
  EmulatedBoard& operator=(const EmulatedBoard&) = delete;

  /// Bytes from the PC; returns how many the line accepted (the rest must be offered again).
  std::size_t rx(std::span<const std::uint8_t> bytes);
  /// Bytes the board transmitted since the last call (at most out.size()).
  std::size_t tx(std::span<std::uint8_t> out);
  /// Advances by one 1 ms tick.
  void tick();

  /// Simulated time since power-on, s.
  double time_s() const;
  const model::State& plant_state() const { return m_state; }
  /// The core's PWM duty, 1/1000 of full scale.
  std::int16_t duty_permille() const;

 private:
  BoardOptions m_options;
  FirmwareCore m_core;
  model::Plant m_plant;
  model::State m_state;
  double m_count = 0.0;      ///< encoder position, counts (floor of theta N / 2 pi)
  std::uint16_t m_pulses = 0; ///< pulses counted during the last tick
};

/// Where and how fast mcg-sim --board serves the emulated board.
struct ServeOptions {
  std::string link_path;           ///< the pseudo-terminal's link, e.g. ./ttyMCG
  std::vector<std::string> configs;   ///< INI files of the model (mcg-sim --config)
  std::vector<std::string> effects;   ///< "NAME:key=value,..." (mcg-sim --effect)
  BoardOptions board;              ///< board.model is replaced by the model of configs and effects
  double speed = 1.0;              ///< simulated seconds per wall-clock second (> 0)
  double seconds = 0.0;            ///< stop after this much simulated time; 0 = until a signal
  std::vector<std::string> options_given;   ///< mcg-sim's options on the command line, e.g. "--seed"
};

/// Throws mcg::Error naming the first of `options_given` that mcg-sim --board does not use, and
/// why: the emulated board measures only what the firmware measures (the encoder, through its
/// own windows), and its clutch and load come from the board's outputs.
void refuse_unused_options(const std::vector<std::string>& options_given);

/// Creates the pseudo-terminal, links it at options.link_path, announces it on `diag` in one
/// report line ("board at LINK (PTY); Ctrl-C ends", flushed, once the link exists), enters
/// it in the list of mcg-serial list (link::EmulatedPortEntry), and runs the board in real
/// time (times `speed`) until SIGINT or SIGTERM (or `seconds`), then removes the link. A
/// client may come and go any number of times. Throws mcg::Error when the link cannot be made.
void serve(const ServeOptions& options, Diagnostics& diag);

}  // namespace mcg::board
