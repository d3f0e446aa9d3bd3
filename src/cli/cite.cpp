// `campaign cite STORE`: the references for what a store used, from the one table below, as
// plain text and BibTeX (cite.hpp). A reference is listed when its condition holds for the
// store: always (hopper, the published study and experiment, the contact model, the random
// generator, the statistics `campaign analyze` computes) or when some point uses the model
// (Hertz contacts, the Gear or Verlet integrator, fields).
#include "cli/cite.hpp"

#include <boost/program_options.hpp>
#include <functional>
#include <iostream>
#include <optional>

#include "cli/parse.hpp"
#include "hopper/campaign/stored_scenes.hpp"
#include "hopper/store/store.hpp"

namespace po = boost::program_options;

namespace hopper::cli {

namespace {

struct Reference {
    const char* key;
    const char* type;     // BibTeX entry type: article, book, techreport, misc
    const char* authors;  // BibTeX form: "Last, First and Last, First"
    const char* title;
    const char* venue;  // journal, publisher (books) or institution (reports)
    const char* volume;
    const char* number;
    const char* pages;
    const char* year;
    const char* doi;
    const char* note;                          // edition, address, report number
    const char* why;                           // what of the store it stands for
    std::function<bool(const CiteUse&)> used;  // whether the store used it
};

bool always(const CiteUse&) {
    return true;
}

// The one table of references. Add a model's reference here with the condition that selects it.
const std::vector<Reference>& references() {
    static const std::vector<Reference> table = {
        {"hopper", "misc", "{the hopper authors}",
         "hopper: ensembles of {2D} granular hopper-discharge {DEM} simulations and their clogging "
         "statistics",
         "", "", "", "", "2026", "", "software, BSD-3-Clause (CITATION.cff)",
         "the code that ran the store's realizations", always},
        {"kondic2014", "article", "Kondic, Lou", "Simulations of two dimensional hopper flow",
         "Granular Matter", "16", "", "235--242", "2014", "", "",
         "the published study whose model and protocol hopper implements", always},
        {"tang2011", "article", "Tang, Junyao and Behringer, Robert P.",
         "How granular materials jam in a hopper", "Chaos", "21", "4", "041107", "2011",
         "10.1063/1.3669495", "", "the experiment the published study models", always},
        {"cundall1979", "article", "Cundall, Peter A. and Strack, Otto D. L.",
         "A discrete numerical model for granular assemblies", "G{\\'e}otechnique", "29", "1",
         "47--65", "1979", "", "",
         "the discrete element method and its tangential spring with Coulomb friction", always},
        {"hertz1882", "article", "Hertz, Heinrich",
         "{\\\"U}ber die {B}er{\\\"u}hrung fester elastischer {K}{\\\"o}rper",
         "Journal f{\\\"u}r die reine und angewandte Mathematik", "92", "", "156--171", "1882", "",
         "", "the Hertzian normal contact law (material.normal_law = hertz)",
         [](const CiteUse& u) { return u.hertz > 0; }},
        {"gear1971", "book", "Gear, C. William",
         "Numerical Initial Value Problems in Ordinary Differential Equations", "Prentice-Hall", "",
         "", "", "1971", "", "Englewood Cliffs, NJ",
         "the fourth-order Gear predictor-corrector (integrator.scheme = gear4)",
         [](const CiteUse& u) { return u.gear4 > 0; }},
        {"swope1982", "article",
         "Swope, William C. and Andersen, Hans C. and Berens, Peter H. and Wilson, Kent R.",
         "A computer simulation method for the calculation of equilibrium constants for the "
         "formation of physical clusters of molecules: Application to small water clusters",
         "The Journal of Chemical Physics", "76", "1", "637--649", "1982", "", "",
         "the velocity Verlet integrator (integrator.scheme = verlet)",
         [](const CiteUse& u) { return u.verlet > 0; }},
        {"blackman2021", "article", "Blackman, David and Vigna, Sebastiano",
         "Scrambled linear pseudorandom number generators",
         "ACM Transactions on Mathematical Software", "47", "4", "36", "2021", "", "",
         "the random generator of the fills and seeds (xoshiro256**)", always},
        {"kaplan1958", "article", "Kaplan, Edward L. and Meier, Paul",
         "Nonparametric estimation from incomplete observations",
         "Journal of the American Statistical Association", "53", "282", "457--481", "1958", "", "",
         "the Kaplan-Meier survival functions (campaign analyze, the survival figure)", always},
        {"lawless2003", "book", "Lawless, Jerald F.",
         "Statistical Models and Methods for Lifetime Data", "Wiley", "", "", "", "2003", "",
         "second edition, Hoboken, NJ",
         "the censored exponential fit of the survival times, tau and its interval", always},
        {"lilliefors1969", "article", "Lilliefors, Hubert W.",
         "On the {K}olmogorov-{S}mirnov test for the exponential distribution with mean unknown",
         "Journal of the American Statistical Association", "64", "325", "387--389", "1969", "", "",
         "the goodness-of-fit test of the exponential law", always},
        {"efron1993", "book", "Efron, Bradley and Tibshirani, Robert J.",
         "An Introduction to the Bootstrap", "Chapman \\& Hall", "", "", "", "1993", "", "New York",
         "the parametric bootstrap of the goodness-of-fit p-value", always},
        {"beverloo1961", "article", "Beverloo, W. A. and Leniger, H. A. and van de Velde, J.",
         "The flow of granular solids through orifices", "Chemical Engineering Science", "15",
         "3--4", "260--269", "1961", "", "", "the Beverloo fit of the flow rate", always},
        {"to2001", "article", "To, Kiwing and Lai, Pik-Yin and Pak, H. K.",
         "Jamming of granular flow in a two-dimensional hopper", "Physical Review Letters", "86",
         "1", "71--74", "2001", "", "",
         "the jam probability per grain and the jam rate against the outlet", always},
        {"zuriguel2005", "article",
         "Zuriguel, Iker and Garcimart{\\'\\i}n, Angel and Maza, Diego and Pugnaloni, Luis A. "
         "and Pastor, J. M.",
         "Jamming during the discharge of granular matter from a silo", "Physical Review E", "71",
         "5", "051303", "2005", "", "",
         "the avalanche sizes and the power-law divergence of <s> at a critical outlet", always},
        {"burnham2002", "book", "Burnham, Kenneth P. and Anderson, David R.",
         "Model Selection and Multimodel Inference", "Springer", "", "", "", "2002", "",
         "second edition, New York",
         "the AIC that chooses between the exponential and power-law fits", always},
        {"welford1962", "article", "Welford, B. P.",
         "Note on a method for calculating corrected sums of squares and products", "Technometrics",
         "4", "3", "419--420", "1962", "", "",
         "the running means and variances of the fields ([fields] enabled)",
         [](const CiteUse& u) { return u.fields > 0; }},
        {"chan1979", "techreport", "Chan, Tony F. and Golub, Gene H. and LeVeque, Randall J.",
         "Updating formulae and a pairwise algorithm for computing sample variances",
         "Department of Computer Science, Stanford University", "", "", "", "1979", "",
         "Technical Report STAN-CS-79-773",
         "the exact merge of the fields' pieces across realizations ([fields] enabled)",
         [](const CiteUse& u) { return u.fields > 0; }},
    };
    return table;
}

// BibTeX's {\"u} and friends, \& and protective braces, as plain UTF-8 text.
std::string plain(std::string s) {
    const std::pair<const char*, const char*> accents[] = {
        {"{\\\"U}", "\xC3\x9C"}, {"{\\\"u}", "\xC3\xBC"},  {"{\\\"o}", "\xC3\xB6"},
        {"{\\'e}", "\xC3\xA9"},  {"{\\'\\i}", "\xC3\xAD"}, {"\\&", "&"},
    };
    for (const auto& [from, to] : accents)
        for (std::size_t at; (at = s.find(from)) != std::string::npos;)
            s.replace(at, std::string(from).size(), to);
    std::string out;  // without braces, "--" (page ranges) as "-"
    for (char c : s)
        if (c != '{' && c != '}' && !(c == '-' && !out.empty() && out.back() == '-')) out += c;
    return out;
}

// "Last, First and Last, First" -> "First Last, First Last and First Last".
std::string plain_authors(const std::string& bib) {
    std::vector<std::string> names;
    for (std::size_t start = 0;;) {
        const std::size_t end = bib.find(" and ", start);
        std::string one = bib.substr(start, end == std::string::npos ? end : end - start);
        const std::size_t comma = one.find(", ");
        if (comma != std::string::npos) one = one.substr(comma + 2) + " " + one.substr(0, comma);
        names.push_back(plain(one));
        if (end == std::string::npos) break;
        start = end + 5;
    }
    std::string out;
    for (std::size_t k = 0; k < names.size(); ++k)
        out += (k == 0 ? "" : k + 1 == names.size() ? " and " : ", ") + names[k];
    return out;
}

std::string plain_text(const Reference& r, const CiteUse& use) {
    const std::string s = r.key;
    std::string t = plain_authors(r.authors) + ", ";
    const std::string type = r.type;
    // (built by appending: GCC 12 warns falsely on "\"" + string)
    if (type == "article") {
        t.append("\"").append(plain(r.title)).append("\", ").append(plain(r.venue));
        t.append(" ").append(r.volume);
        if (*r.number) t.append(" (").append(plain(r.number)).append(")");
        t.append(", ").append(plain(r.pages)).append(" (").append(r.year).append(")");
    } else if (type == "book") {
        t.append(plain(r.title)).append(" (").append(plain(r.venue)).append(", ");
        t.append(r.note).append(", ").append(r.year).append(")");
    } else if (type == "techreport") {
        t.append("\"").append(plain(r.title)).append("\", ").append(r.note).append(", ");
        t.append(plain(r.venue)).append(" (").append(r.year).append(")");
    } else {  // the software
        t += plain(r.title) + (use.code_version.empty() ? "" : ", version " + use.code_version) +
             " (" + r.note + ")";
    }
    if (*r.doi) t += std::string(", doi:") + r.doi;
    return t + ".";
}

void bibtex(std::ostream& os, const Reference& r, const CiteUse& use) {
    os << '@' << r.type << '{' << r.key << ",\n";
    const auto field = [&os](const char* name, const std::string& value) {
        if (!value.empty()) os << "  " << name << " = {" << value << "},\n";
    };
    const std::string type = r.type;
    field("author", r.authors);
    field("title", r.title);
    field(type == "article"      ? "journal"
          : type == "techreport" ? "institution"
                                 : "publisher",
          type == "misc" ? "" : r.venue);
    field("volume", r.volume);
    field("number", r.number);
    field("pages", r.pages);
    field("year", r.year);
    field("doi", r.doi);
    const std::string note = r.note;
    if (type == "book") {  // note: "[second edition, ]ADDRESS"
        const bool second = note.rfind("second edition, ", 0) == 0;
        field("edition", second ? "2" : "");
        field("address", second ? note.substr(16) : note);
    } else if (type == "techreport") {  // note: "Technical Report NUMBER"
        field("type", "Technical Report");
        field("number", note.substr(std::string("Technical Report ").size()));
    } else if (type == "misc") {
        field("note", note + (use.code_version.empty() ? "" : ", version " + use.code_version));
    }
    os << "}\n";
}

}  // namespace

CiteUse cite_use(const std::vector<engine::SceneParams>& scenes) {
    CiteUse u;
    for (const auto& p : scenes) {
        ++u.points;
        u.gear4 += p.integrator.scheme == engine::Scheme::gear4;
        u.verlet += p.integrator.scheme == engine::Scheme::verlet;
        u.hertz += p.material.normal_law == engine::NormalLaw::hertz;
        u.fields += p.fields.enabled;
    }
    return u;
}

std::vector<std::string> cited_keys(const CiteUse& use) {
    std::vector<std::string> keys;
    for (const auto& r : references())
        if (r.used(use)) keys.emplace_back(r.key);
    return keys;
}

void write_citations(std::ostream& os, const CiteUse& use, bool text, bool bib) {
    if (text) {
        for (const auto& r : references()) {
            if (!r.used(use)) continue;
            os << "[" << r.key << "] " << plain_text(r, use) << "\n    for " << r.why << "\n";
        }
    }
    if (text && bib) os << '\n';
    if (bib) {
        bool first = true;
        for (const auto& r : references()) {
            if (!r.used(use)) continue;
            if (!first) os << '\n';
            first = false;
            bibtex(os, r, use);
        }
    }
}

namespace {

po::options_description cite_options() {
    po::options_description d("cite options");
    d.add_options()                                                    //
        ("bibtex", po::bool_switch(), "only the BibTeX entries")       //
        ("text", po::bool_switch(), "only the plain-text references")  //
        ("help,h", "show this help");
    return d;
}

}  // namespace

void print_cite_help(std::ostream& os) {
    os << "usage: campaign cite STORE.h5 [--bibtex | --text]\n\n"
          "The references for what the store used: hopper (with the store's code version), the\n"
          "published study and experiment it follows, the contact model, the integrator and\n"
          "contact law its points used, the random generator, the statistics of `campaign\n"
          "analyze` and, with fields, their merging. Plain text (each with what it stands for),\n"
          "then BibTeX. Read from the store's journal; safe while a run writes it.\n\n"
          "exit codes: 0 listed, 1 no store or not a hopper store, 2 bad command line\n\n"
       << cite_options();
}

CiteUse store_cite_use(const std::string& path, std::string* campaign_name) {
    const store::StoreStatus st = store::read_status(path);
    std::vector<engine::SceneParams> scenes;
    int unknown = 0;
    for (const auto& s : campaign::point_scenes(st.plan, st.runs)) {
        if (s)
            scenes.push_back(*s);
        else
            ++unknown;
    }
    CiteUse use = cite_use(scenes);
    use.unknown = unknown;
    if (!st.runs.empty()) use.code_version = st.runs.back().info.code_version;
    if (campaign_name) *campaign_name = st.campaign_name;
    return use;
}

void write_cite_line(std::ostream& os, const std::string& path, const CiteUse& use) {
    const std::vector<std::string> keys = cited_keys(use);
    os << "to cite: `campaign cite " << path << "` lists " << keys.size()
       << " references as text and BibTeX (";
    for (std::size_t k = 0; k < keys.size(); ++k)
        os << (k ? ", " : "") << keys[k];
    os << ")\n";
}

int cite_command(const std::vector<std::string>& args) {
    const po::variables_map vm = parse_command(args, cite_options(), "store");
    if (vm.count("help")) {
        print_cite_help(std::cout);
        return 0;
    }
    const std::string path = single_positional(vm, "store", "store", "STORE.h5");
    const bool only_bib = vm["bibtex"].as<bool>(), only_text = vm["text"].as<bool>();
    if (only_bib && only_text) throw po::error("--bibtex and --text exclude each other");
    std::string campaign_name;
    const CiteUse use = store_cite_use(path, &campaign_name);
    const int unknown = use.unknown;
    if (!only_bib) {
        std::cout << "References for " << path << " (campaign '" << campaign_name << "', "
                  << use.points << " point(s)";
        if (unknown)
            std::cout << "; " << unknown
                      << " point(s) whose physics this version cannot rebuild are left out";
        std::cout << "):\n\n";
    }
    write_citations(std::cout, use, !only_bib, !only_text);
    return 0;
}

}  // namespace hopper::cli
