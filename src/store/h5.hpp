#pragma once
// A thin RAII layer over the HDF5 C API (private to the store layer; the only place that
// includes hdf5.h besides h5.cpp). Every call goes through check(), which turns a negative
// return into core::StoreError carrying what was being done and HDF5's own error stack.

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hopper::store::h5 {

// Switches off HDF5's automatic error printing (errors become exceptions instead) and its
// cleanup at exit (which crashes after failed writes). Called before any other HDF5 call.
void quiet_errors();

// Throws core::StoreError("<what>: <HDF5 error stack>") when `r` is negative.
hid_t check(hid_t r, std::string_view what);
herr_t check_status(herr_t r, std::string_view what);

// An owned HDF5 identifier (file, group, dataset, dataspace, datatype, attribute, plist).
class Id {
  public:
    Id() = default;
    explicit Id(hid_t id) : id_(id) {}
    Id(Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)) {}
    Id& operator=(Id&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, H5I_INVALID_HID);
        }
        return *this;
    }
    Id(const Id&) = delete;
    Id& operator=(const Id&) = delete;
    ~Id() { reset(); }
    hid_t get() const { return id_; }
    explicit operator bool() const { return id_ >= 0; }
    void reset() noexcept;  // H5Idec_ref: closes whatever kind of object it is
    hid_t release() noexcept { return std::exchange(id_, H5I_INVALID_HID); }

  private:
    hid_t id_ = H5I_INVALID_HID;
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

// Types (owned copies).
Id string_type();                                                       // variable-length UTF-8
Id enum_type(const std::vector<std::pair<std::string, int>>& members);  // int8 base
Id bool_type();  // enum {FALSE=0, TRUE=1}: h5py bool

// Extendible 1-D datasets ("columns"), chunked, shuffle + deflate.
Id create_column(const Id& loc, const std::string& name, hid_t file_type, hsize_t chunk);
Id open_dataset(const Id& loc, const std::string& name);
hsize_t length(const Id& dataset);
// Writes n elements of memory type `mem_type` at [offset, offset + n), extending as needed.
void write_at(const Id& dataset, hid_t mem_type, const void* data, hsize_t offset, hsize_t n,
              std::string_view what);
// Sets the length to n and writes all of it.
void write_all(const Id& dataset, hid_t mem_type, const void* data, hsize_t n,
               std::string_view what);
void read_all(const Id& dataset, hid_t mem_type, void* data, std::string_view what);
std::vector<std::string> read_strings(const Id& dataset, std::string_view what);

// Attributes (scalar). Replaces an existing attribute of the same name.
void set_attr(const Id& loc, const std::string& name, const std::string& value);
void set_attr(const Id& loc, const std::string& name, std::int64_t value);
void set_attr_u64(const Id& loc, const std::string& name, std::uint64_t value);
void set_attr(const Id& loc, const std::string& name, double value);
std::optional<std::string> get_string_attr(const Id& loc, const std::string& name);
std::optional<std::int64_t> get_int_attr(const Id& loc, const std::string& name);
std::optional<std::uint64_t> get_u64_attr(const Id& loc, const std::string& name);

}  // namespace hopper::store::h5
