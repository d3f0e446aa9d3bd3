// The sweep file's scene sections, [sweep] and [[points]], and each point's validated scene,
// label, settings and parameters (Parser members; parser.hpp).
#include <algorithm>
#include <iterator>

#include "config/parser.hpp"
#include "hopper/config/sanity.hpp"
#include "hopper/core/units.hpp"

namespace hopper::config::detail {

using core::ConfigError;
using engine::SceneParams;

Value Parser::read_value(const toml::node& n, const KeyDef& d) const {
    const std::string name(d.name);
    const std::string got = node_text(n) + " has the wrong type: expected ";
    double v = 0.0;
    switch (d.kind) {
        case Kind::real:
            if (auto i = n.as_integer())
                v = static_cast<double>(i->get());
            else if (auto f = n.as_floating_point())
                v = f->get();
            else
                fail(n.source(), name + " = " + got + "a number, got " + type_name(n));
            break;
        case Kind::integer:
            if (auto i = n.as_integer())
                v = static_cast<double>(i->get());
            else
                fail(n.source(),
                     name + " = " + got + "an integer, got " + type_name(n) +
                         (n.is_floating_point() ? " (write it without a decimal point)" : ""));
            break;
        case Kind::choice: {
            std::vector<std::string> options;
            for (std::string_view rest = d.choices; !rest.empty();) {
                const auto comma = rest.find(',');
                options.emplace_back(rest.substr(0, comma));
                rest =
                    comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
            }
            std::string allowed;  // "a", "b"
            for (const auto& o : options)
                allowed += (allowed.empty() ? "\"" : ", \"") + o + "\"";
            auto s = n.as_string();
            if (!s)
                fail(n.source(),
                     name + " = " + got + "a string (" + allowed + "), got " + type_name(n));
            if (std::find(options.begin(), options.end(), s->get()) == options.end())
                fail(n.source(),
                     name + " = " + node_text(n) + " is not one of the allowed values " + allowed);
            return s->get();
        }
        case Kind::boolean: {
            auto b = n.as_boolean();
            if (!b) fail(n.source(), name + " = " + got + "true or false, got " + type_name(n));
            return std::string(b->get() ? "true" : "false");
        }
    }
    if (v == 0.0) v = 0.0;  // no "-0" in labels and seeds
    if (auto err = range_error(d, v, node_text(n))) fail(n.source(), *err);
    return v;
}

void Parser::read_scene_section(std::string_view section, const toml::node& node) {
    const auto* tbl = node.as_table();
    if (!tbl)
        fail(node.source(), std::string(section) + " must be a table ([" + std::string(section) +
                                "]), got " + type_name(node));
    for (auto&& [k, v] : *tbl) {
        const KeyDef* d = find_key(section, k.str());
        if (!d) {
            const auto allowed = keys_of(section);
            fail(k.source(), "unknown key '" + clip(k.str()) + "' in [" + std::string(section) +
                                 "]; allowed: " + join(allowed) + suggestion(k.str(), allowed));
        }
        base_[std::string(d->name)] = Given{d, read_value(v, *d)};
    }
}

std::vector<PointDraft> Parser::read_sweep(const toml::node& node) const {
    const auto* tbl = node.as_table();
    if (!tbl) fail(node.source(), "sweep must be a table ([sweep]), got " + type_name(node));

    struct Axis {
        const KeyDef* def;
        std::vector<Value> values;
    };
    std::vector<Axis> axes;
    std::vector<std::string> all_names;
    for (const auto& d : key_table())
        all_names.emplace_back(d.name);
    const std::string allowed_text =
        "allowed: D_cm, theta_deg, and <section>.<key> for a key of hopper, material, walls, "
        "integrator or protocol (see campaigns/README.md)";

    auto read_axis = [&](const KeyDef& d, const toml::node& v) {
        const auto* arr = v.as_array();
        if (!arr)
            fail(v.source(), std::string(d.name) + " = " + node_text(v) +
                                 " in [sweep] must be a list of values, e.g. " +
                                 std::string(d.name) + " = [" + node_text(v) + "]");
        if (arr->empty())
            fail(v.source(), std::string(d.name) +
                                 " = [] in [sweep] is an empty list: give at "
                                 "least one value or remove the key");
        Axis axis{&d, {}};
        for (const auto& e : *arr)
            axis.values.push_back(read_value(e, d));
        axes.push_back(std::move(axis));
    };

    for (auto&& [k, v] : *tbl) {
        const std::string key(k.str());
        if (key == "D_cm" || key == "theta_deg") {
            read_axis(*find_name(key), v);
        } else if (is_scene_section(key) && v.is_table()) {
            for (auto&& [k2, v2] : *v.as_table()) {
                const std::string full = key + "." + std::string(k2.str());
                if (key == "hopper" && (k2.str() == "D_cm" || k2.str() == "theta_deg"))
                    fail(k2.source(), "write " + clip(k2.str()) +
                                          " = [...] directly in "
                                          "[sweep], not as '" +
                                          full + "'");
                const KeyDef* d = find_key(key, k2.str());
                if (!d) {
                    const auto allowed = keys_of(key);
                    fail(k2.source(), "unknown key '" + clip(full) + "' in [sweep]; allowed in " +
                                          key + ": " + join(allowed) + suggestion(full, all_names));
                }
                read_axis(*d, v2);
            }
        } else if (const KeyDef* quoted = quoted_dotted_key(key)) {
            // "material.mu" = [...] (quoted, one TOML key) means what material.mu = [...] does
            read_axis(*quoted, v);
        } else {
            std::string shown = key;
            if (auto sub = v.as_table(); sub && !sub->empty())
                shown += "." + std::string(sub->begin()->first.str());
            fail(k.source(), "unknown key '" + clip(shown) + "' in [sweep]; " + allowed_text +
                                 suggestion(shown, all_names));
        }
    }
    if (axes.empty())
        fail(node.source(), "[sweep] has no lists: add e.g. D_cm = [2.7, 2.9] or remove it");

    std::sort(axes.begin(), axes.end(), [](const Axis& a, const Axis& b) {
        return canonical_less(a.def->name, b.def->name);
    });
    std::size_t count = 1;
    for (const auto& a : axes) {
        count *= a.values.size();
        if (count > max_points)
            fail(node.source(),
                 "[sweep] has more than " + std::to_string(max_points) + " combinations");
    }
    // Cartesian product in canonical axis order; the last axis varies fastest.
    std::vector<PointDraft> out;
    std::vector<std::size_t> idx(axes.size(), 0);
    for (std::size_t n = 0; n < count; ++n) {
        PointDraft p;
        p.origin = "[sweep] combination " + std::to_string(n + 1);
        for (std::size_t a = 0; a < axes.size(); ++a)
            p.overrides.push_back(Given{axes[a].def, axes[a].values[idx[a]]});
        out.push_back(std::move(p));
        for (std::size_t a = axes.size(); a-- > 0;) {
            if (++idx[a] < axes[a].values.size()) break;
            idx[a] = 0;
        }
    }
    return out;
}

std::vector<PointDraft> Parser::read_points(const toml::node& node) const {
    const auto* arr = node.as_array();
    if (!arr)
        fail(node.source(),
             "points must be an array of tables ([[points]]), got " + type_name(node));
    if (arr->empty()) fail(node.source(), "points is an empty list: give at least one point");
    const std::string allowed =
        "D_cm, theta_deg, realizations, and inline tables hopper, material, walls, integrator, "
        "protocol, fields";
    std::vector<PointDraft> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
        const toml::node& pn = *arr->get(i);
        const auto* tbl = pn.as_table();
        const std::string origin = "[[points]] #" + std::to_string(i + 1);
        if (!tbl) fail(pn.source(), origin + " must be a table, got " + type_name(pn));
        PointDraft p;
        p.origin = origin + (pn.source().begin.line
                                 ? " (line " + std::to_string(pn.source().begin.line) + ")"
                                 : "");
        for (auto&& [k, v] : *tbl) {
            const std::string key(k.str());
            if (key == "D_cm" || key == "theta_deg") {
                const KeyDef* d = find_name(key);
                p.overrides.push_back(Given{d, read_value(v, *d)});
            } else if (key == "realizations") {
                p.realizations = read_realizations(v, origin + " realizations");
            } else if (const KeyDef* quoted = quoted_dotted_key(key)) {
                // "walls.mu" = 0.5 (quoted, one TOML key) means what walls = { mu = 0.5 } does
                p.overrides.push_back(Given{quoted, read_value(v, *quoted)});
            } else if (is_scene_section(key)) {
                const auto* sub = v.as_table();
                if (!sub)
                    fail(v.source(), key + " in " + origin + " must be a table, e.g. " + key +
                                         " = { key = value }, got " + type_name(v));
                for (auto&& [k2, v2] : *sub) {
                    const std::string full = key + "." + std::string(k2.str());
                    if (key == "hopper" && (k2.str() == "D_cm" || k2.str() == "theta_deg"))
                        fail(k2.source(), "write " + clip(k2.str()) +
                                              " directly in the point, not as '" + full + "'");
                    const KeyDef* d = find_key(key, k2.str());
                    if (!d) {
                        const auto keys = keys_of(key);
                        fail(k2.source(), "unknown key '" + clip(full) + "' in " + origin +
                                              "; allowed in " + key + ": " + join(keys) +
                                              suggestion(k2.str(), keys));
                    }
                    p.overrides.push_back(Given{d, read_value(v2, *d)});
                }
            } else {
                std::vector<std::string> opts = {"D_cm", "theta_deg", "realizations"};
                opts.insert(opts.end(), scene_sections.begin(), scene_sections.end());
                fail(k.source(), "unknown key '" + clip(key) + "' in " + origin +
                                     "; allowed: " + allowed + suggestion(key, opts));
            }
        }
        out.push_back(std::move(p));
    }
    return out;
}

