#include "cli/parse.hpp"

namespace po = boost::program_options;

namespace hopper::cli {

po::variables_map parse_command(const std::vector<std::string>& args,
                                po::options_description options, const char* positional_name) {
    options.add_options()(positional_name, po::value<std::vector<std::string>>());
    po::positional_options_description positional;
    positional.add(positional_name, -1);
    po::variables_map vm;
    po::store(
        po::command_line_parser(args)
            .options(options)
            .positional(positional)
            .style(po::command_line_style::default_style & ~po::command_line_style::allow_guessing)
            .run(),
        vm);
    po::notify(vm);
    return vm;
}

}  // namespace hopper::cli
