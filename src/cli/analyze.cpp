#include "cli/analyze.hpp"
#include "cli/parse.hpp"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <set>
#include <sstream>

#include "cli/json_writer.hpp"
#include "cli/options.hpp"
#include "cli/simulate.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/codec.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/records.hpp"
#include "hopper/store/store.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace hopper::cli {

namespace {

constexpr double cm = 0.01;

// "D_cm=3 theta_deg=60 material.mu=0.5" -> [(D_cm, 3), (theta_deg, 60), (material.mu, 0.5)].
std::vector<std::pair<std::string, std::string>> label_settings(const std::string& label) {
    std::vector<std::pair<std::string, std::string>> out;
    std::istringstream in(label);
    std::string tok;
    while (in >> tok) {
        const auto eq = tok.find('=');
        if (eq == std::string::npos) continue;
        out.emplace_back(tok.substr(0, eq), tok.substr(eq + 1));
    }
    return out;
}

std::optional<double> scene_number(const std::map<std::string, std::string>& scene,
                                   const std::string& name) {
    const auto it = scene.find(name);
    if (it == scene.end()) return std::nullopt;
    try {
        std::size_t used = 0;
        const double v = std::stod(it->second, &used);
        if (used != it->second.size() || !std::isfinite(v)) return std::nullopt;
        return v;
    } catch (const std::exception&) {
        return std::nullopt;
    }
}

std::map<std::string, std::string> parse_scene(const std::string& text) {
    std::map<std::string, std::string> out;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        const auto eq = line.find('=');
        if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
    }
    return out;
}

// The window of one realization (discharge time from the opening to its end) and the periods in
// it when the outlet was already jammed (onset to flow restart): the input of the early/late test.
std::optional<stats::JamHistory> jam_history(const engine::RealizationResult& r) {
    double window = 0.0;
    for (double t : r.survival_times)
        window += t;
    for (const auto& e : r.events)
        window = std::max(window, e.time);
    for (double t : r.jam_onsets)
        window = std::max(window, t);
    if (!(window > 0.0)) return std::nullopt;
    stats::JamHistory h;
    h.window = window;
    std::vector<double> restarts;
    for (const auto& e : r.events)
        if (e.kind == engine::Event::Kind::flow_restart) restarts.push_back(e.time);
    std::sort(restarts.begin(), restarts.end());
    for (double onset : r.jam_onsets) {
        h.onsets.push_back(onset);
        const auto it = std::lower_bound(restarts.begin(), restarts.end(), onset);
        const double end = it == restarts.end() ? window : std::min(*it, window);
        if (end > onset) h.not_at_risk.emplace_back(onset, end);
    }
    return h;
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string theta_text(double theta) {
    return json_number(theta);
}

std::string grid_text(const engine::FieldGrid& g) {
    std::string t = std::to_string(g.nx) + " x " + std::to_string(g.ny) + " cells of " +
                    json_number(g.cell) + " m from (" + json_number(g.x0) + ", " +
                    json_number(g.y0) + ") m, kernel " + engine::to_string(g.kernel);
    if (g.kernel == engine::FieldKernel::gaussian) t += " of width " + json_number(g.kernel_width);
    return t;
}

}  // namespace

PointFields merge_point_fields(const AnalysisPointInput& in) {
    PointFields pf;
    pf.enabled = in.scene.count("fields.kernel") > 0;
    const bool rows_known = in.rows.size() == in.results.size();
    const std::string unit = rows_known ? "row" : "result";
    bool any = false;
    std::int64_t first = -1;
    for (std::size_t i = 0; i < in.results.size(); ++i) {
        const auto& r = in.results[i];
        if (!r.fields) continue;
        any = true;
        if (r.status == engine::Status::failed) continue;
        const std::int64_t row = rows_known ? in.rows[i] : static_cast<std::int64_t>(i);
        const engine::FieldMoments& m = *r.fields;
        const auto n = static_cast<std::size_t>(std::max(m.grid.size(), 0));
        bool sizes = m.windows.size() == n && m.weight.size() == n;
        for (int f = 0; f < engine::field_count; ++f)
            sizes = sizes && m.mean[f].size() == n && m.m2[f].size() == n;
        if (!sizes)
            throw core::StoreError("point '" + in.label + "': the fields of " + unit + " " +
                                   std::to_string(row) + " do not match their grid (" +
                                   grid_text(m.grid) + ")");
        if (!pf.merged) {
            pf.merged = m;
            first = row;
        } else if (!(pf.merged->grid == m.grid)) {
            throw core::StoreError(
                "point '" + in.label + "': the fields of " + unit + "s " + std::to_string(first) +
                " and " + std::to_string(row) + " of /realizations have different grids (" +
                grid_text(pf.merged->grid) + "; " + grid_text(m.grid) + "): they cannot be merged");
        } else {
            pf.merged->merge(m);
        }
        ++pf.realizations;
    }
    pf.enabled = pf.enabled || any;
    if (!pf.merged) {
        const bool all_failed =
            std::all_of(in.results.begin(), in.results.end(),
                        [](const auto& r) { return r.status == engine::Status::failed; });
        pf.reason = in.results.empty() ? "no stored realizations"
                    : all_failed       ? "no realizations without failure"
                    : any              ? "no realization without failure has fields"
                                       : "no stored realization has fields";
        return pf;
    }
    const FieldsSummary sum = summarize_fields(*pf.merged);
    pf.cells_with_data = sum.cells_with_data;
    pf.max_mean_speed = sum.max_mean_speed;
    pf.max_mean_pressure = sum.max_mean_pressure;
    return pf;
}

namespace {
bool out_of_realization_order(const AnalysisPointInput& in) {
    return in.realizations.size() == in.results.size() &&
           !std::is_sorted(in.realizations.begin(), in.realizations.end());
}
}  // namespace

