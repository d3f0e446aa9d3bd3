#include "layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <variant>

#include "h5.hpp"
#include "hopper/core/error.hpp"

namespace hopper::store::layout {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// Column kinds and their HDF5 types.

enum class Kind { status, boolean, event_kind, task_state, i32, i64, u64, f64, str };

using Buffer =
    std::variant<std::vector<std::int8_t>, std::vector<std::int32_t>, std::vector<std::int64_t>,
                 std::vector<std::uint64_t>, std::vector<double>, std::vector<std::string>>;

Buffer make_buffer(Kind k) {
    switch (k) {
        case Kind::status:
        case Kind::boolean:
        case Kind::event_kind:
        case Kind::task_state:
            return std::vector<std::int8_t>{};
        case Kind::i32:
            return std::vector<std::int32_t>{};
        case Kind::i64:
            return std::vector<std::int64_t>{};
        case Kind::u64:
            return std::vector<std::uint64_t>{};
        case Kind::f64:
            return std::vector<double>{};
        case Kind::str:
            return std::vector<std::string>{};
    }
    return std::vector<double>{};
}

std::size_t size_of(const Buffer& b) {
    return std::visit([](const auto& v) { return v.size(); }, b);
}

void clear(Buffer& b) {
    std::visit([](auto& v) { v.clear(); }, b);
}

// The enum and string types, created once per file handle.
struct Types {
    h5::Id status =
        h5::enum_type({{"complete", 0}, {"arrested", 1}, {"time_limit", 2}, {"failed", 3}});
    h5::Id boolean = h5::bool_type();
    h5::Id event_kind = h5::enum_type({{"settled", 0},
                                       {"opened", 1},
                                       {"jam", 2},
                                       {"shake_start", 3},
                                       {"shake_end", 4},
                                       {"flow_restart", 5},
                                       {"empty", 6},
                                       {"stop", 7}});
    h5::Id task_state = h5::enum_type({{"pending", 0}, {"done", 1}, {"failed", 2}, {"error", 3}});
    h5::Id str = h5::string_type();

