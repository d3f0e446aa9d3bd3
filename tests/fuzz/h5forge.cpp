// HDF5 forgeries for the store cases: valid HDF5 files that are not what the store wrote. Uses
// the HDF5 C API directly (the store's own wrapper is private to the store layer).

#include <hdf5.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz.hpp"

namespace hopper::fuzz {

namespace {

[[noreturn]] void forge_failed(const std::string& what) {
    H5Eclear2(H5E_DEFAULT);
    throw std::runtime_error("fuzz_inputs forge: " + what);
}

hid_t ok(hid_t id, const std::string& what) {
    if (id < 0) forge_failed(what);
    return id;
}

// An owned identifier.
struct Id {
    hid_t id = H5I_INVALID_HID;
    Id() = default;
    explicit Id(hid_t i) : id(i) {}
    Id(const Id&) = delete;
    Id& operator=(const Id&) = delete;
    ~Id() {
        if (id >= 0) H5Idec_ref(id);
    }
    operator hid_t() const { return id; }
};

hid_t vlen_string() {
    const hid_t t = ok(H5Tcopy(H5T_C_S1), "string type");
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

// A dataset at `name` under `loc` of `type` with the given dimensions, filled with zeros (or
// "x" for variable-length strings). rank 0 = scalar.
void make_dataset(hid_t loc, const std::string& name, hid_t type, std::vector<hsize_t> dims,
                  bool chunked = false) {
    Id space(
        dims.empty()
            ? ok(H5Screate(H5S_SCALAR), "scalar space")
            : ok(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), "space"));
    Id dcpl(ok(H5Pcreate(H5P_DATASET_CREATE), "dcpl"));
    hsize_t n = 1;
    for (hsize_t d : dims)
        n *= d;
    if (chunked && !dims.empty() && n > 0) {
        std::vector<hsize_t> chunk(dims.size(), 1);
        chunk[0] = dims[0] > 0 ? dims[0] : 1;
        H5Pset_chunk(dcpl, static_cast<int>(chunk.size()), chunk.data());
    }
    Id ds(ok(H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT),
             "create dataset " + name));
    if (n == 0) return;
    if (H5Tis_variable_str(type) > 0) {
        std::vector<const char*> v(n, "x");
        H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    } else {
        std::vector<unsigned char> zeros(n * H5Tget_size(type), 0);
        H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data());
    }
}

void set_string_attr(hid_t loc, const std::string& name, const std::string& value) {
    if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
    Id t(vlen_string());
    Id space(ok(H5Screate(H5S_SCALAR), "space"));
    Id a(ok(H5Acreate2(loc, name.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT), "attr " + name));
    const char* p = value.c_str();
    H5Awrite(a, t, &p);
}

template <class T>
void set_num_attr(hid_t loc, const std::string& name, hid_t type, T value) {
    if (H5Aexists(loc, name.c_str()) > 0) H5Adelete(loc, name.c_str());
    Id space(ok(H5Screate(H5S_SCALAR), "space"));
    Id a(ok(H5Acreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), "attr " + name));
    H5Awrite(a, type, &value);
}

// Every dataset and group path of a file (relative to the root), in name order.
struct Objects {
    std::vector<std::string> datasets, groups;
};

herr_t visit(hid_t loc, const char* name, const H5L_info_t* info, void* data) {
    auto* o = static_cast<Objects*>(data);
    if (info->type != H5L_TYPE_HARD) return 0;
    H5O_info_t oi;
    if (H5Oget_info_by_name(loc, name, &oi, H5P_DEFAULT) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return 0;
    }
    if (oi.type == H5O_TYPE_DATASET) o->datasets.emplace_back(name);
    if (oi.type == H5O_TYPE_GROUP) o->groups.emplace_back(name);
    return 0;
}

Objects objects_of(hid_t file) {
    Objects o;
    H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, visit, &o);
    return o;
}

hsize_t length_of(hid_t file, const std::string& path) {
    Id ds(H5Dopen2(file, path.c_str(), H5P_DEFAULT));
    if (ds < 0) return 0;
    Id space(H5Dget_space(ds));
    hsize_t dims[8] = {};
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 8) return 0;
    H5Sget_simple_extent_dims(space, dims, nullptr);
    return dims[0];
}

