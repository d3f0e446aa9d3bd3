#include "hopper/analysis/json.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace hopper::analysis {

Json json_number(double v) {
    if (!std::isfinite(v))
        throw std::logic_error("analysis_json: a non-finite number reached the JSON");
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    const std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));
    if (text.find_first_not_of("-0123456789") == std::string_view::npos) {
        std::int64_t i = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), i);
        if (ec == std::errc{} && end == text.data() + text.size()) return i;
    }
    return v;
}

Json json_number_or_null(double v) {
    return std::isfinite(v) ? json_number(v) : Json(nullptr);
}

void add_fields_summary(Json& j, const engine::FieldMoments& m) {
    const engine::FieldGrid& g = m.grid;
    j["kernel"] = engine::to_string(g.kernel);
    if (g.kernel == engine::FieldKernel::gaussian)
        j["kernel_width_m"] = json_number(g.kernel_width);
    j["cell_m"] = json_number(g.cell);
    j["x0_m"] = json_number(g.x0);
    j["y0_m"] = json_number(g.y0);
    j["nx"] = g.nx;
    j["ny"] = g.ny;
    j["samples"] = m.samples;
    j["total_windows"] = m.total_windows;
    j["t_first"] = json_number(m.t_first);
    j["t_last"] = json_number(m.t_last);
    const FieldsSummary s = summarize(m);
    j["cells_with_data"] = s.cells_with_data;
    j["max_mean_speed"] = json_number(s.max_mean_speed);
    j["max_mean_pressure"] = json_number(s.max_mean_pressure);
}

