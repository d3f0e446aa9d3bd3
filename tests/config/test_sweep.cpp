#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "hopper/config/sanity.hpp"
#include "hopper/config/scene_schema.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/core/units.hpp"

using hopper::config::CampaignSpec;
using hopper::config::derive_seed;
using hopper::config::expand_tasks;
using hopper::config::load_sweep;
using hopper::core::Setting;
using SettingValue = std::variant<double, std::string>;
using hopper::config::parse_sweep;
using hopper::config::Point;
using hopper::config::scene_at;
using hopper::config::SweepFile;
using hopper::config::Task;
using hopper::core::ConfigError;
using hopper::core::pi;
using hopper::engine::Scheme;
using testing::AllOf;
using testing::HasSubstr;
using testing::Not;

namespace fs = std::filesystem;

namespace {

const fs::path source_dir = HOPPER_SOURCE_DIR;

SweepFile parse(const std::string& text) {
    return parse_sweep(text, "test.toml");
}

// The ConfigError message of parsing text, or a marker that makes every HasSubstr fail.
std::string error_of(const std::string& text, const std::string& name = "bad.toml") {
    try {
        parse_sweep(text, name);
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "<<no error was thrown>>";
}

std::string load_error_of(const fs::path& path) {
    try {
        load_sweep(path);
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "<<no error was thrown>>";
}

std::vector<std::string> labels(const CampaignSpec& c) {
    std::vector<std::string> out;
    for (const auto& p : c.points)
        out.push_back(p.label);
    return out;
}

// A minimal valid campaign: prepend sections, append points.
const std::string campaign_head = R"(
[hopper]
D_cm = 2.7
theta_deg = 45
[campaign]
name = "t"
)";

}  // namespace

// ---------------------------------------------------------------------------------------------
// Shipped campaign files

struct Shipped {
    const char* file;
    std::size_t points;
    std::size_t tasks;
};

TEST(ShippedCampaigns, ParseWithTheExpectedPointAndTaskCounts) {
    // Counts from docs/studies.md (see the comment at the top of each file).
    const Shipped files[] = {
        {"campaigns/tiny.toml", 2, 4},
        {"campaigns/adaptive-example.toml", 3, 36},  // rounds: the plan holds max_realizations
        {"campaigns/quickstart.toml", 6, 48},
        {"campaigns/paper/single-material.toml", 12, 15},  // 12 rows + 3 repeats of one row
        {"campaigns/paper/large-outlet-material.toml", 8, 8},
        {"campaigns/paper/survival.toml", 11, 440},
        {"campaigns/paper/empty-time.toml", 8, 5 * 40 + 3},
        {"campaigns/paper/beverloo-angle.toml", 40, 40},
        {"campaigns/paper/discharge-curves.toml", 5, 5},
        {"campaigns/paper/fields.toml", 2, 2},
        {"campaigns/paper/controls.toml", 3, 9},
    };
    for (const auto& f : files) {
        SCOPED_TRACE(f.file);
        const SweepFile s = load_sweep(source_dir / f.file);
        ASSERT_TRUE(s.has_campaign);
        EXPECT_EQ(s.campaign.points.size(), f.points);
        const auto tasks = expand_tasks(s.campaign);
        EXPECT_EQ(tasks.size(), f.tasks);
        // The store defaults to <name>.h5 beside the sweep file.
        EXPECT_EQ(s.campaign.store,
                  (source_dir / f.file).parent_path() / (s.campaign.name + ".h5"));
        std::set<std::uint64_t> seeds;
        for (const auto& t : tasks)
            seeds.insert(t.seed);
        EXPECT_EQ(seeds.size(), tasks.size()) << "task seeds must be distinct";
    }
}

// Study 7 switches the fields on (published settings) for both of its points; the others do not.
TEST(ShippedCampaigns, OnlyTheFieldsStudyHasFields) {
    for (const auto& e : fs::directory_iterator(source_dir / "campaigns/paper")) {
        if (e.path().extension() != ".toml") continue;
        SCOPED_TRACE(e.path().string());
        const SweepFile s = load_sweep(e.path());
        const bool want = e.path().filename() == "fields.toml";
        for (const auto& pt : s.campaign.points) {
            const auto& f = pt.scene.fields;
            EXPECT_EQ(f.enabled, want);
            if (!want) continue;
            EXPECT_DOUBLE_EQ(f.window, 0.01);
            EXPECT_DOUBLE_EQ(f.cell, 2.0);
            EXPECT_EQ(f.kernel, hopper::engine::FieldKernel::cell);
            EXPECT_DOUBLE_EQ(f.start, 1.0);
            ASSERT_TRUE(f.end.has_value());
            EXPECT_DOUBLE_EQ(*f.end, 10.0);
        }
    }
}

// The modelling-choice keys of issue 11 land in SceneParams; their defaults are today's model.
TEST(SweepParse, ModellingChoiceKeysLandInTheScene) {
    namespace e = hopper::engine;
    const auto d = parse("").base;
    EXPECT_EQ(d.hopper.outlet_measure, e::OutletMeasure::surface_gap);
    EXPECT_FALSE(d.hopper.edge_diameter.has_value());
    EXPECT_EQ(d.hopper.edge_offset, 0.0);
    EXPECT_EQ(d.material.gamma_t_over_gamma_n, 0.5);
    EXPECT_EQ(d.material.slip_rule, e::SlipRule::spring_and_dashpot);
    EXPECT_EQ(d.material.lever_arm, e::LeverArm::radius);
    EXPECT_EQ(d.material.normal_damping, e::NormalDamping::nominal);
    EXPECT_EQ(d.protocol.fill_base, 0.0);
    // The default integrator (issue 12): verlet, delta 75, corrections on.
    EXPECT_EQ(d.integrator.scheme, e::Scheme::verlet);
    EXPECT_EQ(d.integrator.steps_per_collision, 75.0);
    EXPECT_TRUE(d.integrator.contact_corrections);
    EXPECT_FALSE(
        parse("[integrator]\ncontact_corrections = false\n").base.integrator.contact_corrections);
    EXPECT_THAT(error_of("[integrator]\ncontact_corrections = 1\n"),
                HasSubstr("integrator.contact_corrections"));
    const SweepFile s = parse(
        "[hopper]\noutlet_measure = \"inner_envelope\"\n"
        "[walls]\nedge_diameter_cm = 0.602\nedge_offset = 0.5\n"
        "[material]\ngamma_t_over_gamma_n = 0.25\nslip_rule = \"spring_only\"\n"
        "lever_arm = \"contact\"\nnormal_damping = \"exact_restitution\"\n"
        "[protocol]\nfill_base = 2\n");
    const auto& p = s.base;
    EXPECT_EQ(p.hopper.outlet_measure, e::OutletMeasure::inner_envelope);
    EXPECT_DOUBLE_EQ(*p.hopper.edge_diameter, 0.00602);
    EXPECT_EQ(p.hopper.edge_offset, 0.5);
    EXPECT_EQ(p.material.gamma_t_over_gamma_n, 0.25);
    EXPECT_EQ(p.material.slip_rule, e::SlipRule::spring_only);
    EXPECT_EQ(p.material.lever_arm, e::LeverArm::contact);
    EXPECT_EQ(p.material.normal_damping, e::NormalDamping::exact_restitution);
    EXPECT_EQ(p.protocol.fill_base, 2.0);
    EXPECT_THAT(error_of("[hopper]\noutlet_measure = \"centre\"\n"),
                AllOf(HasSubstr("hopper.outlet_measure"),
                      HasSubstr("\"surface_gap\", \"centre_gap\", \"inner_envelope\"")));
    EXPECT_THAT(error_of("[walls]\nedge_offset = 11\n"),
                AllOf(HasSubstr("walls.edge_offset"), HasSubstr("[0, 10]")));
    // Sweepable like every other key.
    const SweepFile sw = parse(
        "[campaign]\nname = \"t\"\nrealizations = 1\n[sweep]\nD_cm = [3]\ntheta_deg = [45]\n"
        "material.slip_rule = [\"spring_and_dashpot\", \"spring_only\"]\n");
    ASSERT_EQ(sw.campaign.points.size(), 2u);
    EXPECT_EQ(sw.campaign.points[1].scene.material.slip_rule, e::SlipRule::spring_only);
}

// [fields]: types, choices and the two-key checks give clear errors.
TEST(SweepParse, FieldKeysAreCheckedLikeEveryOther) {
    const SweepFile s = parse(
        "[fields]\nenabled = true\nkernel = \"gaussian\"\nkernel_width_dlarge = 1.5\n"
        "window_s = 0.02\nsample_interval_s = 0\nstart_s = 0.5\nend_s = 2\ncell_dlarge = 1\n");
    const auto& f = s.base.fields;
    EXPECT_TRUE(f.enabled);
    EXPECT_EQ(f.kernel, hopper::engine::FieldKernel::gaussian);
    EXPECT_DOUBLE_EQ(f.kernel_width, 1.5);
    EXPECT_DOUBLE_EQ(f.window, 0.02);
    EXPECT_DOUBLE_EQ(f.sample_interval, 0.0);
    EXPECT_DOUBLE_EQ(f.start, 0.5);
    EXPECT_DOUBLE_EQ(*f.end, 2.0);
    EXPECT_DOUBLE_EQ(f.cell, 1.0);
    EXPECT_FALSE(parse("").base.fields.enabled);
    EXPECT_THAT(error_of("[fields]\nenabled = 1\n"),
                AllOf(HasSubstr("fields.enabled"), HasSubstr("true or false")));
    EXPECT_THAT(error_of("[fields]\nkernel = \"gauss\"\n"),
                AllOf(HasSubstr("fields.kernel"), HasSubstr("\"cell\", \"gaussian\"")));
    EXPECT_THAT(error_of("[fields]\nkernel = 3\n"),
                AllOf(HasSubstr("fields.kernel"), HasSubstr("a string")));
    EXPECT_THAT(error_of("[fields]\ncell_dlarge = 0.1\n"),
                AllOf(HasSubstr("fields.cell_dlarge"), HasSubstr("0.25")));
    EXPECT_THAT(error_of("[fields]\nwindow_s = 0.01\nsample_interval_s = 0.02\n"),
                AllOf(HasSubstr("fields.sample_interval_s"), HasSubstr("fields.window_s")));
    EXPECT_THAT(error_of("[fields]\nstart_s = 2\nend_s = 1\n"),
                AllOf(HasSubstr("fields.end_s"), HasSubstr("fields.start_s")));
    EXPECT_THAT(error_of("[fields]\nenable = true\n"),
                AllOf(HasSubstr("unknown key 'enable'"), HasSubstr("did you mean")));
}

// Found by tests/fuzz: inputs that crashed the parser, overflowed derived constants or gave
// unbounded messages are clean errors now.
// Issue 27: values in the wrong unit pass every range check but fail every realization; they
// are refused before a run, naming the key, the value and what would work.
TEST(SweepSanity, AnOutletNarrowerThanOneDiskNamesTheKeyTheValueAndTheUnit) {
    const std::string msg = error_of(
        "[hopper]\nwidth_cm = 12\nparticles = 500\ntheta_deg = 60\n[campaign]\nname = \"u\"\n"
        "[sweep]\nD_cm = [0.025, 2.5]\n");
    EXPECT_THAT(msg, HasSubstr("D_cm = 0.025"));
    EXPECT_THAT(msg, HasSubstr("narrower than one small disk (hopper.d_small_cm = 0.602)"));
    EXPECT_THAT(msg, HasSubstr("D_cm is in centimetres"));
    EXPECT_THAT(msg, HasSubstr("write D_cm = 2.5"));
    // One small disk passes (the gap is the narrowest a disk can pass, however rarely).
    EXPECT_NO_THROW(parse("[hopper]\nwidth_cm = 12\nparticles = 500\nD_cm = 0.61\n"));
}

// Issue 43, item 3: a wall angle in radians (theta_deg = 0.785 for 45 degrees) is refused with
// the value in degrees, in a sweep file and by scene_at (campaign simulate --theta); so is an
// outlet in metres given to scene_at (--D 0.023).
TEST(SweepSanity, AWallAngleInRadiansIsRefusedInTheFileAndBySceneAt) {
    const std::string msg = error_of(
        "[hopper]\nwidth_cm = 12\nparticles = 500\nD_cm = 2.5\n[campaign]\nname = \"u\"\n"
        "[sweep]\ntheta_deg = [0.785, 60]\n");
    EXPECT_THAT(msg, HasSubstr("theta_deg = 0.785 is the wall angle in degrees"));
    EXPECT_THAT(msg, HasSubstr("write theta_deg = 45"));
    EXPECT_THAT(error_of("[hopper]\nwidth_cm = 12\nparticles = 500\ntheta_deg = 1.5708\n"),
                HasSubstr("write theta_deg = 90"));
    // a flat bottom and real angles pass
    EXPECT_NO_THROW(parse("[hopper]\nwidth_cm = 12\nparticles = 500\ntheta_deg = 0\n"));
    EXPECT_NO_THROW(parse("[hopper]\nwidth_cm = 12\nparticles = 500\ntheta_deg = 2\n"));
    const SweepFile s = load_sweep(source_dir / "campaigns/tiny.toml");
    const auto what = [&](double D, double theta) {
        try {
            scene_at(s, D, theta);
        } catch (const ConfigError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_THAT(what(2.2, 0.785), AllOf(HasSubstr("tiny.toml"), HasSubstr("write theta_deg = 45")));
    EXPECT_THAT(what(0.023, 60), AllOf(HasSubstr("D_cm = 0.023"), HasSubstr("write D_cm = 2.3")));
    EXPECT_EQ(what(2.2, 60), "");
    // a width in metres gets its value in centimetres (issue 43, item 10)
    EXPECT_THAT(error_of("[hopper]\nwidth_cm = 0.1\nparticles = 500\nD_cm = 2.5\n"),
                AllOf(HasSubstr("hopper.width_cm = 0.1 must exceed"),
                      HasSubstr("width_cm is in centimetres: for 10 cm write width_cm = 10")));
}

TEST(SweepSanity, APackingTallerThanTwentyWidthsIsRefused) {
    // 20000 disks in a 12 cm hopper: about 7 m of packing.
    const std::string msg = error_of("[hopper]\nwidth_cm = 12\nparticles = 20000\nD_cm = 3\n");
    EXPECT_THAT(msg, HasSubstr("hopper.particles = 20000"));
    EXPECT_THAT(msg, HasSubstr("hopper.width_cm = 12"));
    EXPECT_THAT(msg, HasSubstr("allowed up to 20 widths"));
    // The published full-size hopper: 8750 disks in 43 cm, about 2 widths.
    const SweepFile paper = parse("[hopper]\nwidth_cm = 43\nparticles = 8750\nD_cm = 2.7\n");
    const double h = hopper::config::settled_fill_height(paper.base);
    // m: by hand about 0.94 from the nominal outline (a funnel 20 cm high holding 460 cm^2,
    // then 74 cm of column); the wall disks' half diameter inside that outline adds 7 cm.
    EXPECT_GT(h, 0.9);
    EXPECT_LT(h, 1.05);
}

TEST(SweepSanity, ContactsTooSoftForThePackingsOwnWeightAreRefused) {
    const std::string msg = error_of(
        "[hopper]\nwidth_cm = 12\nparticles = 500\nD_cm = 2.5\n[material]\n"
        "collision_time_s = 0.8\n");
    EXPECT_THAT(msg, HasSubstr("material.collision_time_s = 0.8"));
    EXPECT_THAT(msg, HasSubstr("every realization would fail while settling"));
    EXPECT_THAT(msg, HasSubstr("Collision times below about"));
    // Hand check of the estimate, quickstart scene at the published tau_c = 8e-4 s: k_n = pi^2
    // m_large / (2 tau_c^2) = 1149 N/m; a column min(H, W/2) = 6 cm of 0.77 cm disks (7.8
    // layers) on two contacts: 7.8 x 1.49e-4 kg x 9.81 / 2 / 1149 = 4.96e-6 m.
    const SweepFile q = parse(
        "[hopper]\nwidth_cm = 12\nparticles = 500\nD_cm = 2.5\n[material]\n"
        "collision_time_s = 8e-4\n");
    EXPECT_NEAR(hopper::config::settled_overlap(q.base), 4.96e-6, 0.05e-6);
}

TEST(SweepParse, AbsurdInputsFoundByTheFuzzerAreCleanErrors) {
    std::string deep;
    for (int k = 0; k < 100000; ++k)
        deep += k ? ".a" : "a";
    EXPECT_THAT(error_of(deep + " = 1\n"), HasSubstr("deeper than 64 levels"));
    EXPECT_THAT(error_of("x = " + std::string(100000, '[') + "\n"),
                HasSubstr("deeper than 64 levels"));
    EXPECT_THAT(error_of("[material]\ncollision_time_s = 1e-300\n"),
                AllOf(HasSubstr("collision_time_s"), HasSubstr("1e-09")));
    EXPECT_THAT(error_of("[material]\nyoungs_modulus_pa = 5e-324\n"),
                HasSubstr("youngs_modulus_pa"));
    EXPECT_THAT(error_of("[walls]\nparticle_diameter_cm = 1e-300\n"),
                HasSubstr("particle_diameter_cm"));
    const std::string long_key(1'000'000, 'q');
    const std::string msg = error_of("[hopper]\n" + long_key + " = 1\n");
    EXPECT_THAT(msg, HasSubstr("1000000 characters"));
    EXPECT_LT(msg.size(), 1000u);
    // Comments and strings may hold any number of dots and brackets.
    EXPECT_NO_THROW(parse("# " + std::string(500, '.') + std::string(500, '[') + "\n"));
}

TEST(ShippedCampaigns, PaperDirectoryHoldsExactlyTheEightStudies) {
    std::set<std::string> found;
    for (const auto& e : fs::directory_iterator(source_dir / "campaigns/paper"))
        if (e.path().extension() == ".toml") found.insert(e.path().filename().string());
    const std::set<std::string> expected = {
        "single-material.toml", "large-outlet-material.toml", "survival.toml", "empty-time.toml",
        "beverloo-angle.toml",  "discharge-curves.toml",      "fields.toml",   "controls.toml"};
    EXPECT_EQ(found, expected);
}

TEST(ShippedCampaigns, PaperFilesUseThePublishedFullSizeSetup) {
    for (const auto& e : fs::directory_iterator(source_dir / "campaigns/paper")) {
        if (e.path().extension() != ".toml") continue;
        SCOPED_TRACE(e.path().string());
        const SweepFile s = load_sweep(e.path());
        for (const auto& p : s.campaign.points) {
            EXPECT_EQ(p.scene.particles.count, 8750);
            EXPECT_DOUBLE_EQ(p.scene.hopper.width, 0.43);
            ASSERT_TRUE(p.scene.material.collision_time.has_value());
            EXPECT_DOUBLE_EQ(*p.scene.material.collision_time, 8.0e-4);
            EXPECT_DOUBLE_EQ(p.scene.integrator.steps_per_collision, 50.0);
            EXPECT_EQ(p.scene.integrator.scheme, Scheme::gear4);
            EXPECT_DOUBLE_EQ(p.scene.material.kt_over_kn,
                             p.label.find("kt_over_kn") == std::string::npos ? 0.8 : 0.0);
        }
    }
}

TEST(ShippedCampaigns, SingleMaterialRowsAreThePublishedOnes) {
    const SweepFile s = load_sweep(source_dir / "campaigns/paper/single-material.toml");
    // (system e_n, wall e_n, system mu, wall mu), docs/studies.md study 1.
    const double rows[12][4] = {{0.5, 0.5, 0.5, 0.8}, {0.5, 0.5, 0.6, 0.8}, {0.5, 0.5, 0.7, 0.8},
                                {0.5, 0.5, 0.8, 0.8}, {0.8, 0.5, 0.5, 0.8}, {0.8, 0.5, 0.6, 0.8},
                                {0.8, 0.5, 0.7, 0.8}, {0.8, 0.5, 0.8, 0.8}, {0.5, 0.3, 0.8, 0.8},
                                {0.5, 0.8, 0.8, 0.8}, {0.5, 0.5, 0.8, 0.5}, {0.3, 0.5, 0.8, 0.8}};
    ASSERT_EQ(s.campaign.points.size(), 12u);
    for (int i = 0; i < 12; ++i) {
        SCOPED_TRACE(i);
        const auto& p = s.campaign.points[i];
        EXPECT_DOUBLE_EQ(p.scene.hopper.outlet, 0.027);
        EXPECT_DOUBLE_EQ(p.scene.hopper.theta, pi / 4);
        EXPECT_EQ(p.scene.material.system.e_n, rows[i][0]);
        EXPECT_EQ(p.scene.material.wall.e_n, rows[i][1]);
        EXPECT_EQ(p.scene.material.system.mu, rows[i][2]);
        EXPECT_EQ(p.scene.material.wall.mu, rows[i][3]);
        EXPECT_EQ(p.realizations, i == 3 ? 4 : 1);  // the (0.5,0.5,0.8,0.8) row: 1 + 3 repeats
    }
}

TEST(ShippedCampaigns, SurvivalAndControlsPoints) {
    const SweepFile s = load_sweep(source_dir / "campaigns/paper/survival.toml");
    EXPECT_THAT(labels(s.campaign),
                testing::ElementsAre(
                    "D_cm=2.7 theta_deg=15", "D_cm=2.7 theta_deg=30", "D_cm=2.7 theta_deg=45",
                    "D_cm=2.7 theta_deg=60", "D_cm=2.9 theta_deg=15", "D_cm=2.9 theta_deg=30",
                    "D_cm=2.9 theta_deg=45", "D_cm=2.9 theta_deg=60", "D_cm=3.1 theta_deg=45",
                    "D_cm=3.3 theta_deg=45", "D_cm=3.5 theta_deg=45"));
    for (const auto& p : s.campaign.points) {
        EXPECT_EQ(p.realizations, 40);
        EXPECT_EQ(p.scene.material.wall.e_n, 0.5);
        EXPECT_EQ(p.scene.material.wall.mu, 0.8);
    }

    const SweepFile c = load_sweep(source_dir / "campaigns/paper/controls.toml");
    ASSERT_EQ(c.campaign.points.size(), 3u);
    const auto& no_mu = c.campaign.points[0].scene.material;
    EXPECT_EQ(no_mu.system.mu, 0.0);
    EXPECT_EQ(no_mu.wall.mu, 0.0);
    EXPECT_EQ(c.campaign.points[1].scene.material.kt_over_kn, 0.0);
    const auto& elastic = c.campaign.points[2].scene.material;
    EXPECT_EQ(elastic.system.e_n, 1.0);
    EXPECT_EQ(elastic.wall.e_n, 1.0);
}

TEST(ShippedCampaigns, ReadmeDocumentsEveryKeyInItsSection) {
    std::ifstream in(source_dir / "campaigns/README.md");
    ASSERT_TRUE(in) << "campaigns/README.md is missing";
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string readme = ss.str();
    auto section_text = [&](const std::string& section) {
        const auto start = readme.find("## [" + section + "]");
        if (start == std::string::npos) return std::string();
        const auto end = readme.find("\n## ", start + 1);
        return readme.substr(start, end == std::string::npos ? std::string::npos : end - start);
    };
    auto names = hopper::config::parameter_names();
    EXPECT_GE(names.size(), 39u);
    for (const char* k :
         {"campaign.name", "campaign.store", "campaign.seed", "campaign.realizations"})
        names.emplace_back(k);
    for (const auto& name : names) {
        const bool top = name == "D_cm" || name == "theta_deg";
        const std::string section = top ? "hopper" : name.substr(0, name.find('.'));
        const std::string key = top ? name : name.substr(name.find('.') + 1);
        EXPECT_THAT(section_text(section), HasSubstr("| `" + key + "` |"))
            << name << " is not documented in campaigns/README.md";
    }
}

// ---------------------------------------------------------------------------------------------
// Defaults and unit conversion

TEST(SweepParse, EmptyFileGivesThePublishedDefaults) {
    const SweepFile s = parse("");
    EXPECT_FALSE(s.has_campaign);
    const hopper::engine::SceneParams defaults{};
    EXPECT_EQ(s.base.particles.count, defaults.particles.count);
    EXPECT_EQ(s.base.hopper.width, defaults.hopper.width);
    EXPECT_EQ(s.base.material.system.mu, defaults.material.system.mu);
    EXPECT_EQ(s.base.material.wall.e_n, defaults.material.system.e_n);
    EXPECT_EQ(s.base.hopper.wall_diameter, defaults.particles.d_large);
    EXPECT_FALSE(s.base.material.collision_time.has_value());
    EXPECT_FALSE(s.base.protocol.t_check.has_value());
    EXPECT_EQ(s.path, fs::path("test.toml"));
}

TEST(SweepParse, ConvertsFileUnitsToSi) {
    const SweepFile s = parse(R"(
[hopper]
width_cm = 20
particles = 1000
small_fraction = 0.5
d_small_cm = 0.5
d_large_cm = 0.8
thickness_cm = 0.4
density_kg_m3 = 1200
D_cm = 2.7
theta_deg = 45
[material]
e_n = 0.6
mu = 0.7
kt_over_kn = 0.5
youngs_modulus_pa = 1e7
poisson_ratio = 0.3
collision_time_s = 8.0e-4
[walls]
spacing = 1.2
[integrator]
scheme = "verlet"
steps_per_collision = 40
skin = 0.3
[protocol]
fill_gap = 0.1
fill_speed_m_s = 0.02
settle_ke = 2e-4
settle_hold_s = 0.1
settle_max_time_s = 10
jam_region_height = 1.5
t_check_s = 0.06
detector_interval_s = 2e-4
shake_amplitude = 0.3
shake_period_s = 0.04
shake_direction_deg = 45
max_shakes = 5
max_time_s = 100
exit_depth = 5
empty_threshold = 3
sample_interval_s = 0.02
max_overlap = 0.2
)");
    const auto& p = s.base;
    EXPECT_DOUBLE_EQ(p.hopper.width, 0.20);
    EXPECT_EQ(p.particles.count, 1000);
    EXPECT_DOUBLE_EQ(p.particles.small_fraction, 0.5);
    EXPECT_DOUBLE_EQ(p.particles.d_small, 0.005);
    EXPECT_DOUBLE_EQ(p.particles.d_large, 0.008);
    EXPECT_DOUBLE_EQ(p.particles.thickness, 0.004);
    EXPECT_DOUBLE_EQ(p.particles.density, 1200.0);
    EXPECT_DOUBLE_EQ(p.hopper.outlet, 0.027);
    EXPECT_DOUBLE_EQ(p.hopper.theta, pi / 4);
    EXPECT_DOUBLE_EQ(p.material.system.e_n, 0.6);
    EXPECT_DOUBLE_EQ(p.material.system.mu, 0.7);
    // Walls default to the particles' material and to wall particles of diameter d_large.
    EXPECT_DOUBLE_EQ(p.material.wall.e_n, 0.6);
    EXPECT_DOUBLE_EQ(p.material.wall.mu, 0.7);
    EXPECT_DOUBLE_EQ(p.hopper.wall_diameter, 0.008);
    EXPECT_DOUBLE_EQ(p.hopper.wall_spacing, 1.2);
    EXPECT_DOUBLE_EQ(p.material.kt_over_kn, 0.5);
    EXPECT_DOUBLE_EQ(p.material.youngs_modulus, 1e7);
    EXPECT_DOUBLE_EQ(p.material.poisson_ratio, 0.3);
    EXPECT_DOUBLE_EQ(p.material.collision_time.value_or(-1), 8.0e-4);
    EXPECT_EQ(p.integrator.scheme, Scheme::verlet);
    EXPECT_DOUBLE_EQ(p.integrator.steps_per_collision, 40.0);
    EXPECT_DOUBLE_EQ(p.integrator.skin, 0.3);
    const auto& pr = p.protocol;
    EXPECT_DOUBLE_EQ(pr.fill_gap, 0.1);
    EXPECT_DOUBLE_EQ(pr.fill_speed, 0.02);
    EXPECT_DOUBLE_EQ(pr.settle_ke, 2e-4);
    EXPECT_DOUBLE_EQ(pr.settle_hold, 0.1);
    EXPECT_DOUBLE_EQ(pr.settle_max_time, 10.0);
    EXPECT_DOUBLE_EQ(pr.jam_region_height, 1.5);
    EXPECT_DOUBLE_EQ(pr.t_check.value_or(-1), 0.06);
    EXPECT_DOUBLE_EQ(pr.detector_interval, 2e-4);
    EXPECT_DOUBLE_EQ(pr.shake_amplitude, 0.3);
    EXPECT_DOUBLE_EQ(pr.shake_period, 0.04);
    EXPECT_DOUBLE_EQ(pr.shake_direction, pi / 4);
    EXPECT_EQ(pr.max_shakes, 5);
    EXPECT_DOUBLE_EQ(pr.max_time, 100.0);
    EXPECT_DOUBLE_EQ(pr.exit_depth, 5.0);
    EXPECT_EQ(pr.empty_threshold, 3);
    EXPECT_DOUBLE_EQ(pr.sample_interval, 0.02);
    EXPECT_DOUBLE_EQ(pr.max_overlap, 0.2);
}

TEST(SweepParse, ExplicitWallValuesAndDiameterOverrideTheDefaults) {
    const SweepFile s = parse(R"(
[material]
e_n = 0.6
[walls]
e_n = 0.3
mu = 0.4
particle_diameter_cm = 1.0
)");
    EXPECT_DOUBLE_EQ(s.base.material.wall.e_n, 0.3);
    EXPECT_DOUBLE_EQ(s.base.material.wall.mu, 0.4);
    EXPECT_DOUBLE_EQ(s.base.material.system.mu, 0.8);
    EXPECT_DOUBLE_EQ(s.base.hopper.wall_diameter, 0.01);
}

TEST(SweepParse, WallsFollowThePointsMaterialAndDiameterUnlessGiven) {
    const SweepFile s = parse(campaign_head + R"(
[sweep]
material.mu = [0.5]
hopper.d_large_cm = [0.7, 0.8]
)");
    ASSERT_EQ(s.campaign.points.size(), 2u);
    EXPECT_DOUBLE_EQ(s.campaign.points[0].scene.material.wall.mu, 0.5);
    EXPECT_DOUBLE_EQ(s.campaign.points[0].scene.hopper.wall_diameter, 0.007);
    EXPECT_DOUBLE_EQ(s.campaign.points[1].scene.hopper.wall_diameter, 0.008);
}

TEST(SweepParse, SceneAtSetsOutletAndAngle) {
    const SweepFile s = load_sweep(source_dir / "campaigns/tiny.toml");
    const auto p = scene_at(s, 3.3, 30);
    EXPECT_DOUBLE_EQ(p.hopper.outlet, 0.033);
    EXPECT_DOUBLE_EQ(p.hopper.theta, pi / 6);
    EXPECT_EQ(p.particles.count, s.base.particles.count);
    EXPECT_THAT(
        [&] {
            try {
                scene_at(s, 12.5, 30);
            } catch (const ConfigError& e) {
                return std::string(e.what());
            }
            return std::string();
        }(),
        AllOf(HasSubstr("tiny.toml"), HasSubstr("D_cm = 12.5"), HasSubstr("width_cm")));
    EXPECT_THROW(scene_at(s, 3.0, 95), ConfigError);
    EXPECT_THROW(scene_at(s, -1.0, 45), ConfigError);
    EXPECT_THROW(scene_at(s, std::nan(""), 45), ConfigError);
}

// ---------------------------------------------------------------------------------------------
// Points, sweeps, labels

TEST(SweepParse, CartesianProductInCanonicalOrderLastAxisFastest) {
    const SweepFile s = parse(campaign_head + R"(
[sweep]
theta_deg = [15, 30]
material.mu = [0.5, 0.8]
D_cm = [2.7, 2.9]
)");
    EXPECT_THAT(
        labels(s.campaign),
        testing::ElementsAre(
            "D_cm=2.7 theta_deg=15 material.mu=0.5", "D_cm=2.7 theta_deg=15 material.mu=0.8",
            "D_cm=2.7 theta_deg=30 material.mu=0.5", "D_cm=2.7 theta_deg=30 material.mu=0.8",
            "D_cm=2.9 theta_deg=15 material.mu=0.5", "D_cm=2.9 theta_deg=15 material.mu=0.8",
            "D_cm=2.9 theta_deg=30 material.mu=0.5", "D_cm=2.9 theta_deg=30 material.mu=0.8"));
    const Point& p = s.campaign.points[5];
    ASSERT_EQ(p.settings.size(), 3u);
    EXPECT_EQ(p.settings[0].name, "D_cm");
    EXPECT_EQ(std::get<double>(p.settings[0].value), 2.9);
    EXPECT_EQ(p.settings[1].name, "theta_deg");
    EXPECT_EQ(std::get<double>(p.settings[1].value), 15.0);
    EXPECT_EQ(p.settings[2].name, "material.mu");
    EXPECT_DOUBLE_EQ(p.scene.hopper.outlet, 0.029);
    EXPECT_DOUBLE_EQ(p.scene.hopper.theta, 15 * pi / 180);
    EXPECT_DOUBLE_EQ(p.scene.material.system.mu, 0.8);
    EXPECT_EQ(p.realizations, 1);
}

// A user stumble: "material.mu" = [...] is one quoted TOML key; it was refused with "did you
// mean 'material.mu'?". It now means exactly what the unquoted dotted key means.
TEST(SweepParse, AQuotedDottedKeyMeansTheSameAsTheDottedKey) {
    const std::string tail = R"(
[[points]]
D_cm = 3.0
"walls.mu" = 0.3
)";
    const SweepFile quoted =
        parse(campaign_head + "[sweep]\n\"material.collision_time_s\" = [8e-4, 4e-4]\n" + tail);
    const SweepFile plain =
        parse(campaign_head + "[sweep]\nmaterial.collision_time_s = [8e-4, 4e-4]\n" + tail);
    ASSERT_EQ(labels(quoted.campaign).size(), 3u);  // the sweep's two and the point
    EXPECT_EQ(labels(quoted.campaign), labels(plain.campaign));
    EXPECT_EQ(labels(quoted.campaign)[1], "D_cm=2.7 theta_deg=45 material.collision_time_s=4e-04");
    EXPECT_EQ(labels(quoted.campaign)[2], "D_cm=3 theta_deg=45 walls.mu=0.3");
    ASSERT_TRUE(quoted.campaign.points[1].scene.material.collision_time.has_value());
    EXPECT_DOUBLE_EQ(*quoted.campaign.points[1].scene.material.collision_time, 4e-4);
    EXPECT_DOUBLE_EQ(quoted.campaign.points[2].scene.material.wall.mu, 0.3);
    EXPECT_EQ(quoted.campaign.points[0].scene.hopper.outlet,
              plain.campaign.points[0].scene.hopper.outlet);
    // a quoted name that is no key is refused as before
    EXPECT_THAT(error_of(campaign_head + "[sweep]\n\"material.muu\" = [0.5]\n"),
                HasSubstr("unknown key 'material.muu' in [sweep]"));
}

TEST(SweepParse, OtherNamesAreSortedAndStringsAndIntegersPrintCanonically) {
    const SweepFile s = parse(campaign_head + R"(
[sweep]
walls.e_n = [0.5]
integrator.scheme = ["gear4", "verlet"]
hopper.particles = [8750]
material.e_n = [1e-1]
)");
    EXPECT_THAT(labels(s.campaign),
                testing::ElementsAre("D_cm=2.7 theta_deg=45 hopper.particles=8750 "
                                     "integrator.scheme=gear4 material.e_n=0.1 walls.e_n=0.5",
                                     "D_cm=2.7 theta_deg=45 hopper.particles=8750 "
                                     "integrator.scheme=verlet material.e_n=0.1 walls.e_n=0.5"));
    EXPECT_EQ(std::get<std::string>(s.campaign.points[1].settings[3].value), "verlet");
    EXPECT_EQ(s.campaign.points[1].scene.integrator.scheme, Scheme::verlet);
}

TEST(SweepParse, PointsWithInlineTablesFollowTheSweepAndOverrideRealizations) {
    const SweepFile s = parse(R"(
[hopper]
theta_deg = 60
[campaign]
name = "mix"
realizations = 3
seed = 7
store = "out/mix.h5"
[sweep]
D_cm = [3.0]
[[points]]
D_cm = 4.5
material = { mu = 0.5, e_n = 0.8 }
walls = { mu = 0.3 }
realizations = 10
[[points]]
D_cm = 4.5
theta_deg = 30
integrator = { scheme = "verlet" }
)");
    const CampaignSpec& c = s.campaign;
    EXPECT_EQ(c.name, "mix");
    EXPECT_EQ(c.seed, 7u);
    EXPECT_EQ(c.realizations, 3);
    EXPECT_EQ(c.store, fs::path("out/mix.h5"));  // source "test.toml" has no directory
    EXPECT_THAT(
        labels(c),
        testing::ElementsAre("D_cm=3 theta_deg=60",
                             "D_cm=4.5 theta_deg=60 material.e_n=0.8 material.mu=0.5 walls.mu=0.3",
                             "D_cm=4.5 theta_deg=30 integrator.scheme=verlet"));
    EXPECT_EQ(c.points[0].realizations, 3);
    EXPECT_EQ(c.points[1].realizations, 10);
    EXPECT_EQ(c.points[2].realizations, 3);
    EXPECT_DOUBLE_EQ(c.points[1].scene.material.system.mu, 0.5);
    EXPECT_DOUBLE_EQ(c.points[1].scene.material.wall.mu, 0.3);
    EXPECT_DOUBLE_EQ(c.points[1].scene.material.wall.e_n, 0.8);  // follows the point's e_n
    EXPECT_EQ(c.points[2].scene.integrator.scheme, Scheme::verlet);

    const auto tasks = expand_tasks(c);
    ASSERT_EQ(tasks.size(), 16u);
    for (std::size_t i = 0; i < tasks.size(); ++i)
        EXPECT_EQ(tasks[i].task_id, int(i));
    EXPECT_EQ(tasks[3].point_index, 1);
    EXPECT_EQ(tasks[3].realization, 0);
    EXPECT_EQ(tasks[12].point_index, 1);
    EXPECT_EQ(tasks[12].realization, 9);
    EXPECT_EQ(tasks[13].point_index, 2);
}

TEST(SweepParse, CampaignWithoutPointsRunsTheBaseScene) {
    const SweepFile s = parse(campaign_head);
    ASSERT_EQ(s.campaign.points.size(), 1u);
    EXPECT_EQ(s.campaign.points[0].label, "D_cm=2.7 theta_deg=45");
    EXPECT_EQ(s.campaign.seed, 1u);  // default seed
    EXPECT_EQ(s.campaign.store, fs::path("t.h5"));
}

TEST(SweepParse, RelativeStoreIsResolvedBesideTheSweepFile) {
    const SweepFile s =
        parse_sweep(campaign_head + "store = \"../data/x.h5\"\n", "/some/dir/sweep.toml");
    EXPECT_EQ(s.campaign.store, fs::path("/some/dir/../data/x.h5"));
    const SweepFile a = parse_sweep(campaign_head + "store = \"/abs/x.h5\"\n", "/some/dir/s.toml");
    EXPECT_EQ(a.campaign.store, fs::path("/abs/x.h5"));
}

// ---------------------------------------------------------------------------------------------
// Seeds

TEST(Seeds, DeterministicAndDistinctPerRealizationAndPoint) {
    const std::vector<Setting> a = {{"D_cm", 2.7}, {"theta_deg", 45.0}};
    const std::vector<Setting> b = {{"D_cm", 2.9}, {"theta_deg", 45.0}};
    EXPECT_EQ(derive_seed(1, a, 0), derive_seed(1, a, 0));
    EXPECT_NE(derive_seed(1, a, 0), derive_seed(1, a, 1));
    EXPECT_NE(derive_seed(1, a, 0), derive_seed(1, b, 0));
    EXPECT_NE(derive_seed(1, a, 0), derive_seed(2, a, 0));
    // A string setting counts too.
    auto c = a;
    c.push_back({"integrator.scheme", std::string("verlet")});
    EXPECT_NE(derive_seed(1, a, 0), derive_seed(1, c, 0));
    // Depends on the settings, not on the order the caller holds them in.
    const std::vector<Setting> a_rev = {{"theta_deg", 45.0}, {"D_cm", 2.7}};
    EXPECT_EQ(derive_seed(1, a, 3), derive_seed(1, a_rev, 3));
    EXPECT_THROW(derive_seed(1, a, -1), ConfigError);
}

TEST(Seeds, SameValueWrittenDifferentlyGivesTheSameSeed) {
    // 45 and 45.0, 2.70 and 2.7 are the same number: same label, same seed.
    const SweepFile x = parse(campaign_head + "[sweep]\nD_cm = [2.70]\ntheta_deg = [45.0]\n");
    const SweepFile y = parse(campaign_head + "[sweep]\nD_cm = [2.7]\ntheta_deg = [45]\n");
    EXPECT_EQ(x.campaign.points[0].label, y.campaign.points[0].label);
    EXPECT_EQ(expand_tasks(x.campaign)[0].seed, expand_tasks(y.campaign)[0].seed);
}

TEST(Seeds, AddingPointsOrRealizationsKeepsExistingSeeds) {
    const SweepFile small = parse(campaign_head + R"(realizations = 2
[sweep]
D_cm = [2.7, 2.9]
)");
    const SweepFile large = parse(campaign_head + R"(realizations = 5
[sweep]
D_cm = [2.5, 2.7, 2.9, 3.1]
theta_deg = [45]
[[points]]
D_cm = 4.0
)");
    std::map<std::pair<std::string, int>, std::uint64_t> before;
    for (const auto& t : expand_tasks(small.campaign))
        before[{small.campaign.points[t.point_index].label, t.realization}] = t.seed;
    ASSERT_EQ(before.size(), 4u);
    int matched = 0;
    std::set<std::uint64_t> all;
    for (const auto& t : expand_tasks(large.campaign)) {
        all.insert(t.seed);
        const auto it = before.find({large.campaign.points[t.point_index].label, t.realization});
        if (it == before.end()) continue;
        EXPECT_EQ(it->second, t.seed);
        ++matched;
    }
    EXPECT_EQ(matched, 4);
    EXPECT_EQ(all.size(), 5u * 5u);
}

TEST(Seeds, GoldenValueIsStable) {
    // Changing derive_seed changes every realization of every campaign: do it only on purpose.
    const std::vector<Setting> s = {{"D_cm", 2.7}, {"theta_deg", 45.0}};
    const std::uint64_t golden = derive_seed(1, s, 0);
    EXPECT_EQ(golden, derive_seed(1, {{"theta_deg", 45.0}, {"D_cm", 2.7}}, 0));
    EXPECT_EQ(hopper::config::to_string(Setting{"D_cm", 2.7}), "D_cm=2.7");
    EXPECT_EQ(hopper::config::to_string(Setting{"theta_deg", 45.0}), "theta_deg=45");
    EXPECT_EQ(golden, 5542539634249134159ULL);
}

// ---------------------------------------------------------------------------------------------
// Errors: every message names the file, the key and the value

TEST(SweepErrors, UnknownKeyInSection) {
    const auto msg = error_of("[material]\nmu = 0.5\nmuu = 0.6\n");
    EXPECT_THAT(msg, AllOf(HasSubstr("bad.toml:3:1"), HasSubstr("unknown key 'muu'"),
                           HasSubstr("[material]"), HasSubstr("allowed: e_n, mu"),
                           HasSubstr("did you mean 'mu'")));
}

TEST(SweepErrors, UnknownSectionAndTopLevelKey) {
    EXPECT_THAT(error_of("[materials]\nmu = 0.5\n"),
                AllOf(HasSubstr("bad.toml"), HasSubstr("unknown section [materials]"),
                      HasSubstr("did you mean 'material'")));
    EXPECT_THAT(error_of("D_cm = 2.7\n"),
                AllOf(HasSubstr("unknown key 'D_cm'"), HasSubstr("top level")));
}

TEST(SweepErrors, MisspeltKeyInSweep) {
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nmaterail.mu = [0.5, 0.8]\n"),
                AllOf(HasSubstr("bad.toml"), HasSubstr("unknown key 'materail.mu' in [sweep]"),
                      HasSubstr("allowed:"), HasSubstr("did you mean 'material.mu'")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nmaterial.muu = [0.5]\n"),
                AllOf(HasSubstr("unknown key 'material.muu' in [sweep]"),
                      HasSubstr("allowed in material: e_n, mu")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD = [2.7]\n"),
                AllOf(HasSubstr("unknown key 'D' in [sweep]"), HasSubstr("D_cm")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nhopper.D_cm = [2.7]\n"),
                HasSubstr("directly in [sweep]"));
}

TEST(SweepErrors, UnknownKeyInPoint) {
    EXPECT_THAT(error_of(campaign_head + "[[points]]\nD_cm = 3.0\nwall = { mu = 0.5 }\n"),
                AllOf(HasSubstr("bad.toml:9:1"), HasSubstr("unknown key 'wall' in [[points]] #1"),
                      HasSubstr("did you mean 'walls'")));
    EXPECT_THAT(error_of(campaign_head + "[[points]]\nwalls = { m = 0.5 }\n"),
                HasSubstr("unknown key 'walls.m' in [[points]] #1"));
}

TEST(SweepErrors, WrongTypes) {
    EXPECT_THAT(error_of("[material]\nmu = \"high\"\n"),
                AllOf(HasSubstr("bad.toml:2:6"), HasSubstr("material.mu = \"high\""),
                      HasSubstr("expected a number"), HasSubstr("got a string")));
    EXPECT_THAT(error_of("[hopper]\nparticles = 250.5\n"),
                AllOf(HasSubstr("hopper.particles = 250.5"), HasSubstr("expected an integer"),
                      HasSubstr("got a float")));
    EXPECT_THAT(error_of("[hopper]\nparticles = 250.0\n"), HasSubstr("expected an integer"));
    EXPECT_THAT(error_of("[protocol]\nmax_shakes = true\n"),
                AllOf(HasSubstr("protocol.max_shakes = true"), HasSubstr("got a boolean")));
    EXPECT_THAT(error_of("[integrator]\nscheme = 4\n"),
                AllOf(HasSubstr("integrator.scheme = 4"), HasSubstr("expected a string")));
    EXPECT_THAT(error_of("[integrator]\nscheme = \"rk4\"\n"),
                AllOf(HasSubstr("\"rk4\""), HasSubstr("gear4"), HasSubstr("verlet")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD_cm = 2.7\n"),
                AllOf(HasSubstr("D_cm = 2.7"), HasSubstr("must be a list")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD_cm = [2.7, \"3\"]\n"),
                AllOf(HasSubstr("D_cm = \"3\""), HasSubstr("expected a number")));
    EXPECT_THAT(error_of("[campaign]\nname = 5\n"),
                AllOf(HasSubstr("campaign.name = 5"), HasSubstr("expected a string")));
    EXPECT_THAT(error_of("[campaign]\nname = \"x\"\nrealizations = 2.5\n"),
                AllOf(HasSubstr("campaign.realizations = 2.5"), HasSubstr("expected an integer")));
    EXPECT_THAT(error_of("hopper = 3\n"), HasSubstr("must be a table"));
    // An integer is fine where a float is expected.
    EXPECT_NO_THROW(parse("[hopper]\ntheta_deg = 45\nwidth_cm = 43\n"));
}

TEST(SweepErrors, OutOfRange) {
    struct Case {
        const char* text;
        const char* expect;
    };
    const Case cases[] = {
        {"[material]\ne_n = 1.5\n", "material.e_n = 1.5 is out of range: allowed (0, 1]"},
        {"[material]\ne_n = 0\n", "material.e_n = 0 is out of range: allowed (0, 1]"},
        {"[walls]\ne_n = -0.1\n", "walls.e_n = -0.1 is out of range"},
        {"[material]\nmu = 11\n", "material.mu = 11 is out of range: allowed [0, 10]"},
        {"[material]\nmu = -0.5\n", "material.mu = -0.5 is out of range"},
        {"[hopper]\ntheta_deg = 95\n", "theta_deg = 95 is out of range: allowed [0, 90] deg"},
        {"[hopper]\ntheta_deg = -1\n", "theta_deg = -1 is out of range"},
        {"[hopper]\nparticles = 9223372036854775807\n",
         "hopper.particles = 9223372036854775807 is out of range"},
        {"[material]\nmu = 1e300\n", "material.mu = 1e+300 is out of range"},
        {"[hopper]\nparticles = 0\n",
         "hopper.particles = 0 is out of range: allowed [1, 10000000]"},
        {"[hopper]\nwidth_cm = -3\n",
         "hopper.width_cm = -3 is out of range: allowed (0, 10000] cm"},
        {"[hopper]\nD_cm = nan\n", "D_cm = nan is out of range"},
        {"[hopper]\nd_small_cm = inf\n", "hopper.d_small_cm = inf is out of range"},
        {"[integrator]\nsteps_per_collision = 1\n", "integrator.steps_per_collision = 1"},
        {"[protocol]\nmax_shakes = -1\n", "protocol.max_shakes = -1 is out of range"},
        {"[protocol]\nshake_direction_deg = 200\n", "protocol.shake_direction_deg = 200"},
        {"[material]\npoisson_ratio = 0.7\n", "material.poisson_ratio = 0.7"},
        {"[walls]\nspacing = 2.5\n", "walls.spacing = 2.5 must be below"},
        {"[hopper]\nd_small_cm = 0.9\n",
         "hopper.d_large_cm = 0.77 must be at least hopper.d_small_cm = 0.9"},
        {"[protocol]\nexit_depth = 1.0\n",
         "protocol.exit_depth = 1 must exceed protocol.jam_region_height = 2"},
        {"[hopper]\nparticles = 10\n[protocol]\nempty_threshold = 10\n",
         "protocol.empty_threshold = 10 must be smaller than hopper.particles = 10"},
        {"[campaign]\nname = \"x\"\nrealizations = 0\n",
         "campaign.realizations = 0 is out of range"},
        {"[campaign]\nname = \"a/b\"\n", "campaign.name = \"a/b\" is not allowed"},
        {"[campaign]\nname = \"\"\n", "campaign.name = \"\" is not allowed"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.text);
        EXPECT_THAT(error_of(c.text), AllOf(HasSubstr("bad.toml"), HasSubstr(c.expect)));
    }
}

TEST(SweepErrors, OutOfRangeInsideSweepAndPoints) {
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nmaterial.mu = [0.5, 12]\n"),
                AllOf(HasSubstr("bad.toml:8:"), HasSubstr("material.mu = 12 is out of range")));
    EXPECT_THAT(error_of(campaign_head + "[[points]]\nwalls = { e_n = 2 }\n"),
                HasSubstr("walls.e_n = 2 is out of range"));
    EXPECT_THAT(error_of(campaign_head + "[[points]]\nrealizations = -4\n"),
                HasSubstr("realizations = -4 is out of range"));
}

TEST(SweepErrors, EmptySweepListAndEmptySweep) {
    EXPECT_THAT(
        error_of(campaign_head + "[sweep]\nD_cm = []\n"),
        AllOf(HasSubstr("bad.toml:8:"), HasSubstr("D_cm = [] in [sweep] is an empty list")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nmaterial.mu = []\n"),
                HasSubstr("material.mu = [] in [sweep] is an empty list"));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\n"), HasSubstr("[sweep] has no lists"));
}

TEST(SweepErrors, OutletWiderThanTheHopper) {
    EXPECT_THAT(error_of("[hopper]\nwidth_cm = 20\nD_cm = 25\n"),
                AllOf(HasSubstr("bad.toml"), HasSubstr("D_cm = 25 must be smaller than "
                                                       "hopper.width_cm = 20")));
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD_cm = [2.7, 50]\n"),
                AllOf(HasSubstr("in point 'D_cm=50 theta_deg=45'"),
                      HasSubstr("[sweep] combination 2"), HasSubstr("D_cm = 50 must be smaller")));
}

TEST(SweepErrors, MissingOutletOrAngle) {
    EXPECT_THAT(error_of("[campaign]\nname = \"x\"\n"),
                AllOf(HasSubstr("bad.toml"), HasSubstr("D_cm and theta_deg")));
    EXPECT_THAT(error_of("[campaign]\nname = \"x\"\n[sweep]\nD_cm = [2.7]\n"),
                AllOf(HasSubstr("[sweep] combination 1 has no theta_deg")));
    EXPECT_THAT(error_of("[hopper]\nD_cm = 3\n[campaign]\nname = \"x\"\n[[points]]\n"
                         "material = { mu = 0.5 }\n"),
                AllOf(HasSubstr("[[points]] #1 (line 5) has no theta_deg")));
}

TEST(SweepErrors, DuplicatePoints) {
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD_cm = [2.7, 2.70]\n"),
                AllOf(HasSubstr("duplicate point 'D_cm=2.7 theta_deg=45'"),
                      HasSubstr("[sweep] combination 1"), HasSubstr("[sweep] combination 2")));
    EXPECT_THAT(error_of(campaign_head +
                         "[sweep]\nmaterial.mu = [0.5]\n[[points]]\nmaterial = { mu = 0.5 }\n"
                         "[[points]]\nD_cm = 2.7\ntheta_deg = 45.0\nmaterial = { mu = 0.5 }\n"),
                AllOf(HasSubstr("duplicate point 'D_cm=2.7 theta_deg=45 material.mu=0.5'"),
                      HasSubstr("[sweep] combination 1 and [[points]] #1")));
    // Different settings are not duplicates, even if one of them equals a default.
    EXPECT_NO_THROW(parse(campaign_head + "[[points]]\n[[points]]\nmaterial = { mu = 0.8 }\n"));
}

TEST(SweepErrors, CampaignProblems) {
    EXPECT_THAT(error_of("[campaign]\nname = \"x\"\nseed = -1\n"),
                AllOf(HasSubstr("bad.toml:3:8"), HasSubstr("campaign.seed = -1 is out of range")));
    EXPECT_THAT(error_of("[campaign]\nseed = 3\n"), HasSubstr("[campaign] needs a name"));
    EXPECT_THAT(
        error_of("[campaign]\nname = \"x\"\nseeds = 3\n"),
        AllOf(HasSubstr("unknown key 'seeds' in [campaign]"), HasSubstr("did you mean 'seed'")));
    EXPECT_THAT(error_of("[sweep]\nD_cm = [2.7]\n"), HasSubstr("[sweep] needs a [campaign]"));
    EXPECT_THAT(error_of("[[points]]\nD_cm = 2.7\n"), HasSubstr("[[points]] needs a [campaign]"));
}

TEST(SweepErrors, TomlSyntaxErrorsNameTheLine) {
    EXPECT_THAT(error_of("[hopper]\nwidth_cm = 43\nD_cm = = 2.7\n"),
                AllOf(HasSubstr("bad.toml:3:"), HasSubstr("TOML syntax error")));
    EXPECT_THAT(error_of("[hopper]\n[hopper]\n"),
                AllOf(HasSubstr("bad.toml:2:"), HasSubstr("TOML syntax error")));
    // Truncated files: an unterminated array, table header and string.
    EXPECT_THAT(error_of(campaign_head + "[sweep]\nD_cm = [2.7, 2.9"),
                AllOf(HasSubstr("bad.toml:8:"), HasSubstr("TOML syntax error")));
    EXPECT_THAT(error_of("[hopper]\nwidth_cm = 43\n[mater"),
                AllOf(HasSubstr("bad.toml:3:"), HasSubstr("TOML syntax error")));
    EXPECT_THAT(error_of("[campaign]\nname = \"trunc"), HasSubstr("TOML syntax error"));
}

TEST(SweepErrors, BinaryGarbage) {
    std::string garbage = "[hopper]\n";
    for (int i = 0; i < 256; ++i)
        garbage.push_back(static_cast<char>((i * 37 + 11) & 0xff));
    EXPECT_THAT(error_of(garbage), AllOf(HasSubstr("bad.toml:"), Not(HasSubstr("no error"))));
    EXPECT_THAT(error_of(std::string("width_cm = 4\0\1\2", 15)),
                AllOf(HasSubstr("bad.toml:1:13"), HasSubstr("NUL")));
    EXPECT_THAT(error_of("\xff\xfe\x80garbage = 1\n"),
                AllOf(HasSubstr("bad.toml:1:"), HasSubstr("TOML syntax error")));
}

TEST(SweepErrors, MissingOrUnreadableFile) {
    const fs::path missing = fs::temp_directory_path() / "hopper-config-no-such-file.toml";
    EXPECT_THAT(load_error_of(missing),
                AllOf(HasSubstr(missing.string()), HasSubstr("cannot read the sweep file")));
    EXPECT_THAT(load_error_of(fs::temp_directory_path()), HasSubstr("is a directory"));
}

TEST(SweepLoad, LoadKeepsPathAndText) {
    const fs::path dir = fs::temp_directory_path() / "hopper-config-test";
    fs::create_directories(dir);
    const fs::path file = dir / "sweep.toml";
    const std::string text = campaign_head + "[sweep]\nD_cm = [2.7, 2.9]\n";
    std::ofstream(file) << text;
    const SweepFile s = load_sweep(file);
    EXPECT_EQ(s.path, file);
    EXPECT_EQ(s.text, text);
    EXPECT_EQ(s.campaign.store, dir / "t.h5");
    // Errors name the file as given.
    std::ofstream(file) << "[material]\nmu = 20\n";
    EXPECT_THAT(load_error_of(file), HasSubstr(file.string() + ":2:6: material.mu = 20"));
    fs::remove_all(dir);
}

// Issue 14, item 5: an integer beyond 64 bits was a bare TOML syntax error naming neither the
// key nor the range.
TEST(SweepParse, AnIntegerBeyond64BitsNamesTheKeyAndTheRange) {
    const std::string campaign = "[campaign]\nname = \"x\"\nrealizations = 1\n";
    EXPECT_THAT(error_of(campaign + "seed = 18446744073709551616\n"),
                HasSubstr("bad.toml:4:28: campaign.seed = 18446744073709551616 is out of range: "
                          "allowed [0, 9223372036854775807]"));
    EXPECT_THAT(error_of("[hopper]\nparticles = 99999999999999999999 # many\n"),
                HasSubstr("hopper.particles = 99999999999999999999 is out of range: allowed"));
    EXPECT_THAT(error_of("[protocol]\nunknown_key = 99999999999999999999\n"),
                HasSubstr("protocol.unknown_key = 99999999999999999999 is not a 64-bit integer"));
    // Other syntax errors are reported as before.
    EXPECT_THAT(error_of("[hopper\n"), HasSubstr("TOML syntax error"));
}

// Issue 14, item 5: a hopper narrower than the built-in default outlet (4.5 cm) needed a dummy
// D_cm in [hopper], because that unused default was checked against the width.
TEST(SweepParse, ANarrowHopperNeedsNoDummyOutlet) {
    const std::string narrow = "[hopper]\nwidth_cm = 4.0\nparticles = 30\ntheta_deg = 60\n";
    const SweepFile f = parse(narrow + "[campaign]\nname = \"n\"\n[sweep]\nD_cm = [1.9, 2.2]\n");
    ASSERT_EQ(f.campaign.points.size(), 2u);
    EXPECT_DOUBLE_EQ(f.campaign.points[0].scene.hopper.outlet, 0.019);
    EXPECT_DOUBLE_EQ(scene_at(f, 2.5, 60).hopper.outlet, 0.025);
    // A D_cm that is given, or an outlet that does not fit in a point, is still refused.
    EXPECT_THAT(error_of(narrow + "D_cm = 4.5\n"), HasSubstr("D_cm = 4.5 must be smaller"));
    EXPECT_THAT(error_of(narrow + "[campaign]\nname = \"n\"\n[sweep]\nD_cm = [1.9, 4.2]\n"),
                HasSubstr("D_cm = 4.2 must be smaller than hopper.width_cm = 4"));
    EXPECT_THROW(scene_at(f, 4.5, 60), ConfigError);
}

// ---------------------------------------------------------------------------------------------
// Typed parameters: every key of the table, as the file gave it or converted from the default

namespace {
const Setting* find_setting(const std::vector<Setting>& v, const std::string& name) {
    for (const auto& s : v)
        if (s.name == name) return &s;
    return nullptr;
}
}  // namespace

TEST(Parameters, EveryKeyUnderItsSweepNameAsGivenOrFromTheDefault) {
    const SweepFile s = parse(R"(
[hopper]
density_kg_m3 = 2500
[campaign]
name = "t"
[sweep]
D_cm = [6]
theta_deg = [45]
material.mu = [0.5]
)");
    ASSERT_EQ(s.campaign.points.size(), 1u);
    const Point& p = s.campaign.points[0];
    // The settings are the label's, in its order.
    ASSERT_EQ(p.settings.size(), 3u);
    EXPECT_EQ(p.settings[0], (Setting{"D_cm", 6.0}));
    EXPECT_EQ(p.settings[2], (Setting{"material.mu", 0.5}));
    // Every name parameter_names() gives, except unset optionals, in that order.
    std::vector<std::string> names;
    for (const auto& q : p.parameters)
        names.push_back(q.name);
    std::vector<std::string> expected;
    for (const auto& n : hopper::config::parameter_names())
        if (n != "walls.edge_diameter_cm" && n != "fields.end_s" &&
            n != "material.collision_time_s" && n != "protocol.t_check_s")
            expected.push_back(n);
    EXPECT_EQ(names, expected);
    // Given values as written, choices by name.
    EXPECT_EQ(find_setting(p.parameters, "D_cm")->value, (SettingValue(6.0)));
    EXPECT_EQ(find_setting(p.parameters, "hopper.density_kg_m3")->value, (SettingValue(2500.0)));
    EXPECT_EQ(find_setting(p.parameters, "integrator.scheme")->value,
              (SettingValue(std::string(to_string(p.scene.integrator.scheme)))));
    EXPECT_EQ(find_setting(p.parameters, "fields.enabled")->value,
              (SettingValue(std::string("false"))));
    // Defaults in file units that convert back to the scene's SI value bit for bit; walls
    // follow the material.
    const auto cm_value = [&](const char* n) {
        return std::get<double>(find_setting(p.parameters, n)->value) * hopper::core::cm;
    };
    EXPECT_EQ(cm_value("hopper.thickness_cm"), p.scene.particles.thickness);
    EXPECT_EQ(cm_value("hopper.d_small_cm"), p.scene.particles.d_small);
    EXPECT_EQ(cm_value("hopper.width_cm"), p.scene.hopper.width);
    EXPECT_EQ(find_setting(p.parameters, "walls.mu")->value, (SettingValue(0.5)));
    EXPECT_EQ(std::get<double>(find_setting(p.parameters, "protocol.shake_direction_deg")->value) *
                  hopper::core::deg,
              p.scene.protocol.shake_direction);
}

// parse_sweep_tree: a tree of values (the Python module's dict scene, docs/usage.md "The engine
// from Python"): the same SweepFile as the text with the same keys, and the same checks.
TEST(SweepTree, GivesWhatTheSameTextGives) {
    const SweepFile text = parse(R"(
[hopper]
width_cm = 10.0
particles = 500
theta_deg = 60
[material]
mu = 0.4
[integrator]
scheme = "gear4"
contact_corrections = false
[campaign]
name = "t"
seed = 7
[sweep]
D_cm = [2.5, 3]
material.e_n = [0.8, 0.9]
[[points]]
D_cm = 4.0
walls = { mu = 0.3 }
)");
    const auto tree = nlohmann::json::parse(R"({
        "hopper": {"width_cm": 10.0, "particles": 500, "theta_deg": 60},
        "material.mu": 0.4,
        "integrator": {"scheme": "gear4", "contact_corrections": false},
        "campaign": {"name": "t", "seed": 7},
        "sweep": {"D_cm": [2.5, 3], "material.e_n": [0.8, 0.9]},
        "points": [{"D_cm": 4.0, "walls": {"mu": 0.3}}]})");
    const SweepFile from_tree = hopper::config::parse_sweep_tree(tree, "<dict>");
    EXPECT_EQ(from_tree.path, fs::path("<dict>"));
    EXPECT_THAT(from_tree.text, AllOf(HasSubstr("[integrator]"), HasSubstr("gear4")));  // as TOML
    ASSERT_EQ(labels(from_tree.campaign), labels(text.campaign));
    ASSERT_EQ(from_tree.campaign.points.size(), 5u);
    for (std::size_t i = 0; i < text.campaign.points.size(); ++i) {
        const Point& a = text.campaign.points[i];
        const Point& b = from_tree.campaign.points[i];
        EXPECT_EQ(hopper::config::scene_fingerprint(a.scene),
                  hopper::config::scene_fingerprint(b.scene));
        EXPECT_EQ(a.parameters, b.parameters);
        EXPECT_EQ(derive_seed(7, a.settings, 3), derive_seed(7, b.settings, 3));
    }
    EXPECT_EQ(from_tree.base_parameters, text.base_parameters);
    EXPECT_EQ(find_setting(text.base_parameters, "theta_deg")->value, (SettingValue(60.0)));
    EXPECT_EQ(find_setting(text.base_parameters, "material.mu")->value, (SettingValue(0.4)));
}

TEST(SweepTree, BadValuesAreNamedByKey) {
    const auto error_of_tree = [](const char* json) -> std::string {
        try {
            hopper::config::parse_sweep_tree(nlohmann::json::parse(json), "<dict>");
        } catch (const ConfigError& e) {
            return e.what();
        }
        return "<<no error was thrown>>";
    };
    // The parser's own messages, without a line number.
    EXPECT_THAT(error_of_tree(R"({"material": {"mux": 0.5}})"),
                AllOf(HasSubstr("<dict>: unknown key 'mux' in [material]"),
                      HasSubstr("did you mean 'mu'")));
    EXPECT_THAT(error_of_tree(R"({"hopper": {"particles": 2.5}})"),
                HasSubstr("<dict>: hopper.particles = 2.5 has the wrong type"));
    // What TOML cannot hold.
    EXPECT_THAT(error_of_tree(R"({"protocol": {"max_time_s": null}})"),
                HasSubstr("<dict>: protocol.max_time_s has no value"));
    EXPECT_THAT(error_of_tree(R"({"campaign": {"name": "t", "seed": 9223372036854775808}})"),
                AllOf(HasSubstr("campaign.seed = 9223372036854775808 is not a 64-bit integer"),
                      HasSubstr("9223372036854775807]")));
    EXPECT_THAT(error_of_tree(R"({"material": {"mu": 0.5}, "material.mu": 0.4})"),
                HasSubstr("<dict>: material.mu is given twice"));
    EXPECT_THAT(error_of_tree(R"({"material": 1, "material.mu": 0.4})"),
                HasSubstr("material is given twice: as a value and as a table"));
    EXPECT_THAT(error_of_tree(R"({"material..mu": 0.4})"), HasSubstr("empty part"));
    EXPECT_THAT(error_of_tree(R"([1, 2])"), HasSubstr("a scene is a table of sections"));
}
