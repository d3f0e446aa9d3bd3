// [campaign]: name, store, seed, realizations and the target of a campaign that stops when good
// enough (Parser members; parser.hpp).
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <limits>

#include "config/parser.hpp"

namespace hopper::config::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::array<std::string_view, 8> campaign_keys = {"name",
                                                           "store",
                                                           "seed",
                                                           "realizations",
                                                           "target",
                                                           "target_rel_ci",
                                                           "max_realizations",
                                                           "round_realizations"};

}  // namespace

void Parser::read_campaign(const toml::node& node, SweepFile& out) const {
    const auto* tbl = node.as_table();
    if (!tbl) fail(node.source(), "campaign must be a table ([campaign]), got " + type_name(node));
    CampaignSpec& c = out.campaign;
    c.seed = 1;
    c.realizations = 1;
    bool target_given = false;
    for (auto&& [k, v] : *tbl) {
        const std::string key(k.str());
        if (key == "name") {
            auto s = v.as_string();
            if (!s)
                fail(v.source(), "campaign.name = " + node_text(v) +
                                     " has the wrong type: expected a string, got " + type_name(v));
            const std::string& name = s->get();
            const bool chars_ok = std::all_of(name.begin(), name.end(), [](char ch) {
                return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' ||
                       ch == '.';
            });
            if (name.empty() || name.size() > 100 || !chars_ok || name.front() == '.')
                fail(v.source(), "campaign.name = " + node_text(v) +
                                     " is not allowed: use 1 to 100 letters, digits, '-', '_' or "
                                     "'.' (not first), since it names the default store file");
            c.name = name;
        } else if (key == "store") {
            auto s = v.as_string();
            if (!s)
                fail(v.source(), "campaign.store = " + node_text(v) +
                                     " has the wrong type: expected a string (a path), got " +
                                     type_name(v));
            if (s->get().empty()) fail(v.source(), "campaign.store = \"\" is empty: give a path");
            c.store = s->get();
        } else if (key == "seed") {
            auto i = v.as_integer();
            if (!i)
                fail(v.source(), "campaign.seed = " + node_text(v) +
                                     " has the wrong type: expected a non-negative integer, got " +
                                     type_name(v));
            if (i->get() < 0)
                fail(v.source(), "campaign.seed = " + std::to_string(i->get()) +
                                     " is out of range: allowed [0, " +
                                     std::to_string(std::numeric_limits<std::int64_t>::max()) +
                                     "]");
            c.seed = static_cast<std::uint64_t>(i->get());
        } else if (key == "realizations") {
            c.realizations = *read_realizations(v, "campaign.realizations");
        } else if (key == "target") {
            auto s = v.as_string();
            if (!s || (s->get() != "tau" && s->get() != "mean_s"))
                fail(v.source(), "campaign.target = " + node_text(v) +
                                     " is not allowed: use \"tau\" (mean survival time) or "
                                     "\"mean_s\" (mean avalanche size)");
            if (!c.target) c.target.emplace();
            c.target->quantity = s->get() == "tau" ? CampaignTarget::Quantity::tau
                                                   : CampaignTarget::Quantity::mean_s;
            target_given = true;
        } else if (key == "target_rel_ci") {
            if (!v.is_integer() && !v.is_floating_point())
                fail(v.source(), "campaign.target_rel_ci = " + node_text(v) +
                                     " has the wrong type: expected a number (the relative "
                                     "half-width of the 95 % interval, e.g. 0.1), got " +
                                     type_name(v));
            const auto x = v.value<double>();
            if (!x || !(*x > 0.0 && *x <= 1.0))
                fail(v.source(), "campaign.target_rel_ci = " + node_text(v) +
                                     " is out of range: allowed (0, 1] (the relative half-width "
                                     "of the 95 % interval, e.g. 0.1)");
            if (!c.target) c.target.emplace();
            c.target->rel_half_width = *x;
        } else if (key == "max_realizations") {
            if (!c.target) c.target.emplace();
            c.target->max_realizations = *read_realizations(v, "campaign.max_realizations");
        } else if (key == "round_realizations") {
            if (!c.target) c.target.emplace();
            c.target->round = *read_realizations(v, "campaign.round_realizations");
        } else {
            std::vector<std::string> allowed(campaign_keys.begin(), campaign_keys.end());
            fail(k.source(), "unknown key '" + clip(key) + "' in [campaign]; allowed: " +
                                 join(allowed) + suggestion(key, allowed));
        }
    }
    if (c.name.empty()) fail(node.source(), "[campaign] needs a name, e.g. name = \"survival\"");
    if (c.target && !target_given)
        fail(node.source(),
             "[campaign] target_rel_ci, max_realizations and round_realizations need "
             "target = \"tau\" or \"mean_s\" (a campaign that stops when good enough)");
    if (c.target && c.target->round == 0) c.target->round = c.realizations;
    if (c.target && c.target->max_realizations == 0)
        fail(node.source(),
             "[campaign] target needs max_realizations (the most realizations a "
             "point may get), e.g. max_realizations = 100");
    const fs::path dir = path_.parent_path();
    if (c.store.empty()) c.store = c.name + ".h5";
    if (c.store.is_relative()) c.store = dir / c.store;
}

std::optional<int> Parser::read_realizations(const toml::node& n, std::string_view name) const {
    auto i = n.as_integer();
    if (!i)
        fail(n.source(), std::string(name) + " = " + node_text(n) +
                             " has the wrong type: expected an integer, got " + type_name(n));
    if (i->get() < 1 || static_cast<double>(i->get()) > max_realizations)
        fail(n.source(), std::string(name) + " = " + std::to_string(i->get()) +
                             " is out of range: allowed [1, " + message_number(max_realizations) +
                             "]");
    return static_cast<int>(i->get());
}

}  // namespace hopper::config::detail
