#include "hopper/engine/arch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hopper/core/units.hpp"

namespace hopper::engine {

namespace {

constexpr double two_pi = 2.0 * core::pi;

// Angle in (0, 2 pi] (0 is mapped to 2 pi: the same direction comes last).
double turn(double a) {
    a = std::fmod(a, two_pi);
    if (a <= 0.0) a += two_pi;
    return a;
}

struct Graph {
    std::span<const ArchDisk> d;
    std::vector<int> keep;              // indices into d that take part
    std::vector<std::vector<int>> nbr;  // by position in d

    double dir(int from, int to) const {
        return std::atan2(d[to].y - d[from].y, d[to].x - d[from].x);
    }

    // Walks the boundary of the empty region below the arch from bond (u, v) until a wall disk
    // is reached. ccw: the next bond is the first counterclockwise from the way back (walking
    // to the right, the region on the right); otherwise clockwise. Returns the nodes after u,
    // loops cut out; empty when no wall is reached.
    std::vector<int> walk(int u, int v, bool ccw) const {
        std::vector<int> path{v};
        const std::size_t limit = 4 * keep.size() + 8;
        for (std::size_t step = 0; !d[v].wall; ++step) {
            if (step > limit) return {};
            const double back = dir(v, u);
            int best = -1;
            double best_angle = std::numeric_limits<double>::infinity();
            for (int w : nbr[v]) {
                const double a = ccw ? turn(dir(v, w) - back) : turn(back - dir(v, w));
                if (a < best_angle) {
                    best_angle = a;
                    best = w;
                }
            }
            if (best < 0) return {};  // an isolated disk (cannot happen: u is a neighbour)
            u = v;
            v = best;
            const auto seen = std::find(path.begin(), path.end(), v);
            if (seen != path.end())
                path.erase(seen + 1, path.end());  // a loop (a dangling branch): cut it out
            else
                path.push_back(v);
        }
        return path;
    }
};

}  // namespace

Arch find_arch(std::span<const ArchDisk> disks, double y_floor) {
    Graph g{disks, {}, std::vector<std::vector<int>>(disks.size())};
    for (std::size_t i = 0; i < disks.size(); ++i)
        if (disks[i].wall || disks[i].y >= y_floor) g.keep.push_back(int(i));
    // Contacts; wall disks never touch each other in the model (and are not bonds of an arch).
    struct Bond {
        int a, b;
    };
    std::vector<Bond> bonds;
    for (std::size_t p = 0; p < g.keep.size(); ++p)
        for (std::size_t q = p + 1; q < g.keep.size(); ++q) {
            const int i = g.keep[p], j = g.keep[q];
            if (disks[i].wall && disks[j].wall) continue;
            const double dx = disks[i].x - disks[j].x, dy = disks[i].y - disks[j].y;
            const double reach = (disks[i].r + disks[j].r) * (1.0 + arch_contact_tolerance);
            if (dx * dx + dy * dy <= reach * reach) {
                g.nbr[i].push_back(j);
                g.nbr[j].push_back(i);
                bonds.push_back({i, j});
            }
        }
    // The first bond the line x = 0 meets going up (a left end at x <= 0, a right end at x > 0).
    int left = -1, right = -1;
    double lowest = std::numeric_limits<double>::infinity();
    for (const Bond& b : bonds) {
        int l = b.a, r = b.b;
        if (disks[l].x > disks[r].x) std::swap(l, r);
        if (!(disks[l].x <= 0.0 && disks[r].x > 0.0)) continue;
        const double y =
            disks[l].y + (0.0 - disks[l].x) * (disks[r].y - disks[l].y) / (disks[r].x - disks[l].x);
        if (y > y_floor && y < lowest) {
            lowest = y;
            left = l;
            right = r;
        }
    }
    Arch arch;
    if (left < 0) return arch;
    const std::vector<int> to_right = g.walk(left, right, true);
    const std::vector<int> to_left = g.walk(right, left, false);
    if (to_right.empty() || to_left.empty()) return arch;
    std::vector<int> chain(to_left.rbegin(), to_left.rend());
    for (int v : to_right) {
        const auto seen = std::find(chain.begin(), chain.end(), v);
        if (seen != chain.end())
            chain.erase(seen + 1, chain.end());
        else
            chain.push_back(v);
    }
    if (chain.size() < 3) return arch;
    const ArchDisk& wl = disks[chain.front()];
    const ArchDisk& wr = disks[chain.back()];
    if (!(wl.wall && wr.wall && wl.x < 0.0 && wr.x > 0.0)) return arch;
    for (std::size_t k = 1; k + 1 < chain.size(); ++k)
        if (disks[chain[k]].wall) return arch;
    // The contact points with the walls: on each end disk's surface towards its wall disk.
    const auto contact = [&](int mobile, int wall, double& cx, double& cy) {
        const ArchDisk& m = disks[mobile];
        const ArchDisk& w = disks[wall];
        const double dx = w.x - m.x, dy = w.y - m.y, len = std::hypot(dx, dy);
        cx = m.x + m.r * dx / len;
        cy = m.y + m.r * dy / len;
    };
    double lx, ly, rx, ry;
    contact(chain[1], chain.front(), lx, ly);
    contact(chain[chain.size() - 2], chain.back(), rx, ry);
    arch.span = std::hypot(rx - lx, ry - ly);
    for (std::size_t k = 1; k + 1 < chain.size(); ++k) {
        const int v = chain[k];
        arch.ids.push_back(disks[v].id);
        arch.x.push_back(disks[v].x);
        arch.y.push_back(disks[v].y);
        // Clockwise from the bond to the right-hand neighbour to the bond to the left-hand one.
        const double a = turn(g.dir(v, chain[k + 1]) - g.dir(v, chain[k - 1]));
        arch.max_angle = std::max(arch.max_angle, a);
    }
    return arch;
}

std::vector<int> arch_removal(std::span<const ArchDisk> disks, double y_floor, double y_outlet,
                              double reach) {
    Arch arch = find_arch(disks, y_floor);
    if (arch.found()) return std::move(arch.ids);
    std::vector<int> out;
    double best = std::numeric_limits<double>::infinity();
    for (const ArchDisk& d : disks) {
        if (d.wall || d.y < y_outlet || std::abs(d.x) > reach) continue;
        const double d2 = d.x * d.x + (d.y - y_outlet) * (d.y - y_outlet);
        if (d2 < best) {
            best = d2;
            out.assign(1, d.id);
        }
    }
    return out;
}

}  // namespace hopper::engine
