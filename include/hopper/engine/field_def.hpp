#pragma once
// How a member of a persisted engine type is described (docs/model.md, "What each realization
// reports"): its name, units, description and the result format version that added it, and
// where the store puts it. The descriptions themselves stand beside their types (result.hpp);
// the journal's codec, the realization's checkpoint and the store file's columns walk them, so
// a member added to a type and its description reaches all three (and hopper_store) without
// another list to edit. The JSON of `campaign simulate` takes its values through them but
// names its keys itself, in a documented order (cli/result_output.cpp).

#include <cstdint>
#include <string_view>

namespace hopper::engine {

// The ragged families of the store file (/realizations/<family>_start and _length): the arrays
// of one family have one value per element of its first array.
enum class Family : std::int8_t { none = -1, survival, jam, exit, curve, event, arch, arch_disk };

// Where a member goes in the store file.
enum class Placement : std::int8_t {
    column,   // /realizations (scalars), /realizations/diagnostics or /ragged (arrays)
    record,   // a column of the result's record (the seed: /realizations/seed)
    own,      // its own layout (the fields: /fields/<row>; the arches: the arch families)
    nowhere,  // reported by `campaign simulate` only, neither journaled nor stored
};

template <class Owner, class Member>
struct FieldDef {
    std::string_view name;  // JSON key; HDF5 column unless `column` is set
    Member Owner::*member;
    std::string_view units;
    std::string_view description;
    std::uint16_t since = 1;  // result format version that added it (result_version)
    Family family = Family::none;
    std::string_view column = {};
    Placement placement = Placement::column;
    bool wall_clock = false;  // a wall-clock measurement: differs between two runs of a realization

    std::string_view column_name() const { return column.empty() ? name : column; }
};

template <class Owner, class Member>
constexpr FieldDef<Owner, Member> field(std::string_view name, Member Owner::*member,
                                        std::string_view units, std::string_view description) {
    return {name, member, units, description};
}

// Copies of `f` with one property changed.
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> in(FieldDef<Owner, Member> f, Family family,
                                     std::string_view column = {}) {
    f.family = family;
    f.column = column;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> since(FieldDef<Owner, Member> f, std::uint16_t version) {
    f.since = version;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> timed(FieldDef<Owner, Member> f) {
    f.wall_clock = true;
    return f;
}
template <class Owner, class Member>
constexpr FieldDef<Owner, Member> placed(FieldDef<Owner, Member> f, Placement p) {
    f.placement = p;
    return f;
}

}  // namespace hopper::engine