// A type unlike the dataset's own, of the same length in elements.
hid_t other_type(hid_t file, const std::string& path, Gen& g, std::string& desc) {
    Id ds(ok(H5Dopen2(file, path.c_str(), H5P_DEFAULT), "open " + path));
    Id t(H5Dget_type(ds));
    const H5T_class_t c = H5Tget_class(t);
    std::vector<std::pair<std::string, hid_t>> options;
    if (c != H5T_FLOAT) options.emplace_back("float64", H5Tcopy(H5T_IEEE_F64LE));
    if (c != H5T_STRING) options.emplace_back("variable-length string", vlen_string());
    if (c != H5T_INTEGER) options.emplace_back("int64", H5Tcopy(H5T_STD_I64LE));
    options.emplace_back("int8", H5Tcopy(H5T_STD_I8LE));
    options.emplace_back("uint16", H5Tcopy(H5T_STD_U16LE));
    {
        const hid_t s8 = H5Tcopy(H5T_C_S1);
        H5Tset_size(s8, 8);
        options.emplace_back("fixed string[8]", s8);
    }
    {
        const hid_t e = H5Tenum_create(H5T_NATIVE_INT8);
        signed char v0 = 0, v1 = 5;
        H5Tenum_insert(e, "ZERO", &v0);
        H5Tenum_insert(e, "FIVE", &v1);
        options.emplace_back("enum {ZERO, FIVE}", e);
    }
    {
        const hid_t cpd = H5Tcreate(H5T_COMPOUND, 16);
        H5Tinsert(cpd, "a", 0, H5T_IEEE_F64LE);
        H5Tinsert(cpd, "b", 8, H5T_STD_I64LE);
        options.emplace_back("compound {a, b}", cpd);
    }
    const std::size_t pick = g.below(options.size());
    for (std::size_t i = 0; i < options.size(); ++i)
        if (i != pick) H5Tclose(options[i].second);
    desc = options[pick].first;
    return options[pick].second;
}

// Replaces the dataset at `path` by something else; returns what.
std::string replace_dataset(hid_t file, const std::string& path, Gen& g) {
    const hsize_t n = length_of(file, path);
    const int what = static_cast<int>(g.below(9));
    std::string desc;
    hid_t type = H5I_INVALID_HID;
    if (what == 0) type = other_type(file, path, g, desc);
    if (H5Ldelete(file, path.c_str(), H5P_DEFAULT) < 0) forge_failed("delete " + path);
    switch (what) {
        case 0: {
            Id t(type);
            make_dataset(file, path, t, {n}, g.chance(0.5));
            return "/" + path + " rewritten as " + desc;
        }
        case 1: {
            Id t(H5Tcopy(H5T_IEEE_F64LE));
            make_dataset(file, path, t, {n, 2});
            return "/" + path + " rewritten 2-D (" + std::to_string(n) + " x 2)";
        }
        case 2: {
            Id t(H5Tcopy(H5T_STD_I64LE));
            make_dataset(file, path, t, {});
            return "/" + path + " rewritten as a scalar";
        }
        case 3:
            ok(H5Gclose(ok(H5Gcreate2(file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                           "group")),
               "close group");
            return "/" + path + " is a group";
        case 4:
            return "/" + path + " deleted";
        case 5:
            H5Lcreate_soft("/nowhere/at/all", file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT);
            return "/" + path + " is a dangling soft link";
        case 6:
            H5Lcreate_external("no-such-file.h5", "/x", file, path.c_str(), H5P_DEFAULT,
                               H5P_DEFAULT);
            return "/" + path + " is an external link to a missing file";
        case 7:
            H5Lcreate_soft("/", file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT);
            return "/" + path + " is a soft link to the root group";
        default: {
            Id t(H5Tcopy(H5T_STD_I64LE));
            const hsize_t m = n > 0 && g.chance(0.5) ? n - 1 : n + 1 + g.below(5);
            make_dataset(file, path, t, {m});
            return "/" + path + " rewritten as int64 of length " + std::to_string(m) + " (was " +
                   std::to_string(n) + ")";
        }
    }
}

}  // namespace

