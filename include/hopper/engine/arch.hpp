#pragma once
// The arch that blocks the outlet at a jam (issue 13): the chain of touching mobile disks that
// spans the outlet from a wall disk on the left to a wall disk on the right, found from the
// contact network as the lower boundary of the packing above the outlet (docs/model.md, "The
// arch at each jam").

#include <span>
#include <vector>

namespace hopper::engine {

// One disk handed to the finder: a mobile particle or a wall particle (centre and radius in m).
struct ArchDisk {
    int id = -1;
    double x = 0.0, y = 0.0, r = 0.0;
    bool wall = false;
};

struct Arch {
    // The mobile disks of the arch, from the left wall to the right wall.
    std::vector<int> ids;
    std::vector<double> x, y;  // m, centres at the moment the jam was detected
    // Distance between the arch's two contact points with the walls (m): where the end disks
    // touch the wall disks they rest on.
    double span = 0.0;
    // Largest angle between consecutive bonds (rad): at each arch disk, the angle from the bond
    // to its right-hand neighbour clockwise (through the outlet side) to the bond to its
    // left-hand neighbour; the end disks' neighbours are the wall disks. A straight horizontal
    // chain has pi at every disk; an arch bulging upward has less; more than pi is a disk that
    // sticks out downward (a "defect" of the arch).
    double max_angle = 0.0;
    bool found() const { return !ids.empty(); }
};

// Two disks touch when their centre distance is at most (r_i + r_j)(1 + contact_tolerance).
inline constexpr double arch_contact_tolerance = 1e-9;

// Finds the arch over the outlet centred at x = 0: the first bond of the contact network that
// the vertical line x = 0 meets going up from y_floor, then the boundary of the empty region
// below it followed to the left and to the right (at each disk the next bond is the first one
// turning towards the outlet side) until a wall disk is reached. Returns an arch only when that
// boundary ends on a wall disk with x < 0 on the left and one with x > 0 on the right; a chain
// that stops (a disk with no further contact), loops back, or ends on a wall on the same side
// is not an arch (found() is false). Disks below y_floor are ignored (they are falling).
Arch find_arch(std::span<const ArchDisk> disks, double y_floor);

// What protocol.unjam = remove_arch takes out of the hopper at a jam (docs/model.md, step 5):
// the mobile disks of the arch find_arch(disks, y_floor) returns; when there is none, the mobile
// disk whose centre is nearest to the outlet's centre (0, y_outlet) among those at or above
// y_outlet with |x| <= reach; nothing when there is no such disk either.
std::vector<int> arch_removal(std::span<const ArchDisk> disks, double y_floor, double y_outlet,
                              double reach);

}  // namespace hopper::engine
