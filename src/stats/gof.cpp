#include "hopper/stats/gof.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hopper/core/random.hpp"
#include "hopper/stats/kaplan_meier.hpp"
#include "hopper/stats/sampling.hpp"

namespace hopper::stats {

namespace {

void check_options(const GofOptions& opt) {
    if (opt.n_bootstrap < 19)
        throw std::invalid_argument(
            "GofOptions: n_bootstrap must be >= 19 (p-value resolution 0.05)");
}

// D = max_i max(i/n - F0(x_(i)), F0(x_(i)) - (i-1)/n) with F0(x) = 1 - exp(-x / mean(x)).
// Sorts x in place.
double complete_distance(std::vector<double>& x) {
    std::sort(x.begin(), x.end());
    const double n = static_cast<double>(x.size());
    double sum = 0.0;
    for (double v : x)
        sum += v;
    const double tau = sum / n;
    double D = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double F0 = -std::expm1(-x[i] / tau);
        D = std::max({D, (i + 1) / n - F0, F0 - i / n});
    }
    return D;
}

// sup_{0 <= t <= last_time} |S_KM(t) - exp(-t/tau)|. S_KM is constant (= s) on each segment
// [a, b) between event times and exp(-t/tau) is monotone, so the sup on a segment is attained at
// its ends: max(|s - S0(a)|, |s - S0(b)|).
double km_distance(const KaplanMeierCurve& km, double tau) {
    double a = 0.0, s = 1.0, D = 0.0;
    auto segment = [&](double b) {
        D = std::max({D, std::abs(s - std::exp(-a / tau)), std::abs(s - std::exp(-b / tau))});
    };
    for (std::size_t j = 0; j < km.time.size(); ++j) {
        segment(km.time[j]);
        a = km.time[j];
        s = km.survival[j];
    }
    segment(std::max(km.last_time, a));
    return D;
}

struct CensoredStat {
    int events = 0;
    double tau = 0.0;
    double D = 0.0;
};

CensoredStat censored_distance(std::span<const double> t, const std::vector<bool>& censored) {
    CensoredStat c;
    double T = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        T += t[i];
        if (!censored[i]) ++c.events;
    }
    if (c.events == 0 || T <= 0.0) return c;
    c.tau = T / c.events;  // censored MLE (exponential_fit.hpp)
    c.D = km_distance(kaplan_meier(t, censored), c.tau);
    return c;
}

}  // namespace

GofResult ks_exponential(std::span<const double> x, const GofOptions& opt) {
    check_options(opt);
    GofResult g;
    g.method =
        "Kolmogorov-Smirnov against the exponential with the fitted mean (complete sample), "
        "p-value by parametric bootstrap (Lilliefors-type)";
    g.n = g.n_events = static_cast<int>(x.size());
    double sum = 0.0;
    for (double v : x) {
        if (!(v >= 0.0) || !std::isfinite(v))
            throw std::invalid_argument("ks_exponential: a value is negative or not finite");
        sum += v;
    }
    if (g.n < kMinGofEvents) {
        g.reason = "too few intervals for a goodness-of-fit test (" + std::to_string(g.n) + " < " +
                   std::to_string(kMinGofEvents) + ")";
        return g;
    }
    if (sum <= 0.0) {
        g.reason = "all intervals are zero";
        return g;
    }
    g.tau = sum / g.n;
    std::vector<double> work(x.begin(), x.end());
    g.statistic = complete_distance(work);

    // The null law of D does not depend on tau: simulate Exp(1).
    core::Rng rng(opt.seed);
    int exceed = 0;
    for (int b = 0; b < opt.n_bootstrap; ++b) {
        for (double& v : work)
            v = draw_exponential(rng, 1.0);
        if (complete_distance(work) >= g.statistic) ++exceed;
    }
    g.n_bootstrap = opt.n_bootstrap;
    g.p_value = (1.0 + exceed) / (1.0 + opt.n_bootstrap);
    g.valid = true;
    return g;
}