    hid_t file_type(Kind k) const {
        switch (k) {
            case Kind::status:
                return status.get();
            case Kind::boolean:
                return boolean.get();
            case Kind::event_kind:
                return event_kind.get();
            case Kind::task_state:
                return task_state.get();
            case Kind::i32:
                return H5T_STD_I32LE;
            case Kind::i64:
                return H5T_STD_I64LE;
            case Kind::u64:
                return H5T_STD_U64LE;
            case Kind::f64:
                return H5T_IEEE_F64LE;
            case Kind::str:
                return str.get();
        }
        return H5T_IEEE_F64LE;
    }
    hid_t mem_type(Kind k) const {
        switch (k) {
            case Kind::i32:
                return H5T_NATIVE_INT32;
            case Kind::i64:
                return H5T_NATIVE_INT64;
            case Kind::u64:
                return H5T_NATIVE_UINT64;
            case Kind::f64:
                return H5T_NATIVE_DOUBLE;
            default:
                return file_type(k);  // enums and strings: the same type in memory
        }
    }
};

void write_buffer(const h5::Id& ds, const Types& t, Kind k, const Buffer& b, hsize_t offset,
                  const std::string& what) {
    const hsize_t n = size_of(b);
    if (n == 0) return;
    if (const auto* s = std::get_if<std::vector<std::string>>(&b)) {
        std::vector<const char*> p;
        p.reserve(s->size());
        for (const auto& x : *s)
            p.push_back(x.c_str());
        h5::write_at(ds, t.mem_type(k), p.data(), offset, n, what);
        return;
    }
    std::visit(
        [&](const auto& v) {
            using V = std::decay_t<decltype(v)>;
            if constexpr (!std::is_same_v<V, std::vector<std::string>>)
                h5::write_at(ds, t.mem_type(k), v.data(), offset, n, what);
        },
        b);
}

Buffer read_buffer(const h5::Id& ds, const Types& t, Kind k, const std::string& what) {
    Buffer b = make_buffer(k);
    if (k == Kind::str) {
        b = h5::read_strings(ds, what);
        return b;
    }
    const hsize_t n = h5::length(ds);
    std::visit(
        [&](auto& v) {
            using V = std::decay_t<decltype(v)>;
            if constexpr (!std::is_same_v<V, std::vector<std::string>>) {
                v.resize(n);
                h5::read_all(ds, t.mem_type(k), v.data(), what);
            }
        },
        b);
    return b;
}

template <class T>
const std::vector<T>& as(const Buffer& b) {
    return std::get<std::vector<T>>(b);
}

// ---------------------------------------------------------------------------------------------
// The realization columns: one value per stored realization, or (ragged) a family of
// concatenated values indexed by <family>_start / <family>_length in /realizations.

struct Src {
    int point;
    const ResultRecord& rec;
    const engine::RealizationResult& r;
};

// Infinite or NaN doubles are never written (the engine guards against them; this is the
// last line of defence): they become 0 and the row's `nonfinite_values` counts them.
double fin(double v) {
    return std::isfinite(v) ? v : 0.0;
}

struct Family {
    const char* name;
    const char* description;
    std::function<std::size_t(const engine::RealizationResult&)> length;
};

const std::vector<Family>& families() {
    static const std::vector<Family> f = {
        {"survival", "survival intervals (survival_times, censored)",
         [](const engine::RealizationResult& r) { return r.survival_times.size(); }},
        {"jam", "jams (jam_onsets, shakes_per_jam)",
         [](const engine::RealizationResult& r) { return r.jam_onsets.size(); }},
        {"exit", "exits (exit_times)",
         [](const engine::RealizationResult& r) { return r.exit_times.size(); }},
        {"curve", "discharge curve samples (curve_time, curve_in_hopper)",
         [](const engine::RealizationResult& r) { return r.curve_time.size(); }},
        {"event", "event log (event_kind, event_time, event_sim_time, event_in_hopper)",
         [](const engine::RealizationResult& r) { return r.events.size(); }},
        // Issue 13: absent from files written before (read_realizations reads such files with
        // none; the writer rebuilds them from the journal).
        {"arch", "arches, one per jam (arch_disks, arch_span, arch_max_angle)",
         [](const engine::RealizationResult& r) { return r.arches.size(); }},
        {"arch_disk",
         "the arches' disks, all arches of the realization in jam order (arch_disk_id, "
         "arch_disk_x, arch_disk_y)",
         [](const engine::RealizationResult& r) {
             std::size_t n = 0;
             for (const auto& a : r.arches)
                 n += a.ids.size();
             return n;
         }},
    };
    return f;
}

struct ColumnDef {
    std::string group;  // "realizations", "realizations/diagnostics" or "ragged"
    std::string name;
    Kind kind;
    std::string units;
    std::string description;
    int family;  // -1: one value per row; otherwise the index in families()
    std::function<void(Buffer&, const Src&)> push;
    std::function<void(StoredRealization&, const Buffer&, std::size_t at, std::size_t n)> pull;
};

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

ColumnDef diag(std::string name, std::string units, std::string description,
               double engine::Diagnostics::*m) {
    return f64_row(
        "realizations/diagnostics", std::move(name), std::move(units), std::move(description),
        [m](const Src& s) { return s.r.diagnostics.*m; },
        [m](StoredRealization& o, double v) { o.result.diagnostics.*m = v; });
}

ColumnDef diag_i64(std::string name, std::string description,
                   std::int64_t engine::Diagnostics::*m) {
    return row<std::int64_t>(
        "realizations/diagnostics", std::move(name), Kind::i64, "1", std::move(description),
        [m](const Src& s) { return s.r.diagnostics.*m; },
        [m](StoredRealization& o, std::int64_t v) { o.result.diagnostics.*m = v; });
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

std::vector<double> to_f64(const double* p, std::size_t n) {
    return {p, p + n};
}
std::vector<int> to_int(const std::int32_t* p, std::size_t n) {
    return {p, p + n};
}

int nonfinite_count(const engine::RealizationResult& r) {
    int n = 0;
    auto count = [&n](double v) { n += std::isfinite(v) ? 0 : 1; };
    for (const auto* v : {&r.survival_times, &r.jam_onsets, &r.exit_times, &r.curve_time})
        for (double x : *v)
            count(x);
    for (const auto& e : r.events) {
        count(e.time);
        count(e.sim_time);
    }
    if (r.empty_time) count(*r.empty_time);
    if (r.discharge_rate) count(*r.discharge_rate);
    count(r.discharge_rate_mass);
    const auto& d = r.diagnostics;
    for (double x :
         {d.settle_time, d.shake_time, d.wall_seconds, d.ns_per_particle_step, d.max_overlap_ratio,
          d.settled_kinetic_energy, d.potential_energy_released, d.dt, d.tau_c, d.k_n,
          d.seconds_forces, d.seconds_integration, d.seconds_neighbors, d.seconds_observers})
        count(x);
    return n;
}

const std::vector<ColumnDef>& columns() {
    using R = engine::RealizationResult;
    using D = engine::Diagnostics;
    const std::string G = "realizations";
    static const std::vector<ColumnDef> c = {
        // Which task, who ran it, when.
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
            "worker that ran it: its MPI rank (1..size-1), or its thread number (1..threads) in a "
            "run without mpirun",
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
        // The engine's result.
        row<std::int8_t>(
            G, "status", Kind::status, "1", "how the realization ended",
            [](const Src& s) { return static_cast<std::int8_t>(s.r.status); },
            [](StoredRealization& o, std::int8_t v) {
                if (v < 0 || v > 3) throw core::StoreError("bad status value in the store");
                o.result.status = static_cast<engine::Status>(v);
            }),
        row<std::string>(
            G, "message", Kind::str, "", "the engine's message (the reason when failed)",
            [](const Src& s) { return s.r.message; },
            [](StoredRealization& o, std::string v) { o.result.message = std::move(v); }),
        row<std::int32_t>(
            G, "particles", Kind::i32, "1", "N at the fill",
            [](const Src& s) { return s.r.particles; },
            [](StoredRealization& o, std::int32_t v) { o.result.particles = v; }),
        row<std::int32_t>(
            G, "wall_particles", Kind::i32, "1", "immobile wall particles",
            [](const Src& s) { return s.r.wall_particles; },
            [](StoredRealization& o, std::int32_t v) { o.result.wall_particles = v; }),
        row<std::int32_t>(
            G, "n_jams", Kind::i32, "1", "jams", [](const Src& s) { return s.r.n_jams; },
            [](StoredRealization& o, std::int32_t v) { o.result.n_jams = v; }),
        row<std::int32_t>(
            G, "n_shakes", Kind::i32, "1", "shakes", [](const Src& s) { return s.r.n_shakes; },
            [](StoredRealization& o, std::int32_t v) { o.result.n_shakes = v; }),
        row<std::int32_t>(
            G, "n_jams_multi_shake", Kind::i32, "1", "jams that needed more than one shake",
            [](const Src& s) { return s.r.n_jams_multi_shake; },
            [](StoredRealization& o, std::int32_t v) { o.result.n_jams_multi_shake = v; }),
        row<std::int32_t>(
            G, "discharged", Kind::i32, "1", "particles that left the hopper",
            [](const Src& s) { return s.r.discharged; },
            [](StoredRealization& o, std::int32_t v) { o.result.discharged = v; }),
        f64_row(
            G, "empty_time", "s",
            "discharge time until the hopper was empty (shaking excluded); 0 when "
            "has_empty_time is false",
            [](const Src& s) { return s.r.empty_time.value_or(0.0); },
            [](StoredRealization& o, double v) { o.result.empty_time = v; }),
        row<std::int8_t>(
            G, "has_empty_time", Kind::boolean, "1", "whether the hopper emptied",
            [](const Src& s) { return static_cast<std::int8_t>(s.r.empty_time ? 1 : 0); },
            [](StoredRealization& o, std::int8_t v) {
                if (!v) o.result.empty_time.reset();
            }),
        f64_row(
            G, "discharge_rate", "1/s",
            "particles per second over the steady part; 0 when has_discharge_rate is false",
            [](const Src& s) { return s.r.discharge_rate.value_or(0.0); },
            [](StoredRealization& o, double v) { o.result.discharge_rate = v; }),
        row<std::int8_t>(
            G, "has_discharge_rate", Kind::boolean, "1", "whether a discharge rate was measured",
            [](const Src& s) { return static_cast<std::int8_t>(s.r.discharge_rate ? 1 : 0); },
            [](StoredRealization& o, std::int8_t v) {
                if (!v) o.result.discharge_rate.reset();
            }),
        f64_row(
            G, "discharge_rate_mass", "kg/s", "mass discharge rate over the steady part (0: none)",
            [](const Src& s) { return s.r.discharge_rate_mass; },
            [](StoredRealization& o, double v) { o.result.discharge_rate_mass = v; }),
        // Diagnostics.
        diag_i64("steps", "time steps (settle + discharge + shaking)", &D::steps),
        diag_i64("settle_steps", "time steps while settling", &D::settle_steps),
        diag_i64("neighbor_rebuilds", "neighbour list rebuilds", &D::neighbor_rebuilds),
        diag("settle_time", "s", "simulated time spent settling", &D::settle_time),
        diag("shake_time", "s", "simulated time spent shaking", &D::shake_time),
        diag("wall_seconds", "s", "wall-clock time of the realization (not reproducible)",
             &D::wall_seconds),
        diag("ns_per_particle_step", "ns", "wall-clock cost per particle and step",
             &D::ns_per_particle_step),
        diag("max_overlap_ratio", "d_small", "largest overlap seen / d_small",
             &D::max_overlap_ratio),
        diag("settled_kinetic_energy", "J", "mean kinetic energy per particle when settled",
             &D::settled_kinetic_energy),
        diag("potential_energy_released", "J", "m g dy of all particles, fill to end",
             &D::potential_energy_released),
        diag("dt", "s", "time step", &D::dt),
        diag("tau_c", "s", "contact duration used", &D::tau_c),
        diag("k_n", "N/m", "normal spring constant", &D::k_n),
        diag("seconds_forces", "s", "wall-clock time in force loops", &D::seconds_forces),
        diag("seconds_integration", "s", "wall-clock time integrating", &D::seconds_integration),
        diag("seconds_neighbors", "s", "wall-clock time in neighbour search",
             &D::seconds_neighbors),
        diag("seconds_observers", "s", "wall-clock time in observers", &D::seconds_observers),
        // Ragged families.
        ragged<double>(
            "survival_times", Kind::f64, 0, "s", "survival intervals in order (discharge time)",
            [](std::vector<double>& v, const R& r) {
                for (double x : r.survival_times)
                    v.push_back(fin(x));
            },
            [](R& r, const double* p, std::size_t n) { r.survival_times = to_f64(p, n); }),
        ragged<std::int8_t>(
            "censored", Kind::boolean, 0, "1", "whether each survival interval is right-censored",
            [](std::vector<std::int8_t>& v, const R& r) {
                for (std::size_t i = 0; i < r.survival_times.size(); ++i)
                    v.push_back(i < r.censored.size() && r.censored[i] ? 1 : 0);
            },
            [](R& r, const std::int8_t* p, std::size_t n) { r.censored.assign(p, p + n); }),
        ragged<double>(
            "jam_onsets", Kind::f64, 1, "s", "discharge time of each jam's onset",
            [](std::vector<double>& v, const R& r) {
                for (double x : r.jam_onsets)
                    v.push_back(fin(x));
            },
            [](R& r, const double* p, std::size_t n) { r.jam_onsets = to_f64(p, n); }),
        ragged<std::int32_t>(
            "shakes_per_jam", Kind::i32, 1, "1", "shakes used on each jam",
            [](std::vector<std::int32_t>& v, const R& r) {
                for (std::size_t i = 0; i < r.jam_onsets.size(); ++i)
                    v.push_back(i < r.shakes_per_jam.size() ? r.shakes_per_jam[i] : 0);
            },
            [](R& r, const std::int32_t* p, std::size_t n) { r.shakes_per_jam = to_int(p, n); }),
        ragged<double>(
            "exit_times", Kind::f64, 2, "s", "discharge time at which each particle left",
            [](std::vector<double>& v, const R& r) {
                for (double x : r.exit_times)
                    v.push_back(fin(x));
            },
            [](R& r, const double* p, std::size_t n) { r.exit_times = to_f64(p, n); }),
        ragged<double>(
            "curve_time", Kind::f64, 3, "s", "discharge curve: sample times (discharge time)",
            [](std::vector<double>& v, const R& r) {
                for (double x : r.curve_time)
                    v.push_back(fin(x));
            },
            [](R& r, const double* p, std::size_t n) { r.curve_time = to_f64(p, n); }),
        ragged<std::int32_t>(
            "curve_in_hopper", Kind::i32, 3, "1", "discharge curve: particles in the hopper",
            [](std::vector<std::int32_t>& v, const R& r) {
                for (std::size_t i = 0; i < r.curve_time.size(); ++i)
                    v.push_back(i < r.curve_count.size() ? r.curve_count[i] : 0);
            },
            [](R& r, const std::int32_t* p, std::size_t n) { r.curve_count = to_int(p, n); }),
        ragged<std::int8_t>(
            "event_kind", Kind::event_kind, 4, "1", "event log: what happened",
            [](std::vector<std::int8_t>& v, const R& r) {
                for (const auto& e : r.events)
                    v.push_back(static_cast<std::int8_t>(e.kind));
            },
            [](R& r, const std::int8_t* p, std::size_t n) {
                r.events.resize(n);
                for (std::size_t i = 0; i < n; ++i) {
                    if (p[i] < 0 || p[i] > 7) throw core::StoreError("bad event kind in the store");
                    r.events[i].kind = static_cast<engine::Event::Kind>(p[i]);
                }
            }),
        ragged<double>(
            "event_time", Kind::f64, 4, "s", "event log: discharge time (shaking excluded)",
            [](std::vector<double>& v, const R& r) {
                for (const auto& e : r.events)
                    v.push_back(fin(e.time));
            },
            [](R& r, const double* p, std::size_t n) {
                r.events.resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    r.events[i].time = p[i];
            }),
        ragged<double>(
            "event_sim_time", Kind::f64, 4, "s", "event log: simulated time since the fill",
            [](std::vector<double>& v, const R& r) {
                for (const auto& e : r.events)
                    v.push_back(fin(e.sim_time));
            },
            [](R& r, const double* p, std::size_t n) {
                r.events.resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    r.events[i].sim_time = p[i];
            }),
        ragged<std::int32_t>(
            "event_in_hopper", Kind::i32, 4, "1", "event log: particles left in the hopper",
            [](std::vector<std::int32_t>& v, const R& r) {
                for (const auto& e : r.events)
                    v.push_back(e.in_hopper);
            },
            [](R& r, const std::int32_t* p, std::size_t n) {
                r.events.resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    r.events[i].in_hopper = p[i];
            }),
        // Issue 13: avalanche sizes and arches (absent in files written before; such files are
        // read with none).
        ragged<std::int32_t>(
            "avalanche_size", Kind::i32, 0, "1",
            "particles that crossed the outlet plane during each survival interval (0 when "
            "has_avalanche_sizes is false)",
            [](std::vector<std::int32_t>& v, const R& r) {
                for (std::size_t i = 0; i < r.survival_times.size(); ++i)
                    v.push_back(i < r.avalanche_sizes.size() ? r.avalanche_sizes[i] : 0);
            },
            [](R& r, const std::int32_t* p, std::size_t n) { r.avalanche_sizes = to_int(p, n); }),
        ragged<std::int32_t>(
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
            }),
        ragged<double>(
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
            }),
        ragged<double>(
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
            }),
        arch_disk_column<std::int32_t>(
            "arch_disk_id", Kind::i32, "1", "particle id of each arch disk, left to right",
            [](const engine::Arch& a, std::size_t k) { return a.ids[k]; },
            [](engine::Arch& a, std::size_t k, std::int32_t v) { a.ids[k] = v; }),
        arch_disk_column<double>(
            "arch_disk_x", Kind::f64, "m", "x of each arch disk's centre when the jam was detected",
            [](const engine::Arch& a, std::size_t k) { return fin(a.x[k]); },
            [](engine::Arch& a, std::size_t k, double v) { a.x[k] = v; }),
        arch_disk_column<double>(
            "arch_disk_y", Kind::f64, "m", "y of each arch disk's centre when the jam was detected",
            [](const engine::Arch& a, std::size_t k) { return fin(a.y[k]); },
            [](engine::Arch& a, std::size_t k, double v) { a.y[k] = v; }),
        // Last, so that its pull sees the avalanche sizes and arches read above.
        row<std::int8_t>(
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
            }),
    };
    return c;
}

