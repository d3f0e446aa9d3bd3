#pragma once
// The sweep-file parser (private to the config layer): TOML table -> validated SweepFile. Its
// members live in parser.cpp (scene sections, [sweep], [[points]], the points' scenes) and
// campaign_section.cpp ([campaign]).

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/key_table.hpp"
#include "config/toml_input.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"

namespace hopper::config::detail {

// Limits that keep a campaign's task list (ints, held in memory on every rank) sane.
inline constexpr double max_realizations = 1e6;
inline constexpr std::size_t max_points = 100'000;
inline constexpr long long max_tasks = 10'000'000;

struct Given {
    const KeyDef* def;
    Value value;
};
using Assignments = std::map<std::string, Given, std::less<>>;  // by canonical name

struct PointDraft {
    std::vector<Given> overrides;
    std::optional<int> realizations;
    std::string origin;  // for messages: "[sweep] combination 3", "[[points]] #2 (line 40)"
};

class Parser {
  public:
    Parser(std::string_view text, std::filesystem::path source)
        : text_(text), path_(std::move(source)) {
        file_ = path_.string();
    }

    // The text given to the constructor, parsed; or a table made otherwise (parse_sweep of a
    // tree: the constructor's text is then its TOML text, kept as the provenance).
    SweepFile run();
    SweepFile run(const toml::table& root);

  private:
    [[noreturn]] void fail(const toml::source_region& where, const std::string& msg) const {
        if (where.begin.line == 0) throw core::ConfigError(file_ + ": " + msg);
        throw core::ConfigError(file_ + ":" + std::to_string(where.begin.line) + ":" +
                                std::to_string(where.begin.column) + ": " + msg);
    }
    [[noreturn]] void fail(const std::string& msg) const {
        throw core::ConfigError(file_ + ": " + msg);
    }

    Value read_value(const toml::node& n, const KeyDef& d) const;
    void read_scene_section(std::string_view section, const toml::node& node);
    void read_campaign(const toml::node& node, SweepFile& out) const;
    std::vector<PointDraft> read_sweep(const toml::node& node) const;
    std::vector<PointDraft> read_points(const toml::node& node) const;
    std::optional<int> read_realizations(const toml::node& n, std::string_view name) const;
    // The base values with `overrides` on top.
    Assignments merged(const std::vector<Given>& overrides) const;
    engine::SceneParams build_scene(const std::vector<Given>& overrides,
                                    const std::string& context) const;
    Point make_point(const PointDraft& draft, int default_realizations) const;
    // Every key under its canonical name, as given (the base values with `overrides` on top),
    // else as `scene` has it: Point::parameters.
    std::vector<core::Setting> parameters_of(const std::vector<Given>& overrides,
                                             const engine::SceneParams& scene) const;

    std::string_view text_;
    std::filesystem::path path_;
    std::string file_;
    Assignments base_;  // values given in the scene sections
};

}  // namespace hopper::config::detail