Assignments Parser::merged(const std::vector<Given>& overrides) const {
    Assignments out = base_;
    for (const auto& g : overrides)
        out[std::string(g.def->name)] = g;
    return out;
}

SceneParams Parser::build_scene(const std::vector<Given>& overrides,
                                const std::string& context) const {
    const Assignments merged = this->merged(overrides);
    SceneParams p{};
    for (const auto& [name, g] : merged)
        g.def->apply(p, g.value);
    // Walls default to the particles' material and to wall particles of diameter d_large
    // (docs/model.md): "follow" the values this scene ends up with unless walls are given.
    if (!merged.count("walls.e_n")) p.material.wall.e_n = p.material.system.e_n;
    if (!merged.count("walls.mu")) p.material.wall.mu = p.material.system.mu;
    if (!merged.count("walls.particle_diameter_cm")) p.hopper.wall_diameter = p.particles.d_large;
    // The base scene without a D_cm in [hopper]: the built-in default outlet is never used
    // (every point and `campaign simulate --D` give theirs), so a hopper narrower than it must
    // not be refused for it. It stands at half the width here.
    if (context.empty() && !merged.count("D_cm") && !(p.hopper.outlet < p.hopper.width))
        p.hopper.outlet = 0.5 * p.hopper.width;

    const std::string where = context.empty() ? "" : context + ": ";
    auto in_cm = [](double m) { return approx_number(m / core::cm); };
    const auto& h = p.hopper;
    const auto& s = p.particles;
    const auto& pr = p.protocol;
    if (s.d_large < s.d_small)
        fail(where + "hopper.d_large_cm = " + in_cm(s.d_large) +
             " must be at least hopper.d_small_cm = " + in_cm(s.d_small));
    if (!(h.width > 2.0 * s.d_large)) {
        std::string msg = where + "hopper.width_cm = " + in_cm(h.width) +
                          " must exceed 2 * hopper.d_large_cm = " + in_cm(2.0 * s.d_large);
        // A width in metres (width_cm = 0.12 for 12 cm) gets the value in centimetres.
        if (h.width * 100 > 2.0 * s.d_large)
            msg += "; width_cm is in centimetres: for " + in_cm(h.width * 100) +
                   " cm write width_cm = " + in_cm(h.width * 100);
        fail(msg);
    }
    if (!(h.outlet < h.width))
        fail(where + "D_cm = " + in_cm(h.outlet) + " must be smaller than hopper.width_cm = " +
             in_cm(h.width) + " (the outlet must fit inside the hopper)");
    const double max_spacing = 1.0 + s.d_small / h.wall_diameter;
    if (!(h.wall_spacing < max_spacing))
        fail(where + "walls.spacing = " + approx_number(h.wall_spacing) +
             " must be below 1 + d_small / " + "wall diameter = " + approx_number(max_spacing) +
             " so that no particle slips between two wall particles");
    if (!(pr.exit_depth > pr.jam_region_height))
        fail(where + "protocol.exit_depth = " + approx_number(pr.exit_depth) +
             " must exceed protocol.jam_region_height = " + approx_number(pr.jam_region_height) +
             " (particles are removed only below the jam region)");
    if (pr.empty_threshold >= s.count)
        fail(where + "protocol.empty_threshold = " + std::to_string(pr.empty_threshold) +
             " must be smaller than hopper.particles = " + std::to_string(s.count));
    const auto& f = p.fields;
    if (f.sample_interval > f.window)
        fail(where + "fields.sample_interval_s = " + approx_number(f.sample_interval) +
             " must not exceed fields.window_s = " + approx_number(f.window) +
             " (every window needs samples)");
    if (f.end && !(*f.end > f.start))
        fail(where + "fields.end_s = " + approx_number(*f.end) +
             " must exceed fields.start_s = " + approx_number(f.start));
    try {
        engine::validate_scene(p);
    } catch (const ConfigError& e) {
        fail(where + e.what());
    }
    // Orders of magnitude (a value in the wrong unit passes the ranges above).
    if (const std::string problem = scene_problem(p); !problem.empty()) fail(where + problem);
    return p;
}

