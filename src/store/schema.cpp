// Column kinds, their HDF5 types and buffers; the small tables' columns. See schema.hpp.

#include "schema.hpp"

#include <cmath>

namespace hopper::store::layout {

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

Types::Types()
    : status(h5::enum_type({{"complete", 0}, {"arrested", 1}, {"time_limit", 2}, {"failed", 3}})),
      boolean(h5::bool_type()),
      event_kind(h5::enum_type({{"settled", 0},
                                {"opened", 1},
                                {"jam", 2},
                                {"shake_start", 3},
                                {"shake_end", 4},
                                {"flow_restart", 5},
                                {"empty", 6},
                                {"stop", 7}})),
      task_state(h5::enum_type({{"pending", 0}, {"done", 1}, {"failed", 2}, {"error", 3}})),
      str(h5::string_type()) {}

h5::hid Types::file_type(Kind k) const {
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
            return h5::file_type(h5::Scalar::i32);
        case Kind::i64:
            return h5::file_type(h5::Scalar::i64);
        case Kind::u64:
            return h5::file_type(h5::Scalar::u64);
        case Kind::f64:
            return h5::file_type(h5::Scalar::f64);
        case Kind::str:
            return str.get();
    }
    return h5::file_type(h5::Scalar::f64);
}

h5::hid Types::mem_type(Kind k) const {
    switch (k) {
        case Kind::i32:
            return h5::mem_type(h5::Scalar::i32);
        case Kind::i64:
            return h5::mem_type(h5::Scalar::i64);
        case Kind::u64:
            return h5::mem_type(h5::Scalar::u64);
        case Kind::f64:
            return h5::mem_type(h5::Scalar::f64);
        default:
            return file_type(k);  // enums and strings: the same type in memory
    }
}

void write_buffer(const h5::Id& ds, const Types& t, Kind k, const Buffer& b, h5::hsize offset,
                  const std::string& what) {
    const h5::hsize n = size_of(b);
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
    const h5::hsize n = h5::length(ds);
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

double fin(double v) {
    return std::isfinite(v) ? v : 0.0;
}

// The small tables: /points, /tasks, /runs, /failures.

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

}  // namespace hopper::store::layout
