#include "hopper/analysis/analyze.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/core/units.hpp"
#include "hopper/store/codec.hpp"

namespace hopper::analysis {

namespace {

using core::cm;

// Shortest round-trip text of a number (as labels and the JSON write it).
std::string number_text(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

const core::Setting* find(const std::vector<core::Setting>& settings, std::string_view name) {
    for (const auto& s : settings)
        if (s.name == name) return &s;
    return nullptr;
}

// A numeric setting, absent when missing or not a number.
std::optional<double> number(const std::vector<core::Setting>& settings, std::string_view name) {
    const core::Setting* s = find(settings, name);
    if (!s) return std::nullopt;
    if (const auto* x = std::get_if<double>(&s->value)) return *x;
    return std::nullopt;
}

std::string value_text(const core::Setting* s) {
    return s ? config::value_text(*s) : "absent";
}

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

std::string grid_text(const engine::FieldGrid& g) {
    std::string t = std::to_string(g.nx) + " x " + std::to_string(g.ny) + " cells of " +
                    number_text(g.cell) + " m from (" + number_text(g.x0) + ", " +
                    number_text(g.y0) + ") m, kernel " + engine::to_string(g.kernel);
    if (g.kernel == engine::FieldKernel::gaussian) t += " of width " + number_text(g.kernel_width);
    return t;
}

}  // namespace

PointFields merge_point_fields(const AnalysisPointInput& in) {
    PointFields pf;
    const core::Setting* enabled = find(in.parameters, "fields.enabled");
    pf.enabled = enabled && std::holds_alternative<std::string>(enabled->value) &&
                 std::get<std::string>(enabled->value) == "true";
    const bool rows_known = in.rows.size() == in.results.size();
    const bool indices_known = in.realizations.size() == in.results.size();
    const std::string unit = rows_known ? "row" : indices_known ? "realization" : "result";
    bool any = false;
    std::int64_t first = -1;
    for (std::size_t i = 0; i < in.results.size(); ++i) {
        const auto& r = in.results[i];
        if (!r.fields) continue;
        any = true;
        if (r.status == engine::Status::failed) continue;
        const std::int64_t row = rows_known      ? in.rows[i]
                                 : indices_known ? std::int64_t{in.realizations[i]}
                                                 : static_cast<std::int64_t>(i);
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
            throw core::StoreError("point '" + in.label + "': the fields of " + unit + "s " +
                                   std::to_string(first) + " and " + std::to_string(row) +
                                   (rows_known ? " of /realizations" : "") +
                                   " have different grids (" + grid_text(pf.merged->grid) + "; " +
                                   grid_text(m.grid) + "): they cannot be merged");
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
    const FieldsSummary sum = summarize(*pf.merged);
    pf.cells_with_data = sum.cells_with_data;
    pf.max_mean_speed = sum.max_mean_speed;
    pf.max_mean_pressure = sum.max_mean_pressure;
    return pf;
}

FieldsSummary summarize(const engine::FieldMoments& m) {
    FieldsSummary s;
    const auto& speed = m.mean[static_cast<int>(engine::Field::speed)];
    const auto& pressure = m.mean[static_cast<int>(engine::Field::pressure)];
    const std::size_t n = std::min({m.windows.size(), speed.size(), pressure.size()});
    for (std::size_t c = 0; c < n; ++c) {
        if (m.windows[c] <= 0) continue;
        s.max_mean_speed = s.cells_with_data == 0 ? speed[c] : std::max(s.max_mean_speed, speed[c]);
        s.max_mean_pressure =
            s.cells_with_data == 0 ? pressure[c] : std::max(s.max_mean_pressure, pressure[c]);
        ++s.cells_with_data;
    }
    return s;
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

void keep_what_analysis_reads(engine::RealizationResult& r) {
    const auto drop = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
    drop(r.exit_times);
    drop(r.curve_time);
    drop(r.curve_count);
    drop(r.shakes_per_jam);
    drop(r.message);
    for (auto& a : r.arches) {
        drop(a.x);
        drop(a.y);
    }
    r.diagnostics = engine::Diagnostics{};
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
        for (const auto& s : in.settings)
            if (s.name != "D_cm") key += config::to_string(s) + " ";
        by_label_group[key].push_back(&in);
    }
    std::map<std::string, std::string> out;
    for (const auto& [key, members] : by_label_group) {
        std::set<std::string> names;
        for (const auto* in : members)
            for (const auto& s : in->parameters)
                names.insert(s.name);
        std::vector<std::string> differing;
        for (const auto& name : names) {
            if (name == "D_cm") continue;
            std::set<std::string> values;
            for (const auto* in : members)
                values.insert(value_text(find(in->parameters, name)));
            if (values.size() > 1) differing.push_back(name);
        }
        for (const auto* in : members) {
            std::string extra;
            for (const auto& name : differing)
                extra += " " + name + "=" + value_text(find(in->parameters, name));
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

namespace {

// One point's statistics; `hidden` is what hidden_settings() adds to its group ("" mostly).
PointAnalysis analyze_point(const AnalysisPointInput& in, const std::string& hidden) {
    PointAnalysis p;
    p.label = in.label;
    // The settings as the user wrote them (the plan's SI round trip gave 59.99999999999999).
    p.D_cm = number(in.settings, "D_cm").value_or(in.D_cm);
    p.theta_deg = number(in.settings, "theta_deg").value_or(in.theta_deg);
    std::string group = "theta_deg=" + number_text(p.theta_deg);
    group += hidden;
    p.planned = in.planned;
    p.stored = static_cast<int>(in.results.size());
    for (const auto& s : in.settings) {
        if (s.name == "D_cm" || s.name == "theta_deg") continue;
        p.varied.push_back(s);
        group += " " + config::to_string(s);
    }
    p.group = group;
    const auto parameter = [&](const char* name) {
        return number(in.parameters, name).value_or(0.0);
    };
    const double density = parameter("hopper.density_kg_m3");
    const double thickness = parameter("hopper.thickness_cm") * cm;
    const double fs = parameter("hopper.small_fraction");
    const double ds = parameter("hopper.d_small_cm") * cm;
    const double dl = parameter("hopper.d_large_cm") * cm;
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
        p.fit_reason = p.used == 0 ? "no realizations without failure" : "no survival intervals";
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

    return p;
}

// The fits across D of one group (its points sorted by D here): Beverloo, jam rate, <s>.
void fit_group(GroupAnalysis& g, const std::vector<PointAnalysis>& points) {
    std::sort(g.points.begin(), g.points.end(), [&](int x, int y) {
        return points[static_cast<std::size_t>(x)].D_cm < points[static_cast<std::size_t>(y)].D_cm;
    });
    // Beverloo: mean mass flow rate per outlet, weighted by its standard error when every
    // point has one (relative weights; the covariance is scaled by the residual variance).
    std::vector<double> D, W, sW;
    bool all_se = true;
    double rho_b = 0.0, d = 0.0;
    for (int i : g.points) {
        const auto& p = points[static_cast<std::size_t>(i)];
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
        const auto& p = points[static_cast<std::size_t>(i)];
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
        const auto& av = points[static_cast<std::size_t>(i)].avalanche;
        if (av.fit && av.fit->tau && av.fit->sigma_log_tau) {
            Ds.push_back(points[static_cast<std::size_t>(i)].D_cm * cm);
            ps.push_back(1.0 / *av.fit->tau);
            ss.push_back(*av.fit->sigma_log_tau);
        } else {
            g.avalanche_left_out.emplace_back(points[static_cast<std::size_t>(i)].D_cm,
                                              av.reason.empty() ? "no jams" : av.reason);
        }
    }
    g.avalanche = stats::fit_jam_rate(Ds, ps, ss);
}

}  // namespace

Analysis analyze_points(const std::vector<AnalysisPointInput>& inputs) {
    Analysis a;
    a.rho_b_source = "estimate: rho_b = " + number_text(kAssumedPackingFraction) +
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
        PointAnalysis p = analyze_point(in, [&] {
            const auto it = hidden.find(in.label);
            return it == hidden.end() ? std::string() : it->second;
        }());
        const std::string& group = p.group;
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

    for (auto& g : a.groups)
        fit_group(g, a.points);
    return a;
}

}  // namespace hopper::analysis