namespace {

// key: the value, or null and key_reason.
void opt_field(Json& j, const std::string& key, const std::optional<double>& v,
               const std::string& reason) {
    if (v) {
        j[key] = json_number(*v);
    } else {
        j[key] = nullptr;
        j[key + "_reason"] = reason.empty() ? std::string("not computed") : reason;
    }
}

Json setting_value(const core::Setting& s) {
    if (const auto* x = std::get_if<double>(&s.value)) return json_number(*x);
    return std::get<std::string>(s.value);
}

// One law of fit_jam_rate: valid, then ln A (for avalanches ln_s0 = -ln A) and its error, the
// law's own parameters (`own`), chi2, dof and aic; or valid = false and the reason.
template <class Law, class Own>
Json law_json(const Law& x, bool of_sizes, Own own) {
    Json o;
    o["valid"] = x.valid;
    if (!x.valid) {
        o["reason"] = x.reason;
        return o;
    }
    o[of_sizes ? "ln_s0" : "ln_A"] = json_number((of_sizes ? -1.0 : 1.0) * x.ln_A);
    o[of_sizes ? "ln_s0_err" : "ln_A_err"] = json_number(x.ln_A_err);
    own(o);
    o["chi2"] = json_number(x.chi2);
    o["dof"] = x.dof;
    o["aic"] = json_number(x.aic);
    return o;
}

// The two laws of fit_jam_rate. For avalanches (of_sizes) the fit is of p = 1/<s>, written as
// <s>: ln_s0 = -ln A, and exponential growth <s> = e^ln_s0 e^(B D), power-law divergence
// <s> = e^ln_s0 (Dc - D)^-gamma (Zuriguel et al. 2005).
void add_rate_fits(Json& j, const stats::JamRateFits& f,
                   const std::vector<std::pair<double, std::string>>& left_out, bool of_sizes) {
    j["n_points"] = f.n_points;
    Json out = Json::array();
    for (const auto& [D, why] : left_out)
        out.push_back(Json{{"D_cm", json_number(D)}, {"reason", why}});
    j["left_out"] = std::move(out);
    const auto& x = f.exponential;
    j["exponential"] = law_json(x, of_sizes, [&x](Json& o) {
        o["B_per_m"] = json_number(x.B);
        o["B_err_per_m"] = json_number(x.B_err);
    });
    const auto& pl = f.power_law;
    j["power_law"] = law_json(pl, of_sizes, [&pl](Json& o) {
        o["gamma"] = json_number(pl.gamma);
        o["gamma_err"] = json_number(pl.gamma_err);
        o["Dc_m"] = json_number(pl.Dc);
        o["Dc_err_m"] = json_number(pl.Dc_err);
    });
    j["preferred"] = f.preferred;
    opt_field(j, "delta_aic", f.has_delta_aic ? std::optional<double>(f.delta_aic) : std::nullopt,
              f.decision);
    j["decision"] = f.decision;
}

Json avalanche_json(const AvalancheAnalysis& av) {
    Json j;
    j["realizations"] = av.realizations;
    j["realizations_without_sizes"] = av.realizations_without;
    const stats::ExponentialFit* f = av.fit ? &*av.fit : nullptr;
    const std::string why = av.reason.empty() ? "no jams" : av.reason;
    j["n_intervals"] = f ? f->n_intervals : 0;
    j["n_uncensored"] = f ? f->n_uncensored : 0;
    j["total_grains"] = json_number(f ? f->total_observed_time : 0.0);
    opt_field(j, "mean_s_algebraic", f ? f->mean_all : std::nullopt, why);
    opt_field(j, "mean_s", f ? f->tau : std::nullopt, why);
    opt_field(j, "mean_s_err",
              f && f->tau && f->sigma_log_tau ? std::optional<double>(*f->tau * *f->sigma_log_tau)
                                              : std::nullopt,
              why);
    if (f && f->tau && f->tau_lo && f->tau_hi) {
        j["mean_s_ci95"] = Json::array({json_number(*f->tau_lo), json_number(*f->tau_hi)});
        j["p_clog_per_grain"] = json_number(1.0 / *f->tau);
        j["p_clog_ci95"] =
            Json::array({json_number(1.0 / *f->tau_hi), json_number(1.0 / *f->tau_lo)});
    } else {
        j["mean_s_ci95"] = nullptr;
        j["mean_s_ci95_reason"] = why;
        j["p_clog_per_grain"] = nullptr;
        j["p_clog_per_grain_reason"] = why;
    }
    opt_field(j, "gof_p", av.gof.valid ? std::optional<double>(av.gof.p_value) : std::nullopt,
              av.gof.reason);
    if (av.gof.valid) j["gof_statistic"] = json_number(av.gof.statistic);
    Json arches;
    arches["jams_with_data"] = av.arch_jams;
    arches["found"] = av.arches_found;
    Json counts = Json::object();
    for (std::size_t n = 1; n < av.arch_size_counts.size(); ++n)
        if (av.arch_size_counts[n] > 0) counts[std::to_string(n)] = av.arch_size_counts[n];
    arches["size_counts"] = std::move(counts);
    const std::string none = "no arch found";
    opt_field(arches, "mean_size", av.arch_mean_size, none);
    opt_field(arches, "mean_span_m", av.arch_mean_span_m, none);
    opt_field(arches, "mean_max_angle_deg", av.arch_mean_max_angle_deg, none);
    j["arches"] = std::move(arches);
    return j;
}

Json point_json(const PointAnalysis& p) {
    Json j;
    j["label"] = p.label;
    j["D_cm"] = json_number(p.D_cm);
    j["theta_deg"] = json_number(p.theta_deg);
    for (const auto& s : p.varied)
        j[s.name] = setting_value(s);
    j["realizations"] = p.stored;
    j["realizations_planned"] = p.planned;
    j["status_counts"] = Json{{"complete", p.n_complete},
                              {"failed", p.n_failed},
                              {"arrested", p.n_arrested},
                              {"time_limit", p.n_time_limit}};
    j["n_jams"] = p.n_jams;
    j["n_shakes"] = p.n_shakes;
    j["n_jams_multi_shake"] = p.n_jams_multi_shake;
    const stats::ExponentialFit* f = p.fit ? &*p.fit : nullptr;
    opt_field(j, "mean_survival", f ? f->mean_all : std::nullopt, f ? std::string() : p.fit_reason);
    opt_field(j, "tau_mle", f ? f->tau : std::nullopt, p.fit_reason);
    if (f && f->tau_lo && f->tau_hi) {
        j["tau_ci95"] = Json::array({json_number(*f->tau_lo), json_number(*f->tau_hi)});
    } else {
        j["tau_ci95"] = nullptr;
        j["tau_ci95_reason"] = p.fit_reason;
    }
    if (f && !f->tau && f->tau_lo) j["tau_lower_bound95"] = json_number(*f->tau_lo);
    j["total_observed_time"] = json_number(f ? f->total_observed_time : 0.0);
    j["n_intervals"] = f ? f->n_intervals : 0;
    j["n_uncensored"] = f ? f->n_uncensored : 0;
    opt_field(j, "gof_p", p.gof.valid ? std::optional<double>(p.gof.p_value) : std::nullopt,
              p.gof.reason);
    if (p.gof.valid) {
        j["gof_statistic"] = json_number(p.gof.statistic);
        j["gof_method"] = p.gof.method;
    }
    opt_field(j, "r2_log_survival", p.line.valid ? std::optional<double>(p.line.r2) : std::nullopt,
              p.line.reason);
    opt_field(j, "empty_time_mean", p.empty_time.mean, p.empty_time.reason);
    opt_field(j, "empty_time_std", p.empty_time.std_dev, p.empty_time.reason);
    opt_field(j, "empty_time_err", p.empty_time.std_err, p.empty_time.reason);
    j["n_emptied"] = p.empty_time.n;
    opt_field(j, "discharge_rate", p.rate.mean, p.rate.reason);
    opt_field(j, "discharge_rate_err", p.rate.std_err, p.rate.reason);
    opt_field(j, "discharge_rate_kg_s", p.rate_kg.mean, p.rate_kg.reason);
    opt_field(j, "discharge_rate_kg_s_err", p.rate_kg.std_err, p.rate_kg.reason);
    const auto& e = p.early_late;
    Json el;
    el["split"] = json_number(e.split);
    el["n_early"] = e.n_early;
    el["n_late"] = e.n_late;
    el["exposure_early"] = json_number(e.exposure_early);
    el["exposure_late"] = json_number(e.exposure_late);
    opt_field(el, "rate_early", e.rate_early, e.reason);
    opt_field(el, "rate_late", e.rate_late, e.reason);
    opt_field(el, "rate_ratio", e.rate_ratio, e.reason.empty() ? "a part without jams" : e.reason);
    opt_field(el, "p_value", e.valid ? std::optional<double>(e.p_value) : std::nullopt, e.reason);
    opt_field(el, "lr_statistic", e.valid ? std::optional<double>(e.lr_statistic) : std::nullopt,
              e.reason);
    j["jam_time_dependence"] = std::move(el);
    j["avalanche"] = avalanche_json(p.avalanche);
    if (p.fields.enabled) {
        if (const auto& m = p.fields.merged) {
            Json fj;
            fj["realizations"] = p.fields.realizations;
            add_fields_summary(fj, *m);
            j["fields"] = std::move(fj);
        } else {
            j["fields"] = nullptr;
            j["fields_reason"] = p.fields.reason;
        }
    }
    return j;
}

}  // namespace

