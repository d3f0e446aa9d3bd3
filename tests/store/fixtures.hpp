#pragma once
// Shared helpers of the store tests: fabricated results with every field set, small plans, and
// scratch directories.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "hopper/engine/result.hpp"
#include "hopper/store/codec.hpp"
#include "hopper/store/records.hpp"

namespace hopper::store::testing {

namespace fs = std::filesystem;

// A fresh scratch directory named after the running test.
inline fs::path scratch() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::path(HOPPER_BINARY_DIR) / "tests" / "store" / "tmp" /
                         (std::string(info->test_suite_name()) + "." + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// A result with every field set to something distinctive (derived from `k`).
inline engine::RealizationResult fabricated(int k, bool with_optionals = true) {
    engine::RealizationResult r;
    r.status = static_cast<engine::Status>(k % 4);
    r.message = "message " + std::to_string(k) + " \xc3\xa9";  // UTF-8 passes through
    r.seed = 1000u + static_cast<unsigned>(k);
    r.particles = 80 + k;
    r.wall_particles = 40 + k;
    for (int i = 0; i <= k % 3; ++i) {
        r.survival_times.push_back(0.125 * (i + 1) + k * 1e-3);
        r.censored.push_back(i == k % 3);
    }
    for (int i = 0; i < k % 3; ++i) {
        r.jam_onsets.push_back(0.5 * (i + 1) + 1.0 / 3.0);
        r.shakes_per_jam.push_back(i + 1);
    }
    r.n_jams = static_cast<int>(r.jam_onsets.size());
    r.n_shakes = 2 * r.n_jams;
    r.n_jams_multi_shake = r.n_jams > 1 ? 1 : 0;
    if (with_optionals) {
        r.empty_time = 1.5 + k * 0.1;
        r.discharge_rate = 55.25 + k;
    }
    r.discharge_rate_mass = with_optionals ? 0.0125 * (k + 1) : 0.0;
    r.discharged = 70 + k;
    for (int i = 0; i < 5 + k; ++i)
        r.exit_times.push_back(0.01 * i + 1e-9 * k);
    for (int i = 0; i < 4 + k; ++i) {
        r.curve_time.push_back(0.01 * i);
        r.curve_count.push_back(100 - i);
    }
    r.events = {{engine::Event::Kind::settled, 0.0, 0.3, 80},
                {engine::Event::Kind::opened, 0.0, 0.3, 80},
                {engine::Event::Kind::jam, 0.4, 0.75, 50 - k},
                {engine::Event::Kind::empty, 1.5, 2.0, 0}};
    auto& d = r.diagnostics;
    d.steps = 123456 + k;
    d.settle_steps = 2345;
    d.neighbor_rebuilds = 77;
    d.settle_time = 0.3;
    d.shake_time = 0.05 * k;
    d.wall_seconds = 0.75 + k;
    d.ns_per_particle_step = 81.5;
    d.max_overlap_ratio = 0.0123;
    d.settled_kinetic_energy = 1e-9;
    d.potential_energy_released = 0.02;
    d.dt = 1.6e-5;
    d.tau_c = 8e-4;
    d.k_n = 1149.25;
    d.seconds_forces = 0.4;
    d.seconds_integration = 0.1;
    d.seconds_neighbors = 0.05;
    d.seconds_observers = 0.01;
    return r;
}

// Fields with every member set, on an nx x ny grid (values derived from `k`; the Gaussian
// kernel for odd k). Some nodes have no windows, as near the walls.
inline engine::FieldMoments fabricated_fields(int k, int nx = 3, int ny = 2) {
    engine::FieldGrid g;
    g.x0 = -0.015 * nx;
    g.y0 = -0.031;
    g.cell = 0.0154 + 1e-4 * k;
    g.nx = nx;
    g.ny = ny;
    g.kernel = k % 2 ? engine::FieldKernel::gaussian : engine::FieldKernel::cell;
    g.kernel_width = k % 2 ? 0.0077 : 0.0;
    engine::FieldMoments m = engine::FieldMoments::zero(g);
    for (int c = 0; c < g.size(); ++c) {
        const auto n = static_cast<std::int64_t>((c + k) % 5);
        m.windows[c] = n;
        if (n == 0) continue;
        m.weight[c] = 10.5 * double(n) + c;
        for (int f = 0; f < engine::field_count; ++f) {
            m.mean[f][c] = (f == 3 ? 2.0 : -0.1) + 0.01 * f + 1.0 / (3.0 + c + k);
            m.m2[f][c] = n > 1 ? 1e-3 * (f + 1) * (c + 1) / 7.0 : 0.0;
        }
    }
    m.total_windows = 7 + k;
    m.samples = 70 + 10 * k;
    m.t_first = 0.001;
    m.t_last = 0.7 + 0.01 * k;
    m.outline_x = {0.0191, 0.0229, 0.0268, 0.1};
    m.outline_y = {0.0, 0.0067, 0.0133, 0.2};
    m.wall_diameter = 0.0077;
    return m;
}

// Avalanche sizes (one per interval) and arches (one per jam; the first not found) (issue 13).
inline engine::RealizationResult with_science(engine::RealizationResult r, int k) {
    r.avalanche_sizes.clear();
    for (std::size_t i = 0; i < r.survival_times.size(); ++i)
        r.avalanche_sizes.push_back(int(7 * i) + k);
    r.arches.assign(r.jam_onsets.size(), {});
    for (std::size_t j = 1; j < r.arches.size(); ++j) {
        auto& a = r.arches[j];
        for (int d = 0; d < 3 + int(j); ++d) {
            a.ids.push_back(100 * k + d);
            a.x.push_back(-0.01 + 0.005 * d);
            a.y.push_back(0.004 + 1e-4 * d);
        }
        a.span = 0.0185 + 1e-3 * k;
        a.max_angle = 2.5 + 0.1 * double(j);
    }
    return r;
}

inline engine::RealizationResult with_fields(engine::RealizationResult r, int k, int nx = 3,
                                             int ny = 2) {
    r.fields = fabricated_fields(k, nx, ny);
    return r;
}

inline PointPlan point(const std::string& label, int realizations, const std::string& scene = "") {
    PointPlan p;
    p.label = label;
    p.scene = scene.empty() ? "hopper.width_m=0.08\nscene_of=" + label + "\n" : scene;
    p.D_cm = 3.0;
    p.theta_deg = 60.0;
    p.particles = 80;
    for (int r = 0; r < realizations; ++r)
        p.seeds.push_back(fnv1a64(label) + static_cast<unsigned>(r));
    return p;
}

inline RunStartRecord run_record(std::vector<PointPlan> points, std::uint64_t seed = 7) {
    RunStartRecord r;
    r.run.start_time = utc_now();
    r.run.code_version = "test";
    r.run.compiler = "test-compiler";
    r.run.command = "test";
    r.run.sweep_path = "test.toml";
    r.run.sweep_text = "[campaign]\nname = \"t\"\n";
    r.run.hosts = {"localhost"};
    r.run.pid = 1;
    r.plan.name = "t";
    r.plan.seed = seed;
    r.plan.points = std::move(points);
    return r;
}

// The record of `r` as realization `realization` of `p` (the result takes the task's seed, as
// the engine's results do).
inline ResultRecord result_record(const PointPlan& p, int realization, engine::RealizationResult r,
                                  int rank = 1) {
    r.seed = p.seeds.at(static_cast<std::size_t>(realization));
    ResultRecord rec;
    rec.label = p.label;
    rec.realization = realization;
    rec.seed = p.seeds.at(static_cast<std::size_t>(realization));
    rec.rank = rank;
    rec.attempt = 1;
    rec.task_seconds = 0.5 + realization;
    rec.finished_unix = 1.7e9 + realization;
    rec.result = encode_result(r);
    return rec;
}

}  // namespace hopper::store::testing
