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

namespace {

// The /realizations and /ragged columns of a file, read whole. A column or family that an older
// file lacks (issue 13: avalanche sizes, arches) is not present: its realizations are read
// without it.
struct Columns {
    std::vector<Buffer> bufs;  // one per columns()
    std::vector<bool> present;
    std::vector<std::vector<std::int64_t>> starts;  // one per families()
    std::vector<std::vector<std::int32_t>> lengths;
    std::vector<bool> family_present;
};

Columns read_columns(const h5::Id& file, const Types& types) {
    h5::Id g_real = h5::open_group(file, "realizations");
    h5::Id g_diag = h5::open_group(g_real, "diagnostics");
    h5::Id g_ragged = h5::open_group(file, "ragged");
    Columns c;
    for (const ColumnDef& d : columns()) {
        const h5::Id& g = d.group == "realizations" ? g_real
                          : d.group == "ragged"     ? g_ragged
                                                    : g_diag;
        c.present.push_back(h5::exists(g, d.name));
        c.bufs.push_back(c.present.back() ? read_buffer(h5::open_dataset(g, d.name), types, d.kind,
                                                        "/" + d.group + "/" + d.name)
                                          : make_buffer(d.kind));
    }
    for (const RaggedFamily& f : families()) {
        const std::string start = std::string(f.name) + "_start";
        c.family_present.push_back(h5::exists(g_real, start));
        if (!c.family_present.back()) {
            c.starts.emplace_back();
            c.lengths.emplace_back();
            continue;
        }
        c.starts.push_back(as<std::int64_t>(
            read_buffer(h5::open_dataset(g_real, start), types, Kind::i64, f.name)));
        c.lengths.push_back(as<std::int32_t>(read_buffer(
            h5::open_dataset(g_real, std::string(f.name) + "_length"), types, Kind::i32, f.name)));
    }
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (columns()[i].family >= 0 &&
            !c.family_present[static_cast<std::size_t>(columns()[i].family)])
            c.present[i] = false;
    return c;
}

// The number of rows, after checking that every present column and index has them.
std::size_t checked_rows(const Columns& c, const fs::path& path) {
    const std::size_t rows = size_of(c.bufs.front());
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (c.present[i] && columns()[i].family < 0 && size_of(c.bufs[i]) != rows)
            throw core::StoreError(
                "store '" + path.string() + "': /realizations/" + columns()[i].name + " has " +
                std::to_string(size_of(c.bufs[i])) + " rows, expected " + std::to_string(rows));
    for (std::size_t f = 0; f < families().size(); ++f)
        if (c.family_present[f] && (c.starts[f].size() != rows || c.lengths[f].size() != rows))
            throw core::StoreError("store '" + path.string() +
                                   "': a ragged index has the wrong length");
    return rows;
}

// Row `row` of every present column, in columns() order (a pull may rely on those before it).
void pull_row(const Columns& c, std::size_t row, StoredRealization& o) {
    for (std::size_t i = 0; i < columns().size(); ++i) {
        const ColumnDef& d = columns()[i];
        if (!c.present[i]) continue;
        if (d.family < 0) {
            d.pull(o, c.bufs[i], row, 1);
            continue;
        }
        const auto f = static_cast<std::size_t>(d.family);
        const std::int64_t start = c.starts[f][row];
        const std::int32_t n = c.lengths[f][row];
        if (start < 0 || n < 0) throw core::StoreError("negative ragged index in the store");
        d.pull(o, c.bufs[i], static_cast<std::size_t>(start), static_cast<std::size_t>(n));
    }
}

}  // namespace

std::vector<StoredRealization> read_realizations(const fs::path& path) {
    const h5::QuietErrors quiet;
    const Inspection in = inspect(path);
    if (!in.readable)
        throw core::StoreError("cannot read store '" + path.string() + "': " + in.problem);
    h5::Id file = h5::open_file(path, false);
    const Types types;
    const std::vector<std::string> labels = h5::read_strings(
        h5::open_dataset(h5::open_group(file, "points"), "label"), "/points/label");
    const Columns c = read_columns(file, types);
    std::vector<StoredRealization> out(checked_rows(c, path));
    for (std::size_t row = 0; row < out.size(); ++row) {
        StoredRealization& o = out[row];
        pull_row(c, row, o);
        if (o.point < 0 || static_cast<std::size_t>(o.point) >= labels.size())
            throw core::StoreError("store '" + path.string() + "': row " + std::to_string(row) +
                                   " names point " + std::to_string(o.point) + " of " +
                                   std::to_string(labels.size()));
        o.label = labels[static_cast<std::size_t>(o.point)];
        o.record.label = o.label;
    }
    if (!h5::exists(file, fields_group_name)) return out;
    h5::Id g_fields = h5::open_group(file, fields_group_name);
    for (std::size_t row = 0; row < out.size(); ++row) {
        const std::string name = std::to_string(row);
        if (!h5::exists(g_fields, name)) continue;
        out[row].result.fields = read_fields(h5::open_group(g_fields, name),
                                             "store '" + path.string() + "': /fields/" + name);
    }
    return out;
}

}  // namespace hopper::store::layout