AnalysisPointInput in_realization_order(AnalysisPointInput in) {
    if (!out_of_realization_order(in)) return in;
    const std::size_t n = in.results.size();
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
        return in.realizations[x] < in.realizations[y];
    });
    AnalysisPointInput out = std::move(in);
    auto permute = [&order](auto& v) {
        std::remove_reference_t<decltype(v)> sorted;
        sorted.reserve(v.size());
        for (std::size_t i : order)
            sorted.push_back(std::move(v[i]));
        v = std::move(sorted);
    };
    permute(out.results);
    permute(out.realizations);
    if (out.rows.size() == n) permute(out.rows);
    return out;
}

namespace {

// Issue 16: points pooled with --allow-mixed can differ in settings their labels do not show.
// Within each group of points whose labels agree on everything but D (the groups the labels
// make), every scene parameter other than the outlet whose value differs is added to the group
// as " name=value", so such points are fitted apart. Stores whose labels show every difference
// get nothing added (their groups are unchanged).
std::map<std::string, std::string> hidden_settings(const std::vector<AnalysisPointInput>& inputs) {
    std::map<std::string, std::vector<const AnalysisPointInput*>> by_label_group;
    for (const auto& in : inputs) {
        std::string key;
        for (const auto& [k, v] : label_settings(in.label))
            if (k != "D_cm") key += k + "=" + v + " ";
        by_label_group[key].push_back(&in);
    }
    std::map<std::string, std::string> out;
    for (const auto& [key, members] : by_label_group) {
        std::set<std::string> names;
        for (const auto* in : members)
            for (const auto& [k, v] : in->scene)
                names.insert(k);
        std::vector<std::string> differing;
        for (const auto& name : names) {
            if (name == "hopper.outlet_m") continue;
            std::set<std::string> values;
            for (const auto* in : members) {
                const auto it = in->scene.find(name);
                values.insert(it == in->scene.end() ? "absent" : it->second);
            }
            if (values.size() > 1) differing.push_back(name);
        }
        for (const auto* in : members) {
            std::string extra;
            for (const auto& name : differing) {
                const auto it = in->scene.find(name);
                extra += " " + name + "=" + (it == in->scene.end() ? "absent" : it->second);
            }
            if (!extra.empty()) out[in->label] = extra;
        }
    }
    return out;
}

AvalancheAnalysis analyze_avalanches(const AnalysisPointInput& in) {
    AvalancheAnalysis av;
    std::vector<double> s, windows;
    std::vector<bool> censored;
    double span = 0.0, angle = 0.0, size = 0.0;
    for (const auto& r : in.results) {
        if (r.status == engine::Status::failed) continue;
        if (r.avalanche_sizes.size() != r.survival_times.size() || r.survival_times.empty()) {
            if (!r.survival_times.empty()) ++av.realizations_without;
        } else {
            ++av.realizations;
            double w = 0.0;
            for (std::size_t i = 0; i < r.avalanche_sizes.size(); ++i) {
                s.push_back(double(r.avalanche_sizes[i]));
                censored.push_back(i < r.censored.size() && r.censored[i]);
                w += double(r.avalanche_sizes[i]);
            }
            windows.push_back(w);
        }
        for (const auto& arch : r.arches) {
            ++av.arch_jams;
            if (!arch.found()) continue;
            ++av.arches_found;
            const std::size_t n = arch.ids.size();
            if (av.arch_size_counts.size() <= n) av.arch_size_counts.resize(n + 1, 0);
            ++av.arch_size_counts[n];
            size += double(n);
            span += arch.span;
            angle += arch.max_angle / core::deg;
        }
    }
    if (av.arches_found > 0) {
        av.arch_mean_size = size / av.arches_found;
        av.arch_mean_span_m = span / av.arches_found;
        av.arch_mean_max_angle_deg = angle / av.arches_found;
    }
    if (s.empty()) {
        av.reason = av.realizations_without > 0
                        ? "the realizations were stored before avalanche sizes were recorded"
                        : "no survival intervals";
        av.gof.reason = av.reason;
        return av;
    }
    av.fit = stats::fit_censored_exponential(s, censored);
    if (!av.fit->tau) av.reason = "no jams";
    stats::GofOptions go;
    go.seed = store::fnv1a64(in.label) ^ 0x5bd1e9955bd1e995ULL;  // from the point
    av.gof = stats::ks_exponential_censored(s, censored, windows, go);
    return av;
}

}  // namespace

