#include "cli/parse.hpp"

#include "config/key_table.hpp"  // detail::suggestion, the sweep keys' "did you mean"
#include "hopper/core/error.hpp"

namespace po = boost::program_options;

namespace hopper::cli {

po::variables_map parse_command(const std::vector<std::string>& args,
                                po::options_description options, const char* positional_name) {
    options.add_options()(positional_name, po::value<std::vector<std::string>>());
    po::positional_options_description positional;
    positional.add(positional_name, -1);
    po::variables_map vm;
    try {
        po::store(po::command_line_parser(args)
                      .options(options)
                      .positional(positional)
                      .style(po::command_line_style::default_style &
                             ~po::command_line_style::allow_guessing)
                      .run(),
                  vm);
    } catch (const po::unknown_option& e) {
        // "--thread": the closest option, as a misspelt sweep key gets (issue 43, item 10).
        std::vector<std::string> names;
        for (const auto& o : options.options())
            if (!o->long_name().empty() && o->long_name() != positional_name)
                names.push_back("--" + o->long_name());
        throw po::error(std::string(e.what()) +
                        config::detail::suggestion(e.get_option_name(), names));
    }
    po::notify(vm);
    return vm;
}

std::string single_positional(const po::variables_map& vm, const char* name,
                              const std::string& what, const std::string& placeholder) {
    const auto values =
        vm.count(name) ? vm[name].as<std::vector<std::string>>() : std::vector<std::string>{};
    if (values.empty()) throw core::ConfigError("missing the " + what + " (" + placeholder + ")");
    if (values.size() > 1)
        throw core::ConfigError("expected one " + what + ", got " + std::to_string(values.size()) +
                                ": '" + values[0] + "', '" + values[1] + "'" +
                                (values.size() > 2 ? ", ..." : ""));
    return values[0];
}

}  // namespace hopper::cli