std::string analysis_json(const Analysis& a, const std::string& store, const std::string& name) {
    Json j;
    j["store"] = store;
    j["campaign"] = name;
    j["rho_b_source"] = a.rho_b_source;
    j["d_definition"] = a.d_definition;
    Json points = Json::array();
    for (const auto& p : a.points)
        points.push_back(point_json(p));
    j["points"] = std::move(points);

    Json bev = Json::array();
    for (const auto& g : a.groups) {
        const auto& b = g.beverloo;
        Json o;
        o["theta_deg"] = json_number(g.theta_deg);
        o["group"] = g.group;
        const std::string reason = b.reason.empty() ? "fit failed" : b.reason;
        opt_field(o, "C", b.valid ? std::optional<double>(b.C) : std::nullopt, reason);
        opt_field(o, "C_err", b.valid ? std::optional<double>(b.C_err) : std::nullopt, reason);
        opt_field(o, "k", b.valid ? std::optional<double>(b.k) : std::nullopt, reason);
        opt_field(o, "k_err", b.valid ? std::optional<double>(b.k_err) : std::nullopt, reason);
        o["n_points"] = b.n_points;
        const auto& p0 = a.points[static_cast<std::size_t>(g.points.front())];
        o["rho_b"] = json_number(p0.rho_b);
        o["d"] = json_number(p0.d_mean);
        bev.push_back(std::move(o));
    }
    j["beverloo"] = std::move(bev);

    const auto fits = [&](auto member, auto left_out, bool of_sizes) {
        Json arr = Json::array();
        for (const auto& g : a.groups) {
            Json o;
            o["theta_deg"] = json_number(g.theta_deg);
            o["group"] = g.group;
            add_rate_fits(o, g.*member, g.*left_out, of_sizes);
            arr.push_back(std::move(o));
        }
        return arr;
    };
    j["avalanche_fits"] = fits(&GroupAnalysis::avalanche, &GroupAnalysis::avalanche_left_out, true);
    j["jam_rate_fits"] = fits(&GroupAnalysis::jam_rate, &GroupAnalysis::jam_rate_left_out, false);
    return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace hopper::analysis