Analysis analyze_points(const std::vector<AnalysisPointInput>& inputs) {
    Analysis a;
    a.rho_b_source = "estimate: rho_b = " + json_number(kAssumedPackingFraction) +
                     " x density x thickness (scene parameters particles.density_kg_m3, "
                     "particles.thickness_m); 0.82 is an assumed packing fraction of a settled "
                     "bidisperse disk packing: the area of the settled packing is not in the store";
    a.d_definition =
        "d = number-weighted mean diameter f_small d_small + (1 - f_small) d_large (scene)";
    std::map<std::string, int> group_index;
    const std::map<std::string, std::string> hidden = hidden_settings(inputs);
    for (const auto& given : inputs) {
        // Realization order, not storage order (a copy only when they differ).
        std::optional<AnalysisPointInput> reordered;
        if (out_of_realization_order(given)) reordered = in_realization_order(given);
        const AnalysisPointInput& in = reordered ? *reordered : given;
        PointAnalysis p;
        p.label = in.label;
        p.D_cm = in.D_cm;
        p.theta_deg = in.theta_deg;
        // The label's settings are the values as the user wrote them (the plan's D and theta
        // went through SI units and back: 59.99999999999999).
        for (const auto& [k, v] : label_settings(in.label)) {
            if (k != "D_cm" && k != "theta_deg") continue;
            try {
                (k == "D_cm" ? p.D_cm : p.theta_deg) = std::stod(v);
            } catch (const std::exception&) {
            }
        }
        std::string group = "theta_deg=" + theta_text(p.theta_deg);
        if (const auto it = hidden.find(in.label); it != hidden.end()) group += it->second;
        p.planned = in.planned;
        p.stored = static_cast<int>(in.results.size());
        for (const auto& [k, v] : label_settings(in.label)) {
            if (k == "D_cm" || k == "theta_deg") continue;
            p.varied.emplace_back(k, v);
            group += " " + k + "=" + v;
        }
        p.group = group;
        const double density = scene_number(in.scene, "particles.density_kg_m3").value_or(0.0);
        const double thickness = scene_number(in.scene, "particles.thickness_m").value_or(0.0);
        const double fs = scene_number(in.scene, "particles.small_fraction").value_or(0.0);
        const double ds = scene_number(in.scene, "particles.d_small_m").value_or(0.0);
        const double dl = scene_number(in.scene, "particles.d_large_m").value_or(0.0);
        p.rho_b = kAssumedPackingFraction * density * thickness;
        p.d_mean = fs * ds + (1.0 - fs) * dl;

        std::vector<double> t, windows, empty, rate, rate_kg;
        std::vector<bool> censored;
        std::vector<stats::JamHistory> histories;
        for (const auto& r : in.results) {
            switch (r.status) {
                case engine::Status::complete:
                    ++p.n_complete;
                    break;
                case engine::Status::failed:
                    ++p.n_failed;
                    break;
                case engine::Status::arrested:
                    ++p.n_arrested;
                    break;
                case engine::Status::time_limit:
                    ++p.n_time_limit;
                    break;
            }
            if (r.status == engine::Status::failed) continue;
            ++p.used;
            p.n_jams += r.n_jams;
            p.n_shakes += r.n_shakes;
            p.n_jams_multi_shake += r.n_jams_multi_shake;
            double w = 0.0;
            for (std::size_t i = 0; i < r.survival_times.size(); ++i) {
                t.push_back(r.survival_times[i]);
                censored.push_back(i < r.censored.size() && r.censored[i]);
                w += r.survival_times[i];
            }
            if (!r.survival_times.empty()) windows.push_back(w);
            if (auto h = jam_history(r)) histories.push_back(std::move(*h));
            if (r.empty_time) empty.push_back(*r.empty_time);
            if (r.discharge_rate) {
                rate.push_back(*r.discharge_rate);
                rate_kg.push_back(r.discharge_rate_mass);
            }
        }
        if (t.empty()) {
            p.fit_reason =
                p.used == 0 ? "no realizations without failure" : "no survival intervals";
            p.gof.reason = p.fit_reason;
            p.line.reason = p.fit_reason;
        } else {
            p.fit = stats::fit_censored_exponential(t, censored);
            if (!p.fit->tau) p.fit_reason = "no jams";
            stats::GofOptions go;
            go.seed = store::fnv1a64(in.label) ^ 0x9e3779b97f4a7c15ULL;  // from the point
            p.gof = stats::ks_exponential_censored(t, censored, windows, go);
            p.line = stats::log_survival_line(t, censored);
            p.km = stats::kaplan_meier(t, censored);
        }
        if (histories.empty())
            p.early_late.reason = "no realization with discharge time";
        else
            p.early_late = stats::early_late_rate_test(histories);
        p.empty_time = stats::summarize(empty);
        if (empty.empty()) p.empty_time.reason = "no realization emptied";
        p.rate = stats::summarize(rate);
        p.rate_kg = stats::summarize(rate_kg);
        if (rate.empty()) p.rate.reason = p.rate_kg.reason = "no realization has a discharge rate";
        p.avalanche = analyze_avalanches(in);
        try {
            p.fields = merge_point_fields(in);
        } catch (const core::StoreError& e) {
            p.fields = PointFields{};
            p.fields.enabled = true;
            p.fields.error = true;
            p.fields.reason = e.what();
        }

        const auto [it, added] = group_index.emplace(group, static_cast<int>(a.groups.size()));
        if (added) {
            GroupAnalysis g;
            g.group = group;
            g.theta_deg = p.theta_deg;
            a.groups.push_back(std::move(g));
        }
        a.groups[static_cast<std::size_t>(it->second)].points.push_back(
            static_cast<int>(a.points.size()));
        a.points.push_back(std::move(p));
    }

    for (auto& g : a.groups) {
        std::sort(g.points.begin(), g.points.end(), [&](int x, int y) {
            return a.points[static_cast<std::size_t>(x)].D_cm <
                   a.points[static_cast<std::size_t>(y)].D_cm;
        });
        // Beverloo: mean mass flow rate per outlet, weighted by its standard error when every
        // point has one (relative weights; the covariance is scaled by the residual variance).
        std::vector<double> D, W, sW;
        bool all_se = true;
        double rho_b = 0.0, d = 0.0;
        for (int i : g.points) {
            const auto& p = a.points[static_cast<std::size_t>(i)];
            rho_b = p.rho_b;
            d = p.d_mean;
            if (!p.rate_kg.mean || !(*p.rate_kg.mean > 0.0)) continue;
            D.push_back(p.D_cm * cm);
            W.push_back(*p.rate_kg.mean);
            if (p.rate_kg.std_err && *p.rate_kg.std_err > 0.0)
                sW.push_back(*p.rate_kg.std_err);
            else
                all_se = false;
        }
        if (!all_se) sW.clear();
        if (rho_b > 0.0 && d > 0.0) {
            g.beverloo = stats::fit_beverloo(D, W, sW, rho_b, d);
        } else {
            g.beverloo.reason = "the scene lacks the density, thickness or diameters";
            g.beverloo.n_points = static_cast<int>(D.size());
        }
        // Jam rate 1/tau versus D: points without a jam have no rate and are left out.
        std::vector<double> Dj, rate, sigma;
        for (int i : g.points) {
            const auto& p = a.points[static_cast<std::size_t>(i)];
            if (p.fit && p.fit->tau && p.fit->sigma_log_tau) {
                Dj.push_back(p.D_cm * cm);
                rate.push_back(1.0 / *p.fit->tau);
                sigma.push_back(*p.fit->sigma_log_tau);
            } else {
                g.jam_rate_left_out.emplace_back(p.D_cm,
                                                 p.fit_reason.empty() ? "no jams" : p.fit_reason);
            }
        }
        g.jam_rate = stats::fit_jam_rate(Dj, rate, sigma);
        // <s>(D) through p = 1/<s>, sigma(ln p) = 1/sqrt(r) as for the jam rate.
        std::vector<double> Ds, ps, ss;
        for (int i : g.points) {
            const auto& av = a.points[static_cast<std::size_t>(i)].avalanche;
            if (av.fit && av.fit->tau && av.fit->sigma_log_tau) {
                Ds.push_back(a.points[static_cast<std::size_t>(i)].D_cm * cm);
                ps.push_back(1.0 / *av.fit->tau);
                ss.push_back(*av.fit->sigma_log_tau);
            } else {
                g.avalanche_left_out.emplace_back(a.points[static_cast<std::size_t>(i)].D_cm,
                                                  av.reason.empty() ? "no jams" : av.reason);
            }
        }
        g.avalanche = stats::fit_jam_rate(Ds, ps, ss);
    }
    return a;
}