Point Parser::make_point(const PointDraft& draft, int default_realizations) const {
    Point pt;
    for (const auto& g : draft.overrides)
        pt.settings.push_back(core::Setting{std::string(g.def->name), g.value});
    for (const char* required : {"D_cm", "theta_deg"}) {
        const bool given = std::any_of(pt.settings.begin(), pt.settings.end(),
                                       [&](const core::Setting& s) { return s.name == required; });
        if (given) continue;
        const auto it = base_.find(required);
        if (it == base_.end())
            fail(draft.origin + " has no " + required +
                 ": D_cm and theta_deg are needed for every "
                 "point; give them in the point, in [sweep], or as defaults in [hopper]");
        pt.settings.push_back(core::Setting{required, it->second.value});
    }
    std::sort(pt.settings.begin(), pt.settings.end(),
              [](const core::Setting& a, const core::Setting& b) {
                  return canonical_less(a.name, b.name);
              });
    for (const auto& s : pt.settings)
        pt.label += (pt.label.empty() ? "" : " ") + to_string(s);
    pt.realizations = draft.realizations.value_or(default_realizations);
    pt.scene = build_scene(draft.overrides, "in point '" + pt.label + "' (" + draft.origin + ")");
    pt.parameters = parameters_of(draft.overrides, pt.scene);
    return pt;
}