// Chunk sizes (elements): rows and tables are short, ragged data long.
constexpr hsize_t row_chunk = 256;
constexpr hsize_t ragged_chunk = 8192;

// ---------------------------------------------------------------------------------------------
// The small tables: /points, /tasks, /runs, /failures.

struct TableColumn {
    std::string name;
    Kind kind;
    std::string units;
    std::string description;
};

const std::vector<TableColumn>& points_columns() {
    static const std::vector<TableColumn> c = {
        {"label", Kind::str, "", "the point's settings, e.g. 'D_cm=2.7 theta_deg=45' (identity)"},
        {"scene", Kind::str, "SI",
         "every scene parameter, one 'name=value' per line, SI units (the physics)"},
        {"physics_hash", Kind::str, "", "FNV-1a 64 of scene, hex"},
        {"D_cm", Kind::f64, "cm", "outlet width D"},
        {"theta_deg", Kind::f64, "deg", "wall angle to the horizontal"},
        {"particles", Kind::i32, "1", "N"},
        {"realizations", Kind::i32, "1", "planned realizations"},
    };
    return c;
}

const std::vector<TableColumn>& tasks_columns() {
    static const std::vector<TableColumn> c = {
        {"point", Kind::i32, "1", "index in /points"},
        {"realization", Kind::i32, "1", "realization index within the point"},
        {"seed", Kind::u64, "1", "the realization's seed"},
        {"state", Kind::task_state, "1",
         "pending | done | failed (result with status failed) | error (attempts raised "
         "exceptions; retried by the next run)"},
        {"row", Kind::i64, "1", "row in /realizations, -1 when none"},
        {"errors", Kind::i32, "1", "attempts that ended in an exception"},
    };
    return c;
}

