#include "hopper/engine/scene.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hopper/core/error.hpp"

namespace hopper::engine {

namespace {

// theta within this of 90 deg is treated as exactly vertical (a slot of free width D).
constexpr double vertical_tolerance = 1e-9;

bool is_slot(const HopperGeometry& g) {
    return g.theta >= core::pi / 2 - vertical_tolerance;
}

// Places particles of diameter d at arc-length steps of at most `spacing` along the polyline
// `pts` (both ends included), mirrored to the left side when `mirror`.
void place_along(const std::vector<Vec2>& pts, double spacing, double d, bool mirror,
                 std::vector<WallParticle>& out) {
    double total = 0.0;
    for (std::size_t k = 1; k < pts.size(); ++k)
        total += (pts[k] - pts[k - 1]).norm();
    const double count = std::ceil(total / spacing - 1e-9);
    if (!(count <= 1e7)) {
        std::ostringstream msg;
        msg << "the walls would need " << count << " wall particles (" << total
            << " m of wall at a spacing of " << spacing
            << " m); use larger wall particles (walls.particle_diameter_cm) or a smaller hopper";
        throw core::ConfigError(msg.str());
    }
    const int n = std::max(1, int(count));
    const double step = total / n;
    std::size_t seg = 1;
    double seg_start = 0.0;
    for (int k = 0; k <= n; ++k) {
        const double s = k * step;
        while (seg + 1 < pts.size() && s > seg_start + (pts[seg] - pts[seg - 1]).norm()) {
            seg_start += (pts[seg] - pts[seg - 1]).norm();
            ++seg;
        }
        const Vec2 a = pts[seg - 1], b = pts[seg];
        const double len = (b - a).norm();
        const double u = len > 0.0 ? std::clamp((s - seg_start) / len, 0.0, 1.0) : 0.0;
        const Vec2 p = a + u * (b - a);
        out.push_back({p, d});
        if (mirror) out.push_back({Vec2(-p.x(), p.y()), d});
    }
}

}  // namespace

double wall_line_crossing(const HopperGeometry& g) {
    const double d_edge = g.edge_diameter.value_or(g.wall_diameter);
    switch (g.outlet_measure) {
        case OutletMeasure::surface_gap:
            return g.outlet / 2 + d_edge / 2;
        case OutletMeasure::centre_gap:
            return g.outlet / 2;
        case OutletMeasure::inner_envelope:
            // The inner envelope is the centre line moved d_w/2 towards the material; at y = 0
            // it lies (d_w/2)/sin(theta) inside the centre line's crossing.
            if (is_slot(g)) return g.outlet / 2 + g.wall_diameter / 2;
            return g.outlet / 2 + g.wall_diameter / 2 / std::sin(g.theta);
    }
    return g.outlet / 2 + d_edge / 2;
}

Vec2 edge_disk_centre(const HopperGeometry& g) {
    // edge_offset wall diameters up the centre line from its crossing with y = 0.
    const double s0 = g.edge_offset * g.wall_diameter;
    const double c = is_slot(g) ? 0.0 : std::cos(g.theta);
    const double s = is_slot(g) ? 1.0 : std::sin(g.theta);
    return {wall_line_crossing(g) + s0 * c, s0 * s};
}

double outlet_free_gap(const HopperGeometry& g) {
    // 2 x_edge - d_edge, written as D plus the edge disk's shift from its default place
    // (D/2 + d_edge/2, 0): that shift is exactly 0 for the default geometry, where this is D.
    const double d_edge = g.edge_diameter.value_or(g.wall_diameter);
    return g.outlet + 2.0 * (edge_disk_centre(g).x() - (g.outlet / 2 + d_edge / 2));
}

double inner_half_width(const HopperGeometry& g, double y) {
    // Centre line of the right funnel wall: through (x_c, 0) at angle theta; the inner surface
    // is offset by d_w/2 towards the material. Horizontal distance at height y.
    const double s = std::sin(g.theta), c = std::cos(g.theta);
    const double centre_x = wall_line_crossing(g);
    if (is_slot(g)) return centre_x - g.wall_diameter / 2;
    double funnel;
    if (s < 1e-12) {
        funnel = (y >= g.wall_diameter / 2) ? 1e300 : centre_x - g.wall_diameter / 2;
    } else {
        // Points on the inner surface satisfy (p - P0).n_in = d_w/2, n_in = (-sin, cos).
        funnel = centre_x + (y * c - g.wall_diameter / 2) / s;
    }
    return std::min(funnel, g.width / 2);
}

SceneLayout build_scene(const SceneParams& p, core::Rng& rng) {
    const auto& g = p.hopper;
    const auto& ps = p.particles;
    const double dw = g.wall_diameter;
    const double spacing = g.wall_spacing * dw;
    const double gap = p.protocol.fill_gap * ps.d_large;
    // The largest disk: d_large, or d_large (1 + w) with a size spread w (hopper.size_spread).
    const double d_max = ps.size_spread > 0.0 ? ps.d_large * (1.0 + ps.size_spread) : ps.d_large;
    const double a = d_max + gap;  // lattice spacing
    const bool slot = is_slot(g);
    const double s = std::sin(g.theta), c = std::cos(g.theta);
    const double x0 = wall_line_crossing(g);  // centre line of the right funnel wall at y = 0
    const double side_x = g.width / 2 + dw / 2;
    const Vec2 edge = edge_disk_centre(g);
    const double d_edge = g.edge_diameter.value_or(dw);

    SceneLayout layout;
    // Where the funnel's centre line reaches the side walls' centre line: (side_x - x0) tan
    // theta, written so that the default geometry (shift = 0) gives the same bits as always.
    const double shift = x0 - (g.outlet / 2 + dw / 2);
    layout.funnel_height = slot ? 1e300 : ((g.width - g.outlet) / 2 - shift) * std::tan(g.theta);

    // Fill: a square lattice, row by row from the gate up. A site is allowed when a large disk
    // centred there keeps `gap` clear of every wall particle whatever its position on the wall's
    // centre line: distance to the centre line >= d_w/2 + d_large/2 + gap.
    const double clear = std::max(dw, d_edge) / 2 + d_max / 2 + gap;
    // The lowest row: above the gate (which sits at the edge disks' height) by `clear`, plus
    // protocol.fill_base.
    const double y_first = edge.y() + p.protocol.fill_base * ps.d_large + clear;
    const long max_rows = 10'000'000;
    long row = 0;
    int placed = 0;
    layout.fill.reserve(ps.count);
    while (placed < ps.count) {
        if (row > max_rows) {
            std::ostringstream msg;
            msg << "cannot place " << ps.count << " particles in the hopper (outlet " << g.outlet
                << " m, theta " << g.theta / core::deg << " deg): the container is narrower than "
                << "one particle plus its clearance; widen the outlet or change theta";
            throw core::ConfigError(msg.str());
        }
        const double y = y_first + row * a;
        // Largest |x| allowed by the funnel wall: (u - x0)(-sin) + y cos >= clear.
        double umax = s > 1e-12 ? x0 + (y * c - clear) / s : 1e300;
        if (!slot) umax = std::min(umax, side_x - clear);
        ++row;
        if (umax < 0.0) continue;
        const int n_row = int(std::floor(2.0 * umax / a + 1e-9)) + 1;
        const double first = -(n_row - 1) * a / 2;
        for (int k = 0; k < n_row && placed < ps.count; ++k, ++placed) {
            FillParticle f;
            f.pos = Vec2(first + k * a, y);
            f.large = !(rng.uniform() < ps.small_fraction);
            f.diameter = f.large ? ps.d_large : ps.d_small;
            // (drawn only with a spread, so that the default's sequence is unchanged)
            if (ps.size_spread > 0.0) f.diameter *= 1.0 + ps.size_spread * rng.uniform(-1.0, 1.0);
            const double vx = rng.uniform(-p.protocol.fill_speed, p.protocol.fill_speed);
            const double vy = rng.uniform(-p.protocol.fill_speed, p.protocol.fill_speed);
            f.vel = Vec2(vx, vy);
            layout.fill.push_back(f);
            layout.fill_top = std::max(layout.fill_top, y);
        }
    }
    layout.wall_top = layout.fill_top + 3.0 * ps.d_large;

    // Walls: funnel (truncated at wall_top) then the vertical side wall, each side, starting at
    // the edge disk.
    std::vector<Vec2> outline{edge};
    if (slot) {
        outline.emplace_back(edge.x(), layout.wall_top);
    } else if (layout.funnel_height >= layout.wall_top) {
        outline.emplace_back(x0 + layout.wall_top * c / s, layout.wall_top);
    } else {
        outline.emplace_back(side_x, layout.funnel_height);
        outline.emplace_back(side_x, layout.wall_top);
    }
    place_along(outline, spacing, dw, /*mirror=*/true, layout.walls);
    layout.walls[0].diameter = layout.walls[1].diameter = d_edge;  // the two edge disks
    layout.outline = outline;

    // Gate: a row across the outlet between the two edge disks, at their height.
    const double xe = edge.x();
    const int n_gate = std::max(1, int(std::min(1e7, std::ceil(2 * xe / spacing - 1e-9))));
    for (int k = 1; k < n_gate; ++k)
        layout.gate.push_back({Vec2(-xe + k * 2 * xe / n_gate, edge.y()), dw});
    return layout;
}

}  // namespace hopper::engine
