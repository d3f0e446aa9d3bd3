#pragma once
// `campaign cite STORE [--bibtex | --text]`: what to cite for a store (as LAMMPS writes
// log.cite): hopper itself, the published study and experiment it follows, and the models and
// methods the store's points used (contact laws, integrator, random generator, statistics,
// fields), from one table of references (cite.cpp) written as plain text and BibTeX.

#include <ostream>
#include <string>
#include <vector>

#include "hopper/engine/params.hpp"

namespace hopper::cli {

// What a store used, for choosing its references.
struct CiteUse {
    std::string code_version;  // of the newest run ("0.4.0+2f9eccb"); empty without runs
    int points = 0;
    int gear4 = 0, verlet = 0, hertz = 0, fields = 0;  // points that use each
    int unknown = 0;  // points whose physics this version cannot rebuild (left out)
};

CiteUse cite_use(const std::vector<engine::SceneParams>& scenes);

// The keys of the references that apply, in the table's order.
std::vector<std::string> cited_keys(const CiteUse& use);

// The references as plain text (one paragraph each, with why it applies) and/or BibTeX.
void write_citations(std::ostream& os, const CiteUse& use, bool text, bool bibtex);

// What the store at `path` used (its points' physics, its newest run's code version);
// `campaign_name`, when given, receives the store's campaign name.
CiteUse store_cite_use(const std::string& path, std::string* campaign_name = nullptr);

// The one line `analyze` ends with: the cite command for the store and the references' keys.
void write_cite_line(std::ostream& os, const std::string& path, const CiteUse& use);

void print_cite_help(std::ostream& os);
int cite_command(const std::vector<std::string>& args);

}  // namespace hopper::cli
