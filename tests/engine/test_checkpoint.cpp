// Checkpoints inside a realization (issue 15): a realization stopped at random time steps and
// resumed from its saved state ends bit-identical to one that never stopped, byte for byte of
// its encoded result (wall-clock measurements aside). Both integrators, with jams and shakes,
// with the fields observer on; interruptions while settling, flowing and shaking, and several
// in a row. A state is refused for another realization, another format or when damaged.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

#include "hopper/core/error.hpp"
#include "hopper/engine/checkpoint.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/store/codec.hpp"

namespace hopper::engine {
namespace {

using core::cm;
using core::deg;

// A 12 cm wide hopper of 300 particles with a 2 cm outlet: it jams and is shaken free a few
// times (the scene of test_realization.cpp's SmallOutletJamsAndShakingUnjamsIt).
SceneParams jamming(Scheme scheme, bool fields) {
    SceneParams p;
    p.hopper.width = 12.0 * cm;
    p.particles.count = 300;
    p.hopper.outlet = 2.0 * cm;
    p.hopper.theta = 45.0 * deg;
    p.material.collision_time = 8.0e-4;
    p.protocol.max_time = 30.0;
    p.integrator.scheme = scheme;
    p.integrator.steps_per_collision = 50.0;
    if (fields) {
        p.fields.enabled = true;
        p.fields.start = 0.05;
    }
    return p;
}

store::Bytes bytes_of(const RealizationResult& r) {
    return store::encode_result(store::without_wall_clock(r));
}

struct Stopped {};

// Runs (or resumes from `state`) and saves the state at the start of step `at` (counted from
// the start of this run), then stops. Returns the state.
std::vector<std::uint8_t> run_until(const SceneParams& p, std::uint64_t seed,
                                    const std::vector<std::uint8_t>* state, std::int64_t at,
                                    Phase* phase_at_stop) {
    std::atomic<bool> request{false};
    std::int64_t steps = 0;
    std::vector<std::uint8_t> saved;
    RunHooks hooks;
    hooks.progress_interval = 1e-12;  // every step
    hooks.on_progress = [&](const Progress& pr) {
        if (++steps == at) {
            request = true;
            *phase_at_stop = pr.phase;
        }
    };
    hooks.checkpoint_request = &request;
    hooks.on_checkpoint = [&](std::vector<std::uint8_t>&& b) {
        saved = std::move(b);
        throw Stopped{};
    };
    try {
        if (state)
            resume_realization(p, seed, *state, hooks);
        else
            run_realization(p, seed, hooks);
    } catch (const Stopped&) {
        return saved;
    }
    ADD_FAILURE() << "the realization ended before step " << at;
    return {};
}

struct Case {
    const char* name;
    Scheme scheme;
    bool fields;
    std::uint64_t seed;
    // Issue 12's contact corrections and issue 13's steady state (re-insertions draw from the
    // realization's generator, which the state must carry).
    bool steady_corrected = false;
    // Issue 39: rolling resistance as a spring (a third history column in the state).
    bool rolling_spring = false;
    // Issue 40: the steady state's lid (a load band the restored state must put back).
    bool lid = false;
    // Issue 41: the settle at a time step of its own (integrator.settle_steps_per_collision):
    // a state saved while settling holds Gear's derivatives scaled to it, one saved later to dt.
    double settle_delta = 0.0;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.name << " seed " << c.seed;
}

class CheckpointResume : public ::testing::TestWithParam<Case> {};

TEST_P(CheckpointResume, StoppedAtRandomStepsAndResumedEndsBitIdentical) {
    const Case c = GetParam();
    SceneParams p = jamming(c.scheme, c.fields);
    if (c.steady_corrected) {
        p.integrator.contact_corrections = true;
        p.protocol.mode = ProtocolMode::steady_state;
        p.protocol.jams_per_realization = 3;
    }
    if (c.lid) p.protocol.lid_gravity = 5.0;
    p.integrator.settle_steps_per_collision = c.settle_delta;
    if (c.rolling_spring) {
        p.material.mu_r = 0.05;
        p.material.rolling_law = RollingLaw::spring;
    }
    const RealizationResult ref = run_realization(p, c.seed);
    ASSERT_EQ(ref.status, Status::complete) << ref.message;
    ASSERT_GE(ref.n_jams, 1) << "the scene must jam for the test to cover the shake state";
    ASSERT_EQ(ref.fields.has_value(), c.fields);
    const std::int64_t total = ref.diagnostics.steps;
    const std::int64_t settle = ref.diagnostics.settle_steps;

    // Interruption points: one while settling, one inside the first shake, and random steps of
    // the discharge; then three interruptions of one realization in a row.
    std::int64_t in_shake = -1;
    for (const Event& e : ref.events)
        if (e.kind == Event::Kind::shake_start) {  // the settle's steps may be of another size
            in_shake =
                settle +
                std::llround((e.sim_time - ref.diagnostics.settle_time) / ref.diagnostics.dt) + 7;
            break;
        }
    ASSERT_GT(in_shake, 0);
    std::mt19937_64 gen(c.seed * 7919 + (c.fields ? 1 : 0));
    std::uniform_int_distribution<std::int64_t> any(settle + 1, total - 2);
    std::vector<std::int64_t> single{settle / 2, in_shake, any(gen), any(gen)};
    for (std::int64_t at : single) {
        Phase phase{};
        const auto state = run_until(p, c.seed, nullptr, at, &phase);
        ASSERT_FALSE(state.empty());
        const RealizationResult resumed = resume_realization(p, c.seed, state);
        EXPECT_EQ(bytes_of(resumed), bytes_of(ref))
            << c.name << ": stopped at step " << at << " of " << total << " (" << to_string(phase)
            << ")";
        std::printf("[ case ] %s seed %llu: stopped at step %lld of %lld (%s), resumed: %s\n",
                    c.name, (unsigned long long)c.seed, (long long)at, (long long)total,
                    std::string(to_string(phase)).c_str(),
                    bytes_of(resumed) == bytes_of(ref) ? "identical" : "DIFFERENT");
    }
    // Three interruptions in a row, each resumed from the previous checkpoint.
    std::vector<std::int64_t> cuts{any(gen), any(gen), any(gen)};
    std::sort(cuts.begin(), cuts.end());
    std::vector<std::uint8_t> state;
    std::int64_t done = 0;
    for (std::int64_t at : cuts) {
        if (at <= done) continue;
        Phase phase{};
        state = run_until(p, c.seed, state.empty() ? nullptr : &state, at - done, &phase);
        ASSERT_FALSE(state.empty());
        done = at;
    }
    const RealizationResult chained = resume_realization(p, c.seed, state);
    EXPECT_EQ(bytes_of(chained), bytes_of(ref))
        << c.name << ": stopped at steps " << cuts[0] << ", " << cuts[1] << ", " << cuts[2];
    EXPECT_EQ(chained.diagnostics.steps, total);
}

INSTANTIATE_TEST_SUITE_P(
    Engine, CheckpointResume,
    ::testing::Values(Case{"gear4", Scheme::gear4, false, 3},
                      Case{"verlet", Scheme::verlet, false, 2},
                      Case{"gear4_fields", Scheme::gear4, true, 2},
                      Case{"verlet_fields", Scheme::verlet, true, 1},
                      Case{"gear4_steady_corrected", Scheme::gear4, false, 1, true},
                      Case{"verlet_steady_corrected", Scheme::verlet, false, 2, true},
                      Case{"gear4_rolling_spring", Scheme::gear4, false, 2, false, true},
                      Case{"verlet_steady_rolling_spring", Scheme::verlet, false, 1, true, true},
                      Case{"gear4_steady_lid", Scheme::gear4, false, 1, true, false, true},
                      Case{"gear4_settle_step", Scheme::gear4, false, 3, false, false, false, 25.0},
                      Case{"verlet_settle_step", Scheme::verlet, false, 2, false, false, false,
                           20.0}),
    [](const ::testing::TestParamInfo<Case>& i) { return std::string(i.param.name); });

// The checkpoint format is a promise to the files users have: a state written by an earlier
// build (tests/engine/data/state-v2-gear4-fields.bin: format 2, written before the state was
// described once, issue 42; the jamming scene with fields, gear4, seed 2, stopped inside its
// first shake) still resumes here, to the uninterrupted realization bit for bit.
// HOPPER_WRITE_STATE_FIXTURE=PATH writes such a state (to make a fixture of a new format).
// Each state format's fixture, written by the build of its day: format 2 (round 3 to issue 42:
// the result's hand-written list; its build's results were format 4) and format 3 (the result
// walked by its description, results of format 5: arch_heights).
struct StateFixture {
    const char* file;
    std::uint16_t result_version;  // of the build that wrote it
};
class CheckpointFormat : public ::testing::TestWithParam<StateFixture> {};

TEST_P(CheckpointFormat, AStateWrittenByAnEarlierBuildStillResumesBitIdentical) {
    const SceneParams p = jamming(Scheme::gear4, true);
    const RealizationResult ref = run_realization(p, 2);
    ASSERT_GE(ref.n_jams, 1);
    if (const char* out = std::getenv("HOPPER_WRITE_STATE_FIXTURE")) {
        std::int64_t in_shake = -1;
        for (const Event& e : ref.events)
            if (e.kind == Event::Kind::shake_start) {
                in_shake = std::llround(e.sim_time / ref.diagnostics.dt) + 7;
                break;
            }
        Phase phase{};
        const auto state = run_until(p, 2, nullptr, in_shake, &phase);
        std::ofstream(out, std::ios::binary)
            .write(reinterpret_cast<const char*>(state.data()), std::streamsize(state.size()));
        std::printf("wrote %zu bytes at step %lld (%s)\n", state.size(), (long long)in_shake,
                    std::string(to_string(phase)).c_str());
    }
    const std::string path =
        std::string(HOPPER_SOURCE_DIR) + "/tests/engine/data/" + GetParam().file;
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << path;
    const std::vector<std::uint8_t> state((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    ASSERT_GT(state.size(), 1000u);
    const RealizationResult resumed = resume_realization(p, 2, state);
    // The arrays of members added after the fixture's build have no values for the jams before
    // the state, so the resumed result leaves them out (drop_incomplete_arrays): it is the
    // uninterrupted one without them, bit for bit.
    RealizationResult then = ref;
    for_each_result_field([&](const auto& f) {
        using M = std::remove_cvref_t<decltype(then.*f.member)>;
        if constexpr (is_std_vector<M>)
            if (f.since > GetParam().result_version) (then.*f.member).clear();
    });
    ASSERT_FALSE(ref.arch_heights.empty());
    EXPECT_EQ(resumed.arch_heights.empty(), GetParam().result_version < 5);
    EXPECT_EQ(bytes_of(resumed), bytes_of(then));
    EXPECT_EQ(resumed.n_jams, ref.n_jams);
}

INSTANTIATE_TEST_SUITE_P(Fixtures, CheckpointFormat,
                         ::testing::Values(StateFixture{"state-v2-gear4-fields.bin", 4},
                                           StateFixture{"state-v3-gear4-fields.bin", 5}),
                         [](const auto& info) {
                             return std::string(info.param.file).substr(6, 2);
                         });

// Format 3 saves the result by walking its description: every described member, set to a value
// other than its default, comes back (a member the walk left out would come back as its default).
TEST(CheckpointResult, EveryDescribedMemberIsSavedAndRestored) {
    RealizationResult x;
    x.status = Status::arrested;
    x.message = "m";
    x.seed = 7;
    x.particles = 3;
    x.wall_particles = 4;
    x.survival_times = {0.5, 1.5};
    x.censored = {false, true};
    x.jam_onsets = {0.5};
    x.shakes_per_jam = {2};
    x.avalanche_sizes = {5, 6};
    x.arches.resize(1);
    x.arches[0].ids = {1, 2};
    x.arches[0].x = {0.1, 0.2};
    x.arches[0].y = {0.3, 0.4};
    x.arches[0].span = 0.05;
    x.arches[0].max_angle = 2.5;
    x.n_jams = 1;
    x.n_shakes = 2;
    x.n_jams_multi_shake = 1;
    x.empty_time = 9.0;
    x.discharge_rate = 8.0;
    x.discharge_rate_mass = 0.25;
    x.discharged = 2;
    x.exit_times = {1.0, 2.0};
    x.curve_time = {0.0};
    x.curve_count = {3};
    x.events = {{Event::Kind::jam, 0.5, 0.7, 2}};
    x.fields.emplace();
    x.fields->windows = {1};
    x.fields->grid.nx = 1;
    x.fields->grid.ny = 1;
    x.fields->weight = {1.0};
    for (int f = 0; f < field_count; ++f) {
        x.fields->mean[f] = {0.5};
        x.fields->m2[f] = {0.25};
    }
    double next = 1.0;
    for_each_diagnostic([&](const auto& f) {
        auto& v = x.diagnostics.*f.member;
        if constexpr (std::is_same_v<std::remove_cvref_t<decltype(v)>, std::string>)
            v = "avx2";
        else
            v = static_cast<std::remove_cvref_t<decltype(v)>>(next++);
    });
    StateWriter w;
    save_result(x, w);
    const std::vector<std::uint8_t> bytes = w.take();
    StateReader r(bytes);
    RealizationResult y;
    restore_result(y, r, state_format_version);
    EXPECT_TRUE(r.at_end());
    for_each_result_field([&](const auto& f) {
        using M = std::remove_cvref_t<decltype(x.*f.member)>;
        constexpr bool plain =
            std::is_arithmetic_v<M> || std::is_enum_v<M> || std::is_same_v<M, std::string> ||
            std::is_same_v<M, std::vector<double>> || std::is_same_v<M, std::vector<int>> ||
            std::is_same_v<M, std::vector<bool>> || std::is_same_v<M, std::optional<double>>;
        if constexpr (plain)
            EXPECT_EQ(y.*f.member, x.*f.member) << f.name;
        else
            EXPECT_EQ(holds_value(y.*f.member), holds_value(x.*f.member)) << f.name;
    });
    for_each_diagnostic([&](const auto& f) {
        EXPECT_EQ(y.diagnostics.*f.member, x.diagnostics.*f.member) << f.name;
    });
    ASSERT_EQ(y.events.size(), 1u);
    EXPECT_EQ(y.events[0].kind, Event::Kind::jam);
    EXPECT_EQ(y.events[0].in_hopper, 2);
    ASSERT_EQ(y.arches.size(), 1u);
    EXPECT_EQ(y.arches[0].y, x.arches[0].y);
    EXPECT_EQ(y.arches[0].max_angle, 2.5);
    ASSERT_TRUE(y.fields);
    EXPECT_EQ(y.fields->m2[field_count - 1], std::vector<double>{0.25});
}

TEST(CheckpointRefusal, AnotherRealizationFormatOrDamageIsRefusedWithTheReason) {
    const SceneParams p = jamming(Scheme::gear4, false);
    Phase phase{};
    const auto state = run_until(p, 1, nullptr, 500, &phase);
    ASSERT_FALSE(state.empty());
    auto message_of = [&](const SceneParams& q, std::uint64_t seed,
                          std::span<const std::uint8_t> b) -> std::string {
        try {
            resume_realization(q, seed, b);
        } catch (const core::ConfigError& e) {
            return e.what();
        }
        return "accepted";
    };
    EXPECT_NE(message_of(p, 2, state).find("seed 1 (this realization: 2)"), std::string::npos);
    SceneParams verlet = p;
    verlet.integrator.scheme = Scheme::verlet;
    EXPECT_NE(message_of(verlet, 1, state).find("another integrator"), std::string::npos);
    SceneParams stiffer = p;
    stiffer.material.collision_time = 6.0e-4;
    EXPECT_NE(message_of(stiffer, 1, state).find("k_n"), std::string::npos);
    auto other_format = state;
    other_format[16] ^= 0x7f;  // the format version, after the 8-byte length and "HOPPERRS"
    EXPECT_NE(message_of(p, 1, other_format).find("state format"), std::string::npos);
    const std::vector<std::uint8_t> truncated(state.begin(), state.begin() + state.size() / 2);
    EXPECT_NE(message_of(p, 1, truncated).find("truncated or damaged"), std::string::npos);
    const std::vector<std::uint8_t> garbage(100, 0x41);
    EXPECT_NE(message_of(p, 1, garbage).find("not a hopper realization state"), std::string::npos);
}

// Issue 29, item 1: a state whose checksum would be right but whose content is not (a bug or a
// memory error before the write, a hand edit) is refused with the reason, never run: a row
// start of the neighbour list set to -1000000 crashed every resume before.
TEST(CheckpointRefusal, AStateThatBreaksItsInvariantsIsRefused) {
    const SceneParams p = jamming(Scheme::gear4, false);
    Phase phase{};
    const auto state = run_until(p, 1, nullptr, 500, &phase);
    ASSERT_FALSE(state.empty());
    // The neighbour list's row starts: a vector of n + 1 ints from 0, non-decreasing, followed
    // by the partner list whose length is their last value.
    const std::uint64_t n = 300;
    auto u64_at = [&](std::size_t o) {
        std::uint64_t v;
        std::memcpy(&v, state.data() + o, 8);
        return v;
    };
    auto i32_at = [&](std::size_t o) {
        std::int32_t v;
        std::memcpy(&v, state.data() + o, 4);
        return v;
    };
    std::size_t pstart = 0;
    for (std::size_t o = 0; o + 8 + 4 * (n + 1) + 8 <= state.size() && !pstart; ++o) {
        if (u64_at(o) != n + 1 || i32_at(o + 8) != 0) continue;
        bool monotone = true;
        for (std::size_t k = 1; k <= n && monotone; ++k)
            monotone = i32_at(o + 8 + 4 * k) >= i32_at(o + 8 + 4 * (k - 1));
        const auto last = i32_at(o + 8 + 4 * n);
        if (monotone && last > 0 && u64_at(o + 8 + 4 * (n + 1)) == std::uint64_t(last))
            pstart = o + 8;
    }
    ASSERT_NE(pstart, 0u) << "row starts of the neighbour list not found in the state";
    auto message_of = [&](const std::vector<std::uint8_t>& b) -> std::string {
        try {
            resume_realization(p, 1, b);
        } catch (const core::ConfigError& e) {
            return e.what();
        }
        return "accepted";
    };
    auto with_i32 = [&](std::size_t o, std::int32_t v) {
        auto b = state;
        std::memcpy(b.data() + o, &v, 4);
        return b;
    };
    EXPECT_NE(message_of(with_i32(pstart + 4 * 5, -1000000)).find("row start"), std::string::npos);
    EXPECT_NE(message_of(with_i32(pstart + 4 * 5, 1 << 30)).find("row start"), std::string::npos);
    // The first partner of the list (after the row starts and its count): the owner itself.
    const std::size_t pj = pstart + 4 * (n + 1) + 8;
    const auto first_owner_with_partner = [&] {
        for (std::size_t i = 0; i < n; ++i)
            if (i32_at(pstart + 4 * (i + 1)) > 0) return std::int32_t(i);
        return std::int32_t(-1);
    }();
    ASSERT_GE(first_owner_with_partner, 0);
    EXPECT_NE(message_of(with_i32(pj, first_owner_with_partner)).find("partner out of range"),
              std::string::npos);
    EXPECT_NE(message_of(with_i32(pj, 1 << 20)).find("partner out of range"), std::string::npos);
    // A NaN in the positions: the first three vectors of n doubles in a row (x, y, vx).
    std::size_t x = 0;
    for (std::size_t o = 0; o + 24 + 24 * n <= pstart && !x; ++o)
        if (u64_at(o) == n && u64_at(o + 8 + 8 * n) == n && u64_at(o + 16 + 16 * n) == n) x = o + 8;
    ASSERT_NE(x, 0u) << "positions not found in the state";
    auto b = state;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::memcpy(b.data() + x + 8 * 3, &nan, 8);
    EXPECT_NE(message_of(b).find("non-finite"), std::string::npos);
}

}  // namespace
}  // namespace hopper::engine
