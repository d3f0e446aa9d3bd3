#pragma once
// `campaign merge A.h5 B.h5 ... --store C.h5`: stores of one campaign (halves of its points run on
// two machines, or a copy resumed elsewhere) joined into a new store; store::merge_stores does
// the work (docs/store.md, "Merging stores"), this prints what it did.

#include <ostream>
#include <string>
#include <vector>

namespace hopper::cli {

void print_merge_help(std::ostream& os);
int merge_command(const std::vector<std::string>& args, const std::string& command_line);

}  // namespace hopper::cli