GofResult ks_exponential_censored(std::span<const double> t, const std::vector<bool>& censored,
                                  std::span<const double> windows, const GofOptions& opt) {
    check_options(opt);
    if (t.size() != censored.size())
        throw std::invalid_argument("ks_exponential_censored: " + std::to_string(t.size()) +
                                    " intervals but " + std::to_string(censored.size()) +
                                    " censoring flags");
    double T = 0.0, Tw = 0.0;
    for (double v : t) {
        if (!(v >= 0.0) || !std::isfinite(v))
            throw std::invalid_argument(
                "ks_exponential_censored: an interval is negative or not finite");
        T += v;
    }
    for (double w : windows) {
        if (!(w >= 0.0) || !std::isfinite(w))
            throw std::invalid_argument(
                "ks_exponential_censored: a window is negative or not finite");
        Tw += w;
    }
    if (std::abs(T - Tw) > 1e-6 * std::max(T, Tw))
        throw std::invalid_argument(
            "ks_exponential_censored: the windows sum to " + std::to_string(Tw) +
            " s but the intervals to " + std::to_string(T) +
            " s; each window must be the sum of its realization's intervals");

    GofResult g;
    g.method =
        "Kolmogorov-Smirnov distance between the Kaplan-Meier curve and the exponential with "
        "the censored MLE, p-value by parametric bootstrap replaying each realization's "
        "flow time";
    g.n = static_cast<int>(t.size());
    const CensoredStat obs = censored_distance(t, censored);
    g.n_events = obs.events;
    if (obs.events < kMinGofEvents) {
        g.reason = "too few jams for a goodness-of-fit test (" + std::to_string(obs.events) +
                   " < " + std::to_string(kMinGofEvents) + ")";
        return g;
    }
    g.tau = obs.tau;
    g.statistic = obs.D;

    core::Rng rng(opt.seed);
    std::vector<double> bt;
    std::vector<bool> bc;
    int exceed = 0, done = 0;
    const long max_attempts = 100L * opt.n_bootstrap;
    for (long attempt = 0; attempt < max_attempts && done < opt.n_bootstrap; ++attempt) {
        bt.clear();
        bc.clear();
        for (double W : windows) {
            if (W <= 0.0) continue;
            double elapsed = 0.0;
            while (true) {
                const double e = draw_exponential(rng, obs.tau);
                if (elapsed + e < W) {
                    bt.push_back(e);
                    bc.push_back(false);
                    elapsed += e;
                } else {
                    bt.push_back(W - elapsed);
                    bc.push_back(true);
                    break;
                }
            }
        }
        const CensoredStat rep = censored_distance(bt, bc);
        if (rep.events < kMinGofEvents) continue;  // condition as the observed data are
        ++done;
        if (rep.D >= obs.D) ++exceed;
    }
    if (done < opt.n_bootstrap) {
        g.reason =
            "the fitted exponential rarely produces enough jams in these windows for a "
            "bootstrap";
        return g;
    }
    g.n_bootstrap = done;
    g.p_value = (1.0 + exceed) / (1.0 + done);
    g.valid = true;
    return g;
}

LogSurvivalLine log_survival_line(std::span<const double> t, const std::vector<bool>& censored) {
    const KaplanMeierCurve km = kaplan_meier(t, censored);
    LogSurvivalLine line;
    std::vector<double> xs, ys;
    for (std::size_t j = 0; j < km.time.size(); ++j) {
        if (km.survival[j] <= 0.0) continue;
        xs.push_back(km.time[j]);
        ys.push_back(std::log(km.survival[j]));
    }
    line.n_points = static_cast<int>(xs.size());
    if (line.n_points < 3) {
        line.reason = "fewer than 3 points of the survival function with S > 0";
        return line;
    }
    // Ordinary least squares: b = Sxy / Sxx, a = ybar - b xbar; R^2 = 1 - SS_res / SS_tot.
    const double n = line.n_points;
    double xbar = 0.0, ybar = 0.0;
    for (int i = 0; i < line.n_points; ++i) {
        xbar += xs[i] / n;
        ybar += ys[i] / n;
    }
    double sxx = 0.0, sxy = 0.0, syy = 0.0;
    for (int i = 0; i < line.n_points; ++i) {
        sxx += (xs[i] - xbar) * (xs[i] - xbar);
        sxy += (xs[i] - xbar) * (ys[i] - ybar);
        syy += (ys[i] - ybar) * (ys[i] - ybar);
    }
    if (sxx <= 0.0 || syy <= 0.0) {
        line.reason = "survival points do not spread in time or in S";
        return line;
    }
    line.slope = sxy / sxx;
    line.intercept = ybar - line.slope * xbar;
    double ss_res = 0.0;
    for (int i = 0; i < line.n_points; ++i) {
        const double r = ys[i] - (line.intercept + line.slope * xs[i]);
        ss_res += r * r;
    }
    line.r2 = 1.0 - ss_res / syy;
    line.valid = true;
    return line;
}

}  // namespace hopper::stats
