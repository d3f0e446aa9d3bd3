// Derived groups (e.g. /analysis) in a store file: see include/hopper/store/analysis.hpp.

#include "hopper/store/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>

#include "h5.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/store.hpp"
#include "layout.hpp"
#include "state.hpp"

namespace fs = std::filesystem;

namespace hopper::store {

namespace {

void check_name(const std::string& name, const std::string& where) {
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
        throw std::invalid_argument("derived group: bad name '" + name + "' in " + where);
}

void validate(const DerivedGroup& g, const std::string& where) {
    check_name(g.name, where);
    const std::string here = where + g.name + "/";
    std::set<std::string> names;
    auto unique = [&](const std::string& n) {
        check_name(n, here);
        if (!names.insert(n).second)
            throw std::invalid_argument("derived group: two members named '" + n + "' in " + here);
    };
    for (const auto& d : g.datasets) {
        unique(d.name);
        if (const auto* v = std::get_if<std::vector<double>>(&d.values))
            for (double x : *v)
                if (!std::isfinite(x))
                    throw std::invalid_argument("derived group: non-finite value in " + here +
                                                d.name + " (write 0 with a has_... flag)");
        if (!d.shape.empty()) {
            std::size_t n = 0;
            std::visit([&](const auto& v) { n = v.size(); }, d.values);
            std::uint64_t product = 1;
            for (std::uint64_t k : d.shape)
                product *= k;
            if (std::holds_alternative<std::vector<std::string>>(d.values) || product != n)
                throw std::invalid_argument("derived group: the shape of " + here + d.name +
                                            " does not match its " + std::to_string(n) + " values");
        }
    }
    for (const auto& [name, v] : g.numbers)
        if (const auto* x = std::get_if<double>(&v); x && !std::isfinite(*x))
            throw std::invalid_argument("derived group: non-finite attribute " + name + " of " +
                                        here);
    for (const auto& s : g.groups) {
        unique(s.name);
        validate(s, here);
    }
}

void write_dataset(const h5::Id& loc, const DerivedDataset& d) {
    const std::string what = "derived dataset '" + d.name + "'";
    h5::hsize n = 0;
    std::visit([&](const auto& v) { n = v.size(); }, d.values);
    const h5::hsize chunk = std::clamp<h5::hsize>(n, 1, 4096);
    const h5::hid f64_file = h5::file_type(h5::Scalar::f64),
                  f64_mem = h5::mem_type(h5::Scalar::f64);
    const h5::hid i64_file = h5::file_type(h5::Scalar::i64),
                  i64_mem = h5::mem_type(h5::Scalar::i64);
    h5::Id ds;
    if (!d.shape.empty()) {  // fixed-size N-D array (numbers only: checked by validate())
        const std::vector<h5::hsize> dims(d.shape.begin(), d.shape.end());
        if (const auto* dv = std::get_if<std::vector<double>>(&d.values)) {
            ds = h5::write_array(loc, d.name, f64_file, f64_mem, dv->data(), dims);
        } else if (const auto* iv = std::get_if<std::vector<std::int64_t>>(&d.values)) {
            ds = h5::write_array(loc, d.name, i64_file, i64_mem, iv->data(), dims);
        } else {
            const auto& bv = std::get<std::vector<bool>>(d.values);
            h5::Id type = h5::bool_type();
            std::vector<std::int8_t> b(bv.begin(), bv.end());
            ds = h5::write_array(loc, d.name, type.get(), type.get(), b.data(), dims);
        }
    } else if (const auto* dv = std::get_if<std::vector<double>>(&d.values)) {
        ds = h5::create_column(loc, d.name, f64_file, chunk);
        h5::write_all(ds, f64_mem, dv->data(), n, what);
    } else if (const auto* iv = std::get_if<std::vector<std::int64_t>>(&d.values)) {
        ds = h5::create_column(loc, d.name, i64_file, chunk);
        h5::write_all(ds, i64_mem, iv->data(), n, what);
    } else if (const auto* bv = std::get_if<std::vector<bool>>(&d.values)) {
        h5::Id type = h5::bool_type();
        ds = h5::create_column(loc, d.name, type.get(), chunk);
        std::vector<std::int8_t> b(bv->begin(), bv->end());
        h5::write_all(ds, type.get(), b.data(), n, what);
    } else {
        const auto& s = std::get<std::vector<std::string>>(d.values);
        h5::Id type = h5::string_type();
        ds = h5::create_column(loc, d.name, type.get(), chunk);
        std::vector<const char*> p;
        p.reserve(s.size());
        for (const auto& x : s)
            p.push_back(x.c_str());
        h5::write_all(ds, type.get(), p.data(), n, what);
    }
    h5::set_attr(ds, "description", d.description);
    if (!std::holds_alternative<std::vector<std::string>>(d.values))
        h5::set_attr(ds, "units", d.units.empty() ? std::string("1") : d.units);
    for (const auto& [k, v] : d.attributes)
        h5::set_attr(ds, k, v);
}

void write_group(const h5::Id& parent, const DerivedGroup& g) {
    h5::Id grp = h5::create_group(parent, g.name);
    for (const auto& [k, v] : g.attributes)
        h5::set_attr(grp, k, v);
    for (const auto& [k, v] : g.numbers)
        std::visit([&, &k = k](auto x) { h5::set_attr(grp, k, x); }, v);
    for (const auto& d : g.datasets)
        write_dataset(grp, d);
    for (const auto& s : g.groups)
        write_group(grp, s);
}

}  // namespace

void write_derived_group(const fs::path& store, const DerivedGroup& group) {
    validate(group, "/");
    const h5::QuietErrors quiet;
    // The journal's lock for the time of the change: no run writes the store meanwhile, and the
    // file's new checksum is recorded in a sync record of its own. A file system without locks
    // is accepted here (analysis does not race runs the way two runs race each other).
    State state;
    JournalScan scan;
    std::optional<Journal> journal;
    try {
        journal.emplace(Journal::open(
            journal_path(store),
            [&](RecordType t, std::uint64_t off, std::span<const std::uint8_t> p) {
                apply_record(state, t, off, p, nullptr);
            },
            scan, JournalOptions{.require_lock = false, .before_link = {}}));
    } catch (const core::StoreError& e) {
        if (std::string(e.what()).find("is in use by another") == std::string::npos) throw;
        throw core::StoreError("'" + store.string() +
                               "' is in use by a `campaign run`; analyze it when the run has "
                               "ended (the analysis is written at the end of every run)");
    }
    const FileCheck file_check = check_closed_file(state, store);
    const layout::Inspection in = file_check == FileCheck::changed || !state.closed_in_step()
                                      ? layout::Inspection{}
                                      : layout::inspect(store);
    if (!state.closed_in_step() || file_check == FileCheck::changed ||
        file_check == FileCheck::other || !in.readable || !in.consistent ||
        in.token != state.last_sync->token || in.journal_bytes != state.last_offset)
        throw core::StoreError(
            "the HDF5 file '" + store.string() + "' is not in step with its journal" +
            (file_check == FileCheck::changed
                 ? std::string(" (it does not match the checksum recorded when it was closed)")
             : in.problem.empty() ? std::string()
                                  : " (" + in.problem + ")") +
            "; run `campaign run` on it once to rebuild it, then analyze again");

    const std::uint64_t at = journal->size();  // where the new sync record goes
    {
        h5::Id file = h5::open_file(store, true);
        // Not consistent while the group is replaced: a kill in between leaves a file the next
        // run rebuilds from the journal instead of one that looks in step. So does a kill
        // before the sync record below (the file names a journal length not yet synced).
        h5::set_attr(file, "consistent", std::int64_t{0});
        h5::flush(file);
        if (h5::exists(file, group.name))
            h5::remove(file, group.name, "cannot delete the previous group '/" + group.name + "'");
        write_group(file, group);
        h5::flush(file);
        h5::set_attr_u64(file, "journal_bytes", at);
        h5::set_attr(file, "consistent", std::int64_t{1});
        h5::close_file(file);
    }
    fsync_path(store);
    SyncRecord sync = *state.last_sync;
    sync.journal_bytes = at;
    sync.file = checksum_file(store);
    journal->append(RecordType::sync, encode(sync));
}

std::vector<std::string> derived_group_members(const fs::path& store, const std::string& name) {
    const h5::QuietErrors quiet;
    h5::Id file = h5::open_file(store, false);
    std::vector<std::string> out;
    if (!h5::exists(file, name)) return out;
    return h5::member_names(h5::open_group(file, name));
}

DerivedDataset read_derived_dataset(const fs::path& store, const std::string& path) {
    const h5::QuietErrors quiet;
    h5::Id file = h5::open_file(store, false);
    if (!h5::exists(file, path))
        throw core::StoreError("'" + store.string() + "' has no dataset '/" + path + "'");
    h5::Id ds = h5::open_dataset(file, path);
    DerivedDataset d;
    d.name = path.substr(path.rfind('/') == std::string::npos ? 0 : path.rfind('/') + 1);
    d.units = h5::get_string_attr(ds, "units").value_or("");
    d.description = h5::get_string_attr(ds, "description").value_or("");
    const std::vector<h5::hsize> dims = h5::dims_of(ds);
    d.shape.assign(dims.begin(), dims.end());
    h5::hsize n = 1;
    for (h5::hsize k : dims)
        n *= k;
    const h5::ValueClass c = h5::value_class(ds);
    const std::string what = "'/" + path + "'";
    if (c == h5::ValueClass::floating) {
        std::vector<double> v(n);
        h5::read_array(ds, h5::mem_type(h5::Scalar::f64), v.data(), what);
        d.values = std::move(v);
    } else if (c == h5::ValueClass::integer) {
        std::vector<std::int64_t> v(n);
        h5::read_array(ds, h5::mem_type(h5::Scalar::i64), v.data(), what);
        d.values = std::move(v);
    } else {
        throw core::StoreError("'/" + path + "' in '" + store.string() + "' is not numeric");
    }
    return d;
}

}  // namespace hopper::store
