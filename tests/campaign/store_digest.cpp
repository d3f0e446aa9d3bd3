// store_digest STORE: one line per stored realization, sorted,
//   <label> TAB <realization> TAB <seed> TAB <status> TAB <physics digest>
// where the digest covers every field except the wall-clock measurements, so two runs of the
// same realization give the same line whatever rank or machine ran them. Reads both the HDF5
// file and the journal, and fails (exit 1, message on stderr) unless they hold the same
// realizations, each exactly once.

#include <algorithm>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "hopper/store/codec.hpp"
#include "hopper/store/store.hpp"

namespace {

std::vector<std::string> lines(const std::vector<hopper::store::StoredRealization>& v,
                               const char* source, bool& ok) {
    std::vector<std::string> out;
    std::set<std::pair<std::string, int>> seen;
    for (const auto& s : v) {
        if (!seen.insert({s.label, s.record.realization}).second) {
            std::cerr << "store_digest: " << source << " holds '" << s.label << "' #"
                      << s.record.realization << " more than once\n";
            ok = false;
        }
        out.push_back(s.label + "\t" + std::to_string(s.record.realization) + "\t" +
                      std::to_string(s.record.seed) + "\t" +
                      hopper::engine::to_string(s.result.status) + "\t" +
                      hopper::store::hex64(hopper::store::physics_digest(s.result)));
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: store_digest STORE.h5\n";
        return 2;
    }
    try {
        bool ok = true;
        const auto h5 = lines(hopper::store::read_realizations(argv[1]), "the HDF5 file", ok);
        const auto journal =
            lines(hopper::store::read_journal_realizations(argv[1]), "the journal", ok);
        if (h5 != journal) {
            std::cerr << "store_digest: the HDF5 file (" << h5.size()
                      << " realizations) and the journal (" << journal.size() << ") differ\n";
            ok = false;
        }
        for (const auto& l : h5)
            std::cout << l << '\n';
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "store_digest: " << e.what() << '\n';
        return 1;
    }
}