const std::vector<TableColumn>& runs_columns() {
    static const std::vector<TableColumn> c = {
        {"start_time", Kind::str, "ISO 8601 UTC", "when the run started"},
        {"end_time", Kind::str, "ISO 8601 UTC", "when it ended; empty: running or killed"},
        {"end_reason", Kind::str, "", "complete, interrupted by SIGTERM, ..."},
        {"code_version", Kind::str, "", "hopper version (git describe)"},
        {"compiler", Kind::str, "", "compiler that built it"},
        {"command", Kind::str, "", "command line"},
        {"sweep_path", Kind::str, "", "sweep file as given"},
        {"sweep_text", Kind::str, "", "the sweep file's full text"},
        {"mpi_size", Kind::i32, "1", "processes (1 without mpirun)"},
        {"workers", Kind::i32, "1", "worker processes or threads"},
        {"hosts", Kind::str, "", "host of each process in rank order, comma-separated"},
        {"pid", Kind::i64, "1", "process id of the master"},
        {"stored", Kind::i32, "1", "realizations this run stored"},
        {"wall_seconds", Kind::f64, "s", "duration of the run"},
        {"master_cpu_seconds", Kind::f64, "s", "CPU time the master used"},
        {"lost_worker_seconds", Kind::f64, "s",
         "worker time of realizations interrupted by this run that no checkpoint keeps (thrown "
         "away: computed again later)"},
        {"saved_worker_seconds", Kind::f64, "s",
         "worker time of realizations interrupted by this run kept in checkpoints (continued "
         "later)"},
    };
    return c;
}

const std::vector<TableColumn>& failures_columns() {
    static const std::vector<TableColumn> c = {
        {"point", Kind::i32, "1", "index in /points"},
        {"realization", Kind::i32, "1", "realization index within the point"},
        {"seed", Kind::u64, "1", "the realization's seed"},
        {"rank", Kind::i32, "1", "worker (MPI rank, or thread number without mpirun)"},
        {"attempt", Kind::i32, "1", "attempt number (1 = first)"},
        {"time_unix", Kind::f64, "s", "when it was recorded, seconds since 1970-01-01 UTC"},
        {"reason", Kind::str, "", "the exception's message"},
    };
    return c;
}

void describe(const h5::Id& obj, const std::string& units, const std::string& description) {
    if (!units.empty()) h5::set_attr(obj, "units", units);
    h5::set_attr(obj, "description", description);
}

std::string hosts_text(const std::vector<std::string>& hosts) {
    std::string s;
    for (const auto& h : hosts)
        s += (s.empty() ? "" : ",") + h;
    return s;
}

// ---------------------------------------------------------------------------------------------
// Fields: /fields/<row>, one group per realization that has fields (README, "The HDF5 file").

constexpr const char* fields_group_name = "fields";

std::string field_text(int f) {
    return std::string(engine::field_name(static_cast<engine::Field>(f)));
}

std::string field_units(int f) {
    return std::string(engine::field_unit(static_cast<engine::Field>(f)));
}

// "fields.window_s" -> its value in a point's scene text ("name=value" lines); absent when the
// line is missing or not a finite number ("unset").
std::optional<double> scene_value(const std::string& scene, const std::string& name) {
    const std::string key = name + "=";
    std::size_t at = 0;
    while (at < scene.size()) {
        const std::size_t end = std::min(scene.find('\n', at), scene.size());
        if (scene.compare(at, key.size(), key) == 0) {
            const std::string v = scene.substr(at + key.size(), end - at - key.size());
            char* stop = nullptr;
            const double x = std::strtod(v.c_str(), &stop);
            if (v.empty() || stop != v.c_str() + v.size() || !std::isfinite(x)) return std::nullopt;
            return x;
        }
        at = end + 1;
    }
    return std::nullopt;
}

void write_fields(const h5::Id& parent, const std::string& scene, int point, std::int64_t row,
                  int realization, const engine::FieldMoments& m) {
    const std::string name = std::to_string(row);
    if (h5::exists(parent, name))  // left by an interrupted write: replace it
        h5::check_status(H5Ldelete(parent.get(), name.c_str(), H5P_DEFAULT),
                         "cannot replace /fields/" + name);
    h5::Id g = h5::create_group(parent, name);
    const engine::FieldGrid& grid = m.grid;
    describe(g, "",
             "coarse-grained fields of /realizations row " + name +
                 ": per grid node (ny x nx, row j = y0 + (j + 1/2) cell, column i = x0 + (i + "
                 "1/2) cell) the windows it took part in, the summed weight, and per field the "
                 "mean and M2 (sum of squared deviations) over those windows; lengths in m, "
                 "times in s of discharge time");
    h5::set_attr(g, "row", static_cast<std::int64_t>(row));
    h5::set_attr(g, "point", static_cast<std::int64_t>(point));
    h5::set_attr(g, "realization", static_cast<std::int64_t>(realization));
    h5::set_attr(g, "x0", fin(grid.x0));
    h5::set_attr(g, "y0", fin(grid.y0));
    h5::set_attr(g, "cell", fin(grid.cell));
    h5::set_attr(g, "nx", static_cast<std::int64_t>(grid.nx));
    h5::set_attr(g, "ny", static_cast<std::int64_t>(grid.ny));
    h5::set_attr(g, "kernel", engine::to_string(grid.kernel));
    h5::set_attr(g, "kernel_width", fin(grid.kernel_width));
    for (const char* key : {"window_s", "sample_interval_s", "start_s", "end_s"})
        if (const auto v = scene_value(scene, std::string("fields.") + key))
            h5::set_attr(g, key, *v);
    h5::set_attr(g, "samples", m.samples);
    h5::set_attr(g, "total_windows", m.total_windows);
    h5::set_attr(g, "t_first", fin(m.t_first));
    h5::set_attr(g, "t_last", fin(m.t_last));
    h5::set_attr(g, "wall_diameter", fin(m.wall_diameter));

    const std::vector<hsize_t> dims = {static_cast<hsize_t>(std::max(grid.ny, 0)),
                                       static_cast<hsize_t>(std::max(grid.nx, 0))};
    const std::size_t nodes = static_cast<std::size_t>(dims[0] * dims[1]);
    auto check_size = [&](std::size_t n, const std::string& what) {
        if (n != nodes)
            throw core::StoreError("the fields of row " + name + ": " + what + " has " +
                                   std::to_string(n) + " values for " + std::to_string(grid.nx) +
                                   " x " + std::to_string(grid.ny) + " nodes");
    };
    check_size(m.windows.size(), "windows");
    h5::Id ds =
        layout::write_array(g, "windows", H5T_STD_I64LE, H5T_NATIVE_INT64, m.windows.data(), dims);
    describe(ds, "1", "windows in which the node took part (n)");
    auto real = [&](const std::string& ds_name, const std::vector<double>& v,
                    const std::string& units, const std::string& description) {
        check_size(v.size(), ds_name);
        std::vector<double> x(v.size());
        std::transform(v.begin(), v.end(), x.begin(), fin);
        h5::Id d =
            layout::write_array(g, ds_name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, x.data(), dims);
        describe(d, units, description);
    };
    real("weight", m.weight, "1",
         "summed kernel weight over all samples (cell kernel: particle-samples in the cell)");
    for (int f = 0; f < engine::field_count; ++f) {
        const std::string u = field_units(f);
        real(
            "mean_" + field_text(f), m.mean[f], u,
            "mean over windows of the window value of " + field_text(f) + " (0 where windows = 0)");
        real("m2_" + field_text(f), m.m2[f], "(" + u + ")^2",
             "sum over windows of squared deviations from the mean of " + field_text(f) +
                 " (Welford; merge with Chan et al.)");
    }
    const std::size_t k = std::min(m.outline_x.size(), m.outline_y.size());
    std::vector<double> ox(k), oy(k);
    for (std::size_t i = 0; i < k; ++i) {
        ox[i] = fin(m.outline_x[i]);
        oy[i] = fin(m.outline_y[i]);
    }
    const std::vector<hsize_t> odims = {static_cast<hsize_t>(k)};
    h5::Id dx =
        layout::write_array(g, "outline_x", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ox.data(), odims);
    describe(dx, "m",
             "centre line of the right-hand wall particles from the outlet upwards (mirror x for "
             "the left wall)");
    h5::Id dy =
        layout::write_array(g, "outline_y", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, oy.data(), odims);
    describe(dy, "m", "y of outline_x");
}

