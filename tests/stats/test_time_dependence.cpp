// Early-versus-late jam-rate test.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "hopper/core/random.hpp"
#include "hopper/stats/sampling.hpp"
#include "hopper/stats/time_dependence.hpp"

using namespace hopper::stats;
using hopper::core::Rng;

namespace {

// Jam onsets of a Poisson process with rate lambda(t) = lambda0 (1 + slope t / W) on [0, W], by
// thinning a homogeneous process of the maximal rate (Lewis & Shedler 1979). Each jam blocks the
// outlet for `dead` seconds (not at risk), which is passed on as a not-at-risk period.
JamHistory history(Rng& rng, double W, double lambda0, double slope, double dead) {
    JamHistory h;
    h.window = W;
    const double lmax = lambda0 * (1.0 + std::max(slope, 0.0));
    double t = 0.0;
    while (true) {
        t += draw_exponential(rng, 1.0 / lmax);
        if (t >= W) break;
        if (rng.uniform() * lmax < lambda0 * (1.0 + slope * t / W)) {
            h.onsets.push_back(t);
            const double end = std::min(t + dead, W);
            h.not_at_risk.emplace_back(t, end);
            t = end;  // no jam while jammed
        }
    }
    return h;
}

}  // namespace

TEST(EarlyLate, CountsAndExposureByHand) {
    std::vector<JamHistory> h(2);
    h[0].window = 10.0;
    h[0].onsets = {1.0, 6.0, 9.0};
    h[0].not_at_risk = {{1.0, 2.0}, {4.5, 5.5}};  // 1 s early, 0.5 + 0.5 s split across the cut
    h[1].window = 4.0;
    h[1].onsets = {2.0};  // exactly at the cut: late
    const EarlyLateTest r = early_late_rate_test(h);
    ASSERT_TRUE(r.valid);
    EXPECT_EQ(r.n_early, 1);
    EXPECT_EQ(r.n_late, 3);
    EXPECT_DOUBLE_EQ(r.exposure_early, (5.0 - 1.5) + 2.0);
    EXPECT_DOUBLE_EQ(r.exposure_late, (5.0 - 0.5) + 2.0);
    EXPECT_DOUBLE_EQ(*r.rate_early, 1.0 / 5.5);
    EXPECT_DOUBLE_EQ(*r.rate_late, 3.0 / 6.5);
    EXPECT_DOUBLE_EQ(*r.rate_ratio, (3.0 / 6.5) / (1.0 / 5.5));
    EXPECT_GT(r.p_value, 0.2);  // 1 versus 3 is no evidence
}

TEST(EarlyLate, HomogeneousPoissonRejectsAtAlpha) {
    Rng rng(31);
    const int trials = 400;
    int rej_exact = 0, rej_lr = 0;
    for (int trial = 0; trial < trials; ++trial) {
        std::vector<JamHistory> hs;
        for (int k = 0; k < 10; ++k)
            hs.push_back(history(rng, 20.0, 0.5, 0.0, 0.3));
        const EarlyLateTest r = early_late_rate_test(hs);  // ~95 jams per trial
        ASSERT_TRUE(r.valid);
        if (r.p_value <= 0.05) ++rej_exact;
        if (r.p_value_lr <= 0.05) ++rej_lr;
    }
    RecordProperty("rejection_exact", std::to_string(rej_exact / double(trials)));
    RecordProperty("rejection_lr", std::to_string(rej_lr / double(trials)));
    // Binomial sd of a 5 % rate over 400 trials: 1.1 %. The exact test is conservative by
    // construction (size <= alpha); the LR test is asymptotic.
    EXPECT_LE(rej_exact / double(trials), 0.05 + 0.035);
    EXPECT_GE(rej_exact / double(trials), 0.015);
    EXPECT_NEAR(rej_lr / double(trials), 0.05, 0.035);
}

TEST(EarlyLate, StronglyIncreasingRateIsRejected) {
    Rng rng(32);
    const int trials = 100;
    int rejected = 0;
    for (int trial = 0; trial < trials; ++trial) {
        std::vector<JamHistory> hs;
        // Rate grows fourfold over the discharge: mean rate 1.75 lambda0 early, 3.25 lambda0
        // late (ratio 1.86); about 200 jams per trial.
        for (int k = 0; k < 20; ++k)
            hs.push_back(history(rng, 20.0, 0.3, 3.0, 0.3));
        const EarlyLateTest r = early_late_rate_test(hs);
        if (r.p_value <= 0.05) ++rejected;
        if (trial == 0) {
            EXPECT_GT(*r.rate_ratio, 1.0);
        }
    }
    RecordProperty("rejection_increasing", std::to_string(rejected / double(trials)));
    EXPECT_GE(rejected, 95);
}

TEST(EarlyLate, NoJamsOrBadInput) {
    std::vector<JamHistory> h(1);
    h[0].window = 5.0;
    const EarlyLateTest r = early_late_rate_test(h);
    EXPECT_FALSE(r.valid);
    EXPECT_FALSE(r.reason.empty());
    EXPECT_FALSE(r.rate_ratio.has_value());
    h[0].onsets = {6.0};
    EXPECT_THROW(early_late_rate_test(h), std::invalid_argument);
    h[0].onsets = {1.0};
    EXPECT_THROW(early_late_rate_test(h, 1.0), std::invalid_argument);
}
