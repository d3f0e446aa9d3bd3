// The neighbour list (cell grid + Verlet skin, rebuilt when a particle has moved more than half
// the skin) must never miss a contact: System::contacts_from_list() has to equal a brute-force
// O(N^2) search over all mobile-mobile and mobile-wall pairs (wall-wall pairs never interact),
// before any step, after small moves, and after large displacements that force many rebuilds.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "physics_fixture.hpp"

namespace {

using namespace hopper::engine;
using namespace hopper::engine::testing;

using PairSet = std::set<std::pair<int, int>>;

std::pair<int, int> ordered(int a, int b) {
    return {std::min(a, b), std::max(a, b)};
}

// All overlapping pairs by brute force, with walls at base position + offset.
PairSet brute_force(const System& s) {
    PairSet out;
    const int n = s.mobile_count();
    const auto x = s.x(), y = s.y(), r = s.r();
    const auto ids = s.ids();
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            const double dx = x[i] - x[j], dy = y[i] - y[j], rs = r[i] + r[j];
            if (dx * dx + dy * dy < rs * rs) out.insert(ordered(ids[i], ids[j]));
        }
    const auto wx = s.wall_x(), wy = s.wall_y(), wr = s.wall_r();
    const auto wid = s.wall_ids();
    const Vec2 off = s.wall_offset();
    for (int i = 0; i < n; ++i)
        for (std::size_t k = 0; k < wx.size(); ++k) {
            const double dx = x[i] - (wx[k] + off.x()), dy = y[i] - (wy[k] + off.y());
            const double rs = r[i] + wr[k];
            if (dx * dx + dy * dy < rs * rs) out.insert(ordered(ids[i], wid[k]));
        }
    return out;
}

PairSet from_list(System& s) {
    PairSet out;
    for (const auto& [a, b] : s.contacts_from_list())
        out.insert(ordered(a, b));
    return out;
}

// Reports the first few differences, so a failure says which pairs were missed or invented.
void expect_same(System& s, const char* when) {
    const PairSet list = from_list(s), brute = brute_force(s);
    std::vector<std::pair<int, int>> missed, extra;
    std::set_difference(brute.begin(), brute.end(), list.begin(), list.end(),
                        std::back_inserter(missed));
    std::set_difference(list.begin(), list.end(), brute.begin(), brute.end(),
                        std::back_inserter(extra));
    EXPECT_TRUE(missed.empty() && extra.empty())
        << when << ": " << brute.size() << " contacts by brute force, " << list.size()
        << " from the list; missed " << missed.size()
        << " (first: " << (missed.empty() ? -1 : missed[0].first) << "-"
        << (missed.empty() ? -1 : missed[0].second) << "), extra " << extra.size();
}

// 500 disks of both sizes at random positions in a 0.25 m box of wall disks (random overlaps
// allowed, up to 0.3 d_small deep), plus 40 wall disks of random sizes scattered inside, which
// exercise the wall grid away from the boundary.
std::unique_ptr<System> random_system(Scheme scheme, std::mt19937_64& gen) {
    const ContactParams cp = contact_params(0.5, 0.5);
    auto s = std::make_unique<System>(system_config(scheme, 50.0, cp, cp));
    const double L = 0.25, dw = d_large;
    std::uniform_real_distribution<double> U(0.0, 1.0);
    for (double t = -0.5 * dw; t <= L + 0.5 * dw; t += 0.5 * dw) {
        s->add_wall(Vec2(t, -0.5 * dw), dw);
        s->add_wall(Vec2(t, L + 0.5 * dw), dw);
        s->add_wall(Vec2(-0.5 * dw, t), dw);
        s->add_wall(Vec2(L + 0.5 * dw, t), dw);
    }
    std::vector<Vec2> inner;
    std::vector<double> inner_d;
    for (int k = 0; k < 40; ++k) {
        inner.emplace_back(0.1 * L + 0.8 * L * U(gen), 0.1 * L + 0.8 * L * U(gen));
        inner_d.push_back((0.5 + 2.0 * U(gen)) * d_large);
        s->add_wall(inner.back(), inner_d.back());
    }
    std::vector<Vec2> pos;
    std::vector<double> dia;
    while (pos.size() < 500) {
        const double d = U(gen) < 0.62 ? d_small : d_large;
        const Vec2 p(0.5 * d + (L - d) * U(gen), 0.5 * d + (L - d) * U(gen));
        bool ok = true;
        for (std::size_t k = 0; k < pos.size() && ok; ++k)
            ok = (p - pos[k]).norm() > 0.5 * (d + dia[k]) - 0.3 * d_small;
        for (std::size_t k = 0; k < inner.size() && ok; ++k)
            ok = (p - inner[k]).norm() > 0.5 * (d + inner_d[k]) - 0.3 * d_small;
        if (!ok) continue;
        pos.push_back(p);
        dia.push_back(d);
    }
    std::uniform_real_distribution<double> V(-0.2, 0.2);
    for (std::size_t k = 0; k < pos.size(); ++k)
        add_disk(*s, pos[k], dia[k], Vec2(V(gen), V(gen)), 10.0 * V(gen));
    return s;
}

class Neighbors : public ::testing::TestWithParam<Scheme> {};

TEST_P(Neighbors, ListFindsExactlyTheOverlappingPairs) {
    std::mt19937_64 gen(99);
    auto s = random_system(GetParam(), gen);
    expect_same(*s, "before the first step");
    EXPECT_GT(brute_force(*s).size(), 50u);  // the random placement does produce contacts
    for (int k = 1; k <= 10; ++k) {
        s->step();
        expect_same(*s, "after a few steps");
    }
    // Shake them up: fast random velocities (up to 2 m/s per component, i.e. 3e-5 m per step:
    // the skin of 1.5e-3 m is used up within ~25 steps, so the list is rebuilt often).
    std::uniform_real_distribution<double> V(-2.0, 2.0);
    for (int i = 0; i < s->mobile_count(); ++i)
        s->set_velocity(i, Vec2(V(gen), V(gen)), 0.0);
    const auto rebuilds0 = s->neighbor_rebuilds();
    for (int k = 0; k < 2000; ++k) {
        s->step();
        if (k % 25 == 0) expect_same(*s, "while moving fast");
        if (HasFailure()) return;
    }
    EXPECT_GT(s->neighbor_rebuilds() - rebuilds0, 20);
    // Moving walls (the shaking protocol): a rigid offset of the walls must be seen too.
    s->set_wall_motion(Vec2(0.3 * d_large, -0.2 * d_large), Vec2::Zero());
    s->step();
    expect_same(*s, "after a wall offset");
    for (int k = 0; k < 200; ++k) {
        const double t = 1e-4 * k;
        s->set_wall_motion(
            Vec2(0.3 * d_large * std::cos(300.0 * t), 0.5 * d_large * std::sin(300.0 * t)),
            Vec2::Zero());
        s->step();
        if (k % 10 == 0) expect_same(*s, "while the walls move");
    }
}

INSTANTIATE_TEST_SUITE_P(BothSchemes, Neighbors, ::testing::Values(Scheme::verlet, Scheme::gear4),
                         [](const ::testing::TestParamInfo<Scheme>& p) {
                             return to_string(p.param);
                         });

}  // namespace
