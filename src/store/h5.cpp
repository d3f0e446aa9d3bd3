#include "h5.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <type_traits>

#include "hopper/core/error.hpp"

namespace hopper::store::h5 {

static_assert(std::is_same_v<hid, hid_t>);
static_assert(std::is_same_v<hsize, hsize_t>);
static_assert(invalid_hid == H5I_INVALID_HID);

namespace {

herr_t check_status(herr_t r, std::string_view what);

herr_t collect_error(unsigned n, const H5E_error2_t* e, void* data) {
    auto* out = static_cast<std::vector<std::string>*>(data);
    std::string line = e->func_name ? e->func_name : "?";
    if (e->desc && *e->desc) line += ": " + std::string(e->desc);
    char minor[128] = {};
    if (H5Eget_msg(e->min_num, nullptr, minor, sizeof minor) > 0)
        line += " (" + std::string(minor) + ")";
    out->push_back(line);
    (void)n;
    return 0;
}

[[noreturn]] void fail(std::string_view what) {
    std::vector<std::string> stack;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &stack);
    H5Eclear2(H5E_DEFAULT);
    std::string msg(what);
    if (!stack.empty()) {
        // The innermost entries are the most specific; the outermost names the API call.
        msg += ": " + stack.front();
        if (stack.size() > 1) msg += " <- " + stack.back();
    }
    for (const auto& line : stack)
        if (line.find("unable to lock file") != std::string::npos) {
            msg +=
                ". The file system does not support HDF5's file locks (NFS without a lock "
                "daemon, Lustre without flock): run with HDF5_USE_FILE_LOCKING=FALSE in the "
                "environment (`campaign run --no-file-locking` sets it)";
            break;
        }
    throw core::StoreError(msg);
}

Id make(hid_t id, std::string_view what) {
    return Id(check(id, what));
}

Id scalar_space() {
    return make(H5Screate(H5S_SCALAR), "cannot create a scalar dataspace");
}

void delete_attr_if_present(const Id& loc, const std::string& name) {
    const htri_t e = H5Aexists(loc.get(), name.c_str());
    check(e, "cannot look up attribute '" + name + "'");
    if (e > 0)
        check_status(H5Adelete(loc.get(), name.c_str()), "cannot replace attribute '" + name + "'");
}

template <class T>
std::optional<T> get_numeric_attr(const Id& loc, const std::string& name, hid_t mem_type) {
    if (H5Aexists(loc.get(), name.c_str()) <= 0) return std::nullopt;
    Id a(H5Aopen(loc.get(), name.c_str(), H5P_DEFAULT));
    if (!a) return std::nullopt;
    T v{};
    if (H5Aread(a.get(), mem_type, &v) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    return v;
}

}  // namespace

namespace {

// The guards' shared state: how many live, and the printing they replaced.
struct Quiet {
    std::mutex mutex;
    int depth = 0;
    H5E_auto2_t func = nullptr;
    void* data = nullptr;
};

Quiet& quiet() {
    static Quiet q;
    return q;
}

}  // namespace

QuietErrors::QuietErrors() {
    Quiet& q = quiet();
    const std::lock_guard lock(q.mutex);
    if (q.depth++ > 0) return;
    // No cleanup at exit: every file is closed explicitly, and HDF5 1.10's own cleanup crashes
    // (H5D_close) on a file whose writes failed, e.g. on a full disk (issue 14, item 2). Only
    // effective before the library's first use, so it comes before any other HDF5 call.
    H5dont_atexit();
    H5Eget_auto2(H5E_DEFAULT, &q.func, &q.data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

QuietErrors::~QuietErrors() {
    Quiet& q = quiet();
    const std::lock_guard lock(q.mutex);
    if (--q.depth > 0) return;
    H5Eset_auto2(H5E_DEFAULT, q.func, q.data);
    q.func = nullptr;
    q.data = nullptr;
}

hid check(hid r, std::string_view what) {
    if (r < 0) fail(what);
    return r;
}

namespace {
herr_t check_status(herr_t r, std::string_view what) {
    if (r < 0) fail(what);
    return r;
}
}  // namespace

void Id::reset() noexcept {
    if (id_ >= 0 && H5Iis_valid(id_) > 0) H5Idec_ref(id_);
    id_ = H5I_INVALID_HID;
}

namespace {
Id file_access() {
    Id fapl = make(H5Pcreate(H5P_FILE_ACCESS), "cannot create file access properties");
    // Closing the file closes every object still open in it, so nothing lingers.
    check_status(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG), "cannot set close degree");
    // Each dataset's raw-data chunk cache: 256 kB instead of HDF5's 1 MB. The store appends
    // rows, so a column needs its last, partial chunk cached (2 kB of 256 rows, 64 kB of a
    // ragged column's 8192 values), not the hundreds of full ones the default keeps: with some
    // 100 columns the default held about 75 MB in the master at 10^5 realizations (heaptrack;
    // issue 44). The file's contents do not change.
    check_status(H5Pset_cache(fapl.get(), 0, 521, 256 * 1024, 0.75), "cannot set the chunk cache");
    return fapl;
}
}  // namespace

Id create_file(const std::filesystem::path& path) {
    Id fapl = file_access();
    return make(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                "cannot create HDF5 file '" + path.string() + "'");
}

Id open_file(const std::filesystem::path& path, bool write) {
    Id fapl = file_access();
    return make(H5Fopen(path.c_str(), write ? H5F_ACC_RDWR : H5F_ACC_RDONLY, fapl.get()),
                "cannot open HDF5 file '" + path.string() + "'");
}

void flush(const Id& file) {
    check_status(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "cannot flush the HDF5 file");
}

void close_file(Id& file) {
    if (!file) return;
    check_status(H5Fclose(file.release()), "cannot close the HDF5 file");
}

bool is_hdf5(const std::filesystem::path& path) {
    const htri_t r = H5Fis_hdf5(path.c_str());
    if (r < 0) H5Eclear2(H5E_DEFAULT);
    return r > 0;
}

Id create_group(const Id& loc, const std::string& name) {
    return make(H5Gcreate2(loc.get(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                "cannot create group '" + name + "'");
}

Id open_group(const Id& loc, const std::string& name) {
    return make(H5Gopen2(loc.get(), name.c_str(), H5P_DEFAULT), "cannot open group '" + name + "'");
}

bool exists(const Id& loc, const std::string& name) {
    const htri_t r = H5Lexists(loc.get(), name.c_str(), H5P_DEFAULT);
    if (r < 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
    }
    return r > 0;
}

Id string_type() {
    Id t = make(H5Tcopy(H5T_C_S1), "cannot create a string type");
    check_status(H5Tset_size(t.get(), H5T_VARIABLE), "cannot make a variable-length string type");
    check_status(H5Tset_cset(t.get(), H5T_CSET_UTF8), "cannot set the string character set");
    return t;
}

Id enum_type(const std::vector<std::pair<std::string, int>>& members) {
    Id t = make(H5Tenum_create(H5T_NATIVE_INT8), "cannot create an enum type");
    for (const auto& [name, value] : members) {
        const std::int8_t v = static_cast<std::int8_t>(value);
        check_status(H5Tenum_insert(t.get(), name.c_str(), &v),
                     "cannot add enum member '" + name + "'");
    }
    return t;
}

Id bool_type() {
    return enum_type({{"FALSE", 0}, {"TRUE", 1}});
}

Id create_column(const Id& loc, const std::string& name, hid_t file_type, hsize_t chunk) {
    const hsize_t dims[1] = {0};
    const hsize_t maxdims[1] = {H5S_UNLIMITED};
    Id space = make(H5Screate_simple(1, dims, maxdims), "cannot create a dataspace");
    Id dcpl = make(H5Pcreate(H5P_DATASET_CREATE), "cannot create dataset properties");
    const hsize_t chunks[1] = {chunk};
    check_status(H5Pset_chunk(dcpl.get(), 1, chunks), "cannot set the chunk size");
    const bool is_vlen = H5Tis_variable_str(file_type) > 0;
    if (!is_vlen && H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
        check_status(H5Pset_shuffle(dcpl.get()), "cannot set the shuffle filter");
        check_status(H5Pset_deflate(dcpl.get(), 1), "cannot set the deflate filter");
    }
    return make(H5Dcreate2(loc.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(),
                           H5P_DEFAULT),
                "cannot create dataset '" + name + "'");
}

Id open_dataset(const Id& loc, const std::string& name) {
    return make(H5Dopen2(loc.get(), name.c_str(), H5P_DEFAULT),
                "cannot open dataset '" + name + "'");
}

hsize_t length(const Id& dataset) {
    Id space = make(H5Dget_space(dataset.get()), "cannot get a dataset's dataspace");
    const int rank = check(H5Sget_simple_extent_ndims(space.get()), "cannot get a dataset's rank");
    if (rank != 1)
        throw core::StoreError("a dataset expected to be 1-D has rank " + std::to_string(rank));
    hsize_t dims[1] = {0};
    check(H5Sget_simple_extent_dims(space.get(), dims, nullptr), "cannot get a dataset's size");
    return dims[0];
}

void write_at(const Id& dataset, hid_t mem_type, const void* data, hsize_t offset, hsize_t n,
              std::string_view what) {
    if (n == 0) return;
    const std::string context = "cannot write " + std::string(what);
    if (offset + n > length(dataset)) {
        const hsize_t size[1] = {offset + n};
        check_status(H5Dset_extent(dataset.get(), size), context + " (extend)");
    }
    Id file_space = make(H5Dget_space(dataset.get()), context);
    const hsize_t start[1] = {offset};
    const hsize_t count[1] = {n};
    check_status(
        H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr),
        context + " (select)");
    Id mem_space = make(H5Screate_simple(1, count, nullptr), context);
    check_status(
        H5Dwrite(dataset.get(), mem_type, mem_space.get(), file_space.get(), H5P_DEFAULT, data),
        context);
}

void write_all(const Id& dataset, hid_t mem_type, const void* data, hsize_t n,
               std::string_view what) {
    const hsize_t size[1] = {n};
    check_status(H5Dset_extent(dataset.get(), size), "cannot resize " + std::string(what));
    write_at(dataset, mem_type, data, 0, n, what);
}

void read_all(const Id& dataset, hid_t mem_type, void* data, std::string_view what) {
    if (length(dataset) == 0) return;
    check_status(H5Dread(dataset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
                 "cannot read " + std::string(what));
}

std::vector<std::string> read_strings(const Id& dataset, std::string_view what) {
    const hsize_t n = length(dataset);
    std::vector<std::string> out;
    if (n == 0) return out;
    Id type = string_type();
    std::vector<char*> buf(n, nullptr);
    check_status(H5Dread(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()),
                 "cannot read " + std::string(what));
    out.reserve(n);
    for (char* s : buf)
        out.emplace_back(s ? s : "");
    Id space = make(H5Dget_space(dataset.get()), "cannot get a dataspace");
    H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, buf.data());
    return out;
}

void set_attr(const Id& loc, const std::string& name, const std::string& value) {
    delete_attr_if_present(loc, name);
    Id type = string_type();
    Id space = scalar_space();
    Id a =
        make(H5Acreate2(loc.get(), name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
             "cannot create attribute '" + name + "'");
    const char* p = value.c_str();
    check_status(H5Awrite(a.get(), type.get(), &p), "cannot write attribute '" + name + "'");
}

void set_attr(const Id& loc, const std::string& name, const std::vector<std::string>& values) {
    delete_attr_if_present(loc, name);
    Id type = string_type();
    const hsize_t dims[1] = {values.size()};
    Id space = make(H5Screate_simple(1, dims, nullptr), "cannot create a dataspace");
    Id a =
        make(H5Acreate2(loc.get(), name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
             "cannot create attribute '" + name + "'");
    std::vector<const char*> p;
    for (const auto& v : values)
        p.push_back(v.c_str());
    if (!p.empty())
        check_status(H5Awrite(a.get(), type.get(), p.data()),
                     "cannot write attribute '" + name + "'");
}

namespace {
void set_numeric_attr(const Id& loc, const std::string& name, hid_t type, const void* v) {
    delete_attr_if_present(loc, name);
    Id space = scalar_space();
    Id a = make(H5Acreate2(loc.get(), name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                "cannot create attribute '" + name + "'");
    check_status(H5Awrite(a.get(), type, v), "cannot write attribute '" + name + "'");
}
}  // namespace

void set_attr(const Id& loc, const std::string& name, std::int64_t value) {
    set_numeric_attr(loc, name, H5T_NATIVE_INT64, &value);
}

void set_attr_u64(const Id& loc, const std::string& name, std::uint64_t value) {
    set_numeric_attr(loc, name, H5T_NATIVE_UINT64, &value);
}

void set_attr(const Id& loc, const std::string& name, double value) {
    set_numeric_attr(loc, name, H5T_NATIVE_DOUBLE, &value);
}

std::optional<std::string> get_string_attr(const Id& loc, const std::string& name) {
    if (H5Aexists(loc.get(), name.c_str()) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    Id a(H5Aopen(loc.get(), name.c_str(), H5P_DEFAULT));
    if (!a) return std::nullopt;
    Id ftype(H5Aget_type(a.get()));
    if (!ftype || H5Tget_class(ftype.get()) != H5T_STRING) return std::nullopt;
    if (H5Tis_variable_str(ftype.get()) > 0) {
        Id type = string_type();
        char* p = nullptr;
        if (H5Aread(a.get(), type.get(), &p) < 0) {
            H5Eclear2(H5E_DEFAULT);
            return std::nullopt;
        }
        std::string s = p ? p : "";
        H5free_memory(p);
        return s;
    }
    const std::size_t size = H5Tget_size(ftype.get());
    std::string s(size, '\0');
    if (H5Aread(a.get(), ftype.get(), s.data()) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    s.resize(s.find('\0') == std::string::npos ? s.size() : s.find('\0'));
    return s;
}

std::optional<std::int64_t> get_int_attr(const Id& loc, const std::string& name) {
    return get_numeric_attr<std::int64_t>(loc, name, H5T_NATIVE_INT64);
}

std::optional<std::uint64_t> get_u64_attr(const Id& loc, const std::string& name) {
    return get_numeric_attr<std::uint64_t>(loc, name, H5T_NATIVE_UINT64);
}

void remove(const Id& loc, const std::string& name, std::string_view what) {
    check_status(H5Ldelete(loc.get(), name.c_str(), H5P_DEFAULT), what);
}

std::vector<std::string> member_names(const Id& group) {
    H5G_info_t info;
    check_status(H5Gget_info(group.get(), &info), "cannot list a group");
    std::vector<std::string> out;
    for (hsize_t i = 0; i < info.nlinks; ++i) {
        const ssize_t len = H5Lget_name_by_idx(group.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i,
                                               nullptr, 0, H5P_DEFAULT);
        check(static_cast<hid_t>(len), "cannot read a member name of a group");
        std::string s(static_cast<std::size_t>(len), '\0');
        check(static_cast<hid_t>(H5Lget_name_by_idx(group.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i,
                                                    s.data(), s.size() + 1, H5P_DEFAULT)),
              "cannot read a member name of a group");
        out.push_back(s);
    }
    std::sort(out.begin(), out.end());
    return out;
}

hid file_type(Scalar s) {
    switch (s) {
        case Scalar::i8:
            return H5T_STD_I8LE;
        case Scalar::i32:
            return H5T_STD_I32LE;
        case Scalar::i64:
            return H5T_STD_I64LE;
        case Scalar::u64:
            return H5T_STD_U64LE;
        case Scalar::f64:
            return H5T_IEEE_F64LE;
    }
    return H5T_IEEE_F64LE;
}

hid mem_type(Scalar s) {
    switch (s) {
        case Scalar::i8:
            return H5T_NATIVE_INT8;
        case Scalar::i32:
            return H5T_NATIVE_INT32;
        case Scalar::i64:
            return H5T_NATIVE_INT64;
        case Scalar::u64:
            return H5T_NATIVE_UINT64;
        case Scalar::f64:
            return H5T_NATIVE_DOUBLE;
    }
    return H5T_NATIVE_DOUBLE;
}

ValueClass value_class(const Id& dataset) {
    Id type = make(H5Dget_type(dataset.get()), "cannot read a dataset's type");
    switch (H5Tget_class(type.get())) {
        case H5T_INTEGER:
            return ValueClass::integer;
        case H5T_FLOAT:
            return ValueClass::floating;
        default:
            return ValueClass::other;
    }
}

void set_length(const Id& dataset, hsize n, std::string_view what) {
    const hsize_t size[1] = {n};
    check_status(H5Dset_extent(dataset.get(), size), "cannot resize " + std::string(what));
}

Id write_array(const Id& loc, const std::string& name, hid file_type, hid mem_type,
               const void* data, const std::vector<hsize>& dims) {
    const std::string what = "cannot write dataset '" + name + "'";
    if (dims.empty()) throw core::StoreError(what + ": no dimensions");
    hsize_t n = 1;
    for (hsize_t d : dims)
        n *= d;
    Id space = make(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                    what + " (dataspace)");
    Id dcpl = make(H5Pcreate(H5P_DATASET_CREATE), what + " (properties)");
    if (n > 0) {
        // Chunks of whole rows (the last dimension), about 1 MB each.
        std::vector<hsize_t> chunk = dims;
        const hsize_t row = std::max<hsize_t>(1, n / dims[0]);
        chunk[0] = std::clamp<hsize_t>((1u << 17) / row, 1, dims[0]);
        check_status(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()),
                     what + " (chunk)");
        if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
            check_status(H5Pset_shuffle(dcpl.get()), what + " (shuffle)");
            check_status(H5Pset_deflate(dcpl.get(), 1), what + " (deflate)");
        }
    }
    Id ds = make(H5Dcreate2(loc.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT,
                            dcpl.get(), H5P_DEFAULT),
                 what);
    if (n > 0)
        check_status(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), what);
    return ds;
}

Id write_records(const Id& loc, const std::string& name, const std::vector<RecordField>& fields,
                 hsize_t n) {
    const std::string what = "cannot write dataset '" + name + "'";
    // Packed rows: 8 bytes per number or text pointer, 1 per flag.
    std::vector<std::size_t> offset;
    std::size_t row = 0;
    for (const auto& f : fields) {
        offset.push_back(row);
        row += f.flag ? 1 : 8;
    }
    if (row == 0) throw core::StoreError(what + ": no fields");
    Id mem = make(H5Tcreate(H5T_COMPOUND, row), what + " (type)");
    Id file = make(H5Tcreate(H5T_COMPOUND, row), what + " (type)");
    Id text = string_type();
    Id flag = bool_type();
    std::vector<unsigned char> buf(row * std::max<hsize_t>(n, 1));
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const auto& f = fields[i];
        const std::size_t size = (f.f64    ? f.f64->size()
                                  : f.i64  ? f.i64->size()
                                  : f.text ? f.text->size()
                                  : f.flag ? f.flag->size()
                                           : 0);
        if (size != n)
            throw core::StoreError(what + ": field '" + f.name + "' has the wrong length");
        hid_t mt = f.f64    ? H5T_NATIVE_DOUBLE
                   : f.i64  ? H5T_NATIVE_INT64
                   : f.text ? text.get()
                            : flag.get();
        hid_t ft = f.f64 ? H5T_IEEE_F64LE : f.i64 ? H5T_STD_I64LE : mt;
        check_status(H5Tinsert(mem.get(), f.name.c_str(), offset[i], mt),
                     what + " (" + f.name + ")");
        check_status(H5Tinsert(file.get(), f.name.c_str(), offset[i], ft),
                     what + " (" + f.name + ")");
        for (hsize_t r = 0; r < n; ++r) {
            unsigned char* at = buf.data() + r * row + offset[i];
            if (f.f64) {
                std::memcpy(at, &(*f.f64)[r], 8);
            } else if (f.i64) {
                std::memcpy(at, &(*f.i64)[r], 8);
            } else if (f.text) {
                const char* p = (*f.text)[r].c_str();
                std::memcpy(at, &p, sizeof p);
            } else {
                *at = (*f.flag)[r] ? 1 : 0;
            }
        }
    }
    const hsize_t dims[1] = {n};
    const hsize_t maxdims[1] = {H5S_UNLIMITED};
    Id space = make(H5Screate_simple(1, dims, maxdims), what + " (dataspace)");
    Id dcpl = make(H5Pcreate(H5P_DATASET_CREATE), what + " (properties)");
    const hsize_t chunk[1] = {std::max<hsize_t>(n, 1)};
    check_status(H5Pset_chunk(dcpl.get(), 1, chunk), what + " (chunk)");
    if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
        check_status(H5Pset_shuffle(dcpl.get()), what + " (shuffle)");
        check_status(H5Pset_deflate(dcpl.get(), 1), what + " (deflate)");
    }
    Id ds = make(H5Dcreate2(loc.get(), name.c_str(), file.get(), space.get(), H5P_DEFAULT,
                            dcpl.get(), H5P_DEFAULT),
                 what);
    if (n > 0)
        check_status(H5Dwrite(ds.get(), mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()),
                     what);
    return ds;
}

std::vector<hsize> dims_of(const Id& dataset) {
    Id space = make(H5Dget_space(dataset.get()), "cannot get a dataset's dataspace");
    const int rank = static_cast<int>(
        check(H5Sget_simple_extent_ndims(space.get()), "cannot get a dataset's rank"));
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    if (rank > 0)
        check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr),
              "cannot get a dataset's dimensions");
    return dims;
}

void read_array(const Id& dataset, hid mem_type, void* data, std::string_view what) {
    hsize_t n = 1;
    for (hsize_t d : dims_of(dataset))
        n *= d;
    if (n == 0) return;
    check_status(H5Dread(dataset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
                 "cannot read " + std::string(what));
}

std::optional<double> get_f64_attr(const Id& loc, const std::string& name) {
    if (H5Aexists(loc.get(), name.c_str()) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    Id a(H5Aopen(loc.get(), name.c_str(), H5P_DEFAULT));
    if (!a) return std::nullopt;
    Id type(H5Aget_type(a.get()));
    const H5T_class_t c = type ? H5Tget_class(type.get()) : H5T_NO_CLASS;
    double v = 0.0;
    if ((c != H5T_FLOAT && c != H5T_INTEGER) || H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    return v;
}

}  // namespace hopper::store::h5
