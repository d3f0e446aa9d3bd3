#pragma once
// Units: the engine works in SI (m, kg, s, rad) everywhere. Sweep files may use cm and degrees;
// the conversion happens once, in the config layer, with the factors below.

#include <numbers>

namespace hopper::core {

inline constexpr double pi = std::numbers::pi;
inline constexpr double cm = 1e-2;                // metres per centimetre
inline constexpr double deg = pi / 180.0;         // radians per degree
inline constexpr double standard_gravity = 9.81;  // m/s^2 (docs/model.md, particles)

}  // namespace hopper::core
