#pragma once
// The HDF5 layout of a store (private to the store layer): writing it from the journal's state
// (writer.cpp) and reading realizations back (reader.cpp), both from the schema (schema.hpp).
// The layout is documented in docs/store.md; `format_version` changes whenever it changes
// incompatibly. No HDF5 type passes through this header.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hopper/store/store.hpp"
#include "state.hpp"

namespace hopper::store::layout {

inline constexpr std::int64_t format_version = 1;
inline constexpr const char* format_name = "hopper campaign store";

class Writer {
  public:
    // A new file with every group and dataset of the schema, empty (truncates `path`).
    // `journal_name` is the file name of the journal, recorded as an attribute.
    // `parameters` (optional) gives /points/parameters, rewritten with /points.
    static Writer create(const std::filesystem::path& path, const std::string& journal_name,
                         PointParameters parameters = {});
    // An existing store file, for appending.
    static Writer open(const std::filesystem::path& path, PointParameters parameters = {});
    Writer(Writer&&) noexcept;
    Writer& operator=(Writer&&) noexcept;
    ~Writer();  // closes without marking the file consistent

    void run_start(const State& s, bool plan_changed);
    // A target campaign's next round allotted realizations (the /points and /tasks tables).
    void allotment(const State& s, bool plan_changed);
    void result(const State& s, int point, std::int64_t row, const ResultRecord& rec,
                const engine::RealizationResult& r);
    void error(const State& s, int point, const ErrorRecord& rec);
    void run_end(const State& s);
    // Writes what is buffered or changed, marks the file "not consistent", flushes.
    // `partial` (test hook) stops after the realization rows, before the tables.
    void flush(const State& s, bool partial = false);
    // Flushes, records the token and journal length, marks the file consistent, closes.
    void close(const State& s, std::uint64_t token, std::uint64_t journal_bytes);

  private:
    struct Impl;
    explicit Writer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

// What a store file says about itself; never throws.
struct Inspection {
    bool readable = false;  // an HDF5 file with our format attributes
    bool foreign = false;   // not HDF5, or an HDF5 file that is not a hopper store
    std::string problem;    // why not readable
    bool consistent = false;
    std::uint64_t token = 0;
    std::uint64_t journal_bytes = 0;
    std::int64_t rows = -1;
};
Inspection inspect(const std::filesystem::path& path);

// Every stored realization, in row order, with its fields (/fields/<row>) when it has them.
// Throws core::StoreError.
std::vector<StoredRealization> read_realizations(const std::filesystem::path& path);

}  // namespace hopper::store::layout