namespace {

void opt_field(JsonWriter& w, const std::string& key, const std::optional<double>& v,
               const std::string& reason) {
    w.key(key);
    if (v) {
        w.value(*v);
    } else {
        w.null();
        w.field(key + "_reason", reason.empty() ? std::string("not computed") : reason);
    }
}

}  // namespace

namespace {

// The two laws of fit_jam_rate. For avalanches (of_sizes) the fit is of p = 1/<s>, written as
// <s>: ln_s0 = -ln A, and exponential growth <s> = e^ln_s0 e^(B D), power-law divergence
// <s> = e^ln_s0 (Dc - D)^-gamma (Zuriguel et al. 2005).
void write_rate_fits(JsonWriter& w, const stats::JamRateFits& j,
                     const std::vector<std::pair<double, std::string>>& left_out, bool of_sizes) {
    w.field("n_points", j.n_points);
    w.key("left_out").begin_array_inline();
    for (const auto& [D, why] : left_out) {
        w.begin_object_inline().field("D_cm", D).field("reason", why).end_object();
    }
    w.end_array();
    const char* lnA = of_sizes ? "ln_s0" : "ln_A";
    const char* lnA_err = of_sizes ? "ln_s0_err" : "ln_A_err";
    const double sign = of_sizes ? -1.0 : 1.0;
    const auto& x = j.exponential;
    w.key("exponential").begin_object_inline();
    w.field("valid", x.valid);
    if (x.valid) {
        w.field(lnA, sign * x.ln_A).field(lnA_err, x.ln_A_err);
        w.field("B_per_m", x.B).field("B_err_per_m", x.B_err);
        w.field("chi2", x.chi2).field("dof", x.dof).field("aic", x.aic);
    } else {
        w.field("reason", x.reason);
    }
    w.end_object();
    const auto& pl = j.power_law;
    w.key("power_law").begin_object_inline();
    w.field("valid", pl.valid);
    if (pl.valid) {
        w.field(lnA, sign * pl.ln_A).field(lnA_err, pl.ln_A_err);
        w.field("gamma", pl.gamma).field("gamma_err", pl.gamma_err);
        w.field("Dc_m", pl.Dc).field("Dc_err_m", pl.Dc_err);
        w.field("chi2", pl.chi2).field("dof", pl.dof).field("aic", pl.aic);
    } else {
        w.field("reason", pl.reason);
    }
    w.end_object();
    w.field("preferred", j.preferred);
    opt_field(w, "delta_aic", j.has_delta_aic ? std::optional<double>(j.delta_aic) : std::nullopt,
              j.decision);
    w.field("decision", j.decision);
}

void write_avalanche(JsonWriter& w, const AvalancheAnalysis& av) {
    w.key("avalanche").begin_object();
    w.field("realizations", av.realizations);
    w.field("realizations_without_sizes", av.realizations_without);
    const stats::ExponentialFit* f = av.fit ? &*av.fit : nullptr;
    const std::string why = av.reason.empty() ? "no jams" : av.reason;
    w.field("n_intervals", f ? f->n_intervals : 0);
    w.field("n_uncensored", f ? f->n_uncensored : 0);
    w.field("total_grains", f ? f->total_observed_time : 0.0);
    opt_field(w, "mean_s_algebraic", f ? f->mean_all : std::nullopt, why);
    opt_field(w, "mean_s", f ? f->tau : std::nullopt, why);
    opt_field(w, "mean_s_err",
              f && f->tau && f->sigma_log_tau ? std::optional<double>(*f->tau * *f->sigma_log_tau)
                                              : std::nullopt,
              why);
    w.key("mean_s_ci95");
    if (f && f->tau && f->tau_lo && f->tau_hi) {
        w.begin_array_inline().value(*f->tau_lo).value(*f->tau_hi).end_array();
        w.field("p_clog_per_grain", 1.0 / *f->tau);
        w.key("p_clog_ci95").begin_array_inline().value(1.0 / *f->tau_hi).value(1.0 / *f->tau_lo);
        w.end_array();
    } else {
        w.null();
        w.field("mean_s_ci95_reason", why);
        w.key("p_clog_per_grain").null();
        w.field("p_clog_per_grain_reason", why);
    }
    opt_field(w, "gof_p", av.gof.valid ? std::optional<double>(av.gof.p_value) : std::nullopt,
              av.gof.reason);
    if (av.gof.valid) w.field("gof_statistic", av.gof.statistic);
    w.key("arches").begin_object_inline();
    w.field("jams_with_data", av.arch_jams);
    w.field("found", av.arches_found);
    w.key("size_counts").begin_object_inline();
    for (std::size_t n = 1; n < av.arch_size_counts.size(); ++n)
        if (av.arch_size_counts[n] > 0) w.field(std::to_string(n), av.arch_size_counts[n]);
    w.end_object();
    const std::string none = "no arch found";
    opt_field(w, "mean_size", av.arch_mean_size, none);
    opt_field(w, "mean_span_m", av.arch_mean_span_m, none);
    opt_field(w, "mean_max_angle_deg", av.arch_mean_max_angle_deg, none);
    w.end_object();
    w.end_object();
}

}  // namespace

