// Unit conversions written once: pi and rpm <-> rad/s (omega_rad_s = rpm * 2 pi / 60).
#pragma once

#include <numbers>

namespace mcg {

inline constexpr double k_pi = std::numbers::pi;

/// Seconds per minute over the radians per revolution, reduced: rpm = omega_rad_s * 30 / pi.
inline constexpr double k_rpm_per_pi_rad_s = 30.0;

/// omega_rad_s = rpm * pi / 30 (multiplied, then divided, so results match the factor below).
constexpr double rad_s_from_rpm(double rpm) { return rpm * k_pi / k_rpm_per_pi_rad_s; }
/// rpm = omega_rad_s * 30 / pi.
constexpr double rpm_from_rad_s(double omega_rad_s) { return omega_rad_s * k_rpm_per_pi_rad_s / k_pi; }

/// The same conversions as factors, for scaling whole columns: rad/s per rpm and rpm per rad/s.
inline constexpr double k_rad_s_per_rpm = k_pi / k_rpm_per_pi_rad_s;
inline constexpr double k_rpm_per_rad_s = k_rpm_per_pi_rad_s / k_pi;

}  // namespace mcg
