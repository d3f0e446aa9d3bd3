// Writing a store file: its schema when created, then the journal's state as it grows
// (realization rows buffered and flushed together, the small tables rewritten when they change).

#include <algorithm>
#include <map>
#include <type_traits>
#include <variant>

#include "hopper/core/error.hpp"
#include "layout.hpp"
#include "schema.hpp"

namespace hopper::store::layout {

namespace fs = std::filesystem;

namespace {

std::string hosts_text(const std::vector<std::string>& hosts) {
    std::string s;
    for (const auto& h : hosts)
        s += (s.empty() ? "" : ",") + h;
    return s;
}

}  // namespace

struct Writer::Impl {
    h5::QuietErrors quiet;  // first: outlives every handle below
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

    PointParameters parameters;  // /points/parameters (none when empty)
    bool plan_dirty = true;      // /points and all of /tasks
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
        std::vector<std::string> members(families().size());  // each family's arrays
        for (const ColumnDef& d : columns()) {
            h5::Id ds = h5::create_column(group_of(d.group), d.name, types.file_type(d.kind),
                                          d.family < 0 ? row_chunk : ragged_chunk);
            describe(ds, d.units, d.description);
            if (d.family >= 0) {
                const auto fi = static_cast<std::size_t>(d.family);
                h5::set_attr(ds, "family", std::string(families()[fi].name));
                members[fi] += (members[fi].empty() ? "" : ", ") + d.name;
            }
            if (d.since > 1) h5::set_attr(ds, "since", std::int64_t{d.since});
        }
        for (const RaggedFamily& f : families()) {
            const std::string what =
                std::string(f.description) + " (" + members[std::size_t(&f - &families()[0])] + ")";
            h5::Id s = h5::create_column(g_real, std::string(f.name) + "_start",
                                         h5::file_type(h5::Scalar::i64), row_chunk);
            describe(s, "1", "offset into /ragged of this realization's " + what);
            h5::Id l = h5::create_column(g_real, std::string(f.name) + "_length",
                                         h5::file_type(h5::Scalar::i32), row_chunk);
            describe(l, "1", "number of " + what);
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
        for (const RaggedFamily& f : families()) {
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
            h5::set_length(t.ds[i], size_of(bufs[i]), what);
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
        write_point_parameters(s);
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

    // /points/parameters: one compound dataset, a record per point (its row in /points) with a
    // typed member per scene parameter, rewritten whole with /points (the plan changes once per
    // run at most). Members' units and descriptions are attributes, one element per member
    // (docs/store.md). A file without it (written without parameters, or by a version before
    // them) gets it at the next change of the plan.
    void write_point_parameters(const State& s) {
        if (!parameters) return;
        if (h5::exists(g_points, "parameters"))
            h5::remove(g_points, "parameters", "/points/parameters");
        const std::vector<DerivedDataset> columns = parameters(s.plan, s.runs);
        std::vector<h5::RecordField> fields;
        std::vector<std::string> units, descriptions;
        std::map<std::string, std::vector<std::string>> extra;  // further attributes, by name
        for (const auto& c : columns) {
            h5::RecordField f{c.name};
            std::visit(
                [&f](const auto& v) {
                    using T = std::decay_t<decltype(v)>;
                    if constexpr (std::is_same_v<T, std::vector<double>>) f.f64 = &v;
                    if constexpr (std::is_same_v<T, std::vector<std::int64_t>>) f.i64 = &v;
                    if constexpr (std::is_same_v<T, std::vector<std::string>>) f.text = &v;
                    if constexpr (std::is_same_v<T, std::vector<bool>>) f.flag = &v;
                },
                c.values);
            fields.push_back(f);
            const bool text = std::holds_alternative<std::vector<std::string>>(c.values);
            units.push_back(text ? std::string() : c.units.empty() ? std::string("1") : c.units);
            descriptions.push_back(c.description);
            for (const auto& [k, v] : c.attributes)
                extra[k].resize(columns.size());
        }
        for (std::size_t i = 0; i < columns.size(); ++i)
            for (const auto& [k, v] : columns[i].attributes)
                extra[k][i] = v;
        h5::Id ds = h5::write_records(g_points, "parameters", fields, s.plan.points.size());
        h5::set_attr(ds, "description",
                     std::string("every scene parameter of each point (record: the point's row "
                                 "in /points), typed, in SI; generated from the scene schema"));
        h5::set_attr(ds, "units", units);
        h5::set_attr(ds, "descriptions", descriptions);
        for (const auto& [k, v] : extra)
            h5::set_attr(ds, k, v);
    }

    void write_changed_tasks(const State& s) {
        // Row of task (p, r) in /tasks: the planned realizations of the points before p, plus r.
        std::vector<std::int64_t> offset(s.plan.points.size() + 1, 0);
        for (std::size_t p = 0; p < s.plan.points.size(); ++p)
            offset[p + 1] = offset[p] + s.plan.points[p].realizations();
        for (const auto& [p, r] : changed_tasks) {
            if (r >= s.plan.points[static_cast<std::size_t>(p)].realizations()) continue;
            const TaskEntry& e = s.tasks[static_cast<std::size_t>(p)][static_cast<std::size_t>(r)];
            const h5::hsize at = static_cast<h5::hsize>(offset[static_cast<std::size_t>(p)] + r);
            const std::int8_t state = static_cast<std::int8_t>(e.state);
            h5::write_at(tasks.ds[3], types.task_state.get(), &state, at, 1, "/tasks/state");
            h5::write_at(tasks.ds[4], h5::mem_type(h5::Scalar::i64), &e.row, at, 1, "/tasks/row");
            const std::int32_t errors = e.errors;
            h5::write_at(tasks.ds[5], h5::mem_type(h5::Scalar::i32), &errors, at, 1,
                         "/tasks/errors");
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
            const h5::hsize offset =
                c.def->family < 0
                    ? static_cast<h5::hsize>(rows_written)
                    : static_cast<h5::hsize>(fam[static_cast<std::size_t>(c.def->family)].written);
            write_buffer(c.ds, types, c.def->kind, c.buf, offset, what);
            clear(c.buf);
        }
        for (std::size_t f = 0; f < fam.size(); ++f) {
            FamilyIndex& fi = fam[f];
            const std::string name = "/realizations/" + std::string(families()[f].name);
            h5::write_at(fi.start_ds, h5::mem_type(h5::Scalar::i64), fi.start.data(),
                         static_cast<h5::hsize>(rows_written), fi.start.size(), name + "_start");
            h5::write_at(fi.length_ds, h5::mem_type(h5::Scalar::i32), fi.length.data(),
                         static_cast<h5::hsize>(rows_written), fi.length.size(), name + "_length");
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
                         static_cast<h5::hsize>(failures_written),
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

Writer Writer::create(const fs::path& path, const std::string& journal_name,
                      PointParameters parameters) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->parameters = std::move(parameters);
    impl->file = h5::create_file(path);
    impl->create_schema(journal_name);
    impl->open_handles();
    return Writer(std::move(impl));
}

Writer Writer::open(const fs::path& path, PointParameters parameters) {
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->parameters = std::move(parameters);
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

void Writer::allotment(const State&, bool plan_changed) {
    if (plan_changed) impl_->plan_dirty = true;
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

}  // namespace hopper::store::layout