std::string analysis_json(const Analysis& a, const std::string& store, const std::string& name) {
    JsonWriter w;
    w.begin_object();
    w.field("store", store);
    w.field("campaign", name);
    w.field("rho_b_source", a.rho_b_source);
    w.field("d_definition", a.d_definition);
    w.key("points").begin_array();
    for (const auto& p : a.points) {
        w.begin_object();
        w.field("label", p.label);
        w.field("D_cm", p.D_cm);
        w.field("theta_deg", p.theta_deg);
        for (const auto& [k, v] : p.varied) {
            w.key(k);
            try {
                std::size_t used = 0;
                const double x = std::stod(v, &used);
                if (used == v.size() && std::isfinite(x))
                    w.value(x);
                else
                    w.value(v);
            } catch (const std::exception&) {
                w.value(v);
            }
        }
        w.field("realizations", p.stored);
        w.field("realizations_planned", p.planned);
        w.key("status_counts").begin_object_inline();
        w.field("complete", p.n_complete).field("failed", p.n_failed);
        w.field("arrested", p.n_arrested).field("time_limit", p.n_time_limit);
        w.end_object();
        w.field("n_jams", p.n_jams);
        w.field("n_shakes", p.n_shakes);
        w.field("n_jams_multi_shake", p.n_jams_multi_shake);
        const stats::ExponentialFit* f = p.fit ? &*p.fit : nullptr;
        opt_field(w, "mean_survival", f ? f->mean_all : std::nullopt,
                  f ? std::string() : p.fit_reason);
        opt_field(w, "tau_mle", f ? f->tau : std::nullopt, p.fit_reason);
        w.key("tau_ci95");
        if (f && f->tau_lo && f->tau_hi) {
            w.begin_array_inline().value(*f->tau_lo).value(*f->tau_hi).end_array();
        } else {
            w.null();
            w.field("tau_ci95_reason", p.fit_reason);
        }
        if (f && !f->tau && f->tau_lo) w.field("tau_lower_bound95", *f->tau_lo);
        w.field("total_observed_time", f ? f->total_observed_time : 0.0);
        w.field("n_intervals", f ? f->n_intervals : 0);
        w.field("n_uncensored", f ? f->n_uncensored : 0);
        opt_field(w, "gof_p", p.gof.valid ? std::optional<double>(p.gof.p_value) : std::nullopt,
                  p.gof.reason);
        if (p.gof.valid) {
            w.field("gof_statistic", p.gof.statistic);
            w.field("gof_method", p.gof.method);
        }
        opt_field(w, "r2_log_survival",
                  p.line.valid ? std::optional<double>(p.line.r2) : std::nullopt, p.line.reason);
        opt_field(w, "empty_time_mean", p.empty_time.mean, p.empty_time.reason);
        opt_field(w, "empty_time_std", p.empty_time.std_dev, p.empty_time.reason);
        opt_field(w, "empty_time_err", p.empty_time.std_err, p.empty_time.reason);
        w.field("n_emptied", p.empty_time.n);
        opt_field(w, "discharge_rate", p.rate.mean, p.rate.reason);
        opt_field(w, "discharge_rate_err", p.rate.std_err, p.rate.reason);
        opt_field(w, "discharge_rate_kg_s", p.rate_kg.mean, p.rate_kg.reason);
        opt_field(w, "discharge_rate_kg_s_err", p.rate_kg.std_err, p.rate_kg.reason);
        const auto& e = p.early_late;
        w.key("jam_time_dependence").begin_object_inline();
        w.field("split", e.split);
        w.field("n_early", e.n_early).field("n_late", e.n_late);
        w.field("exposure_early", e.exposure_early).field("exposure_late", e.exposure_late);
        opt_field(w, "rate_early", e.rate_early, e.reason);
        opt_field(w, "rate_late", e.rate_late, e.reason);
        opt_field(w, "rate_ratio", e.rate_ratio,
                  e.reason.empty() ? "a part without jams" : e.reason);
        opt_field(w, "p_value", e.valid ? std::optional<double>(e.p_value) : std::nullopt,
                  e.reason);
        opt_field(w, "lr_statistic", e.valid ? std::optional<double>(e.lr_statistic) : std::nullopt,
                  e.reason);
        w.end_object();
        write_avalanche(w, p.avalanche);
        if (p.fields.enabled) {
            w.key("fields");
            if (const auto& m = p.fields.merged) {
                w.begin_object_inline();
                w.field("realizations", p.fields.realizations);
                write_fields_summary(w, *m);
                w.end_object();
            } else {
                w.null();
                w.field("fields_reason", p.fields.reason);
            }
        }
        w.end_object();
    }
    w.end_array();

    w.key("beverloo").begin_array();
    for (const auto& g : a.groups) {
        const auto& b = g.beverloo;
        w.begin_object_inline();
        w.field("theta_deg", g.theta_deg);
        w.field("group", g.group);
        const std::string reason = b.reason.empty() ? "fit failed" : b.reason;
        opt_field(w, "C", b.valid ? std::optional<double>(b.C) : std::nullopt, reason);
        opt_field(w, "C_err", b.valid ? std::optional<double>(b.C_err) : std::nullopt, reason);
        opt_field(w, "k", b.valid ? std::optional<double>(b.k) : std::nullopt, reason);
        opt_field(w, "k_err", b.valid ? std::optional<double>(b.k_err) : std::nullopt, reason);
        w.field("n_points", b.n_points);
        const auto& p0 = a.points[static_cast<std::size_t>(g.points.front())];
        w.field("rho_b", p0.rho_b);
        w.field("d", p0.d_mean);
        w.end_object();
    }
    w.end_array();

    w.key("avalanche_fits").begin_array();
    for (const auto& g : a.groups) {
        w.begin_object();
        w.field("theta_deg", g.theta_deg);
        w.field("group", g.group);
        write_rate_fits(w, g.avalanche, g.avalanche_left_out, true);
        w.end_object();
    }
    w.end_array();

    w.key("jam_rate_fits").begin_array();
    for (const auto& g : a.groups) {
        w.begin_object();
        w.field("theta_deg", g.theta_deg);
        w.field("group", g.group);
        write_rate_fits(w, g.jam_rate, g.jam_rate_left_out, false);
        w.end_object();
    }
    w.end_array();
    w.end_object();
    if (w.nonfinite_count() != 0)
        throw std::logic_error("analysis_json: a non-finite number reached the JSON");
    return w.str();
}

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

    using I = std::int64_t;
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

    // The columns every fit across D shares (jam rate, avalanche size): the group and its
    // angle first, the verdict last; `fits` is the group's member holding the fits.
    const auto head = [&](Columns& c, auto fits) {
        c.text("group", "theta and other varied settings",
               per_group(a, [](auto& g) { return g.group; }));
        c.real("theta_deg", "deg", "wall angle", per_group(a, [](auto& g) { return g.theta_deg; }));
        c.integer("n_points", "outlets with jams",
                  per_group(a, [&](auto& g) { return I((g.*fits).n_points); }));
    };
    const auto verdict = [&](Columns& c, auto fits) {
        c.text("preferred", "exponential, power_law or undecided",
               per_group(a, [&](auto& g) { return (g.*fits).preferred; }));
        c.text("decision", "why", per_group(a, [&](auto& g) { return (g.*fits).decision; }));
    };
    using Group = std::decay_t<decltype(a.groups.front())>;

    Columns j;
    head(j, &Group::jam_rate);
    const auto ex = [&](auto get) {
        return per_group(a, [&](auto& g) {
            return when(g.jam_rate.exponential.valid, get(g.jam_rate.exponential));
        });
    };
    const auto pw = [&](auto get) {
        return per_group(a, [&](auto& g) {
            return when(g.jam_rate.power_law.valid, get(g.jam_rate.power_law));
        });
    };
    j.optional("exp_ln_A", "1", "exponential: ln(A / (1/s))", ex([](auto& f) { return f.ln_A; }));
    j.optional("exp_B", "1/m", "exponential: B", ex([](auto& f) { return f.B; }));
    j.optional("exp_B_err", "1/m", "exponential: s.e. of B", ex([](auto& f) { return f.B_err; }));
    j.optional("exp_aic", "1", "exponential: AIC", ex([](auto& f) { return f.aic; }));
    j.optional("pow_ln_A", "1", "power law: ln A", pw([](auto& f) { return f.ln_A; }));
    j.optional("pow_gamma", "1", "power law: gamma", pw([](auto& f) { return f.gamma; }));
    j.optional("pow_Dc", "m", "power law: critical outlet Dc", pw([](auto& f) { return f.Dc; }));
    j.optional("pow_aic", "1", "power law: AIC", pw([](auto& f) { return f.aic; }));
    verdict(j, &Group::jam_rate);
    store::DerivedGroup jr{
        "jam_rate", {{"description", "jam rate 1/tau versus D per group"}}, std::move(j.ds), {}};

    // <s>(D) per group: the fit of p = 1/<s>, written as <s> (ln_s0 = -ln A).
    Columns v;
    head(v, &Group::avalanche);
    const auto vex = [&](auto get) {
        return per_group(a, [&](auto& g) {
            return when(g.avalanche.exponential.valid, get(g.avalanche.exponential));
        });
    };
    const auto vpw = [&](auto get) {
        return per_group(a, [&](auto& g) {
            return when(g.avalanche.power_law.valid, get(g.avalanche.power_law));
        });
    };
    v.optional("exp_ln_s0", "1", "exponential growth <s> = exp(ln_s0 + B D): ln_s0",
               vex([](auto& f) { return -f.ln_A; }));
    v.optional("exp_B", "1/m", "exponential growth: B", vex([](auto& f) { return f.B; }));
    v.optional("exp_B_err", "1/m", "exponential growth: s.e. of B",
               vex([](auto& f) { return f.B_err; }));
    v.optional("exp_aic", "1", "exponential growth: AIC", vex([](auto& f) { return f.aic; }));
    v.optional("pow_ln_s0", "1", "power law <s> = exp(ln_s0) (Dc - D)^-gamma: ln_s0",
               vpw([](auto& f) { return -f.ln_A; }));
    v.optional("pow_gamma", "1", "power law: gamma", vpw([](auto& f) { return f.gamma; }));
    v.optional("pow_gamma_err", "1", "power law: s.e. of gamma",
               vpw([](auto& f) { return f.gamma_err; }));
    v.optional("pow_Dc", "m", "power law: critical outlet Dc", vpw([](auto& f) { return f.Dc; }));
    v.optional("pow_Dc_err", "m", "power law: s.e. of Dc", vpw([](auto& f) { return f.Dc_err; }));
    v.optional("pow_aic", "1", "power law: AIC", vpw([](auto& f) { return f.aic; }));
    verdict(v, &Group::avalanche);
    store::DerivedGroup av{"avalanche",
                           {{"description", "mean avalanche size <s> versus D per group"}},
                           std::move(v.ds),
                           {}};

    root.groups = {std::move(points), std::move(km), std::move(bev), std::move(jr), std::move(av)};
    if (auto f = fields_group(a)) root.groups.push_back(std::move(*f));
    return root;
}

