#pragma once
// Derived data in a store file: a named group of 1-D datasets and string attributes (e.g.
// /analysis, written by `campaign analyze`), replacing any previous group of that name.
//
// The group is a view of a view: it is computed from the realizations, which the journal holds,
// so it is not in the journal. When the HDF5 file is rebuilt from the journal (after a crash or a
// damaged file) the group is gone; running `campaign analyze` again restores it. Writing it
// marks the file "not consistent" first and consistent again after the close, so a writer killed
// in the middle leaves a file that the next `campaign run` rebuilds (dropping the partial group)
// rather than one that looks in step.
//
// Datasets follow the store's conventions (README, "The HDF5 file"): chunked, compressed, with
// `description` and `units` attributes; no NaN or infinity (the caller writes 0 with a has_...
// flag, or leaves the value out, and states why). They are 1-D unless `shape` is given (e.g. the
// ny x nx field maps of /analysis/fields).

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace hopper::store {

struct DerivedDataset {
    std::string name;
    std::string units;  // "s", "1/s", "kg/s", "1", ...; "" for strings
    std::string description;
    // bool is written as the store's enum {FALSE, TRUE} (h5py: numpy bool).
    std::variant<std::vector<double>, std::vector<std::int64_t>, std::vector<bool>,
                 std::vector<std::string>>
        values;
    // Empty: 1-D (extendible). Otherwise the dimensions, row-major; their product must be the
    // number of values (not for strings).
    std::vector<std::uint64_t> shape = {};
    // Further string attributes of the dataset (beside description and units).
    std::vector<std::pair<std::string, std::string>> attributes = {};
};

struct DerivedGroup {
    std::string name;  // one path component (no '/'), e.g. "analysis" or "points"
    std::vector<std::pair<std::string, std::string>> attributes;  // string attributes
    std::vector<DerivedDataset> datasets;
    std::vector<DerivedGroup> groups;  // nested groups
    // Numeric attributes (finite), written as HDF5 doubles or 64-bit integers.
    std::vector<std::pair<std::string, std::variant<double, std::int64_t>>> numbers = {};
};

// Writes `group` as /<group.name> of the store file, replacing any group (or dataset) of that name,
// and closes the file. The file must be a readable hopper store that is in step with its journal
// (closed cleanly, see store.hpp) and no `campaign run` may hold the store; otherwise
// core::StoreError says why and nothing is written. A non-finite double, an empty or
// slash-containing name, or two members of one group with the same name throw
// std::invalid_argument before the file is opened.
void write_derived_group(const std::filesystem::path& store, const DerivedGroup& group);

// The names of the members (groups and datasets) of /<name>, sorted; empty when absent.
// Throws core::StoreError when the file cannot be read.
std::vector<std::string> derived_group_members(const std::filesystem::path& store,
                                               const std::string& name);

// A numeric dataset of a store file read back, e.g. "analysis/fields/<label>/mean_vx": its
// values (doubles or 64-bit integers, as written), `shape` its dimensions and `units` and
// `description` its attributes. Throws core::StoreError when it is missing or not numeric.
DerivedDataset read_derived_dataset(const std::filesystem::path& store, const std::string& path);

}  // namespace hopper::store
