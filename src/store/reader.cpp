// Reading a store file: what it says about itself (inspect) and every stored realization.

#include "hopper/core/error.hpp"
#include "layout.hpp"
#include "schema.hpp"

namespace hopper::store::layout {

namespace fs = std::filesystem;

Inspection inspect(const fs::path& path) {
    const h5::QuietErrors quiet;
    Inspection in;
    std::error_code ec;
    if (!fs::exists(path, ec)) {
        in.problem = "missing";
        return in;
    }
    if (!h5::is_hdf5(path)) {
        in.problem = "not an HDF5 file";
        in.foreign = true;
        return in;
    }
    try {
        h5::Id file = h5::open_file(path, false);
        const auto format = h5::get_string_attr(file, "format");
        if (!format || *format != format_name) {
            in.foreign = true;
            in.problem = "an HDF5 file without the attribute format = '" +
                         std::string(format_name) + "' (not a hopper store)";
            return in;
        }
        const auto version = h5::get_int_attr(file, "format_version");
        if (!version || *version != format_version) {
            in.problem = "store format version " +
                         (version ? std::to_string(*version) : std::string("?")) +
                         ", this build writes version " + std::to_string(format_version);
            return in;
        }
        in.consistent = h5::get_int_attr(file, "consistent").value_or(0) == 1;
        in.token = h5::get_u64_attr(file, "sync_token").value_or(0);
        in.journal_bytes = h5::get_u64_attr(file, "journal_bytes").value_or(0);
        h5::Id g = h5::open_group(file, "realizations");
        h5::Id ds = h5::open_dataset(g, "point");
        in.rows = static_cast<std::int64_t>(h5::length(ds));
        in.readable = true;
    } catch (const core::StoreError& e) {
        in.problem = e.what();
    }
    return in;
}

std::vector<StoredRealization> read_realizations(const fs::path& path) {
    const h5::QuietErrors quiet;
    const Inspection in = inspect(path);
    if (!in.readable)
        throw core::StoreError("cannot read store '" + path.string() + "': " + in.problem);
    h5::Id file = h5::open_file(path, false);
    Types types;
    const std::vector<std::string> labels = h5::read_strings(
        h5::open_dataset(h5::open_group(file, "points"), "label"), "/points/label");
    h5::Id g_real = h5::open_group(file, "realizations");
    h5::Id g_diag = h5::open_group(g_real, "diagnostics");
    h5::Id g_ragged = h5::open_group(file, "ragged");
    std::vector<Buffer> bufs;
    // Columns added later (issue 13: avalanche sizes, arches) are absent from older files:
    // their realizations are read without them.
    std::vector<bool> present;
    for (const ColumnDef& d : columns()) {
        const h5::Id& g = d.group == "realizations" ? g_real
                          : d.group == "ragged"     ? g_ragged
                                                    : g_diag;
        present.push_back(h5::exists(g, d.name));
        bufs.push_back(present.back() ? read_buffer(h5::open_dataset(g, d.name), types, d.kind,
                                                    "/" + d.group + "/" + d.name)
                                      : make_buffer(d.kind));
    }
    std::vector<std::vector<std::int64_t>> starts;
    std::vector<std::vector<std::int32_t>> lengths;
    std::vector<bool> family_present;
    for (const RaggedFamily& f : families()) {
        const std::string start = std::string(f.name) + "_start";
        family_present.push_back(h5::exists(g_real, start));
        if (!family_present.back()) {
            starts.emplace_back();
            lengths.emplace_back();
            continue;
        }
        starts.push_back(as<std::int64_t>(
            read_buffer(h5::open_dataset(g_real, start), types, Kind::i64, f.name)));
        lengths.push_back(as<std::int32_t>(read_buffer(
            h5::open_dataset(g_real, std::string(f.name) + "_length"), types, Kind::i32, f.name)));
    }
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (columns()[i].family >= 0 &&
            !family_present[static_cast<std::size_t>(columns()[i].family)])
            present[i] = false;
    const std::size_t rows = size_of(bufs.front());
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (present[i] && columns()[i].family < 0 && size_of(bufs[i]) != rows)
            throw core::StoreError("store '" + path.string() + "': /realizations/" +
                                   columns()[i].name + " has " + std::to_string(size_of(bufs[i])) +
                                   " rows, expected " + std::to_string(rows));
    for (std::size_t f = 0; f < families().size(); ++f)
        if (family_present[f] && (starts[f].size() != rows || lengths[f].size() != rows))
            throw core::StoreError("store '" + path.string() +
                                   "': a ragged index has the wrong length");
    std::vector<StoredRealization> out(rows);
    for (std::size_t row = 0; row < rows; ++row) {
        StoredRealization& o = out[row];
        for (std::size_t i = 0; i < columns().size(); ++i) {
            const ColumnDef& d = columns()[i];
            if (!present[i]) continue;
            if (d.family < 0) {
                d.pull(o, bufs[i], row, 1);
            } else {
                const auto f = static_cast<std::size_t>(d.family);
                const std::int64_t start = starts[f][row];
                const std::int32_t n = lengths[f][row];
                if (start < 0 || n < 0)
                    throw core::StoreError("negative ragged index in the store");
                d.pull(o, bufs[i], static_cast<std::size_t>(start), static_cast<std::size_t>(n));
            }
        }
        if (o.point < 0 || static_cast<std::size_t>(o.point) >= labels.size())
            throw core::StoreError("store '" + path.string() + "': row " + std::to_string(row) +
                                   " names point " + std::to_string(o.point) + " of " +
                                   std::to_string(labels.size()));
        o.label = labels[static_cast<std::size_t>(o.point)];
        o.record.label = o.label;
    }
    if (h5::exists(file, fields_group_name)) {
        h5::Id g_fields = h5::open_group(file, fields_group_name);
        for (std::size_t row = 0; row < rows; ++row) {
            const std::string name = std::to_string(row);
            if (!h5::exists(g_fields, name)) continue;
            out[row].result.fields = read_fields(h5::open_group(g_fields, name),
                                                 "store '" + path.string() + "': /fields/" + name);
        }
    }
    return out;
}

}  // namespace hopper::store::layout