namespace {

std::string num(const std::optional<double>& v, const char* f = "%.4g") {
    return v ? fmt(f, *v) : std::string("-");
}

// A p-value with the digits that matter: 0.28, 0.046, 0.004, <0.001 (never "0.00").
std::string p_text(double p) {
    if (p < 0.001) return "<0.001";
    return fmt(p < 0.1 ? "%.2g" : "%.2f", p);
}

}  // namespace

namespace {

// One group's fits across D (jam rate or avalanche size), as one line of the text output.
void write_fits_line(std::ostream& out, const std::string& group, const stats::JamRateFits& j,
                     std::size_t left_out, const char* left_out_text) {
    out << "  " << group << ": " << j.n_points << " outlet(s) with jams";
    if (left_out > 0) out << ", " << left_out << left_out_text;
    out << "; exponential: "
        << (j.exponential.valid ? "B = " + fmt("%.4g", j.exponential.B) + " 1/m"
                                : j.exponential.reason)
        << "; power law: "
        << (j.power_law.valid ? "gamma = " + fmt("%.3g", j.power_law.gamma) +
                                    ", Dc = " + fmt("%.4g", j.power_law.Dc) + " m"
                              : j.power_law.reason)
        << "; preferred: " << j.preferred << " (" << j.decision << ")\n";
}

void write_avalanche_text(std::ostream& out, const Analysis& a, std::size_t width) {
    char buf[1024];
    out << "avalanches per point (s: grains that crossed the outlet per survival interval; <s>: "
           "censored MLE = grains / jams, +- its standard error <s>/sqrt(jams), 95 % CI; p: "
           "clogging probability per grain 1/<s>; gof p: exponential law of s; arches: found / "
           "jams, mean disks)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %26s  %10s  %6s  %14s\n", static_cast<int>(width),
                  "point", "<s> +- se [95% CI]", "p", "gof p", "arches");
    out << buf;
    for (const auto& p : a.points) {
        const auto& av = p.avalanche;
        std::string s = av.reason.empty() ? "-" : av.reason;
        std::string pc = "-";
        if (av.fit && av.fit->tau && av.fit->tau_lo && av.fit->tau_hi && av.fit->sigma_log_tau) {
            s = fmt("%.4g", *av.fit->tau) + " +- " +
                fmt("%.2g", *av.fit->tau * *av.fit->sigma_log_tau) + " [" +
                fmt("%.3g", *av.fit->tau_lo) + ", " + fmt("%.3g", *av.fit->tau_hi) + "]";
            pc = fmt("%.3g", 1.0 / *av.fit->tau);
        }
        const std::string arches =
            std::to_string(av.arches_found) + "/" + std::to_string(av.arch_jams) +
            (av.arch_mean_size ? ", " + fmt("%.2f", *av.arch_mean_size) : std::string());
        std::snprintf(buf, sizeof buf, "%-*s  %26s  %10s  %6s  %14s\n", static_cast<int>(width),
                      p.label.c_str(), s.c_str(), pc.c_str(),
                      av.gof.valid ? p_text(av.gof.p_value).c_str() : "-", arches.c_str());
        out << buf;
    }
    out << "mean avalanche size <s> versus D (exponential growth vs power-law divergence "
           "<s> = A (Dc - D)^-gamma)\n";
    for (const auto& g : a.groups)
        write_fits_line(out, g.group, g.avalanche, g.avalanche_left_out.size(), " left out");
}

}  // namespace

