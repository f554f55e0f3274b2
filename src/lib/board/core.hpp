// The firmware's portable core on its host board layer (firmware/board/host/host_board.h): the
// same C that the 8051 image runs, as the emulated board and mcg-sim's closed loop drive it.
#pragma once

#include <cstdint>

namespace mcg::board {

/// The process's one firmware core (the core keeps its state in globals, as on the 8051): a
/// second instance while one lives is a programming error (MCG_DEMAND). Constructed at power-on
/// reset with its registers at their table defaults.
class FirmwareCore {
 public:
  /// baud: the serial line's rate (0 = unlimited, for a core that is never spoken to).
  explicit FirmwareCore(std::uint32_t baud = 0);
  ~FirmwareCore();
  FirmwareCore(const FirmwareCore&) = delete;
  FirmwareCore& operator=(const FirmwareCore&) = delete;

  /// Writes register `reg` (MCG_REG_*) as `mcg-serial set` would, raw value: a register of the
  /// controller's set is staged and committed at once. Returns MCG_ST_OK or the board's refusal.
  std::uint8_t apply(std::uint8_t reg, std::int16_t raw);
  /// apply() that the caller knows the board takes (range checked, gains present): MCG_DEMAND.
  void write(std::uint8_t reg, std::int16_t raw);
  std::int16_t read(std::uint8_t reg) const;

  /// One 1 ms tick in which the encoder input counted `pulses` (no direction, as the 80C515's
  /// counter input), then the main loop: returns the PWM duty, 1/1000 of full scale, that the
  /// core applies from now until the next tick.
  std::int16_t tick(std::uint16_t pulses);

  std::int16_t duty_permille() const;
  bool clutch_engaged() const;
  bool load_closed() const;
};

}  // namespace mcg::board