void write_unrelated_hdf5(const fs::path& path, Gen& g) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    Id file(ok(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create"));
    Id grp(ok(H5Gcreate2(file, "data", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "group"));
    Id f64(H5Tcopy(H5T_IEEE_F64LE));
    make_dataset(grp, "matrix", f64, {4, 3});
    Id i32(H5Tcopy(H5T_STD_I32LE));
    make_dataset(file, "counts", i32, {static_cast<hsize_t>(g.range(0, 100))});
    if (g.chance(0.5)) set_string_attr(file, "format", "some other format");
    if (g.chance(0.3)) set_num_attr<long long>(file, "format_version", H5T_NATIVE_LLONG, 1);
    if (g.chance(0.3)) set_num_attr<double>(file, "format", H5T_NATIVE_DOUBLE, 1.0);
}

void write_lookalike_hdf5(const fs::path& path, const fs::path& model, Gen& g) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    Objects objs;
    struct RootAttrs {
        std::string format;
        long long version = 1, consistent = 1, stored = 0;
        unsigned long long token = 0, journal_bytes = 0;
    } attrs;
    std::vector<std::pair<std::string, hsize_t>> lengths;
    {
        Id m(ok(H5Fopen(model.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open model"));
        objs = objects_of(m);
        for (const auto& d : objs.datasets)
            lengths.emplace_back(d, length_of(m, d));
        auto read_num = [&](const char* name, hid_t mem, void* out) {
            if (H5Aexists(m, name) <= 0) return;
            Id a(H5Aopen(m, name, H5P_DEFAULT));
            H5Aread(a, mem, out);
        };
        read_num("format_version", H5T_NATIVE_LLONG, &attrs.version);
        read_num("consistent", H5T_NATIVE_LLONG, &attrs.consistent);
        read_num("realizations_stored", H5T_NATIVE_LLONG, &attrs.stored);
        read_num("sync_token", H5T_NATIVE_ULLONG, &attrs.token);
        read_num("journal_bytes", H5T_NATIVE_ULLONG, &attrs.journal_bytes);
        H5Eclear2(H5E_DEFAULT);
    }
    Id file(ok(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "create"));
    set_string_attr(file, "format", "hopper campaign store");
    set_num_attr<long long>(file, "format_version", H5T_NATIVE_LLONG, attrs.version);
    set_num_attr<long long>(file, "consistent", H5T_NATIVE_LLONG, attrs.consistent);
    set_num_attr<long long>(file, "realizations_stored", H5T_NATIVE_LLONG, attrs.stored);
    set_num_attr<unsigned long long>(file, "sync_token", H5T_NATIVE_ULLONG, attrs.token);
    set_num_attr<unsigned long long>(file, "journal_bytes", H5T_NATIVE_ULLONG, attrs.journal_bytes);
    for (const auto& grp : objs.groups)
        H5Gclose(ok(H5Gcreate2(file, grp.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                    "group " + grp));
    // Every dataset of the model, each with a type, shape or length of its own choosing.
    for (const auto& [name, n] : lengths) {
        const int what = static_cast<int>(g.below(6));
        Id f64(H5Tcopy(H5T_IEEE_F64LE)), i64(H5Tcopy(H5T_STD_I64LE)), s(vlen_string());
        switch (what) {
            case 0:
                make_dataset(file, name, f64, {n}, true);
                break;
            case 1:
                make_dataset(file, name, i64, {n + g.below(3)}, true);
                break;
            case 2:
                make_dataset(file, name, s, {n});
                break;
            case 3:
                make_dataset(file, name, f64, {n, 3});
                break;
            case 4:
                make_dataset(file, name, i64, {});
                break;
            default:
                break;  // missing
        }
    }
}

std::string mutate_store_schema(const fs::path& path, Gen& g) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    Id file(ok(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open " + path.string()));
    const Objects objs = objects_of(file);
    if (objs.datasets.empty()) forge_failed("no datasets in " + path.string());
    const int what = static_cast<int>(g.below(6));
    if (what == 0 || what == 1) {
        // Prefer what the readers touch: /realizations, /ragged, /points/label.
        std::vector<std::string> hot;
        for (const auto& d : objs.datasets)
            if (d.rfind("realizations", 0) == 0 || d.rfind("ragged", 0) == 0 || d == "points/label")
                hot.push_back(d);
        const auto& pool = hot.empty() || g.chance(0.3) ? objs.datasets : hot;
        return replace_dataset(file, g.pick(pool), g);
    }
    if (what == 2) {
        // Values out of range in an index or enum column.
        static const std::vector<std::string> columns = {"realizations/point",
                                                         "realizations/survival_start",
                                                         "realizations/survival_length",
                                                         "realizations/exit_start",
                                                         "realizations/exit_length",
                                                         "realizations/event_start",
                                                         "realizations/status",
                                                         "ragged/event_kind",
                                                         "tasks/row",
                                                         "tasks/point",
                                                         "realizations/curve_length",
                                                         "realizations/jam_start"};
        const std::string col = g.pick(columns);
        Id ds(H5Dopen2(file, col.c_str(), H5P_DEFAULT));
        if (ds < 0) return "no /" + col + " to change";
        const hsize_t n = length_of(file, col);
        if (n == 0) return "/" + col + " is empty";
        static const std::vector<long long> values = {
            -1, -2147483648LL, 2147483647, 1LL << 40, -(1LL << 62), 127, -128, 100000};
        const long long v = g.pick(values);
        const hsize_t row = g.below(n);
        Id space(H5Dget_space(ds));
        const hsize_t start[1] = {row}, count[1] = {1};
        H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
        Id mem(H5Screate_simple(1, count, nullptr));
        // An enum column: written with its own file type there is no conversion, so the raw
        // byte goes in whether or not it names a member.
        Id ftype(H5Dget_type(ds));
        if (H5Tget_class(ftype) == H5T_ENUM) {
            const signed char b = static_cast<signed char>(v);
            H5Dwrite(ds, ftype, mem, space, H5P_DEFAULT, &b);
        } else {
            H5Dwrite(ds, H5T_NATIVE_LLONG, mem, space, H5P_DEFAULT, &v);
        }
        H5Eclear2(H5E_DEFAULT);
        return "/" + col + "[" + std::to_string(row) + "] = " + std::to_string(v);
    }
    if (what == 3) {
        // The extent of a column: shorter, longer, empty or absurdly long (unallocated chunks).
        const std::string d = g.pick(objs.datasets);
        Id ds(ok(H5Dopen2(file, d.c_str(), H5P_DEFAULT), "open " + d));
        const hsize_t n = length_of(file, d);
        static const std::vector<hsize_t> huge = {1ull << 32, 1ull << 40, 1ull << 50};
        hsize_t m = 0;
        switch (g.below(4)) {
            case 0:
                m = n > 0 ? n - 1 : 0;
                break;
            case 1:
                m = n + 1 + g.below(100);
                break;
            case 2:
                m = 0;
                break;
            default:
                m = g.pick(huge);
        }
        const hsize_t size[1] = {m};
        if (H5Dset_extent(ds, size) < 0) {
            H5Eclear2(H5E_DEFAULT);
            return "/" + d + " cannot be resized (not chunked); unchanged";
        }
        return "/" + d + " resized from " + std::to_string(n) + " to " + std::to_string(m);
    }
    if (what == 4) {
        // A root attribute of the wrong type or value, or missing.
        switch (g.below(10)) {
            case 0:
                set_num_attr<long long>(file, "format_version", H5T_NATIVE_LLONG, 2);
                return "format_version = 2";
            case 1:
                set_string_attr(file, "format_version", "1");
                return "format_version = \"1\" (a string)";
            case 2:
                set_num_attr<long long>(file, "consistent", H5T_NATIVE_LLONG, 2);
                return "consistent = 2";
            case 3:
                set_string_attr(file, "sync_token", "0xdeadbeef");
                return "sync_token is a string";
            case 4:
                set_num_attr<double>(file, "journal_bytes", H5T_NATIVE_DOUBLE, -1.5);
                return "journal_bytes = -1.5 (a float)";
            case 5:
                H5Adelete(file, "format");
                return "no format attribute";
            case 6:
                set_string_attr(file, "format", "hopper campaign store ");
                return "format with a trailing space";
            case 7:
                set_num_attr<double>(file, "format", H5T_NATIVE_DOUBLE, 1.0);
                return "format is a number";
            case 8:
                set_num_attr<unsigned long long>(file, "journal_bytes", H5T_NATIVE_ULLONG, ~0ull);
                return "journal_bytes = 2^64 - 1";
            default:
                set_num_attr<long long>(file, "format_version", H5T_NATIVE_LLONG, -1);
                return "format_version = -1";
        }
    }
    // A group renamed or deleted.
    const std::string grp = g.pick(objs.groups.empty() ? objs.datasets : objs.groups);
    if (g.chance(0.5)) {
        H5Lmove(file, grp.c_str(), file, (grp + "_renamed").c_str(), H5P_DEFAULT, H5P_DEFAULT);
        H5Eclear2(H5E_DEFAULT);
        return "/" + grp + " renamed";
    }
    H5Ldelete(file, grp.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    return "/" + grp + " deleted";
}

}  // namespace hopper::fuzz