template <class T>
std::vector<T> read_array(const h5::Id& g, const std::string& name, hid_t mem_type,
                          const std::vector<hsize_t>& dims, const std::string& where) {
    h5::Id ds = h5::open_dataset(g, name);
    if (layout::dims_of(ds) != dims)
        throw core::StoreError(where + "/" + name + " does not have the grid's shape");
    hsize_t n = 1;
    for (hsize_t d : dims)
        n *= d;
    std::vector<T> v(static_cast<std::size_t>(n));
    if (n > 0)
        h5::check_status(H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()),
                         "cannot read " + where + "/" + name);
    return v;
}

engine::FieldMoments read_fields(const h5::Id& g, const std::string& where) {
    auto need_f64 = [&](const char* name) {
        const auto v = layout::get_f64_attr(g, name);
        if (!v) throw core::StoreError(where + " lacks the attribute " + name);
        return *v;
    };
    auto need_int = [&](const char* name) {
        const auto v = h5::get_int_attr(g, name);
        if (!v) throw core::StoreError(where + " lacks the attribute " + name);
        return *v;
    };
    engine::FieldMoments m;
    engine::FieldGrid& grid = m.grid;
    grid.x0 = need_f64("x0");
    grid.y0 = need_f64("y0");
    grid.cell = need_f64("cell");
    const std::int64_t nx = need_int("nx"), ny = need_int("ny");
    if (nx <= 0 || ny <= 0 || nx > max_field_nodes || ny > max_field_nodes ||
        nx * ny > max_field_nodes)
        throw core::StoreError(where + " has a grid of " + std::to_string(nx) + " x " +
                               std::to_string(ny) + " nodes");
    grid.nx = static_cast<int>(nx);
    grid.ny = static_cast<int>(ny);
    const auto kernel = h5::get_string_attr(g, "kernel");
    if (!kernel || (*kernel != "cell" && *kernel != "gaussian"))
        throw core::StoreError(where + " has no valid kernel attribute");
    grid.kernel = *kernel == "gaussian" ? engine::FieldKernel::gaussian : engine::FieldKernel::cell;
    grid.kernel_width = need_f64("kernel_width");
    m.samples = need_int("samples");
    m.total_windows = need_int("total_windows");
    m.t_first = need_f64("t_first");
    m.t_last = need_f64("t_last");
    m.wall_diameter = need_f64("wall_diameter");
    const std::vector<hsize_t> dims = {static_cast<hsize_t>(ny), static_cast<hsize_t>(nx)};
    m.windows = read_array<std::int64_t>(g, "windows", H5T_NATIVE_INT64, dims, where);
    m.weight = read_array<double>(g, "weight", H5T_NATIVE_DOUBLE, dims, where);
    for (int f = 0; f < engine::field_count; ++f) {
        m.mean[f] = read_array<double>(g, "mean_" + field_text(f), H5T_NATIVE_DOUBLE, dims, where);
        m.m2[f] = read_array<double>(g, "m2_" + field_text(f), H5T_NATIVE_DOUBLE, dims, where);
    }
    auto outline = [&](const char* name) {
        const auto d = layout::dims_of(h5::open_dataset(g, name));
        if (d.size() != 1) throw core::StoreError(where + "/" + name + " is not 1-D");
        return read_array<double>(g, name, H5T_NATIVE_DOUBLE, d, where);
    };
    m.outline_x = outline("outline_x");
    m.outline_y = outline("outline_y");
    if (m.outline_x.size() != m.outline_y.size())
        throw core::StoreError(where + ": outline_x and outline_y differ in length");
    return m;
}

}  // namespace

h5::Id write_array(const h5::Id& loc, const std::string& name, hid_t file_type, hid_t mem_type,
                   const void* data, const std::vector<hsize_t>& dims) {
    const std::string what = "cannot write dataset '" + name + "'";
    if (dims.empty()) throw core::StoreError(what + ": no dimensions");
    hsize_t n = 1;
    for (hsize_t d : dims)
        n *= d;
    h5::Id space(h5::check(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                           what + " (dataspace)"));
    h5::Id dcpl(h5::check(H5Pcreate(H5P_DATASET_CREATE), what + " (properties)"));
    if (n > 0) {
        // Chunks of whole rows (the last dimension), about 1 MB each.
        std::vector<hsize_t> chunk = dims;
        const hsize_t row = std::max<hsize_t>(1, n / dims[0]);
        chunk[0] = std::clamp<hsize_t>((1u << 17) / row, 1, dims[0]);
        h5::check_status(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()),
                         what + " (chunk)");
        if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
            h5::check_status(H5Pset_shuffle(dcpl.get()), what + " (shuffle)");
            h5::check_status(H5Pset_deflate(dcpl.get(), 1), what + " (deflate)");
        }
    }
    h5::Id ds(h5::check(H5Dcreate2(loc.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT,
                                   dcpl.get(), H5P_DEFAULT),
                        what));
    if (n > 0)
        h5::check_status(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), what);
    return ds;
}

std::vector<hsize_t> dims_of(const h5::Id& dataset) {
    h5::Id space(h5::check(H5Dget_space(dataset.get()), "cannot get a dataset's dataspace"));
    const int rank =
        h5::check(H5Sget_simple_extent_ndims(space.get()), "cannot get a dataset's rank");
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    if (rank > 0)
        h5::check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr),
                  "cannot get a dataset's dimensions");
    return dims;
}