void write_analysis(std::ostream& out, const Analysis& a) {
    std::size_t width = 5;
    for (const auto& p : a.points)
        width = std::max(width, p.label.size());
    char buf[1024];
    out << "analysis per point (c/f/a/t = complete/failed/arrested/time_limit; avg: plain "
           "average of the survival intervals, biased low by censoring; tau: mean survival time, "
           "censored MLE = flow time / jams, 95 % CI; gof p: exponential law; flow: particles "
           "per second; early/late: p of equal jam rates)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %9s  %5s  %6s  %9s  %22s  %6s  %6s  %16s  %18s  %10s\n",
                  static_cast<int>(width), "point", "c/f/a/t", "jams", "shakes", "avg (s)",
                  "tau (s) [95% CI]", "gof p", "R2", "empty (s) +- sd", "flow (1/s) +- se",
                  "early/late");
    out << buf;
    for (const auto& p : a.points) {
        const std::string cfat = std::to_string(p.n_complete) + "/" + std::to_string(p.n_failed) +
                                 "/" + std::to_string(p.n_arrested) + "/" +
                                 std::to_string(p.n_time_limit);
        std::string tau = "-";
        if (p.fit && p.fit->tau && p.fit->tau_lo && p.fit->tau_hi)
            tau = fmt("%.3g", *p.fit->tau) + " [" + fmt("%.3g", *p.fit->tau_lo) + ", " +
                  fmt("%.3g", *p.fit->tau_hi) + "]";
        else if (p.fit && p.fit->tau_lo)
            tau = "> " + fmt("%.3g", *p.fit->tau_lo);
        const std::string empty =
            num(p.empty_time.mean) + " +- " + num(p.empty_time.std_dev, "%.2g");
        const std::string rate = num(p.rate.mean) + " +- " + num(p.rate.std_err, "%.2g");
        std::snprintf(
            buf, sizeof buf, "%-*s  %9s  %5d  %6d  %9s  %22s  %6s  %6s  %16s  %18s  %10s\n",
            static_cast<int>(width), p.label.c_str(), cfat.c_str(), p.n_jams, p.n_shakes,
            num(p.fit ? p.fit->mean_all : std::nullopt).c_str(), tau.c_str(),
            p.gof.valid ? p_text(p.gof.p_value).c_str() : "-",
            p.line.valid ? fmt("%.3f", p.line.r2).c_str() : "-", empty.c_str(), rate.c_str(),
            p.early_late.valid ? p_text(p.early_late.p_value).c_str() : "-");
        out << buf;
    }
    out << "Beverloo W = C rho_b sqrt(g) (D - k d)^(3/2) per wall angle\n  rho_b: "
        << a.rho_b_source << "\n  " << a.d_definition << '\n';
    for (const auto& g : a.groups) {
        const auto& b = g.beverloo;
        out << "  " << g.group << ": ";
        if (b.valid)
            out << "C = " << fmt("%.4g", b.C) << " +- " << fmt("%.2g", b.C_err)
                << ", k = " << fmt("%.4g", b.k) << " +- " << fmt("%.2g", b.k_err) << " ("
                << b.n_points << " outlets, rho_b = " << fmt("%.4g", b.rho_b)
                << " kg/m^2, d = " << fmt("%.4g", b.d) << " m)\n";
        else
            out << "no fit: " << b.reason << '\n';
    }
    out << "jam rate 1/tau versus D\n";
    for (const auto& g : a.groups)
        write_fits_line(out, g.group, g.jam_rate, g.jam_rate_left_out.size(),
                        " left out (no jams)");
    write_avalanche_text(out, a, width);
    if (std::none_of(a.points.begin(), a.points.end(),
                     [](const PointAnalysis& p) { return p.fields.enabled; }))
        return;
    out << "fields per point (merged over the realizations that did not fail; windows: "
           "windows sampled; cells: with data / all; maxima of the cell means)\n";
    std::snprintf(buf, sizeof buf, "%-*s  %12s  %8s  %11s  %15s  %18s\n", static_cast<int>(width),
                  "point", "realizations", "windows", "cells", "max speed (m/s)",
                  "max pressure (m g)");
    out << buf;
    for (const auto& p : a.points) {
        if (!p.fields.enabled) continue;
        const auto& f = p.fields;
        if (!f.merged) {
            std::snprintf(buf, sizeof buf, "%-*s  ", static_cast<int>(width), p.label.c_str());
            out << buf << (f.error ? "error: " : "no fields: ") << f.reason << '\n';
            continue;
        }
        const std::string cells =
            std::to_string(f.cells_with_data) + "/" + std::to_string(f.merged->grid.size());
        std::snprintf(buf, sizeof buf, "%-*s  %12d  %8lld  %11s  %15s  %18s\n",
                      static_cast<int>(width), p.label.c_str(), f.realizations,
                      static_cast<long long>(f.merged->total_windows), cells.c_str(),
                      fmt("%.3g", f.max_mean_speed).c_str(),
                      fmt("%.3g", f.max_mean_pressure).c_str());
        out << buf;
    }
}

