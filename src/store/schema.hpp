#pragma once
// The schema of a store file (private to the store layer): the kinds of its columns and their
// HDF5 types, typed column buffers, the /realizations and /ragged columns (columns.cpp), the
// small tables /points, /tasks, /runs and /failures, and the /fields groups (fields_io.cpp).
// The writer (writer.cpp) and the reader (reader.cpp) both work from these tables.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "h5.hpp"
#include "hopper/engine/result.hpp"
#include "state.hpp"

namespace hopper::store::layout {

// ---------------------------------------------------------------------------------------------
// Column kinds, their HDF5 types and typed buffers.

enum class Kind { status, boolean, event_kind, task_state, i32, i64, u64, f64, str };

using Buffer =
    std::variant<std::vector<std::int8_t>, std::vector<std::int32_t>, std::vector<std::int64_t>,
                 std::vector<std::uint64_t>, std::vector<double>, std::vector<std::string>>;

Buffer make_buffer(Kind k);
std::size_t size_of(const Buffer& b);
void clear(Buffer& b);
template <class T>
const std::vector<T>& as(const Buffer& b) {
    return std::get<std::vector<T>>(b);
}
template <class T>
std::vector<T>& as(Buffer& b) {
    return std::get<std::vector<T>>(b);
}

// The enum and string types, created once per file handle.
struct Types {
    h5::Id status;
    h5::Id boolean;
    h5::Id event_kind;
    h5::Id task_state;
    h5::Id str;

    Types();
    h5::hid file_type(Kind k) const;
    h5::hid mem_type(Kind k) const;
};

void write_buffer(const h5::Id& ds, const Types& t, Kind k, const Buffer& b, h5::hsize offset,
                  const std::string& what);
Buffer read_buffer(const h5::Id& ds, const Types& t, Kind k, const std::string& what);

// Infinite or NaN doubles are never written (the engine guards against them; this is the
// last line of defence): they become 0 and the row's `nonfinite_values` counts them.
double fin(double v);

// "units" (when not empty) and "description" attributes.
void describe(const h5::Id& obj, const std::string& units, const std::string& description);

// Chunk sizes (elements): rows and tables are short, ragged data long.
inline constexpr h5::hsize row_chunk = 256;
inline constexpr h5::hsize ragged_chunk = 8192;

// ---------------------------------------------------------------------------------------------
// The realization columns (columns.cpp): one value per stored realization, or (ragged) a family
// of concatenated values indexed by <family>_start / <family>_length in /realizations.

struct Src {
    int point;
    const ResultRecord& rec;
    const engine::RealizationResult& r;
};

struct RaggedFamily {
    const char* name;
    const char* description;  // the writer adds the names of the family's arrays
    std::function<std::size_t(const engine::RealizationResult&)> length;
};
const std::vector<RaggedFamily>& families();

struct ColumnDef {
    std::string group;  // "realizations", "realizations/diagnostics" or "ragged"
    std::string name;
    Kind kind;
    std::string units;
    std::string description;
    int family;  // -1: one value per row; otherwise the index in families()
    std::function<void(Buffer&, const Src&)> push;
    std::function<void(StoredRealization&, const Buffer&, std::size_t at, std::size_t n)> pull;
    // The result format version that added the member (engine/result.hpp); > 1 is written as
    // the dataset's "since" attribute: rows whose result_version is older hold padding there.
    std::uint16_t since = 1;
};
// In creation order; read back in this order (a pull may rely on the columns before it).
const std::vector<ColumnDef>& columns();

// ---------------------------------------------------------------------------------------------
// The small tables: /points, /tasks, /runs, /failures.

struct TableColumn {
    std::string name;
    Kind kind;
    std::string units;
    std::string description;
};
const std::vector<TableColumn>& points_columns();
const std::vector<TableColumn>& tasks_columns();
const std::vector<TableColumn>& runs_columns();
const std::vector<TableColumn>& failures_columns();

// ---------------------------------------------------------------------------------------------
// Fields (fields_io.cpp): /fields/<row>, one group per realization that has fields.

inline constexpr const char* fields_group_name = "fields";
void write_fields(const h5::Id& parent, const std::string& scene, int point, std::int64_t row,
                  int realization, const engine::FieldMoments& m);
engine::FieldMoments read_fields(const h5::Id& g, const std::string& where);

}  // namespace hopper::store::layout