std::optional<double> get_f64_attr(const h5::Id& loc, const std::string& name) {
    if (H5Aexists(loc.get(), name.c_str()) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    h5::Id a(H5Aopen(loc.get(), name.c_str(), H5P_DEFAULT));
    if (!a) return std::nullopt;
    h5::Id type(H5Aget_type(a.get()));
    const H5T_class_t c = type ? H5Tget_class(type.get()) : H5T_NO_CLASS;
    double v = 0.0;
    if ((c != H5T_FLOAT && c != H5T_INTEGER) || H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return std::nullopt;
    }
    return v;
}

// ---------------------------------------------------------------------------------------------

struct Writer::Impl {
    fs::path path;
    h5::Id file;
    Types types;
    h5::Id g_real, g_diag, g_ragged, g_points, g_tasks, g_runs, g_failures;
    h5::Id g_fields;  // /fields: created with the first realization that has fields

    struct Col {
        const ColumnDef* def;
        h5::Id ds;
        Buffer buf;
    };
    std::vector<Col> cols;
    struct FamilyIndex {
        h5::Id start_ds, length_ds;
        std::vector<std::int64_t> start;
        std::vector<std::int32_t> length;
        std::int64_t total = 0;    // values written + buffered
        std::int64_t written = 0;  // values written
    };
    std::vector<FamilyIndex> fam;
    std::int64_t rows_written = 0;
    std::int64_t rows_buffered = 0;

    struct Table {
        const std::vector<TableColumn>* defs;
        std::vector<h5::Id> ds;
    };
    Table points, tasks, runs, failures;
    std::vector<Buffer> failure_buf;
    std::int64_t failures_written = 0;

    bool plan_dirty = true;  // /points and all of /tasks
    bool runs_dirty = true;
    std::vector<std::pair<int, int>> changed_tasks;  // (point, realization)
    bool marked_open = false;

    h5::Id& group_of(const std::string& g) {
        if (g == "realizations") return g_real;
        if (g == "realizations/diagnostics") return g_diag;
        return g_ragged;
    }

    void create_schema(const std::string& journal_name) {
        h5::set_attr(file, "format", std::string(format_name));
        h5::set_attr(file, "format_version", format_version);
        h5::set_attr(file, "consistent", std::int64_t{0});
        h5::set_attr(file, "journal", journal_name);
        g_real = h5::create_group(file, "realizations");
        describe(g_real, "",
                 "one row per stored realization, in the order they were stored; ragged data in "
                 "/ragged indexed by <family>_start and <family>_length");
        g_diag = h5::create_group(g_real, "diagnostics");
        describe(g_diag, "", "engine diagnostics, one row per realization (same rows)");
        g_ragged = h5::create_group(file, "ragged");
        describe(g_ragged, "",
                 "concatenated per-realization arrays; realization i's values of family f are "
                 "[f_start[i], f_start[i] + f_length[i]) in /realizations");
        for (const ColumnDef& d : columns()) {
            h5::Id ds = h5::create_column(group_of(d.group), d.name, types.file_type(d.kind),
                                          d.family < 0 ? row_chunk : ragged_chunk);
            describe(ds, d.units, d.description);
        }
        for (const Family& f : families()) {
            h5::Id s =
                h5::create_column(g_real, std::string(f.name) + "_start", H5T_STD_I64LE, row_chunk);
            describe(s, "1",
                     std::string("offset into /ragged of this realization's ") + f.description);
            h5::Id l = h5::create_column(g_real, std::string(f.name) + "_length", H5T_STD_I32LE,
                                         row_chunk);
            describe(l, "1", std::string("number of ") + f.description);
        }
        auto table = [&](const char* name, const char* description,
                         const std::vector<TableColumn>& defs) {
            h5::Id g = h5::create_group(file, name);
            describe(g, "", description);
            for (const auto& c : defs) {
                h5::Id ds = h5::create_column(g, c.name, types.file_type(c.kind), row_chunk);
                describe(ds, c.units, c.description);
            }
            return g;
        };
        g_points = table("points", "one row per point, in the order they entered the campaign",
                         points_columns());
        g_tasks = table("tasks",
                        "one row per planned task: points in /points order, realizations "
                        "ascending",
                        tasks_columns());
        g_runs = table("runs", "one row per `campaign run` (allocation, resume)", runs_columns());
        g_failures = table("failures",
                           "attempts that ended in an exception (no result); results with "
                           "status failed are rows of /realizations",
                           failures_columns());
    }

    void open_handles() {
        g_real = h5::open_group(file, "realizations");
        g_diag = h5::open_group(g_real, "diagnostics");
        g_ragged = h5::open_group(file, "ragged");
        g_points = h5::open_group(file, "points");
        g_tasks = h5::open_group(file, "tasks");
        g_runs = h5::open_group(file, "runs");
        g_failures = h5::open_group(file, "failures");
        if (h5::exists(file, fields_group_name)) g_fields = h5::open_group(file, fields_group_name);
        cols.clear();
        for (const ColumnDef& d : columns())
            cols.push_back(
                Col{&d, h5::open_dataset(group_of(d.group), d.name), make_buffer(d.kind)});
        rows_written = static_cast<std::int64_t>(h5::length(cols.front().ds));
        fam.clear();
        for (const Family& f : families()) {
            FamilyIndex fi;
            fi.start_ds = h5::open_dataset(g_real, std::string(f.name) + "_start");
            fi.length_ds = h5::open_dataset(g_real, std::string(f.name) + "_length");
            fam.push_back(std::move(fi));
        }
        for (const Col& c : cols)
            if (c.def->family >= 0)
                fam[static_cast<std::size_t>(c.def->family)].written =
                    static_cast<std::int64_t>(h5::length(c.ds));
        for (auto& fi : fam)
            fi.total = fi.written;
        for (const Col& c : cols)
            if (c.def->family < 0 && static_cast<std::int64_t>(h5::length(c.ds)) != rows_written)
                throw core::StoreError("the store's /realizations columns differ in length");
        auto open_table = [&](Table& t, const h5::Id& g, const std::vector<TableColumn>& defs) {
            t.defs = &defs;
            t.ds.clear();
            for (const auto& c : defs) {
                // A column added later (the runs table's worker seconds, issue 15) is created
                // in a file written before it; write_runs fills it for every row.
                if (&defs == &runs_columns() && !h5::exists(g, c.name)) {
                    h5::Id ds = h5::create_column(g, c.name, types.file_type(c.kind), row_chunk);
                    describe(ds, c.units, c.description);
                    t.ds.push_back(std::move(ds));
                    continue;
                }
                t.ds.push_back(h5::open_dataset(g, c.name));
            }
        };
        open_table(points, g_points, points_columns());
        open_table(tasks, g_tasks, tasks_columns());
        open_table(runs, g_runs, runs_columns());
        open_table(failures, g_failures, failures_columns());
        failure_buf.clear();
        for (const auto& c : failures_columns())
            failure_buf.push_back(make_buffer(c.kind));
        failures_written = static_cast<std::int64_t>(h5::length(failures.ds.front()));
    }

    void write_table(Table& t, std::vector<Buffer>& bufs, const std::string& group) {
        for (std::size_t i = 0; i < t.ds.size(); ++i) {
            const TableColumn& c = (*t.defs)[i];
            const std::string what = "/" + group + "/" + c.name;
            h5::check_status(
                H5Dset_extent(t.ds[i].get(), std::array<hsize_t, 1>{size_of(bufs[i])}.data()),
                "cannot resize " + what);
            write_buffer(t.ds[i], types, c.kind, bufs[i], 0, what);
        }
    }

    std::vector<Buffer> buffers(const std::vector<TableColumn>& defs) {
        std::vector<Buffer> b;
        for (const auto& c : defs)
            b.push_back(make_buffer(c.kind));
        return b;
    }

    void write_points_and_tasks(const State& s) {
        auto pb = buffers(points_columns());
        for (const auto& p : s.plan.points) {
            std::get<std::vector<std::string>>(pb[0]).push_back(p.label);
            std::get<std::vector<std::string>>(pb[1]).push_back(p.scene);
            std::get<std::vector<std::string>>(pb[2]).push_back(hex64(p.physics_hash()));
            std::get<std::vector<double>>(pb[3]).push_back(fin(p.D_cm));
            std::get<std::vector<double>>(pb[4]).push_back(fin(p.theta_deg));
            std::get<std::vector<std::int32_t>>(pb[5]).push_back(p.particles);
            std::get<std::vector<std::int32_t>>(pb[6]).push_back(p.realizations());
        }
        write_table(points, pb, "points");
        auto tb = buffers(tasks_columns());
        for (std::size_t p = 0; p < s.plan.points.size(); ++p) {
            const int planned = s.plan.points[p].realizations();
            for (int r = 0; r < planned; ++r) {
                const TaskEntry& e = s.tasks[p][static_cast<std::size_t>(r)];
                std::get<std::vector<std::int32_t>>(tb[0]).push_back(static_cast<std::int32_t>(p));
                std::get<std::vector<std::int32_t>>(tb[1]).push_back(r);
                std::get<std::vector<std::uint64_t>>(tb[2]).push_back(
                    s.seed_of(static_cast<int>(p), r));
                std::get<std::vector<std::int8_t>>(tb[3]).push_back(
                    static_cast<std::int8_t>(e.state));
                std::get<std::vector<std::int64_t>>(tb[4]).push_back(e.row);
                std::get<std::vector<std::int32_t>>(tb[5]).push_back(e.errors);
            }
        }
        write_table(tasks, tb, "tasks");
    }

    void write_changed_tasks(const State& s) {
        // Row of task (p, r) in /tasks: the planned realizations of the points before p, plus r.
        std::vector<std::int64_t> offset(s.plan.points.size() + 1, 0);
        for (std::size_t p = 0; p < s.plan.points.size(); ++p)
            offset[p + 1] = offset[p] + s.plan.points[p].realizations();
        for (const auto& [p, r] : changed_tasks) {
            if (r >= s.plan.points[static_cast<std::size_t>(p)].realizations()) continue;
            const TaskEntry& e = s.tasks[static_cast<std::size_t>(p)][static_cast<std::size_t>(r)];
            const hsize_t at = static_cast<hsize_t>(offset[static_cast<std::size_t>(p)] + r);
            const std::int8_t state = static_cast<std::int8_t>(e.state);
            h5::write_at(tasks.ds[3], types.task_state.get(), &state, at, 1, "/tasks/state");
            h5::write_at(tasks.ds[4], H5T_NATIVE_INT64, &e.row, at, 1, "/tasks/row");
            const std::int32_t errors = e.errors;
            h5::write_at(tasks.ds[5], H5T_NATIVE_INT32, &errors, at, 1, "/tasks/errors");
        }
    }

    void write_runs(const State& s) {
        auto b = buffers(runs_columns());
        for (const RunSummary& r : s.runs) {
            auto str = [&](std::size_t i, const std::string& v) {
                std::get<std::vector<std::string>>(b[i]).push_back(v);
            };
            str(0, r.info.start_time);
            str(1, r.end ? r.end->end_time : "");
            str(2, r.end ? r.end->reason : "");
            str(3, r.info.code_version);
            str(4, r.info.compiler);
            str(5, r.info.command);
            str(6, r.info.sweep_path);
            str(7, r.info.sweep_text);
            std::get<std::vector<std::int32_t>>(b[8]).push_back(r.info.mpi_size);
            std::get<std::vector<std::int32_t>>(b[9]).push_back(r.info.workers);
            str(10, hosts_text(r.info.hosts));
            std::get<std::vector<std::int64_t>>(b[11]).push_back(r.info.pid);
            std::get<std::vector<std::int32_t>>(b[12]).push_back(r.stored);
            std::get<std::vector<double>>(b[13]).push_back(r.end ? fin(r.end->wall_seconds) : 0.0);
            std::get<std::vector<double>>(b[14]).push_back(r.end ? fin(r.end->master_cpu_seconds)
                                                                 : 0.0);
            std::get<std::vector<double>>(b[15]).push_back(r.end ? fin(r.end->lost_worker_seconds)
                                                                 : 0.0);
            std::get<std::vector<double>>(b[16]).push_back(r.end ? fin(r.end->saved_worker_seconds)
                                                                 : 0.0);
        }
        write_table(runs, b, "runs");
    }

    void write_root_attrs(const State& s) {
        h5::set_attr(file, "campaign_name", s.plan.name);
        h5::set_attr_u64(file, "campaign_seed", s.plan.seed);
        h5::set_attr(file, "physics_hash", hex64(s.plan.physics_hash()));
        h5::set_attr(file, "realizations_stored", static_cast<std::int64_t>(s.rows));
        if (!s.runs.empty()) h5::set_attr(file, "code_version", s.runs.back().info.code_version);
    }

    void flush_rows() {
        if (rows_buffered == 0) return;
        for (Col& c : cols) {
            const std::string what = "/" + c.def->group + "/" + c.def->name;
            const hsize_t offset =
                c.def->family < 0
                    ? static_cast<hsize_t>(rows_written)
                    : static_cast<hsize_t>(fam[static_cast<std::size_t>(c.def->family)].written);
            write_buffer(c.ds, types, c.def->kind, c.buf, offset, what);
            clear(c.buf);
        }
        for (std::size_t f = 0; f < fam.size(); ++f) {
            FamilyIndex& fi = fam[f];
            const std::string name = "/realizations/" + std::string(families()[f].name);
            h5::write_at(fi.start_ds, H5T_NATIVE_INT64, fi.start.data(),
                         static_cast<hsize_t>(rows_written), fi.start.size(), name + "_start");
            h5::write_at(fi.length_ds, H5T_NATIVE_INT32, fi.length.data(),
                         static_cast<hsize_t>(rows_written), fi.length.size(), name + "_length");
            fi.start.clear();
            fi.length.clear();
            fi.written = fi.total;
        }
        rows_written += rows_buffered;
        rows_buffered = 0;
    }

    void flush_failures() {
        const std::size_t n = size_of(failure_buf.front());
        if (n == 0) return;
        for (std::size_t i = 0; i < failure_buf.size(); ++i) {
            write_buffer(failures.ds[i], types, failures_columns()[i].kind, failure_buf[i],
                         static_cast<hsize_t>(failures_written),
                         "/failures/" + failures_columns()[i].name);
            clear(failure_buf[i]);
        }
        failures_written += static_cast<std::int64_t>(n);
    }
};

Writer::Writer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&&) noexcept = default;
Writer::~Writer() = default;

