#include "hopper/analysis/derived.hpp"

#include <algorithm>
#include <cstdint>

#include "hopper/store/records.hpp"

namespace hopper::analysis {

namespace {

// Builds columns of one table: optional values become 0 plus a has_<name> flag.
struct Columns {
    std::vector<store::DerivedDataset> ds;
    void real(const std::string& name, const std::string& units, const std::string& desc,
              std::vector<double> v) {
        ds.push_back({name, units, desc, std::move(v)});
    }
    void integer(const std::string& name, const std::string& desc, std::vector<std::int64_t> v) {
        ds.push_back({name, "1", desc, std::move(v)});
    }
    void optional(const std::string& name, const std::string& units, const std::string& desc,
                  const std::vector<std::optional<double>>& v) {
        std::vector<double> x;
        std::vector<bool> has;
        for (const auto& o : v) {
            x.push_back(o.value_or(0.0));
            has.push_back(o.has_value());
        }
        ds.push_back({name, units, desc + " (0 where has_" + name + " is FALSE)", std::move(x)});
        ds.push_back({"has_" + name, "1", "whether " + name + " is defined", std::move(has)});
    }
    void text(const std::string& name, const std::string& desc, std::vector<std::string> v) {
        ds.push_back({name, "", desc, std::move(v)});
    }
};

template <class F>
auto per_point(const Analysis& a, F f) {
    std::vector<decltype(f(a.points.front()))> out;
    for (const auto& p : a.points)
        out.push_back(f(p));
    return out;
}

template <class F>
auto per_group(const Analysis& a, F f) {
    std::vector<decltype(f(a.groups.front()))> out;
    for (const auto& g : a.groups)
        out.push_back(f(g));
    return out;
}

std::optional<double> when(bool ok, double v) {
    return ok ? std::optional<double>(v) : std::nullopt;
}

// /analysis/fields/<label>: one point's merged fields as ny x nx maps.
store::DerivedGroup point_fields_group(const PointAnalysis& p) {
    const engine::FieldMoments& m = *p.fields.merged;
    const engine::FieldGrid& g = m.grid;
    std::string name = p.label;
    std::replace(name.begin(), name.end(), '/', '_');  // an HDF5 path component
    store::DerivedGroup out;
    out.name = name;
    out.attributes = {
        {"label", p.label},
        {"description",
         "fields of the point merged over its realizations that did not fail: per cell the mean "
         "over all windows and the fluctuation std = sqrt(M2 / (n - 1)) (0 where n < 2); cells "
         "without data (windows == 0) hold 0 in every map: mask them with windows == 0"},
        {"kernel", engine::to_string(g.kernel)}};
    for (int f = 0; f < engine::field_count; ++f) {
        const auto field = static_cast<engine::Field>(f);
        out.attributes.emplace_back("units_" + std::string(engine::field_name(field)),
                                    std::string(engine::field_unit(field)));
    }
    using I = std::int64_t;
    out.numbers = {{"cell", g.cell},
                   {"x0", g.x0},
                   {"y0", g.y0},
                   {"kernel_width", g.kernel_width},
                   {"nx", I(g.nx)},
                   {"ny", I(g.ny)},
                   {"realizations", I(p.fields.realizations)},
                   {"total_windows", m.total_windows},
                   {"samples", m.samples},
                   {"t_first", m.t_first},
                   {"t_last", m.t_last},
                   {"cells_with_data", p.fields.cells_with_data},
                   {"wall_diameter", m.wall_diameter}};
    const std::vector<std::uint64_t> shape = {std::uint64_t(g.ny), std::uint64_t(g.nx)};
    std::vector<double> x(std::size_t(g.nx)), y(std::size_t(g.ny));
    for (int i = 0; i < g.nx; ++i)
        x[std::size_t(i)] = g.x0 + (i + 0.5) * g.cell;
    for (int j = 0; j < g.ny; ++j)
        y[std::size_t(j)] = g.y0 + (j + 0.5) * g.cell;
    auto& ds = out.datasets;
    ds.push_back({"x", "m", "x of the cell centres (columns)", std::move(x)});
    ds.push_back({"y", "m", "y of the cell centres (rows); the outlet is at y = 0", std::move(y)});
    ds.push_back({"windows", "1",
                  "windows in which the cell took part, over all merged realizations (n); 0: no "
                  "data",
                  m.windows, shape});
    ds.push_back({"weight", "1",
                  "summed kernel weight over all samples (cell kernel: particle-samples)", m.weight,
                  shape});
    for (int f = 0; f < engine::field_count; ++f) {
        const auto field = static_cast<engine::Field>(f);
        const std::string fname(engine::field_name(field)), unit(engine::field_unit(field));
        std::vector<double> mean(m.mean[f].size()), sd(m.mean[f].size());
        for (std::size_t c = 0; c < mean.size(); ++c) {
            const bool data = m.windows[c] > 0;
            mean[c] = data ? m.mean[f][c] : 0.0;
            sd[c] = data ? m.fluctuation(field, int(c)) : 0.0;
        }
        ds.push_back({"mean_" + fname, unit,
                      "mean over windows of " + fname + " (0 where windows == 0)", std::move(mean),
                      shape});
        ds.push_back({"std_" + fname, unit,
                      "fluctuation of " + fname +
                          ": standard deviation over windows sqrt(M2 / (n - 1)); 0 where n < 2",
                      std::move(sd), shape});
    }
    ds.push_back({"outline_x", "m",
                  "centre line of the right-hand wall particles from the outlet upwards (mirror x "
                  "for the left wall); wall particle diameter: attribute wall_diameter",
                  m.outline_x});
    ds.push_back({"outline_y", "m", "y of outline_x", m.outline_y});
    return out;
}

std::optional<store::DerivedGroup> fields_group(const Analysis& a) {
    store::DerivedGroup out;
    out.name = "fields";
    out.attributes = {{"description",
                       "coarse-grained fields per point (one group per point with fields, named "
                       "by its label; `labels` lists them in /points order)"}};
    std::vector<std::string> labels;
    for (const auto& p : a.points) {
        if (!p.fields.merged) continue;
        labels.push_back(p.label);
        out.groups.push_back(point_fields_group(p));
    }
    if (labels.empty()) return std::nullopt;
    out.datasets.push_back(
        {"labels", "", "labels of the points with fields, in /points order", std::move(labels)});
    return out;
}

}  // namespace

namespace {

using I = std::int64_t;

// /analysis/points (one row per point) and /analysis/km (the Kaplan–Meier curves it indexes).
std::pair<store::DerivedGroup, store::DerivedGroup> points_and_km(const Analysis& a) {
    Columns c;
    c.text("label", "the point's settings", per_point(a, [](auto& p) { return p.label; }));
    c.text("group", "theta and other varied settings: the points of one fit",
           per_point(a, [](auto& p) { return p.group; }));
    c.real("D_cm", "cm", "outlet width", per_point(a, [](auto& p) { return p.D_cm; }));
    c.real("theta_deg", "deg", "wall angle", per_point(a, [](auto& p) { return p.theta_deg; }));
    c.integer("realizations", "stored realizations",
              per_point(a, [](auto& p) { return I(p.stored); }));
    c.integer("realizations_planned", "planned realizations",
              per_point(a, [](auto& p) { return I(p.planned); }));
    c.integer("n_complete", "realizations that emptied",
              per_point(a, [](auto& p) { return I(p.n_complete); }));
    c.integer("n_failed", "realizations that failed (left out of the statistics)",
              per_point(a, [](auto& p) { return I(p.n_failed); }));
    c.integer("n_arrested", "realizations arrested by an unclearable jam",
              per_point(a, [](auto& p) { return I(p.n_arrested); }));
    c.integer("n_time_limit", "realizations stopped at max_time",
              per_point(a, [](auto& p) { return I(p.n_time_limit); }));
    c.integer("n_jams", "jams", per_point(a, [](auto& p) { return I(p.n_jams); }));
    c.integer("n_shakes", "shakes", per_point(a, [](auto& p) { return I(p.n_shakes); }));
    c.integer("n_uncensored", "survival intervals ended by a jam",
              per_point(a, [](auto& p) { return I(p.fit ? p.fit->n_uncensored : 0); }));
    c.integer("n_intervals", "survival intervals",
              per_point(a, [](auto& p) { return I(p.fit ? p.fit->n_intervals : 0); }));
    c.real("total_observed_time", "s", "sum of all survival intervals",
           per_point(a, [](auto& p) { return p.fit ? p.fit->total_observed_time : 0.0; }));
    c.optional("mean_survival", "s", "algebraic mean of all intervals (biased low by censoring)",
               per_point(a, [](auto& p) { return p.fit ? p.fit->mean_all : std::nullopt; }));
    c.optional("tau_mle", "s", "censored exponential MLE T/r",
               per_point(a, [](auto& p) { return p.fit ? p.fit->tau : std::nullopt; }));
    c.optional(
        "tau_ci95_lo", "s", "95 % chi-square interval of tau, lower end (r >= 1)",
        per_point(a, [](auto& p) { return p.fit && p.fit->tau ? p.fit->tau_lo : std::nullopt; }));
    c.optional("tau_ci95_hi", "s", "95 % chi-square interval of tau, upper end",
               per_point(a, [](auto& p) { return p.fit ? p.fit->tau_hi : std::nullopt; }));
    c.optional(
        "tau_lower_bound95", "s", "one-sided 95 % bound tau > T/ln 20 when r = 0",
        per_point(a, [](auto& p) { return p.fit && !p.fit->tau ? p.fit->tau_lo : std::nullopt; }));
    c.optional("gof_p", "1", "bootstrap KS p-value of the exponential law (censored data)",
               per_point(a, [](auto& p) { return when(p.gof.valid, p.gof.p_value); }));
    c.optional("r2_log_survival", "1", "R^2 of a line fitted to ln S_KM(t) (descriptive)",
               per_point(a, [](auto& p) { return when(p.line.valid, p.line.r2); }));
    c.optional("empty_time_mean", "s", "mean empty time",
               per_point(a, [](auto& p) { return p.empty_time.mean; }));
    c.optional("empty_time_std", "s", "standard deviation of the empty time",
               per_point(a, [](auto& p) { return p.empty_time.std_dev; }));
    c.optional("empty_time_err", "s", "standard error of the mean empty time",
               per_point(a, [](auto& p) { return p.empty_time.std_err; }));
    c.optional("discharge_rate", "1/s", "mean discharge rate (particles/s)",
               per_point(a, [](auto& p) { return p.rate.mean; }));
    c.optional("discharge_rate_err", "1/s", "standard error of the mean discharge rate",
               per_point(a, [](auto& p) { return p.rate.std_err; }));
    c.optional("discharge_rate_kg_s", "kg/s", "mean mass flow rate",
               per_point(a, [](auto& p) { return p.rate_kg.mean; }));
    c.optional("discharge_rate_kg_s_err", "kg/s", "standard error of the mean mass flow rate",
               per_point(a, [](auto& p) { return p.rate_kg.std_err; }));
    c.optional(
        "early_late_p", "1", "exact test of equal jam rates, early vs late half",
        per_point(a, [](auto& p) { return when(p.early_late.valid, p.early_late.p_value); }));
    c.optional("rate_early", "1/s", "jam rate in the early half",
               per_point(a, [](auto& p) { return p.early_late.rate_early; }));
    c.optional("rate_late", "1/s", "jam rate in the late half",
               per_point(a, [](auto& p) { return p.early_late.rate_late; }));
    const auto av_tau = [](auto& p) {
        return p.avalanche.fit ? p.avalanche.fit->tau : std::optional<double>();
    };
    c.optional("mean_avalanche", "1", "mean avalanche size <s>: censored MLE grains / jams",
               per_point(a, av_tau));
    c.optional("mean_avalanche_err", "1", "standard error of <s>: <s> / sqrt(jams)",
               per_point(a, [](auto& p) {
                   const auto& f = p.avalanche.fit;
                   return f && f->tau && f->sigma_log_tau
                              ? std::optional<double>(*f->tau * *f->sigma_log_tau)
                              : std::nullopt;
               }));
    c.optional("mean_avalanche_ci95_lo", "1", "95 % chi-square interval of <s>, lower end",
               per_point(a, [](auto& p) {
                   const auto& f = p.avalanche.fit;
                   return f && f->tau ? f->tau_lo : std::nullopt;
               }));
    c.optional("mean_avalanche_ci95_hi", "1", "95 % chi-square interval of <s>, upper end",
               per_point(a, [](auto& p) {
                   const auto& f = p.avalanche.fit;
                   return f && f->tau ? f->tau_hi : std::nullopt;
               }));
    c.optional("p_clog_per_grain", "1", "clogging probability per grain 1/<s>",
               per_point(a, [&](auto& p) {
                   const auto t = av_tau(p);
                   return t ? std::optional<double>(1.0 / *t) : std::nullopt;
               }));
    c.optional(
        "avalanche_gof_p", "1", "bootstrap KS p-value of the exponential law of s",
        per_point(a, [](auto& p) { return when(p.avalanche.gof.valid, p.avalanche.gof.p_value); }));
    c.integer("arches_found", "jams whose arch was found",
              per_point(a, [](auto& p) { return I(p.avalanche.arches_found); }));
    c.integer("arch_jams", "jams with arch data",
              per_point(a, [](auto& p) { return I(p.avalanche.arch_jams); }));
    c.optional("arch_mean_size", "1", "mean number of disks of the arches found",
               per_point(a, [](auto& p) { return p.avalanche.arch_mean_size; }));
    c.real("rho_b", "kg/m^2", "2D bulk density used (estimate, see rho_b_source)",
           per_point(a, [](auto& p) { return p.rho_b; }));
    c.real("d", "m", "mean particle diameter (see d_definition)",
           per_point(a, [](auto& p) { return p.d_mean; }));

    // Kaplan–Meier curves, concatenated: point i's steps are [km_start[i], +km_length[i]).
    std::vector<double> kt, ks, ke;
    std::vector<std::int64_t> kstart, klen;
    for (const auto& p : a.points) {
        kstart.push_back(static_cast<I>(kt.size()));
        klen.push_back(static_cast<I>(p.km.time.size()));
        kt.insert(kt.end(), p.km.time.begin(), p.km.time.end());
        ks.insert(ks.end(), p.km.survival.begin(), p.km.survival.end());
        ke.insert(ke.end(), p.km.std_err.begin(), p.km.std_err.end());
    }
    c.integer("km_start", "first row of the point's Kaplan–Meier steps in /analysis/km",
              std::move(kstart));
    c.integer("km_length", "number of the point's Kaplan–Meier steps", std::move(klen));
    store::DerivedGroup points{
        "points", {{"description", "one row per point"}}, std::move(c.ds), {}};

    store::DerivedGroup km{
        "km", {{"description", "Kaplan–Meier survival curves of all points"}}, {}, {}};
    km.datasets.push_back({"time", "s", "event time t_j", std::move(kt)});
    km.datasets.push_back({"survival", "1", "S_KM(t_j)", std::move(ks)});
    km.datasets.push_back({"std_err", "1", "Greenwood standard error of S_KM(t_j)", std::move(ke)});

    return {std::move(points), std::move(km)};
}

// /analysis/beverloo: one row per group.
store::DerivedGroup beverloo_table(const Analysis& a) {
    Columns b;
    b.text("group", "theta and other varied settings",
           per_group(a, [](auto& g) { return g.group; }));
    b.real("theta_deg", "deg", "wall angle", per_group(a, [](auto& g) { return g.theta_deg; }));
    b.integer("n_points", "outlets with a flow rate",
              per_group(a, [](auto& g) { return I(g.beverloo.n_points); }));
    const auto bv = [&](auto get) {
        return per_group(a, [&](auto& g) { return when(g.beverloo.valid, get(g.beverloo)); });
    };
    b.optional("C", "1", "Beverloo C", bv([](auto& f) { return f.C; }));
    b.optional("C_err", "1", "standard error of C", bv([](auto& f) { return f.C_err; }));
    b.optional("k", "1", "Beverloo k", bv([](auto& f) { return f.k; }));
    b.optional("k_err", "1", "standard error of k", bv([](auto& f) { return f.k_err; }));
    b.real("rho_b", "kg/m^2", "2D bulk density used",
           per_group(a, [&](auto& g) { return a.points[std::size_t(g.points.front())].rho_b; }));
    b.real("d", "m", "particle diameter used",
           per_group(a, [&](auto& g) { return a.points[std::size_t(g.points.front())].d_mean; }));
    b.text("reason", "why the fit is missing (empty when valid)", per_group(a, [](auto& g) {
               return g.beverloo.valid ? std::string() : g.beverloo.reason;
           }));
    store::DerivedGroup bev{"beverloo",
                            {{"description", "W = C rho_b sqrt(g) (D - k d)^(3/2) per group"}},
                            std::move(b.ds),
                            {}};

    return bev;
}

// One table of fits across D per group (jam rate, avalanche size): the group and its angle
// first, then the columns `laws` adds (given per-group getters of the exponential and the
// power-law fit, absent where the law is not valid), the verdict last.
template <class Laws>
store::DerivedGroup fits_table(const Analysis& a, stats::JamRateFits GroupAnalysis::*fits,
                               const std::string& name, const std::string& description, Laws laws) {
    Columns cols;
    cols.text("group", "theta and other varied settings",
              per_group(a, [](auto& g) { return g.group; }));
    cols.real("theta_deg", "deg", "wall angle", per_group(a, [](auto& g) { return g.theta_deg; }));
    cols.integer("n_points", "outlets with jams",
                 per_group(a, [&](auto& g) { return I((g.*fits).n_points); }));
    const auto ex = [&](auto get) {
        return per_group(a, [&](auto& g) {
            const auto& f = (g.*fits).exponential;
            return when(f.valid, get(f));
        });
    };
    const auto pw = [&](auto get) {
        return per_group(a, [&](auto& g) {
            const auto& f = (g.*fits).power_law;
            return when(f.valid, get(f));
        });
    };
    laws(cols, ex, pw);
    cols.text("preferred", "exponential, power_law or undecided",
              per_group(a, [&](auto& g) { return (g.*fits).preferred; }));
    cols.text("decision", "why", per_group(a, [&](auto& g) { return (g.*fits).decision; }));
    return {name, {{"description", description}}, std::move(cols.ds), {}};
}

}  // namespace

store::DerivedGroup analysis_group(const Analysis& a, const std::string& json) {
    store::DerivedGroup root;
    root.name = "analysis";
    root.attributes = {
        {"description",
         "derived by `campaign analyze` from the realizations (replaced on re-analysis; lost "
         "when the file is rebuilt from the journal: run `campaign analyze` again)"},
        {"created", store::utc_now()},
        {"rho_b_source", a.rho_b_source},
        {"d_definition", a.d_definition},
        {"json", json}};
    if (a.points.empty()) return root;

    auto [points, km] = points_and_km(a);
    store::DerivedGroup jr = fits_table(
        a, &GroupAnalysis::jam_rate, "jam_rate", "jam rate 1/tau versus D per group",
        [](Columns& j, const auto& ex, const auto& pw) {
            j.optional("exp_ln_A", "1", "exponential: ln(A / (1/s))",
                       ex([](auto& f) { return f.ln_A; }));
            j.optional("exp_B", "1/m", "exponential: B", ex([](auto& f) { return f.B; }));
            j.optional("exp_B_err", "1/m", "exponential: s.e. of B",
                       ex([](auto& f) { return f.B_err; }));
            j.optional("exp_aic", "1", "exponential: AIC", ex([](auto& f) { return f.aic; }));
            j.optional("pow_ln_A", "1", "power law: ln A", pw([](auto& f) { return f.ln_A; }));
            j.optional("pow_gamma", "1", "power law: gamma", pw([](auto& f) { return f.gamma; }));
            j.optional("pow_Dc", "m", "power law: critical outlet Dc",
                       pw([](auto& f) { return f.Dc; }));
            j.optional("pow_aic", "1", "power law: AIC", pw([](auto& f) { return f.aic; }));
        });
    // <s>(D) per group: the fit of p = 1/<s>, written as <s> (ln_s0 = -ln A).
    store::DerivedGroup av = fits_table(
        a, &GroupAnalysis::avalanche, "avalanche", "mean avalanche size <s> versus D per group",
        [](Columns& v, const auto& ex, const auto& pw) {
            v.optional("exp_ln_s0", "1", "exponential growth <s> = exp(ln_s0 + B D): ln_s0",
                       ex([](auto& f) { return -f.ln_A; }));
            v.optional("exp_B", "1/m", "exponential growth: B", ex([](auto& f) { return f.B; }));
            v.optional("exp_B_err", "1/m", "exponential growth: s.e. of B",
                       ex([](auto& f) { return f.B_err; }));
            v.optional("exp_aic", "1", "exponential growth: AIC",
                       ex([](auto& f) { return f.aic; }));
            v.optional("pow_ln_s0", "1", "power law <s> = exp(ln_s0) (Dc - D)^-gamma: ln_s0",
                       pw([](auto& f) { return -f.ln_A; }));
            v.optional("pow_gamma", "1", "power law: gamma", pw([](auto& f) { return f.gamma; }));
            v.optional("pow_gamma_err", "1", "power law: s.e. of gamma",
                       pw([](auto& f) { return f.gamma_err; }));
            v.optional("pow_Dc", "m", "power law: critical outlet Dc",
                       pw([](auto& f) { return f.Dc; }));
            v.optional("pow_Dc_err", "m", "power law: s.e. of Dc",
                       pw([](auto& f) { return f.Dc_err; }));
            v.optional("pow_aic", "1", "power law: AIC", pw([](auto& f) { return f.aic; }));
        });
    root.groups = {std::move(points), std::move(km), beverloo_table(a), std::move(jr),
                   std::move(av)};
    if (auto f = fields_group(a)) root.groups.push_back(std::move(*f));
    return root;
}

}  // namespace hopper::analysis