std::vector<core::Setting> Parser::parameters_of(const std::vector<Given>& overrides,
                                                 const engine::SceneParams& scene) const {
    // Every key of the table: as the file gave it, else as the scene has it (its default, or the
    // value it follows), in file units. Unset optionals are left out.
    std::vector<core::Setting> out;
    const Assignments given = merged(overrides);
    for (const auto& d : key_table()) {
        const std::string name(d.name);
        if (const auto it = given.find(name); it != given.end())
            out.push_back(core::Setting{name, it->second.value});
        else if (auto v = d.read(scene))
            out.push_back(core::Setting{name, std::move(*v)});
    }
    return out;
}

SweepFile Parser::run() {
    return run(parse_toml(text_, file_));
}

SweepFile Parser::run(const toml::table& root) {
    SweepFile out;
    out.path = path_;
    out.text = std::string(text_);

    const toml::node* sweep = nullptr;
    const toml::node* points = nullptr;
    const toml::node* campaign = nullptr;
    std::vector<std::string> sections(scene_sections.begin(), scene_sections.end());
    sections.insert(sections.end(), {"campaign", "sweep", "points"});
    for (auto&& [k, v] : root) {
        const std::string key(k.str());
        if (is_scene_section(key))
            read_scene_section(key, v);
        else if (key == "campaign")
            campaign = &v;
        else if (key == "sweep")
            sweep = &v;
        else if (key == "points")
            points = &v;
        else if (v.is_table())
            fail(k.source(), "unknown section [" + clip(key) + "]; allowed: " + join(sections) +
                                 suggestion(key, sections));
        else
            fail(k.source(), "unknown key '" + clip(key) +
                                 "' at the top level (outside any section); "
                                 "allowed sections: " +
                                 join(sections) + suggestion(key, sections));
    }

    out.base = build_scene({}, "");
    out.base_parameters = parameters_of({}, out.base);

    if (!campaign) {
        if (sweep) fail(sweep->source(), "[sweep] needs a [campaign] section (at least a name)");
        if (points)
            fail(points->source(), "[[points]] needs a [campaign] section (at least a name)");
        return out;
    }
    out.has_campaign = true;
    read_campaign(*campaign, out);

    std::vector<PointDraft> drafts;
    if (sweep) drafts = read_sweep(*sweep);
    if (points) {
        auto more = read_points(*points);
        drafts.insert(drafts.end(), std::make_move_iterator(more.begin()),
                      std::make_move_iterator(more.end()));
    }
    if (drafts.empty()) {
        if (!base_.count("D_cm") || !base_.count("theta_deg"))
            fail(campaign->source(),
                 "[campaign] has neither [sweep] nor [[points]], so it runs the base scene, which "
                 "needs D_cm and theta_deg: give both in [hopper]");
        drafts.push_back(PointDraft{{}, std::nullopt, "the base scene"});
    }
    if (drafts.size() > max_points)
        fail("the campaign has " + std::to_string(drafts.size()) + " points; at most " +
             std::to_string(max_points) + " are allowed");

    std::map<std::string, std::string> seen;  // label -> origin
    long long tasks = 0;
    for (const auto& d : drafts) {
        Point pt = make_point(d, out.campaign.realizations);
        if (const auto& t = out.campaign.target) {
            // Rounds: the point's realizations are the first round; the plan holds
            // max_realizations (their seeds are fixed by the index, so the set run stays
            // deterministic whatever the rounds decide).
            if (pt.realizations > t->max_realizations)
                fail("point '" + pt.label + "' (" + d.origin + ") has " +
                     std::to_string(pt.realizations) +
                     " realizations in its first round, more than campaign.max_realizations = " +
                     std::to_string(t->max_realizations) + "; allowed: at most max_realizations");
            pt.first_round = pt.realizations;
            pt.realizations = t->max_realizations;
        }
        if (auto [it, fresh] = seen.emplace(pt.label, d.origin); !fresh)
            fail("duplicate point '" + pt.label + "': " + it->second + " and " + d.origin +
                 " have the same settings (to run a point more often, raise its realizations)");
        tasks += pt.realizations;
        if (tasks > max_tasks)
            fail("the campaign has more than " + std::to_string(max_tasks) + " tasks");
        out.campaign.points.push_back(std::move(pt));
    }
    return out;
}
}  // namespace hopper::config::detail
