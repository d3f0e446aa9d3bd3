#pragma once
// A thin RAII layer over the HDF5 C API, private to the store layer. h5.cpp is the only file
// that includes <hdf5.h>: this header speaks in its own small types (hid, hsize, Scalar), so
// nothing that includes it sees the C API. Every call is checked: a failure becomes
// core::StoreError carrying what was being done and HDF5's own error stack.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hopper::store::h5 {

using hid = std::int64_t;          // hid_t (static_assert in h5.cpp)
using hsize = unsigned long long;  // hsize_t
inline constexpr hid invalid_hid = -1;

// While at least one QuietErrors lives, HDF5 prints no error stacks (check() puts them in the
// exception instead). The first one also turns off HDF5's cleanup at exit, which crashes on a
// file whose writes failed (issue 14; effective only before the library's first use, so every
// entry point of the store makes one before its first HDF5 call). Guards nest and may end in
// any order: the last one to end puts back the printing that was there before the first.
class QuietErrors {
  public:
    QuietErrors();
    ~QuietErrors();
    QuietErrors(const QuietErrors&) = delete;
    QuietErrors& operator=(const QuietErrors&) = delete;
};

// Throws core::StoreError("<what>: <HDF5 error stack>") when `r` is negative.
hid check(hid r, std::string_view what);

// An owned HDF5 identifier (file, group, dataset, dataspace, datatype, attribute, plist).
class Id {
  public:
    Id() = default;
    explicit Id(hid id) : id_(id) {}
    Id(Id&& o) noexcept : id_(std::exchange(o.id_, invalid_hid)) {}
    Id& operator=(Id&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, invalid_hid);
        }
        return *this;
    }
    Id(const Id&) = delete;
    Id& operator=(const Id&) = delete;
    ~Id() { reset(); }
    hid get() const { return id_; }
    explicit operator bool() const { return id_ >= 0; }
    void reset() noexcept;  // H5Idec_ref: closes whatever kind of object it is
    hid release() noexcept { return std::exchange(id_, invalid_hid); }

  private:
    hid id_ = invalid_hid;
};

// Files.
Id create_file(const std::filesystem::path& path);  // truncates
Id open_file(const std::filesystem::path& path, bool write);
void flush(const Id& file);
void close_file(Id& file);  // H5Fclose, checked
bool is_hdf5(const std::filesystem::path& path);

// Groups and links.
Id create_group(const Id& loc, const std::string& name);
Id open_group(const Id& loc, const std::string& name);
bool exists(const Id& loc, const std::string& name);
void remove(const Id& loc, const std::string& name, std::string_view what);  // unlinks
std::vector<std::string> member_names(const Id& group);                      // in name order

// Types. Numbers are little-endian in the file and native in memory.
enum class Scalar { i8, i32, i64, u64, f64 };
hid file_type(Scalar s);
hid mem_type(Scalar s);
Id string_type();                                                       // variable-length UTF-8
Id enum_type(const std::vector<std::pair<std::string, int>>& members);  // int8 base
Id bool_type();  // enum {FALSE=0, TRUE=1}: h5py bool
// What a dataset holds.
enum class ValueClass { integer, floating, other };
ValueClass value_class(const Id& dataset);

// Extendible 1-D datasets ("columns"), chunked, shuffle + deflate.
Id create_column(const Id& loc, const std::string& name, hid file_type, hsize chunk);
Id open_dataset(const Id& loc, const std::string& name);
hsize length(const Id& dataset);
void set_length(const Id& dataset, hsize n, std::string_view what);
// Writes n elements of memory type `mem_type` at [offset, offset + n), extending as needed.
void write_at(const Id& dataset, hid mem_type, const void* data, hsize offset, hsize n,
              std::string_view what);
// Sets the length to n and writes all of it.
void write_all(const Id& dataset, hid mem_type, const void* data, hsize n, std::string_view what);
void read_all(const Id& dataset, hid mem_type, void* data, std::string_view what);
std::vector<std::string> read_strings(const Id& dataset, std::string_view what);

// Fixed-size N-D datasets (the field maps; also used by derived groups): `dims` row-major,
// written whole, chunked (about 1 MB per chunk) with shuffle + deflate (unchunked when empty).
Id write_array(const Id& loc, const std::string& name, hid file_type, hid mem_type,
               const void* data, const std::vector<hsize>& dims);
// A 1-D table of n records (one compound dataset), written whole, chunked with shuffle +
// deflate: one member per field, in order. Each field points at n values: numbers (f64 or i64),
// texts (variable-length UTF-8) or flags (the bool enum).
struct RecordField {
    std::string name;
    const std::vector<double>* f64 = nullptr;
    const std::vector<std::int64_t>* i64 = nullptr;
    const std::vector<std::string>* text = nullptr;
    const std::vector<bool>* flag = nullptr;
};
Id write_records(const Id& loc, const std::string& name, const std::vector<RecordField>& fields,
                 hsize n);
// The dimensions of a dataset, any rank.
std::vector<hsize> dims_of(const Id& dataset);
// Reads a whole dataset of any rank (nothing when it has no elements).
void read_array(const Id& dataset, hid mem_type, void* data, std::string_view what);

// Attributes (scalar). Replaces an existing attribute of the same name.
void set_attr(const Id& loc, const std::string& name, const std::string& value);
// A 1-D attribute of strings (variable-length UTF-8), one per element.
void set_attr(const Id& loc, const std::string& name, const std::vector<std::string>& values);
void set_attr(const Id& loc, const std::string& name, std::int64_t value);
void set_attr_u64(const Id& loc, const std::string& name, std::uint64_t value);
void set_attr(const Id& loc, const std::string& name, double value);
std::optional<std::string> get_string_attr(const Id& loc, const std::string& name);
std::optional<std::int64_t> get_int_attr(const Id& loc, const std::string& name);
std::optional<std::uint64_t> get_u64_attr(const Id& loc, const std::string& name);
// A double attribute, absent when missing or not numeric.
std::optional<double> get_f64_attr(const Id& loc, const std::string& name);

}  // namespace hopper::store::h5
