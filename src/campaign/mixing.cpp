#include "hopper/campaign/mixing.hpp"

#include <map>
#include <set>
#include <sstream>

namespace hopper::campaign {

namespace {

std::map<std::string, std::string> scene_values(const std::string& text) {
    std::map<std::string, std::string> m;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        if (const auto eq = line.find('='); eq != std::string::npos)
            m[line.substr(0, eq)] = line.substr(eq + 1);
    return m;
}

std::string value_or_absent(const std::map<std::string, std::string>& m, const std::string& k) {
    const auto it = m.find(k);
    return it == m.end() ? "absent" : it->second;
}

}  // namespace

namespace {

// A label's settings other than the outlet: {"theta_deg": "60", "material.mu": "0.5"}.
std::map<std::string, std::string> label_settings(const std::string& label) {
    std::map<std::string, std::string> m;
    std::istringstream in(label);
    for (std::string token; in >> token;)
        if (const auto eq = token.find('=');
            eq != std::string::npos && token.compare(0, eq, "D_cm"))
            m[token.substr(0, eq)] = token.substr(eq + 1);
    return m;
}

std::string section(const std::string& name) {
    const auto dot = name.find('.');
    return dot == std::string::npos ? name : name.substr(0, dot);
}

// Whether a difference in scene parameter `k` is told by a label setting `s` that differs: the
// wall angle by theta_deg; a section's parameters by a setting of that section ([hopper] also
// holds the particles' keys; walls follow the material unless set).
bool explains(const std::string& s, const std::string& k) {
    if (s == "theta_deg") return k == "hopper.theta_rad";
    const std::string ss = section(s), ks = section(k);
    return ss == ks || (ss == "hopper" && ks == "particles") || (ss == "material" && ks == "walls");
}

}  // namespace

std::vector<MixedSetting> mixed_settings(const store::CampaignPlan& stored,
                                         const store::CampaignPlan& sweep) {
    std::map<std::string, MixedSetting> found;
    std::map<std::string, std::set<std::string>> others;
    for (const auto& p : sweep.points) {
        if (stored.find(p.label) != nullptr) continue;  // only new points can mix
        const auto mine = scene_values(p.scene);
        const auto my_labels = label_settings(p.label);
        for (const auto& q : stored.points) {
            const auto theirs = scene_values(q.scene);
            const auto their_labels = label_settings(q.label);
            std::set<std::string> told;  // label settings that differ between p and q
            for (const auto& [k, v] : my_labels)
                if (value_or_absent(their_labels, k) != v) told.insert(k);
            for (const auto& [k, v] : their_labels)
                if (value_or_absent(my_labels, k) != v) told.insert(k);
            std::set<std::string> names;
            for (const auto& [k, v] : mine)
                names.insert(k);
            for (const auto& [k, v] : theirs)
                names.insert(k);
            for (const auto& k : names) {
                if (k == "hopper.outlet_m") continue;  // D is in every label
                const std::string a = value_or_absent(mine, k), b = value_or_absent(theirs, k);
                if (a == b) continue;
                bool is_told = false;
                for (const auto& s : told)
                    is_told = is_told || explains(s, k);
                if (is_told) continue;
                auto [it, fresh] = found.try_emplace(k, MixedSetting{k, a, {}, q.label});
                (void)fresh;
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
        std::string values;
        for (const auto& v : m.store_values)
            values += (values.empty() ? "" : ", ") + v;
        s += "\n    " + m.name + " = " + m.sweep_value + " in this sweep, " + values +
             " in the store (point '" + m.store_point + "')";
    }
    return s;
}

}  // namespace hopper::campaign
