// Issue 12: every force path gives the same bits. The reference loop and each batched path this
// CPU can run (baseline, AVX2, AVX-512) run the same hopper through settling, the opening and
// part of the discharge; the full particle state and the result must be identical, for every
// contact law, both integrators, with and without the contact corrections and the lever arm.
// Round 3: so do the fused arrangements of the integrator's passes (StepFusion: the corrector
// inside the force pass, and the predictor too), on the reference and on the last batched path.
// Round 3, third session: the whole System's state is compared too (its checkpoint bytes: the
// springs of every list entry, with the sign of their zeros, the forces, the Gear derivatives and
// the list), since the force passes reset the springs of the entries that do not touch by a mask
// on their bits.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "hopper/core/error.hpp"
#include "hopper/engine/checkpoint.hpp"
#include "hopper/engine/realization.hpp"
#include "hopper/engine/system.hpp"

using namespace hopper::engine;

namespace {

SceneParams small_hopper() {
    SceneParams p;
    p.hopper.width = 12.0 * cm;
    p.particles.count = 300;
    p.hopper.outlet = 3.0 * cm;
    p.hopper.theta = 45.0 * deg;
    p.material.collision_time = 8.0e-4;
    p.integrator.steps_per_collision = 50.0;
    p.protocol.settle_max_time = 1.5;  // settle may end unsettled: the comparison holds anyway
    return p;
}

struct State {
    std::vector<double> x, y, vx, vy, w;
    std::vector<int> id;
    double wall_fx, wall_fy, max_overlap;
    int contacts;
    RealizationResult result;
    std::vector<std::uint8_t> system;  // the System's checkpoint bytes, without its timings
};

// The System's whole state as checkpoint bytes (CheckpointAccess::save), less the three
// phase timings (PhaseSeconds, doubles) that it writes last: they are the only part that
// differs between runs of the same bits.
std::vector<std::uint8_t> system_bytes(const System& s) {
    StateWriter w;
    CheckpointAccess::save(s, w);
    std::vector<std::uint8_t> b = w.take();
    b.resize(b.size() - 3 * sizeof(double));
    return b;
}

State run(const SceneParams& p, KernelPath path, StepFusion fusion = StepFusion::none) {
    RunHooks hooks;
    hooks.kernel = path;
    Realization r(p, 7, hooks);
    r.system().set_step_fusion(fusion);
    r.settle();
    r.open();
    r.advance(0.4);
    const System& s = r.system();
    State st;
    auto copy = [](std::span<const double> c) { return std::vector<double>(c.begin(), c.end()); };
    st.x = copy(s.x());
    st.y = copy(s.y());
    st.vx = copy(s.vx());
    st.vy = copy(s.vy());
    st.w = copy(s.w());
    st.id.assign(s.ids().begin(), s.ids().end());
    st.wall_fx = s.wall_force().x();
    st.wall_fy = s.wall_force().y();
    st.max_overlap = s.max_overlap();
    st.contacts = s.contact_count();
    st.result = r.result();
    st.system = system_bytes(s);
    return st;
}

// Bitwise: memcmp, so that even the sign of a zero must agree.
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

void expect_identical(const State& a, const State& b, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(a.id, b.id);
    EXPECT_TRUE(same_bits(a.x, b.x));
    EXPECT_TRUE(same_bits(a.y, b.y));
    EXPECT_TRUE(same_bits(a.vx, b.vx));
    EXPECT_TRUE(same_bits(a.vy, b.vy));
    EXPECT_TRUE(same_bits(a.w, b.w));
    EXPECT_EQ(std::memcmp(&a.wall_fx, &b.wall_fx, sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(&a.wall_fy, &b.wall_fy, sizeof(double)), 0);
    EXPECT_EQ(a.max_overlap, b.max_overlap);
    EXPECT_EQ(a.contacts, b.contacts);
    EXPECT_TRUE(same_bits(a.result.exit_times, b.result.exit_times));
    EXPECT_EQ(a.result.diagnostics.steps, b.result.diagnostics.steps);
    EXPECT_EQ(a.result.diagnostics.neighbor_rebuilds, b.result.diagnostics.neighbor_rebuilds);
    EXPECT_TRUE(a.system == b.system) << "the System's checkpoint bytes differ";
}

std::vector<KernelPath> batched_paths() {
    std::vector<KernelPath> out{KernelPath::baseline};
    for (KernelPath p : {KernelPath::avx2, KernelPath::avx512, KernelPath::avx512_gather}) {
        try {
            SystemConfig sc;
            sc.kernel = p;
            System s(sc);
            out.push_back(p);
        } catch (const hopper::core::ConfigError&) {
            std::printf("note: this CPU cannot run the %s path; not compared\n",
                        to_string(p).c_str());
        }
    }
    return out;
}

struct Case {
    std::string name;
    SceneParams p;
};

std::vector<Case> cases() {
    std::vector<Case> out;
    for (Scheme scheme : {Scheme::gear4, Scheme::verlet})
        for (bool corr : {false, true}) {
            SceneParams p = small_hopper();
            p.integrator.scheme = scheme;
            p.integrator.contact_corrections = corr;
            const std::string tag = to_string(scheme) + (corr ? " corrected" : "");
            out.push_back({tag + ", spring friction", p});
            SceneParams v = p;
            v.material.kt_over_kn = 0.0;
            out.push_back({tag + ", viscous friction", v});
            SceneParams f = p;
            f.material.system.mu = f.material.wall.mu = 0.0;
            out.push_back({tag + ", frictionless", f});
            // Issue 28: the Hertz law (its stiffness from the material, not collision_time_s).
            SceneParams h = p;
            h.material.normal_law = NormalLaw::hertz;
            h.material.collision_time.reset();
            out.push_back({tag + ", Hertz", h});
            // Rolling resistance on the spring law and on the Hertz law.
            SceneParams r = p;
            r.material.mu_r = 0.1;
            out.push_back({tag + ", spring friction, rolling resistance", r});
            r.material.rolling_law = RollingLaw::spring;  // issue 39
            out.push_back({tag + ", spring friction, rolling spring", r});
            h.material.mu_r = 0.1;
            out.push_back({tag + ", Hertz, rolling resistance", h});
        }
    SceneParams l = small_hopper();
    l.material.lever_arm = LeverArm::contact;
    l.integrator.contact_corrections = true;
    out.push_back({"gear4 corrected, lever arm R - x/2", l});
    SceneParams o = small_hopper();
    o.material.slip_rule = SlipRule::spring_only;
    out.push_back({"gear4, slip rule spring only", o});
    return out;
}

TEST(KernelPaths, EveryPathGivesTheReferenceBits) {
    const std::vector<KernelPath> paths = batched_paths();
    for (const Case& c : cases()) {
        const State ref = run(c.p, KernelPath::reference);
        // The comparison has teeth only if the scene moved and touched.
        ASSERT_GT(ref.contacts, 100) << c.name;
        ASSERT_GT(ref.result.exit_times.size(), 10u) << c.name;
        for (KernelPath path : paths)
            expect_identical(ref, run(c.p, path), c.name + ", " + to_string(path));
        for (StepFusion f : {StepFusion::corrector, StepFusion::step})
            expect_identical(ref, run(c.p, KernelPath::reference, f),
                             c.name + ", reference, fusion " + to_string(f));
        expect_identical(ref, run(c.p, paths.back(), StepFusion::step),
                         c.name + ", " + to_string(paths.back()) + ", fusion step");
    }
}

TEST(KernelPaths, AutomaticResolvesToAConcretePathAndNamesAreParsed) {
    System s{SystemConfig()};
    EXPECT_NE(s.kernel_path(), KernelPath::automatic);
    EXPECT_EQ(parse_kernel_path("avx512"), KernelPath::avx512);
    EXPECT_EQ(parse_kernel_path("avx512-gather"), KernelPath::avx512_gather);
    EXPECT_EQ(to_string(KernelPath::avx512_gather), "avx512-gather");
    EXPECT_EQ(parse_kernel_path("auto"), KernelPath::automatic);
    try {
        parse_kernel_path("sse9");
        FAIL() << "an unknown path was accepted";
    } catch (const hopper::core::ConfigError& e) {
        EXPECT_NE(
            std::string(e.what()).find("auto, reference, baseline, avx2, avx512 or avx512-gather"),
            std::string::npos);
    }
}

}  // namespace
