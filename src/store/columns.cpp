// The /realizations and /ragged columns of a store file (see schema.hpp): for each, its name,
// kind, units and description, how a result fills it (push) and how it is read back (pull).
// The result's columns are generated from its description (result_fields.hpp); the record's
// columns (which task, who ran it, when) and the arches' are written out here.

#include <cmath>

#include <type_traits>

#include "hopper/core/error.hpp"
#include "hopper/store/result_fields.hpp"
#include "schema.hpp"

namespace hopper::store::layout {

const std::vector<RaggedFamily>& families() {
    static const std::vector<RaggedFamily> f = {
        {"survival", "survival intervals",
         [](const engine::RealizationResult& r) { return r.survival_times.size(); }},
        {"jam", "jams", [](const engine::RealizationResult& r) { return r.jam_onsets.size(); }},
        {"exit", "exits", [](const engine::RealizationResult& r) { return r.exit_times.size(); }},
        {"curve", "discharge curve samples",
         [](const engine::RealizationResult& r) { return r.curve_time.size(); }},
        {"event", "events of the log",
         [](const engine::RealizationResult& r) { return r.events.size(); }},
        // Issue 13: absent from files written before (read_realizations reads such files with
        // none; the writer rebuilds them from the journal).
        {"arch", "arches, one per jam",
         [](const engine::RealizationResult& r) { return r.arches.size(); }},
        {"arch_disk", "the arches' disks, all arches of the realization in jam order",
         [](const engine::RealizationResult& r) {
             std::size_t n = 0;
             for (const auto& a : r.arches)
                 n += a.ids.size();
             return n;
         }},
    };
    return f;
}

namespace {

template <class T>
ColumnDef row(std::string group, std::string name, Kind kind, std::string units,
              std::string description, std::function<T(const Src&)> get,
              std::function<void(StoredRealization&, T)> set) {
    return ColumnDef{
        std::move(group),
        std::move(name),
        kind,
        std::move(units),
        std::move(description),
        -1,
        [get](Buffer& b, const Src& s) { std::get<std::vector<T>>(b).push_back(get(s)); },
        [set](StoredRealization& o, const Buffer& b, std::size_t at, std::size_t) {
            set(o, as<T>(b)[at]);
        }};
}

ColumnDef f64_row(std::string group, std::string name, std::string units, std::string description,
                  std::function<double(const Src&)> get,
                  std::function<void(StoredRealization&, double)> set) {
    return row<double>(
        std::move(group), std::move(name), Kind::f64, std::move(units), std::move(description),
        [get](const Src& s) { return fin(get(s)); }, std::move(set));
}

template <class T>
ColumnDef ragged(std::string name, Kind kind, int family, std::string units,
                 std::string description,
                 std::function<void(std::vector<T>&, const engine::RealizationResult&)> push_all,
                 std::function<void(engine::RealizationResult&, const T*, std::size_t)> set) {
    return ColumnDef{
        "ragged",
        std::move(name),
        kind,
        std::move(units),
        std::move(description),
        family,
        [push_all](Buffer& b, const Src& s) { push_all(std::get<std::vector<T>>(b), s.r); },
        [set](StoredRealization& o, const Buffer& b, std::size_t at, std::size_t n) {
            const auto& v = as<T>(b);
            if (at + n > v.size())
                throw core::StoreError("a ragged index points past the end of its dataset");
            set(o.result, v.data() + at, n);
        }};
}

// A column of the arch_disk family: the disks of all arches of a realization in jam order. Its
// pull runs after arch_disks has sized each arch.
template <class T>
ColumnDef arch_disk_column(std::string name, Kind kind, std::string units, std::string description,
                           std::function<T(const engine::Arch&, std::size_t)> get,
                           std::function<void(engine::Arch&, std::size_t, T)> set) {
    return ragged<T>(
        std::move(name), kind, 6, std::move(units), std::move(description),
        [get](std::vector<T>& v, const engine::RealizationResult& r) {
            for (const auto& a : r.arches)
                for (std::size_t k = 0; k < a.ids.size(); ++k)
                    v.push_back(get(a, k));
        },
        [set](engine::RealizationResult& r, const T* p, std::size_t n) {
            std::size_t total = 0;
            for (const auto& a : r.arches)
                total += a.ids.size();
            if (total != n)
                throw core::StoreError("the store's arch disks (" + std::to_string(n) +
                                       ") do not add up to its arch sizes (" +
                                       std::to_string(total) + ")");
            std::size_t at = 0;
            for (auto& a : r.arches) {
                a.x.resize(a.ids.size());
                a.y.resize(a.ids.size());
                for (std::size_t k = 0; k < a.ids.size(); ++k)
                    set(a, k, p[at++]);
            }
        });
}

// ---------------------------------------------------------------------------------------------
// The result's columns, generated from its description (result_fields.hpp) by the C++ type of
// each member: its kind, how a value is stored (enums and booleans as int8, doubles through
// fin) and how it is read back (enums checked).

template <class T>
struct Stored {
    using type = T;
};
template <>
struct Stored<engine::Status> {
    using type = std::int8_t;
};
template <>
struct Stored<engine::Event::Kind> {
    using type = std::int8_t;
};
template <>
struct Stored<bool> {
    using type = std::int8_t;
};
template <>
struct Stored<int> {
    using type = std::int32_t;
};
template <class T>
using stored_t = typename Stored<T>::type;

template <class T>
constexpr Kind kind_of() {
    if constexpr (std::is_same_v<T, engine::Status>)
        return Kind::status;
    else if constexpr (std::is_same_v<T, engine::Event::Kind>)
        return Kind::event_kind;
    else if constexpr (std::is_same_v<T, bool>)
        return Kind::boolean;
    else if constexpr (std::is_same_v<T, int>)
        return Kind::i32;
    else if constexpr (std::is_same_v<T, std::int64_t>)
        return Kind::i64;
    else if constexpr (std::is_same_v<T, std::uint64_t>)
        return Kind::u64;
    else if constexpr (std::is_same_v<T, double>)
        return Kind::f64;
    else
        return Kind::str;
}

template <class T>
stored_t<T> to_stored(const T& v) {
    if constexpr (std::is_same_v<T, double>)
        return fin(v);
    else if constexpr (std::is_same_v<stored_t<T>, std::int8_t>)
        return static_cast<std::int8_t>(v);
    else
        return v;
}

template <class T>
void from_stored(const stored_t<T>& v, T& out) {
    if constexpr (std::is_same_v<T, engine::Status>) {
        if (v < 0 || v > 3) throw core::StoreError("bad status value in the store");
        out = static_cast<engine::Status>(v);
    } else if constexpr (std::is_same_v<T, engine::Event::Kind>) {
        if (v < 0 || v > 7) throw core::StoreError("bad event kind in the store");
        out = static_cast<engine::Event::Kind>(v);
    } else if constexpr (std::is_same_v<T, bool>) {
        out = v != 0;
    } else {
        out = v;
    }
}

template <class>
constexpr bool is_vector = false;
template <class E>
constexpr bool is_vector<std::vector<E>> = true;

// A member of the result itself, or of its diagnostics.
constexpr auto whole = [](auto& r) -> auto& {
    return r;
};
constexpr auto diagnostics_of = [](auto& r) -> auto& {
    return r.diagnostics;
};

// One value per row: /realizations/<name> or /realizations/diagnostics/<name>.
template <class Owner, class M, class Access>
ColumnDef scalar_column(const std::string& group, const FieldDef<Owner, M>& f, Access owner) {
    using T = stored_t<M>;
    const auto m = f.member;
    return ColumnDef{
        group,
        std::string(f.column_name()),
        kind_of<M>(),
        std::string(f.units),
        std::string(f.description),
        -1,
        [m, owner](Buffer& b, const Src& s) { as<T>(b).push_back(to_stored(owner(s.r).*m)); },
        [m, owner](StoredRealization& o, const Buffer& b, std::size_t at, std::size_t) {
            from_stored(as<T>(b)[at], owner(o.result).*m);
        }};
}

// An optional number: its value (0 when absent) and a has_<name> flag, read after it.
template <class Owner>
void optional_columns(std::vector<ColumnDef>& out, const std::string& group,
                      const FieldDef<Owner, std::optional<double>>& f) {
    const auto m = f.member;
    out.push_back(row<double>(
        group, std::string(f.column_name()), Kind::f64, std::string(f.units),
        std::string(f.description), [m](const Src& s) { return fin((s.r.*m).value_or(0.0)); },
        [m](StoredRealization& o, double v) { o.result.*m = v; }));
    out.push_back(row<std::int8_t>(
        group, "has_" + std::string(f.column_name()), Kind::boolean, "1",
        "whether " + std::string(f.column_name()) + " has a value",
        [m](const Src& s) { return static_cast<std::int8_t>((s.r.*m) ? 1 : 0); },
        [m](StoredRealization& o, std::int8_t v) {
            if (!v) (o.result.*m).reset();
        }));
}

// An array of a ragged family: one value per element of the family (padded with 0 when the
// array is shorter), concatenated over the rows in /ragged/<name>.
template <class E>
ColumnDef array_column(const FieldDef<engine::RealizationResult, std::vector<E>>& f) {
    using T = stored_t<E>;
    const auto m = f.member;
    const int family = static_cast<int>(f.family);
    ColumnDef c = ragged<T>(
        std::string(f.column_name()), kind_of<E>(), family, std::string(f.units),
        std::string(f.description),
        [m, family](std::vector<T>& out, const engine::RealizationResult& r) {
            const auto& v = r.*m;
            const std::size_t n = families()[static_cast<std::size_t>(family)].length(r);
            for (std::size_t i = 0; i < n; ++i)
                out.push_back(i < v.size() ? to_stored<E>(v[i]) : T{0});
        },
        [m](engine::RealizationResult& r, const T* p, std::size_t n) {
            auto& v = r.*m;
            v.resize(n);
            for (std::size_t i = 0; i < n; ++i) {
                E x{};
                from_stored<E>(p[i], x);
                v[i] = x;
            }
        });
    c.since = f.since;
    return c;
}

// A member of every event: /ragged/event_<name> in the event family.
template <class M>
ColumnDef event_column(const FieldDef<engine::Event, M>& f) {
    using T = stored_t<M>;
    const auto m = f.member;
    return ragged<T>(
        "event_" + std::string(f.name), kind_of<M>(), static_cast<int>(Family::event),
        std::string(f.units), std::string(f.description),
        [m](std::vector<T>& out, const engine::RealizationResult& r) {
            for (const auto& e : r.events)
                out.push_back(to_stored(e.*m));
        },
        [m](engine::RealizationResult& r, const T* p, std::size_t n) {
            r.events.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                from_stored<M>(p[i], r.events[i].*m);
        });
}

// The arches: per jam its disk count, span and largest angle (family arch), and per disk its
// id and position (family arch_disk).
void arch_columns(std::vector<ColumnDef>& out) {
    using R = engine::RealizationResult;
    out.push_back(ragged<std::int32_t>(
        "arch_disks", Kind::i32, 5, "1",
        "disks in the arch of each jam (0: no arch found); its disks are the next "
        "arch_disks values of the arch_disk family",
        [](std::vector<std::int32_t>& v, const R& r) {
            for (const auto& a : r.arches)
                v.push_back(static_cast<std::int32_t>(a.ids.size()));
        },
        [](R& r, const std::int32_t* p, std::size_t n) {
            r.arches.assign(n, {});
            for (std::size_t i = 0; i < n; ++i) {
                if (p[i] < 0) throw core::StoreError("a negative arch size in the store");
                r.arches[i].ids.assign(static_cast<std::size_t>(p[i]), -1);
            }
        }));
    out.push_back(ragged<double>(
        "arch_span", Kind::f64, 5, "m",
        "distance between the arch's contact points with the two walls (0: no arch)",
        [](std::vector<double>& v, const R& r) {
            for (const auto& a : r.arches)
                v.push_back(fin(a.span));
        },
        [](R& r, const double* p, std::size_t n) {
            r.arches.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                r.arches[i].span = p[i];
        }));
    out.push_back(ragged<double>(
        "arch_max_angle", Kind::f64, 5, "rad",
        "largest angle between consecutive bonds of the arch, measured through the outlet "
        "side (pi: straight; 0: no arch)",
        [](std::vector<double>& v, const R& r) {
            for (const auto& a : r.arches)
                v.push_back(fin(a.max_angle));
        },
        [](R& r, const double* p, std::size_t n) {
            r.arches.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                r.arches[i].max_angle = p[i];
        }));
    out.push_back(arch_disk_column<std::int32_t>(
        "arch_disk_id", Kind::i32, "1", "particle id of each arch disk, left to right",
        [](const engine::Arch& a, std::size_t k) { return a.ids[k]; },
        [](engine::Arch& a, std::size_t k, std::int32_t v) { a.ids[k] = v; }));
    out.push_back(arch_disk_column<double>(
        "arch_disk_x", Kind::f64, "m", "x of each arch disk's centre when the jam was detected",
        [](const engine::Arch& a, std::size_t k) { return fin(a.x[k]); },
        [](engine::Arch& a, std::size_t k, double v) { a.x[k] = v; }));
    out.push_back(arch_disk_column<double>(
        "arch_disk_y", Kind::f64, "m", "y of each arch disk's centre when the jam was detected",
        [](const engine::Arch& a, std::size_t k) { return fin(a.y[k]); },
        [](engine::Arch& a, std::size_t k, double v) { a.y[k] = v; }));
}

// Every member of the result in its columns, in the order of result_fields.hpp.
void result_columns(std::vector<ColumnDef>& out) {
    const std::string G = "realizations";
    for_each_result_field([&](const auto& f) {
        using M = std::remove_cvref_t<decltype(engine::RealizationResult{}.*f.member)>;
        if constexpr (std::is_same_v<M, std::vector<engine::Arch>>) {
            arch_columns(out);  // Placement::own
        } else if constexpr (std::is_same_v<M, std::optional<double>>) {
            optional_columns(out, G, f);
        } else if constexpr (std::is_same_v<M, std::vector<engine::Event>>) {
            for_each_event_field([&](const auto& e) { out.push_back(event_column(e)); });
        } else if constexpr (std::is_same_v<M, engine::Diagnostics>) {
            for_each_diagnostic([&](const auto& d) {
                if (d.placement == Placement::column)
                    out.push_back(scalar_column(G + "/diagnostics", d, diagnostics_of));
            });
        } else if constexpr (is_vector<M>) {
            out.push_back(array_column(f));
        } else if constexpr (!std::is_same_v<M, std::optional<engine::FieldMoments>>) {
            if (f.placement == Placement::column) out.push_back(scalar_column(G, f, whole));
        }
    });
}

// The doubles of a result that are stored (the arches' are not counted, as before).
struct NonfiniteCounter {
    int n = 0;
    void add(double v) { n += std::isfinite(v) ? 0 : 1; }
    void operator()(double v) { add(v); }
    void operator()(const std::optional<double>& v) {
        if (v) add(*v);
    }
    void operator()(const std::vector<double>& v) {
        for (double x : v)
            add(x);
    }
    void operator()(const std::vector<engine::Event>& v) {
        for (const auto& e : v)
            for_each_event_field([&](const auto& f) {
                if constexpr (std::is_same_v<std::remove_cvref_t<decltype(e.*f.member)>, double>)
                    add(e.*f.member);
            });
    }
    void operator()(const engine::Diagnostics& d) {
        for_each_diagnostic([&](const auto& f) {
            if constexpr (std::is_same_v<std::remove_cvref_t<decltype(d.*f.member)>, double>)
                if (f.placement == Placement::column) add(d.*f.member);
        });
    }
    template <class T>
    void operator()(const T&) {}
};

int nonfinite_count(const engine::RealizationResult& r) {
    NonfiniteCounter c;
    for_each_result_field([&](const auto& f) {
        if (f.placement == Placement::column) c(r.*f.member);
    });
    return c.n;
}

}  // namespace

const std::vector<ColumnDef>& columns() {
    static const std::vector<ColumnDef> c = [] {
        const std::string G = "realizations";
        // Which task, who ran it, when.
        std::vector<ColumnDef> out = {
            row<std::int32_t>(
                G, "point", Kind::i32, "1", "index of the point in /points",
                [](const Src& s) { return s.point; },
                [](StoredRealization& o, std::int32_t v) { o.point = v; }),
            row<std::int32_t>(
                G, "realization", Kind::i32, "1", "realization index within the point (0-based)",
                [](const Src& s) { return s.rec.realization; },
                [](StoredRealization& o, std::int32_t v) { o.record.realization = v; }),
            row<std::uint64_t>(
                G, "seed", Kind::u64, "1", "random seed of the realization",
                [](const Src& s) { return s.rec.seed; },
                [](StoredRealization& o, std::uint64_t v) {
                    o.record.seed = v;
                    o.result.seed = v;
                }),
            row<std::int32_t>(
                G, "rank", Kind::i32, "1",
                "worker that ran it: its MPI rank (1..size-1), or its thread number "
                "(1..threads) in a run without mpirun",
                [](const Src& s) { return s.rec.rank; },
                [](StoredRealization& o, std::int32_t v) { o.record.rank = v; }),
            row<std::int32_t>(
                G, "attempt", Kind::i32, "1", "attempt that produced this result (1 = first)",
                [](const Src& s) { return s.rec.attempt; },
                [](StoredRealization& o, std::int32_t v) { o.record.attempt = v; }),
            f64_row(
                G, "task_seconds", "s", "wall-clock time of the task on its worker",
                [](const Src& s) { return s.rec.task_seconds; },
                [](StoredRealization& o, double v) { o.record.task_seconds = v; }),
            f64_row(
                G, "finished_unix", "s", "when the master stored it, seconds since 1970-01-01 UTC",
                [](const Src& s) { return s.rec.finished_unix; },
                [](StoredRealization& o, double v) { o.record.finished_unix = v; }),
            row<std::int32_t>(
                G, "nonfinite_values", Kind::i32, "1",
                "non-finite numbers the engine reported, written as 0 (always 0 in practice)",
                [](const Src& s) { return nonfinite_count(s.r); },
                [](StoredRealization&, std::int32_t) {}),
        };
        // The engine's result.
        result_columns(out);
        // Last, so that its pull sees the avalanche sizes and arches read above.
        out.push_back(row<std::int8_t>(
            G, "has_avalanche_sizes", Kind::boolean, "1",
            "whether the realization recorded avalanche sizes and arches (false for results "
            "stored before they existed)",
            [](const Src& s) {
                return static_cast<std::int8_t>(
                    !s.r.avalanche_sizes.empty() || !s.r.arches.empty() ? 1 : 0);
            },
            [](StoredRealization& o, std::int8_t v) {
                if (!v) {
                    o.result.avalanche_sizes.clear();
                    o.result.arches.clear();
                }
            }));
        // Last of all, so that its pull sees every array read above: the result format version
        // of the row's result. The arrays of later members hold padding (one 0 per element of
        // their family) in the rows of older results; reading them back leaves them empty, as
        // the journal's decoding does.
        out.push_back(row<std::int32_t>(
            G, "result_version", Kind::i32, "1",
            "result format version of the realization's record: the newest member it holds "
            "(arrays with a later 'since' attribute hold padding in its row)",
            [](const Src& s) { return static_cast<std::int32_t>(engine::result_version(s.r)); },
            [](StoredRealization& o, std::int32_t v) {
                for_each_result_field([&](const auto& f) {
                    using M = std::remove_cvref_t<decltype(o.result.*f.member)>;
                    if constexpr (is_vector<M>)
                        if (f.placement == Placement::column && f.since > v)
                            (o.result.*f.member).clear();
                });
            }));
        return out;
    }();
    return c;
}

}  // namespace hopper::store::layout
