#pragma once
// Small vector type for locals in the engine. State is stored in columns (structure of arrays);
// Vec2 is for computing with, never for storing per-particle state.

#include <Eigen/Core>

namespace hopper::core {

using Vec2 = Eigen::Vector2d;

// z-component of the 2D cross product a x b.
inline double cross(const Vec2& a, const Vec2& b) {
    return a.x() * b.y() - a.y() * b.x();
}

// z x a for a vector in the plane (rotation by +90 degrees).
inline Vec2 perp(const Vec2& a) {
    return Vec2(-a.y(), a.x());
}

}  // namespace hopper::core