Writer Writer::create(const fs::path& path, const std::string& journal_name) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->file = h5::create_file(path);
    impl->create_schema(journal_name);
    impl->open_handles();
    return Writer(std::move(impl));
}

Writer Writer::open(const fs::path& path) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->file = h5::open_file(path, true);
    impl->open_handles();
    impl->plan_dirty = false;
    impl->runs_dirty = false;
    return Writer(std::move(impl));
}

void Writer::run_start(const State&, bool plan_changed) {
    if (plan_changed) impl_->plan_dirty = true;
    impl_->runs_dirty = true;
}

void Writer::result(const State& s, int point, std::int64_t row, const ResultRecord& rec,
                    const engine::RealizationResult& r) {
    Impl& m = *impl_;
    if (row != m.rows_written + m.rows_buffered)
        throw core::StoreError("internal: result row " + std::to_string(row) +
                               " out of step with the HDF5 file (" +
                               std::to_string(m.rows_written + m.rows_buffered) + " rows)");
    const Src src{point, rec, r};
    for (auto& c : m.cols)
        c.def->push(c.buf, src);
    for (std::size_t f = 0; f < m.fam.size(); ++f) {
        auto& fi = m.fam[f];
        const std::size_t n = families()[f].length(r);
        fi.start.push_back(fi.total);
        fi.length.push_back(static_cast<std::int32_t>(n));
        fi.total += static_cast<std::int64_t>(n);
    }
    ++m.rows_buffered;
    m.changed_tasks.emplace_back(point, rec.realization);
    m.runs_dirty = true;  // the run's stored count
    if (r.fields) {
        // Written at once (a realization's fields can be large; the rows are small and
        // buffered). The file is marked not consistent from begin_run's flush on, so an
        // interrupted write is rebuilt from the journal.
        if (!m.g_fields) {
            m.g_fields = h5::create_group(m.file, fields_group_name);
            describe(m.g_fields, "",
                     "coarse-grained velocity and pressure fields: one group per realization "
                     "that has them, named by its row in /realizations");
        }
        write_fields(m.g_fields, s.plan.points.at(static_cast<std::size_t>(point)).scene, point,
                     row, rec.realization, *r.fields);
    }
}