namespace {

// Every point the store was ever asked for, in the order it entered (the journal's plans).
std::vector<store::PointPlan> read_points(const fs::path& store, std::string& name) {
    std::vector<store::PointPlan> points;
    std::map<std::string, std::size_t> index;
    store::scan_journal(store::journal_path(store), [&](store::RecordType type, std::uint64_t,
                                                        std::span<const std::uint8_t> payload) {
        if (type != store::RecordType::run_start) return;
        const store::RunStartRecord r = store::decode_run_start(payload);
        name = r.plan.name;
        for (const auto& p : r.plan.points) {
            const auto [it, added] = index.emplace(p.label, points.size());
            if (added)
                points.push_back(p);
            else if (p.seeds.size() > points[it->second].seeds.size())
                points[it->second].seeds = p.seeds;
        }
    });
    return points;
}

}  // namespace

int analyze_store(const fs::path& store, bool json, bool write, std::ostream& out,
                  std::ostream& err) {
    std::error_code ec;
    const bool journal_exists = fs::exists(store::journal_path(store), ec);
    if (ec)
        throw core::StoreError("cannot access the store's journal '" +
                               store::journal_path(store).string() + "': " + ec.message());
    if (!journal_exists)
        throw core::StoreError("no store at '" + store.string() + "' (its journal '" +
                               store::journal_path(store).string() + "' does not exist)");
    std::string name;
    const auto plans = read_points(store, name);
    std::vector<AnalysisPointInput> inputs;
    std::map<std::string, std::size_t> index;
    for (const auto& p : plans) {
        index[p.label] = inputs.size();
        AnalysisPointInput in;
        in.label = p.label;
        in.scene = parse_scene(p.scene);
        in.D_cm = p.D_cm;
        in.theta_deg = p.theta_deg;
        in.planned = p.realizations();
        inputs.push_back(std::move(in));
    }
    std::int64_t row = 0;  // the journal's results in order are the rows of /realizations
    for (auto& r : store::read_journal_realizations(store)) {
        const auto it = index.find(r.label);
        if (it != index.end()) {
            inputs[it->second].results.push_back(std::move(r.result));
            inputs[it->second].rows.push_back(row);
            inputs[it->second].realizations.push_back(r.record.realization);
        }
        ++row;
    }
    const Analysis a = analyze_points(inputs);
    const std::string text = analysis_json(a, store.string(), name);
    if (json)
        out << text << '\n';
    else
        write_analysis(out, a);
    out.flush();
    // Inconsistent fields (grids that differ inside a point) are reported and make the exit
    // code 1; everything else is printed and written.
    int code = 0;
    for (const auto& p : a.points)
        if (p.fields.error) {
            err << "campaign: fields left out: " << p.fields.reason << std::endl;
            code = exit_error;
        }
    if (!write) return code;
    try {
        store::write_derived_group(store, analysis_group(a, text));
    } catch (const core::StoreError& e) {
        err << "campaign: analysis not written into the store: " << e.what() << std::endl;
        return exit_error;
    }
    if (!json) out << "analysis written to " << store.string() << ":/analysis\n";
    return code;
}

namespace {

po::options_description analyze_options() {
    po::options_description d("analyze options");
    d.add_options()("json", po::bool_switch(), "print one JSON object instead of the tables")  //
        ("no-write", po::bool_switch(), "do not write /analysis into the store")               //
        ("help,h", "show this help");
    return d;
}

}  // namespace

void print_analyze_help(std::ostream& os) {
    os << "usage: campaign analyze STORE.h5 [--json] [--no-write]\n\n"
          "Statistics of every point of a store (survival times: their plain average and the\n"
          "mean survival time tau, the censored exponential MLE, with its 95 % interval;\n"
          "goodness of fit; early/late jam rates; empty times; flow rates in particles per\n"
          "second and kg/s) and across points (Beverloo fit per group, jam rate 1/tau versus\n"
          "D), printed as tables or one JSON object, and written into the store's /analysis\n"
          "group (replacing the previous one). Reads the journal; refuses to write while a\n"
          "`campaign run` holds the store. Figures: campaign plot STORE.h5\n\n"
          "exit codes: 0 analyzed (and written), 1 no store, or /analysis could not be written\n"
          "            (a run holds the store, or the HDF5 file is not in step; the tables are\n"
          "            printed anyway), 2 bad command line\n\n"
       << analyze_options();
}

int analyze_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, analyze_options(), "store");
    if (vm.count("help")) {
        print_analyze_help(std::cout);
        return 0;
    }
    const std::string store_path = single_positional(vm, "store", "store", "STORE.h5");
    return analyze_store(store_path, vm["json"].as<bool>(), !vm["no-write"].as<bool>(), std::cout,
                         std::cerr);
}

}  // namespace hopper::cli
