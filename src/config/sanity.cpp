// Orders of magnitude of a scene, checked before a campaign starts: see
// include/hopper/config/sanity.hpp and docs/model.md ("Checked before a run").

#include "hopper/config/sanity.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "config/key_table.hpp"
#include "hopper/core/units.hpp"
#include "hopper/engine/scene.hpp"

namespace hopper::config {

namespace {

std::string cm(double metres) {
    return detail::approx_number(metres / core::cm);
}

// Rounds to 2 significant digits for a suggestion ("below 0.0073 s").
std::string two_digits(double v) {
    if (!(v > 0)) return detail::approx_number(v);
    const double scale = std::pow(10.0, std::floor(std::log10(v)) - 1);
    return detail::approx_number(std::floor(v / scale) * scale);
}

}  // namespace

double settled_fill_height(const engine::SceneParams& p) {
    const auto& s = p.particles;
    const double mean_area =
        std::numbers::pi / 4 *
        (s.small_fraction * s.d_small * s.d_small + (1 - s.small_fraction) * s.d_large * s.d_large);
    double left = s.count * mean_area / dense_packing_fraction;  // m^2 still to place
    // Up the funnel in thin slices until the container stops widening, then a straight column.
    const double dy = s.d_small / 4;
    const double full = 2 * engine::inner_half_width(p.hopper, 1e300);
    double y = 0.0;
    for (;;) {
        const double width = 2 * std::max(0.0, engine::inner_half_width(p.hopper, y + dy / 2));
        if (width >= full * (1 - 1e-12) || y > 1e3) break;
        if (width * dy >= left) return y + left / width;
        left -= width * dy;
        y += dy;
    }
    return full > 0 ? y + left / full : 1e300;
}

double settled_overlap(const engine::SceneParams& p) {
    const auto c = engine::derive_constants(p);
    const double depth = std::min(settled_fill_height(p), p.hopper.width / 2);
    const double layers = std::max(1.0, depth / p.particles.d_large);
    return layers * c.m_large * p.gravity / 2 / c.k_n;
}

std::string scene_problem(const engine::SceneParams& p) {
    const auto& h = p.hopper;
    const auto& s = p.particles;
    const double gap = engine::outlet_free_gap(h);
    if (gap < s.d_small) {
        std::string msg = "D_cm = " + cm(h.outlet) + " leaves a free gap of " + cm(gap) +
                          " cm at the outlet, narrower than one small disk (hopper.d_small_cm = " +
                          cm(s.d_small) +
                          "): no particle can leave, every realization would jam at t = 0. D_cm "
                          "is in centimetres";
        const double as_metres = h.outlet * 100;  // the value read as metres
        if (as_metres < h.width)
            msg += ": for " + cm(as_metres) + " cm write D_cm = " + cm(as_metres);
        return msg;
    }
    // A wall angle given in radians: 0 < theta_deg < 1.6 (90 degrees read as radians is
    // pi / 2 = 1.5708). Walls that close to horizontal are a flat bottom, theta_deg = 0.
    const double theta_deg = h.theta / core::deg;
    if (theta_deg > 0 && theta_deg < 1.6) {
        const std::string value = detail::approx_number(theta_deg);
        const double as_radians = std::round(theta_deg * 180 / std::numbers::pi * 10) / 10;
        return "theta_deg = " + value + " is the wall angle in degrees (walls " + value +
               " degrees from horizontal; a flat bottom is theta_deg = 0): for " + value +
               " radians write theta_deg = " + detail::approx_number(as_radians);
    }
    const double height = settled_fill_height(p);
    if (height > max_fill_widths * h.width)
        return "hopper.particles = " + std::to_string(s.count) + " would stand about " +
               detail::approx_number(std::round(height / core::cm)) +
               " cm high in a hopper of hopper.width_cm = " + cm(h.width) + " cm wide (" +
               detail::approx_number(std::round(height / h.width)) +
               " widths; their area at packing fraction " +
               detail::approx_number(dense_packing_fraction) +
               "): a tube, not a hopper, allowed up to " + detail::approx_number(max_fill_widths) +
               " widths. Check the units of width_cm (centimetres) and the particle count";
    const double overlap = settled_overlap(p);
    const double limit = p.protocol.max_overlap * s.d_small;
    if (overlap > limit) {
        const auto c = engine::derive_constants(p);
        // The overlap scales as tau_c^2 (k_n = pi^2 m / (2 tau_c^2)).
        const double tau_max = c.tau_c * std::sqrt(limit / overlap);
        const std::string key =
            p.material.collision_time
                ? "material.collision_time_s = " + detail::approx_number(*p.material.collision_time)
                : "the collision time " + detail::approx_number(c.tau_c) +
                      " s (from material.youngs_modulus_pa)";
        return key + " makes the contacts so soft (k_n = " + two_digits(c.k_n) +
               " N/m) that the settled packing alone would overlap by about " +
               two_digits(overlap / s.d_small) + " d_small, above protocol.max_overlap = " +
               detail::approx_number(p.protocol.max_overlap) +
               ": every realization would fail while settling. Collision times below about " +
               two_digits(tau_max) + " s keep it within (the published study: 8.0e-4 s)";
    }
    return {};
}

}  // namespace hopper::config