void Writer::error(const State& s, int point, const ErrorRecord& rec) {
    Impl& m = *impl_;
    std::get<std::vector<std::int32_t>>(m.failure_buf[0]).push_back(point);
    std::get<std::vector<std::int32_t>>(m.failure_buf[1]).push_back(rec.realization);
    std::get<std::vector<std::uint64_t>>(m.failure_buf[2]).push_back(rec.seed);
    std::get<std::vector<std::int32_t>>(m.failure_buf[3]).push_back(rec.rank);
    std::get<std::vector<std::int32_t>>(m.failure_buf[4]).push_back(rec.attempt);
    std::get<std::vector<double>>(m.failure_buf[5]).push_back(fin(rec.time_unix));
    std::get<std::vector<std::string>>(m.failure_buf[6]).push_back(rec.reason);
    m.changed_tasks.emplace_back(point, rec.realization);
    (void)s;
}

void Writer::run_end(const State&) {
    impl_->runs_dirty = true;
}

void Writer::flush(const State& s, bool partial) {
    Impl& m = *impl_;
    if (!m.marked_open) {
        h5::set_attr(m.file, "consistent", std::int64_t{0});
        m.marked_open = true;
    }
    m.flush_rows();
    if (partial) return;
    m.flush_failures();
    if (m.plan_dirty) {
        m.write_points_and_tasks(s);
        m.plan_dirty = false;
    } else {
        m.write_changed_tasks(s);
    }
    m.changed_tasks.clear();
    if (m.runs_dirty) {
        m.write_runs(s);
        m.runs_dirty = false;
    }
    m.write_root_attrs(s);
    h5::flush(m.file);
}

void Writer::close(const State& s, std::uint64_t token, std::uint64_t journal_bytes) {
    flush(s);
    Impl& m = *impl_;
    h5::set_attr_u64(m.file, "sync_token", token);
    h5::set_attr_u64(m.file, "journal_bytes", journal_bytes);
    h5::set_attr(m.file, "consistent", std::int64_t{1});
    // Close every handle, then the file (checked).
    m.cols.clear();
    m.fam.clear();
    m.points.ds.clear();
    m.tasks.ds.clear();
    m.runs.ds.clear();
    m.failures.ds.clear();
    for (h5::Id* g : {&m.g_real, &m.g_diag, &m.g_ragged, &m.g_points, &m.g_tasks, &m.g_runs,
                      &m.g_failures, &m.g_fields})
        g->reset();
    h5::close_file(m.file);
}

Inspection inspect(const fs::path& path) {
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

std::vector<StoredRealization> read_realizations(const fs::path& path) {
    const Inspection in = inspect(path);
    if (!in.readable)
        throw core::StoreError("cannot read store '" + path.string() + "': " + in.problem);
    h5::Id file = h5::open_file(path, false);
    Types types;
    const std::vector<std::string> labels = h5::read_strings(
        h5::open_dataset(h5::open_group(file, "points"), "label"), "/points/label");
    h5::Id g_real = h5::open_group(file, "realizations");
    h5::Id g_diag = h5::open_group(g_real, "diagnostics");
    h5::Id g_ragged = h5::open_group(file, "ragged");
    std::vector<Buffer> bufs;
    // Columns added later (issue 13: avalanche sizes, arches) are absent from older files:
    // their realizations are read without them.
    std::vector<bool> present;
    for (const ColumnDef& d : columns()) {
        const h5::Id& g = d.group == "realizations" ? g_real
                          : d.group == "ragged"     ? g_ragged
                                                    : g_diag;
        present.push_back(h5::exists(g, d.name));
        bufs.push_back(present.back() ? read_buffer(h5::open_dataset(g, d.name), types, d.kind,
                                                    "/" + d.group + "/" + d.name)
                                      : make_buffer(d.kind));
    }
    std::vector<std::vector<std::int64_t>> starts;
    std::vector<std::vector<std::int32_t>> lengths;
    std::vector<bool> family_present;
    for (const Family& f : families()) {
        const std::string start = std::string(f.name) + "_start";
        family_present.push_back(h5::exists(g_real, start));
        if (!family_present.back()) {
            starts.emplace_back();
            lengths.emplace_back();
            continue;
        }
        starts.push_back(as<std::int64_t>(
            read_buffer(h5::open_dataset(g_real, start), types, Kind::i64, f.name)));
        lengths.push_back(as<std::int32_t>(read_buffer(
            h5::open_dataset(g_real, std::string(f.name) + "_length"), types, Kind::i32, f.name)));
    }
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (columns()[i].family >= 0 &&
            !family_present[static_cast<std::size_t>(columns()[i].family)])
            present[i] = false;
    const std::size_t rows = size_of(bufs.front());
    for (std::size_t i = 0; i < columns().size(); ++i)
        if (present[i] && columns()[i].family < 0 && size_of(bufs[i]) != rows)
            throw core::StoreError("store '" + path.string() + "': /realizations/" +
                                   columns()[i].name + " has " + std::to_string(size_of(bufs[i])) +
                                   " rows, expected " + std::to_string(rows));
    for (std::size_t f = 0; f < families().size(); ++f)
        if (family_present[f] && (starts[f].size() != rows || lengths[f].size() != rows))
            throw core::StoreError("store '" + path.string() +
                                   "': a ragged index has the wrong length");
    std::vector<StoredRealization> out(rows);
    for (std::size_t row = 0; row < rows; ++row) {
        StoredRealization& o = out[row];
        for (std::size_t i = 0; i < columns().size(); ++i) {
            const ColumnDef& d = columns()[i];
            if (!present[i]) continue;
            if (d.family < 0) {
                d.pull(o, bufs[i], row, 1);
            } else {
                const auto f = static_cast<std::size_t>(d.family);
                const std::int64_t start = starts[f][row];
                const std::int32_t n = lengths[f][row];
                if (start < 0 || n < 0)
                    throw core::StoreError("negative ragged index in the store");
                d.pull(o, bufs[i], static_cast<std::size_t>(start), static_cast<std::size_t>(n));
            }
        }
        if (o.point < 0 || static_cast<std::size_t>(o.point) >= labels.size())
            throw core::StoreError("store '" + path.string() + "': row " + std::to_string(row) +
                                   " names point " + std::to_string(o.point) + " of " +
                                   std::to_string(labels.size()));
        o.label = labels[static_cast<std::size_t>(o.point)];
        o.record.label = o.label;
    }
    if (h5::exists(file, fields_group_name)) {
        h5::Id g_fields = h5::open_group(file, fields_group_name);
        for (std::size_t row = 0; row < rows; ++row) {
            const std::string name = std::to_string(row);
            if (!h5::exists(g_fields, name)) continue;
            out[row].result.fields = read_fields(h5::open_group(g_fields, name),
                                                 "store '" + path.string() + "': /fields/" + name);
        }
    }
    return out;
}

}  // namespace hopper::store::layout
