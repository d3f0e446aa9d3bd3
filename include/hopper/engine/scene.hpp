#pragma once
// The hopper scene: wall particles along the outline, the gate that closes the outlet while the
// packing settles, and the fill lattice (docs/model.md, geometry and realization step 1).
//
// Coordinates: x horizontal with the outlet centred at x = 0, y up with the outlet at y = 0.
// Each funnel wall is a row of wall particles whose centres lie on a line at angle theta to the
// horizontal through (+-x_c, 0), x_c = wall_line_crossing(); by default (outlet_measure =
// surface_gap, no edge offset) x_c = D/2 + d_w/2, so D is the free gap between the two
// innermost wall particles (the edge disks). The row starts edge_offset wall diameters up the
// line from the crossing; its first disk (the edge disk) may have its own diameter. Above the
// funnel, vertical side walls have their centres at
// x = +-(W/2 + d_w/2), so W is the free width between them. theta = 0 gives a flat bottom with a
// hole; theta = 90 deg gives a vertical slot of free width D (the funnel walls never reach the
// side walls, so the scene is a channel; the fill then stacks up inside that channel).

#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/core/vec.hpp"
#include "hopper/engine/params.hpp"

namespace hopper::engine {

using core::Vec2;

struct WallParticle {
    Vec2 pos;
    double diameter;
};

struct FillParticle {
    Vec2 pos;
    Vec2 vel;
    double diameter;
    bool large;
};

struct SceneLayout {
    std::vector<WallParticle> walls;  // funnel and side walls
    std::vector<WallParticle> gate;   // closes the outlet while settling; removed at opening
    std::vector<FillParticle> fill;
    double funnel_height = 0.0;  // height where the funnel meets the side walls (m)
    double fill_top = 0.0;       // highest fill centre (m)
    double wall_top = 0.0;       // top of the side walls (m)
    // Centre line of the right-hand wall particles from the outlet up (mirror x for the left).
    std::vector<Vec2> outline;
};

// Where the centre line of the right funnel wall crosses the outlet plane y = 0, from D and
// how it is measured (params.hpp, OutletMeasure).
double wall_line_crossing(const HopperGeometry& g);

// Centre of the right edge disk (the lowest wall particle of the right funnel wall).
Vec2 edge_disk_centre(const HopperGeometry& g);

// The free gap between the two edge disks' surfaces: the narrowest opening of the outlet.
// Equals D for the default geometry.
double outlet_free_gap(const HopperGeometry& g);

// Half of the free width of the container at height y >= 0 (distance from the axis to the inner
// surface of the wall, measured horizontally).
double inner_half_width(const HopperGeometry& g, double y);

// Builds walls, gate and the fill lattice. The fill draws each particle's size (small with
// probability small_fraction) and a small random velocity from rng. Throws core::ConfigError when
// the particles cannot be placed (e.g. absurd geometry).
SceneLayout build_scene(const SceneParams& p, core::Rng& rng);

}  // namespace hopper::engine
