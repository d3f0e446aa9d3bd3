#include "hopper/campaign/mixing.hpp"

#include <map>
#include <set>

#include "hopper/config/sweep.hpp"

namespace hopper::campaign {

namespace {

// Name -> value text ("0.5", "verlet"), as labels write them.
std::map<std::string, std::string> values(const std::vector<core::Setting>& settings) {
    std::map<std::string, std::string> m;
    for (const auto& s : settings)
        m[s.name] = config::value_text(s);
    return m;
}

std::string value_or_absent(const std::map<std::string, std::string>& m, const std::string& k) {
    const auto it = m.find(k);
    return it == m.end() ? "absent" : it->second;
}

std::string section(const std::string& name) {
    const auto dot = name.find('.');
    return dot == std::string::npos ? name : name.substr(0, dot);
}

// Whether a difference in scene parameter `k` is told by a label setting `s` that differs: the
// wall angle by theta_deg; a section's parameters by a setting of that section (walls follow
// the material unless set).
bool explains(const std::string& s, const std::string& k) {
    if (s == "theta_deg") return k == "theta_deg";
    const std::string ss = section(s), ks = section(k);
    return ss == ks || (ss == "material" && ks == "walls");
}

// The label settings (other than the outlet) in which two points differ.
std::set<std::string> told_apart(const std::map<std::string, std::string>& a,
                                 const std::map<std::string, std::string>& b) {
    std::set<std::string> told;
    for (const auto& [k, v] : a)
        if (k != "D_cm" && value_or_absent(b, k) != v) told.insert(k);
    for (const auto& [k, v] : b)
        if (k != "D_cm" && value_or_absent(a, k) != v) told.insert(k);
    return told;
}

// A point stored before setting `k` existed has no value for it and ran with its default (new
// settings keep the earlier physics at their defaults): absent there and the default here is
// the same physics.
bool same_as_default(const std::string& a, const std::string& b, const std::string& k) {
    if (a != "absent" && b != "absent") return false;
    const auto d = config::default_parameter(k);
    return d && config::value_text(*d) == (a == "absent" ? b : a);
}

}  // namespace

std::vector<MixedSetting> mixed_settings(const store::CampaignPlan& stored,
                                         const store::CampaignPlan& sweep) {
    std::map<std::string, MixedSetting> found;
    std::map<std::string, std::set<std::string>> others;
    for (const auto& p : sweep.points) {
        if (stored.find(p.label) != nullptr) continue;  // only new points can mix
        const auto mine = values(p.parameters);
        const auto my_labels = values(p.settings);
        for (const auto& q : stored.points) {
            // A point stored before typed parameters whose sweep text could not be read back
            // (campaign::restore_settings) cannot be compared.
            if (q.parameters.empty()) continue;
            const auto theirs = values(q.parameters);
            const std::set<std::string> told = told_apart(my_labels, values(q.settings));
            std::set<std::string> names;
            for (const auto& [k, v] : mine)
                names.insert(k);
            for (const auto& [k, v] : theirs)
                names.insert(k);
            for (const auto& k : names) {
                if (k == "D_cm") continue;  // D is in every label
                const std::string a = value_or_absent(mine, k), b = value_or_absent(theirs, k);
                if (a == b || same_as_default(a, b, k)) continue;
                bool is_told = false;
                for (const auto& s : told)
                    is_told = is_told || explains(s, k);
                if (is_told) continue;
                found.try_emplace(k, MixedSetting{k, a, {}, q.label});
                others[k].insert(b);
            }
        }
    }
    std::vector<MixedSetting> out;
    for (auto& [k, m] : found) {
        m.store_values.assign(others[k].begin(), others[k].end());
        out.push_back(std::move(m));
    }
    return out;
}

std::string describe(const std::vector<MixedSetting>& mixed) {
    std::string s;
    for (const auto& m : mixed) {
        std::string vals;
        for (const auto& v : m.store_values)
            vals += (vals.empty() ? "" : ", ") + v;
        s += "\n    " + m.name + " = " + m.sweep_value + " in this sweep, " + vals +
             " in the store (point '" + m.store_point + "')";
    }
    return s;
}

}  // namespace hopper::campaign
