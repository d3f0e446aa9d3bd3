#include "hopper/campaign/point_columns.hpp"

#include <string>

#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/config/scene_schema.hpp"

namespace hopper::campaign {

namespace {

std::string enters_text(const config::FingerprintLine& f) {
    std::string s;
    switch (f.enters) {
        case config::Enters::always:
            s = "always";
            break;
        case config::Enters::unless_default:
            s = "unless at " +
                (f.absent_at.empty() ? std::string("its default") : std::string(f.absent_at));
            break;
        case config::Enters::when_set:
            s = "when set";
            break;
        case config::Enters::never:
            s = "never (shows through the rows that need it)";
            break;
    }
    if (!f.only_with.empty()) s += ", only with " + std::string(f.only_with) + " off its default";
    return s;
}

}  // namespace

std::vector<store::DerivedDataset> point_parameter_columns(
    const store::CampaignPlan& plan, const std::vector<store::RunSummary>& runs) {
    const auto scenes = point_scenes(plan, runs);
    std::vector<store::DerivedDataset> out;
    for (const auto& row : config::scene_schema()) {
        store::DerivedDataset d;
        d.name = std::string(row.fingerprint.name.empty() ? row.name : row.fingerprint.name);
        d.units = config::si_unit(row);
        const auto def = config::default_value(row);
        d.description = std::string(row.in_sweep_file ? "sweep key " : "not a sweep key: ") +
                        std::string(row.name) +
                        (row.unit.empty() ? std::string() : " [" + std::string(row.unit) + "]") +
                        ", default " + (def ? config::value_text({"", *def}) : "unset") +
                        "; in the physics text: " + enters_text(row.fingerprint);
        d.attributes = {{"sweep_name", std::string(row.name)},
                        {"sweep_unit", std::string(row.unit)},
                        {"fingerprint", enters_text(row.fingerprint)}};
        const bool number =
            row.kind == config::ValueKind::real || row.kind == config::ValueKind::integer;
        // An optional parameter (unset by default) gets a has_ flag: the store writes no NaN.
        const bool optional = !def.has_value();
        std::vector<bool> has;
        std::vector<double> reals;
        std::vector<std::int64_t> integers;
        std::vector<std::string> texts;
        for (const auto& scene : scenes) {
            const config::SchemaRead v =
                scene ? config::value_in_si(row, *scene) : config::SchemaRead{};
            has.push_back(v.has_value());
            if (!number)
                texts.push_back(v ? std::get<std::string>(*v) : std::string());
            else if (row.kind == config::ValueKind::integer)
                integers.push_back(v ? static_cast<std::int64_t>(std::get<double>(*v)) : 0);
            else
                reals.push_back(v ? std::get<double>(*v) : 0.0);
        }
        if (!number)
            d.values = std::move(texts);
        else if (row.kind == config::ValueKind::integer)
            d.values = std::move(integers);
        else
            d.values = std::move(reals);
        out.push_back(std::move(d));
        if (optional) {
            store::DerivedDataset flag;
            flag.name = "has_" + out.back().name;
            flag.description = "TRUE where " + out.back().name + " is set (unset: 0 beside it)";
            flag.attributes = {{"sweep_name", ""}, {"sweep_unit", ""}, {"fingerprint", ""}};
            flag.values = std::move(has);
            out.push_back(std::move(flag));
        }
    }
    store::DerivedDataset typed;
    typed.name = "typed";
    typed.description =
        "TRUE where the point's values are in this group (from its typed parameters, or for a "
        "store older than them from a recorded sweep text); FALSE: nothing recorded explains its "
        "scene text (numbers 0, texts empty): read /points/scene";
    std::vector<bool> flags;
    for (const auto& s : scenes)
        flags.push_back(s.has_value());
    typed.values = std::move(flags);
    out.push_back(std::move(typed));
    return out;
}

}  // namespace hopper::campaign
