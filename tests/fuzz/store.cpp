// Store cases: a copy of a real store (made once per run by prepare_stores() through
// store::Store with fabricated results), damaged by one of the kinds below, then exercised by
// every reader and the writer:
//   status          store::read_status, and `campaign status`'s JSON and table
//   journal_read    store::read_journal_realizations
//   h5_read         store::read_realizations
//   analyze         `campaign analyze`'s entry point (cli::analyze_store, --json and tables,
//                   --no-write)
//   store_run       store::Store (open), begin_run, one result and one error appended when a
//                   task is pending, end_run
//   after_run       when store_run succeeded: read_status (in step), read_realizations and
//                   analyze with writing /analysis must succeed
// Each must end in a core::Error (StoreError, ConfigError) with a message, or succeed with finite
// data; JSON and tables never show "nan" or "inf".

#include <cxxabi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <sstream>
#include <typeinfo>

#include "cli/analyze.hpp"
#include "cli/status.hpp"
#include "fuzz.hpp"
#include "hopper/campaign/plan.hpp"
#include "hopper/config/sweep.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/analysis.hpp"
#include "hopper/store/codec.hpp"
#include "hopper/store/journal.hpp"
#include "hopper/store/store.hpp"

namespace hopper::fuzz {

namespace {

// --------------------------------------------------------------------------------------------
// The undamaged stores.

// A plausible result of realization `seed` of a point with `particles` particles.
engine::RealizationResult fabricate(std::uint64_t seed, int particles, int k) {
    Gen g(seed);
    engine::RealizationResult r;
    const int s = static_cast<int>(g.below(10));
    r.status = s < 6   ? engine::Status::complete
               : s < 8 ? engine::Status::arrested
               : s < 9 ? engine::Status::time_limit
                       : engine::Status::failed;
    r.message = r.status == engine::Status::failed
                    ? "overlap above max_overlap (fabricated " + std::to_string(k) + ")"
                    : "fabricated result " + std::to_string(k);
    r.seed = seed;
    r.particles = particles;
    r.wall_particles = 120;
    const int intervals = static_cast<int>(g.range(1, 6));
    double t = 0.0;
    for (int i = 0; i < intervals; ++i) {
        const double dt = g.uniform() * 2.0 + 0.01;
        r.survival_times.push_back(dt);
        const bool last = i + 1 == intervals;
        const bool censored = last && r.status != engine::Status::arrested;
        r.censored.push_back(censored);
        t += dt;
        if (!censored) {
            r.jam_onsets.push_back(t);
            r.shakes_per_jam.push_back(static_cast<int>(g.range(1, 3)));
            r.events.push_back({engine::Event::Kind::jam, t, t + 0.3, particles / 2});
        }
    }
    r.n_jams = static_cast<int>(r.jam_onsets.size());
    for (int n : r.shakes_per_jam) {
        r.n_shakes += n;
        if (n > 1) ++r.n_jams_multi_shake;
    }
    r.events.insert(r.events.begin(), {{engine::Event::Kind::settled, 0.0, 0.3, particles},
                                       {engine::Event::Kind::opened, 0.0, 0.3, particles}});
    if (r.status == engine::Status::complete) {
        r.empty_time = t;
        r.discharged = particles;
        r.events.push_back({engine::Event::Kind::empty, t, t + 0.4, 0});
    } else {
        r.discharged = particles / 2;
    }
    if (r.status != engine::Status::failed) {
        r.discharge_rate = 50.0 + 10.0 * g.uniform();
        r.discharge_rate_mass = 0.005 * *r.discharge_rate;
    }
    for (int i = 0; i < std::min(r.discharged, 250); ++i)
        r.exit_times.push_back(t * (i + 1) / (std::min(r.discharged, 250) + 1));
    for (int i = 0; i < 20; ++i) {
        r.curve_time.push_back(0.01 * i);
        r.curve_count.push_back(particles - i * particles / 40);
    }
    auto& d = r.diagnostics;
    d.steps = 100000 + static_cast<std::int64_t>(g.below(1000));
    d.settle_steps = 20000;
    d.neighbor_rebuilds = 300;
    d.settle_time = 0.3;
    d.shake_time = 0.05 * r.n_shakes;
    d.wall_seconds = 1.5;
    d.ns_per_particle_step = 40.0;
    d.max_overlap_ratio = 0.02;
    d.settled_kinetic_energy = 1e-9;
    d.potential_energy_released = 0.01;
    d.dt = 1.6e-5;
    d.tau_c = 8e-4;
    d.k_n = 1149.0;
    d.seconds_forces = 1.0;
    d.seconds_integration = 0.3;
    d.seconds_neighbors = 0.1;
    d.seconds_observers = 0.1;
    return r;
}

store::ResultRecord result_record(const store::PointPlan& p, int realization, int k) {
    store::ResultRecord rec;
    rec.label = p.label;
    rec.realization = realization;
    rec.seed = p.seeds.at(static_cast<std::size_t>(realization));
    rec.rank = 1 + k % 2;
    rec.task_seconds = 1.0 + 0.1 * k;
    rec.finished_unix = 1.7e9 + k;
    rec.result = store::encode_result(fabricate(rec.seed, p.particles, k));
    return rec;
}

store::RunStartRecord run_record(const store::CampaignPlan& plan, const std::string& sweep) {
    store::RunStartRecord r;
    r.run.start_time = "2024-05-01T12:00:00Z";
    r.run.code_version = "fuzz_inputs";
    r.run.compiler = "fuzz";
    r.run.command = "fuzz_inputs";
    r.run.sweep_path = sweep;
    r.run.sweep_text = "# fabricated by fuzz_inputs\n";
    r.run.hosts = {"localhost", "localhost"};
    r.run.mpi_size = 1;
    r.run.workers = 2;
    r.run.pid = 4242;
    r.plan = plan;
    return r;
}

store::RunEndRecord end_record(int stored, const std::string& reason = "complete") {
    return store::RunEndRecord{"2024-05-01T12:05:00Z", reason, stored, 300.0, 1.5};
}

// The plan of a shipped sweep file with `realizations` per point.
store::CampaignPlan plan_of(const Context& ctx, const char* file, int realizations) {
    config::SweepFile sf = config::load_sweep(ctx.campaigns / file);
    for (auto& p : sf.campaign.points)
        p.realizations = realizations;
    return campaign::make_plan(sf.campaign);
}

fs::path base_dir(const Context& ctx, const std::string& which) {
    return ctx.workdir / "base" / which;
}

// tiny.toml's two points with 4 realizations in run 1, extended to 6 in run 2; in the "crashed"
// store run 2 never ends (the writer was killed: no end or sync record, HDF5 not in step).
void make_base(const Context& ctx, const std::string& which) {
    const fs::path dir = base_dir(ctx, which);
    fs::create_directories(dir);
    const fs::path p = dir / "s.h5";
    int k = 0;
    if (which == "other") {
        const store::CampaignPlan plan = plan_of(ctx, "quickstart.toml", 1);
        store::Store s(p);
        s.begin_run(run_record(plan, "quickstart.toml"));
        for (int i = 0; i < 2; ++i)
            s.append(result_record(plan.points[static_cast<std::size_t>(i)], 0, k++));
        s.end_run(end_record(2));
        return;
    }
    const store::CampaignPlan plan4 = plan_of(ctx, "tiny.toml", 4);
    const store::CampaignPlan plan6 = plan_of(ctx, "tiny.toml", 6);
    {
        store::Store s(p);
        s.begin_run(run_record(plan4, "tiny.toml"));
        int stored = 0;
        for (const auto& pt : plan4.points)
            for (int r = 0; r < 4; ++r) {
                if (r == 3 && &pt == &plan4.points.front()) {
                    s.append(store::ErrorRecord{pt.label, r, pt.seeds[3], 1, 1, 1.7e9,
                                                "std::bad_alloc (fabricated)"});
                    continue;
                }
                s.append(result_record(pt, r, k++));
                ++stored;
            }
        s.end_run(end_record(stored, "interrupted by SIGUSR1"));
    }
    {
        store::Store s(p);
        s.begin_run(run_record(plan6, "tiny.toml"));
        int stored = 0;
        for (const auto& pt : plan6.points)
            for (int r = 3; r < 6; ++r)
                if (!s.task(pt.label, r) || s.task(pt.label, r)->state != store::TaskState::done) {
                    s.append(result_record(pt, r, k++));
                    ++stored;
                }
        if (which == "clean") s.end_run(end_record(stored));
    }
    if (which == "clean") {
        std::ostringstream out, err;
        if (cli::analyze_store(p, true, true, out, err) != 0)
            throw std::runtime_error("fuzz_inputs: cannot analyze the base store: " + err.str());
    }
}

// --------------------------------------------------------------------------------------------
// Journal records, for damage that keeps the checksums valid.

struct Rec {
    std::uint8_t type = 0;
    std::string payload;
};

struct JournalBytes {
    std::string header;
    std::vector<Rec> records;
    std::string tail;  // bytes after the last complete record
};

std::uint32_t get_u32(const std::string& s, std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
        v |= static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + i])) << (8 * i);
    return v;
}

void put_u32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        s += static_cast<char>((v >> (8 * i)) & 0xff);
}

JournalBytes parse_journal(const std::string& bytes) {
    JournalBytes j;
    j.header = bytes.substr(0, std::min<std::size_t>(bytes.size(), store::journal_header_size));
    std::size_t pos = j.header.size();
    while (pos + store::record_header_size <= bytes.size()) {
        const std::uint32_t len = get_u32(bytes, pos + 8);
        if (pos + store::record_header_size + len > bytes.size()) break;
        j.records.push_back(Rec{static_cast<std::uint8_t>(bytes[pos + 4]),
                                bytes.substr(pos + store::record_header_size, len)});
        pos += store::record_header_size + len;
    }
    j.tail = bytes.substr(pos);
    return j;
}

std::string record_bytes(const Rec& r) {
    std::string s;
    put_u32(s, 0x43524A48);  // "HJRC"
    s += static_cast<char>(r.type);
    s += std::string(3, '\0');
    put_u32(s, static_cast<std::uint32_t>(r.payload.size()));
    std::uint8_t head[8] = {r.type, 0, 0, 0};
    for (int i = 0; i < 4; ++i)
        head[4 + i] = static_cast<std::uint8_t>((r.payload.size() >> (8 * i)) & 0xff);
    const auto* p = reinterpret_cast<const std::uint8_t*>(r.payload.data());
    put_u32(s, store::crc32c(std::span<const std::uint8_t>(p, r.payload.size()),
                             store::crc32c(std::span<const std::uint8_t>(head, 8))));
    return s + r.payload;
}

std::string journal_bytes(const JournalBytes& j) {
    std::string s = j.header;
    for (const auto& r : j.records)
        s += record_bytes(r);
    return s;
}

const char* type_name(std::uint8_t t) {
    static const char* names[] = {"?", "run_start", "result", "error", "run_end", "sync"};
    return t >= 1 && t <= 5 ? names[t] : "unknown";
}

// One record's payload changed, its checksum made valid again: a journal that frames
// correctly but says something no writer wrote.
std::string reseal(std::string& bytes, Gen& g) {
    JournalBytes j = parse_journal(bytes);
    if (j.records.empty()) return "";
    // Prefer the records with structure: run starts and results.
    std::size_t i = g.below(j.records.size());
    for (int t = 0; t < 3 && j.records[i].type != 1 && j.records[i].type != 2; ++t)
        i = g.below(j.records.size());
    Rec& r = j.records[i];
    std::string& p = r.payload;
    std::string desc = "record " + std::to_string(i) + " (" + type_name(r.type) + ", " +
                       std::to_string(p.size()) + " B): ";
    const int what = static_cast<int>(g.below(8));
    if (p.empty() && what != 5 && what != 6) return "";
    const std::size_t at = p.empty() ? 0 : g.below(p.size());
    switch (what) {
        case 0: {
            const int n = static_cast<int>(g.range(1, 4));
            for (int k = 0; k < n; ++k) {
                const std::size_t b = g.below(p.size());
                p[b] = static_cast<char>(p[b] ^ (1 << g.below(8)));
            }
            desc += std::to_string(n) + " bit flip(s) from byte " + std::to_string(at);
            break;
        }
        case 1: {
            static const std::uint32_t words[] = {0xFFFFFFFFu, 0x7FFFFFFFu, 0x80000000u,
                                                  0u,          0x40000000u, 0x00010000u};
            const std::uint32_t w = words[g.below(6)];
            for (int k = 0; k < 4 && at + k < p.size(); ++k)
                p[at + k] = static_cast<char>((w >> (8 * k)) & 0xff);
            char buf[64];
            std::snprintf(buf, sizeof buf, "u32 0x%08x at byte %zu", w, at);
            desc += buf;
            break;
        }
        case 2: {
            static const std::uint64_t bits[] = {0x7FF8000000000000ull, 0x7FF0000000000000ull,
                                                 0xFFF0000000000000ull, 0x8000000000000000ull,
                                                 0x7FEFFFFFFFFFFFFFull, 0x0000000000000001ull};
            const std::uint64_t b = bits[g.below(6)];
            for (int k = 0; k < 8 && at + k < p.size(); ++k)
                p[at + k] = static_cast<char>((b >> (8 * k)) & 0xff);
            char buf[64];
            std::snprintf(buf, sizeof buf, "f64 bits 0x%016llx at byte %zu",
                          static_cast<unsigned long long>(b), at);
            desc += buf;
            break;
        }
        case 3:
            p.resize(at);
            desc += "payload cut to " + std::to_string(at) + " B";
            break;
        case 4: {
            const std::size_t n = g.range(1, 64);
            for (std::size_t k = 0; k < n; ++k)
                p += static_cast<char>(g.below(256));
            desc += std::to_string(n) + " random bytes appended";
            break;
        }
        case 5: {
            static const std::uint8_t types[] = {0, 1, 2, 3, 4, 5, 6, 255};
            const std::uint8_t t = types[g.below(8)];
            desc += std::string("type ") + type_name(r.type) + " -> " + std::to_string(t);
            r.type = t;
            break;
        }
        case 6:
            p.clear();
            desc += "payload emptied";
            break;
        default: {
            const std::size_t n = std::min<std::size_t>(p.size() - at, g.range(1, 32));
            for (std::size_t k = 0; k < n; ++k)
                p[at + k] = static_cast<char>(g.below(256));
            desc += std::to_string(n) + " random bytes at " + std::to_string(at);
        }
    }
    bytes = journal_bytes(j) + j.tail;
    return desc;
}

// Whole records dropped, repeated, reordered or taken from another store's journal.
std::string shuffle_records(std::string& bytes, const std::string& other, Gen& g) {
    JournalBytes j = parse_journal(bytes);
    if (j.records.empty()) return "";
    const JournalBytes o = parse_journal(other);
    const std::size_t n = j.records.size();
    const std::size_t i = g.below(n), k = g.below(n);
    std::string desc;
    switch (g.below(8)) {
        case 0:
            desc =
                "dropped record " + std::to_string(i) + " (" + type_name(j.records[i].type) + ")";
            j.records.erase(j.records.begin() + static_cast<long>(i));
            break;
        case 1:
            desc = "repeated record " + std::to_string(i) + " (" + type_name(j.records[i].type) +
                   ") at " + std::to_string(k);
            j.records.insert(j.records.begin() + static_cast<long>(k), j.records[i]);
            break;
        case 2:
            desc = "swapped records " + std::to_string(i) + " and " + std::to_string(k);
            std::swap(j.records[i], j.records[k]);
            break;
        case 3: {
            desc = "dropped every run_start record";
            std::erase_if(j.records, [](const Rec& r) { return r.type == 1; });
            break;
        }
        case 4:
            desc = "the records twice over";
            j.records.insert(j.records.end(), j.records.begin(), j.records.begin() + n);
            break;
        case 5:
            if (o.records.empty()) return "";
            desc = "another store's record " + std::string(type_name(o.records.back().type)) +
                   " appended";
            j.records.push_back(o.records[g.below(o.records.size())]);
            break;
        case 6:
            desc = "records in reverse order";
            std::reverse(j.records.begin(), j.records.end());
            break;
        default:
            desc = "last record moved to the front";
            j.records.insert(j.records.begin(), j.records.back());
            j.records.pop_back();
    }
    bytes = journal_bytes(j) + j.tail;
    return desc;
}

// --------------------------------------------------------------------------------------------
// Byte-level damage.

std::size_t offset_in(std::size_t size, Gen& g) {
    if (size == 0) return 0;
    // Half the time in the first 4 kB (superblock, root group, journal header and run record),
    // where damage does the most.
    return g.chance(0.5) ? g.below(std::min<std::size_t>(size, 4096)) : g.below(size);
}

std::string flip_bits(const fs::path& f, Gen& g) {
    std::string b = read_file(f);
    if (b.empty()) return "";
    const int n = static_cast<int>(g.range(1, 16));
    std::string desc = std::to_string(n) + " bit flip(s) in " + f.filename().string() + " at";
    for (int i = 0; i < n; ++i) {
        const std::size_t at = offset_in(b.size(), g);
        b[at] = static_cast<char>(b[at] ^ (1 << g.below(8)));
        if (i < 4) desc += " " + std::to_string(at);
    }
    write_file(f, b);
    return desc;
}

std::string overwrite_block(const fs::path& f, Gen& g) {
    std::string b = read_file(f);
    if (b.empty()) return "";
    const std::size_t at = offset_in(b.size(), g);
    const std::size_t n = std::min(b.size() - at, static_cast<std::size_t>(g.range(1, 512)));
    const int fill = static_cast<int>(g.below(3));  // random, zeros, 0xFF
    for (std::size_t i = 0; i < n; ++i)
        b[at + i] = fill == 0 ? static_cast<char>(g.below(256)) : fill == 1 ? '\0' : '\xff';
    write_file(f, b);
    return std::to_string(n) + " bytes of " +
           (fill == 0   ? "random"
            : fill == 1 ? "zeros"
                        : "0xFF") +
           " in " + f.filename().string() + " at " + std::to_string(at);
}

std::string truncate_file(const fs::path& f, Gen& g, bool at_record = false) {
    std::string b = read_file(f);
    std::size_t at = offset_in(b.size() + 1, g);
    if (at_record) {  // exactly after a record: a valid, shorter journal
        const JournalBytes j = parse_journal(b);
        std::size_t pos = j.header.size();
        std::vector<std::size_t> ends = {pos};
        for (const auto& r : j.records) {
            pos += store::record_header_size + r.payload.size();
            ends.push_back(pos);
        }
        at = ends[g.below(ends.size())];
    }
    b.resize(std::min(at, b.size()));
    write_file(f, b);
    return f.filename().string() + " truncated to " + std::to_string(b.size()) + " B" +
           (at_record ? " (at a record boundary)" : "");
}

std::string random_bytes(Gen& g, std::size_t n) {
    std::string s(n, '\0');
    for (auto& c : s)
        c = static_cast<char>(g.below(256));
    return s;
}

// --------------------------------------------------------------------------------------------
// Checks.

std::string demangled(const std::type_info& t) {
    int status = 0;
    char* d = abi::__cxa_demangle(t.name(), nullptr, nullptr, &status);
    std::string s = status == 0 && d ? d : t.name();
    std::free(d);
    return s;
}

// Runs one operation: a core::Error with a message is a clean error; any other exception is BAD.
bool op(Outcome& out, const std::string& name, const std::function<void()>& f) {
    announce_operation(name);
    try {
        f();
        return true;
    } catch (const core::Error& e) {
        if (std::string(e.what()).empty())
            out.mark_bad(name + ": " + demangled(typeid(e)) + " with an empty message");
        out.clean(name, e.what());
    } catch (const std::exception& e) {
        out.mark_bad(name + ": unexpected exception " + demangled(typeid(e)) + ": " +
                     one_line(e.what(), 300));
        out.note(name, std::string("unexpected ") + demangled(typeid(e)) + ": " + e.what());
    }
    return false;
}

// The first non-finite value of a stored realization, or "".
std::string nonfinite_in(const store::StoredRealization& s) {
    const auto& r = s.result;
    auto bad = [](double v) { return !std::isfinite(v); };
    const std::pair<const char*, const std::vector<double>*> lists[] = {
        {"survival_times", &r.survival_times},
        {"jam_onsets", &r.jam_onsets},
        {"exit_times", &r.exit_times},
        {"curve_time", &r.curve_time}};
    for (const auto& [name, v] : lists)
        if (std::any_of(v->begin(), v->end(), bad)) return name;
    for (const auto& e : r.events)
        if (bad(e.time) || bad(e.sim_time)) return "events";
    if (r.empty_time && bad(*r.empty_time)) return "empty_time";
    if (r.discharge_rate && bad(*r.discharge_rate)) return "discharge_rate";
    if (bad(r.discharge_rate_mass)) return "discharge_rate_mass";
    const auto& d = r.diagnostics;
    for (double v :
         {d.settle_time, d.shake_time, d.wall_seconds, d.ns_per_particle_step, d.max_overlap_ratio,
          d.settled_kinetic_energy, d.potential_energy_released, d.dt, d.tau_c, d.k_n,
          d.seconds_forces, d.seconds_integration, d.seconds_neighbors, d.seconds_observers})
        if (bad(v)) return "diagnostics";
    if (bad(s.record.task_seconds) || bad(s.record.finished_unix)) return "record times";
    return "";
}

void check_realizations(Outcome& out, const std::string& name,
                        const std::vector<store::StoredRealization>& v, bool forged) {
    for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string what = nonfinite_in(v[i]);
        if (what.empty()) continue;
        const std::string msg = name + ": row " + std::to_string(i) + " has a non-finite " + what;
        if (forged)  // a record with a valid checksum that no writer wrote: garbage in
            out.note(name, msg + " (from a forged journal record; passed through)");
        else
            out.mark_bad(msg);
        return;
    }
}

void check_status(Outcome& out, const store::StoreStatus& s, bool forged) {
    if (s.total != s.done + s.failed + s.pending)
        out.mark_bad("status: total " + std::to_string(s.total) + " != done + failed + pending");
    if (s.total < 0 || s.done < 0 || s.failed < 0 || s.pending < 0 || s.errors < 0)
        out.mark_bad("status: negative counts");
    for (const auto& p : s.points)
        if (!std::isfinite(p.survival_sum) || !std::isfinite(p.empty_sum)) {
            if (forged)
                out.note("status", "non-finite sums of point '" + p.label +
                                       "' (from a forged journal record)");
            else
                out.mark_bad("status: non-finite sums of point '" + p.label + "'");
        }
    const std::string json = cli::status_json(s);
    if (mentions_nonfinite(json)) out.mark_bad("status: JSON shows a non-finite number");
    std::ostringstream table;
    cli::write_status(table, s);
    if (mentions_nonfinite(table.str()))
        out.mark_bad("status: the table shows a non-finite number");
}

void analyze(Outcome& out, const fs::path& p, bool write, const std::string& name) {
    op(out, name, [&] {
        std::ostringstream json, err;
        const int code = cli::analyze_store(p, true, write, json, err);
        if (mentions_nonfinite(json.str()))
            out.mark_bad(name + ": the JSON shows a non-finite number");
        // Exit code 1 says the analysis could not be written (e.g. a damaged /analysis group in
        // a file that looked in step): a clean error when it says why.
        if (code != 0) {
            if (err.str().empty())
                out.mark_bad(name + ": exit code " + std::to_string(code) + " without a message");
            out.clean(name, "exit code " + std::to_string(code) + ": " + err.str());
        }
        if (!write) {
            std::ostringstream tables, err2;
            cli::analyze_store(p, false, false, tables, err2);
            if (mentions_nonfinite(tables.str()))
                out.mark_bad(name + ": the tables show a non-finite number");
        }
    });
}

std::map<std::string, store::Bytes> by_task(const std::vector<store::StoredRealization>& v) {
    std::map<std::string, store::Bytes> m;
    for (const auto& s : v)
        m[s.label + "#" + std::to_string(s.record.realization)] = store::encode_result(s.result);
    return m;
}

struct Kind {
    const char* name;
    std::function<std::string(const Context&, const fs::path& dir, Gen&)> apply;
};

fs::path h5_of(const fs::path& dir) {
    return dir / "s.h5";
}
fs::path journal_of(const fs::path& dir) {
    return store::journal_path(dir / "s.h5");
}

const std::vector<Kind>& kinds() {
    static const std::vector<Kind> k = {
        {"none", [](const Context&, const fs::path&, Gen&) { return std::string("undamaged"); }},
        {"h5_truncate",
         [](const Context&, const fs::path& d, Gen& g) { return truncate_file(h5_of(d), g); }},
        {"journal_truncate", [](const Context&, const fs::path& d,
                                Gen& g) { return truncate_file(journal_of(d), g, g.chance(0.3)); }},
        {"both_truncate",
         [](const Context&, const fs::path& d, Gen& g) {
             return truncate_file(h5_of(d), g) + "; " + truncate_file(journal_of(d), g);
         }},
        {"h5_bitflip",
         [](const Context&, const fs::path& d, Gen& g) { return flip_bits(h5_of(d), g); }},
        {"h5_overwrite",
         [](const Context&, const fs::path& d, Gen& g) { return overwrite_block(h5_of(d), g); }},
        {"journal_bitflip",
         [](const Context&, const fs::path& d, Gen& g) { return flip_bits(journal_of(d), g); }},
        {"journal_overwrite", [](const Context&, const fs::path& d,
                                 Gen& g) { return overwrite_block(journal_of(d), g); }},
        {"journal_resealed",
         [](const Context&, const fs::path& d, Gen& g) {
             std::string b = read_file(journal_of(d));
             const std::string desc = reseal(b, g);
             write_file(journal_of(d), b);
             return desc;
         }},
        {"journal_records",
         [](const Context& ctx, const fs::path& d, Gen& g) {
             std::string b = read_file(journal_of(d));
             const std::string desc =
                 shuffle_records(b, read_file(journal_of(base_dir(ctx, "other"))), g);
             write_file(journal_of(d), b);
             return desc;
         }},
        {"h5_foreign_unrelated",
         [](const Context&, const fs::path& d, Gen& g) {
             write_unrelated_hdf5(h5_of(d), g);
             return std::string("s.h5 replaced by an unrelated HDF5 file");
         }},
        {"h5_foreign_lookalike",
         [](const Context&, const fs::path& d, Gen& g) {
             const fs::path model = d / "model.h5";
             fs::copy_file(h5_of(d), model);
             write_lookalike_hdf5(h5_of(d), model, g);
             fs::remove(model);
             return std::string(
                 "s.h5 replaced by an HDF5 file with the store's names and "
                 "attributes but wrong datasets");
         }},
        {"h5_schema", [](const Context&, const fs::path& d,
                         Gen& g) { return mutate_store_schema(h5_of(d), g); }},
        {"zero_length",
         [](const Context&, const fs::path& d, Gen& g) {
             const int w = static_cast<int>(g.below(3));
             if (w != 1) write_file(h5_of(d), "");
             if (w != 0) write_file(journal_of(d), "");
             return std::string(w == 0 ? "s.h5" : w == 1 ? "the journal" : "both") + " zero-length";
         }},
        {"directory",
         [](const Context&, const fs::path& d, Gen& g) {
             const int w = static_cast<int>(g.below(4));
             const fs::path f = w % 2 == 0 ? h5_of(d) : journal_of(d);
             fs::remove(f);
             fs::create_directory(f);
             if (w >= 2) write_file(f / "inside", "x");
             return f.filename().string() + " is a" + (w >= 2 ? " non-empty" : "n empty") +
                    " directory";
         }},
        {"missing",
         [](const Context&, const fs::path& d, Gen& g) {
             const int w = static_cast<int>(g.below(3));
             if (w != 1) fs::remove(journal_of(d));
             if (w != 0) fs::remove(h5_of(d));
             return std::string(w == 0 ? "the journal" : w == 1 ? "s.h5" : "both") + " missing";
         }},
        {"swapped",
         [](const Context& ctx, const fs::path& d, Gen& g) {
             const fs::path other = base_dir(ctx, "other");
             switch (g.below(4)) {
                 case 0:
                     fs::copy_file(journal_of(other), journal_of(d),
                                   fs::copy_options::overwrite_existing);
                     return std::string("the journal of another store");
                 case 1:
                     fs::copy_file(h5_of(other), h5_of(d), fs::copy_options::overwrite_existing);
                     return std::string("the s.h5 of another store");
                 case 2: {
                     const std::string h = read_file(h5_of(d));
                     write_file(h5_of(d), read_file(journal_of(d)));
                     write_file(journal_of(d), h);
                     return std::string("s.h5 and its journal swapped");
                 }
                 default:
                     fs::copy_file(journal_of(d), h5_of(d), fs::copy_options::overwrite_existing);
                     return std::string("s.h5 is a copy of the journal");
             }
         }},
        {"garbage",
         [](const Context&, const fs::path& d, Gen& g) {
             const bool h5 = g.chance(0.6);
             const fs::path f = h5 ? h5_of(d) : journal_of(d);
             const std::size_t n = g.skewed(200000);
             std::string b;
             switch (g.below(4)) {
                 case 0:
                     b = random_bytes(g, n);
                     break;
                 case 1:  // a valid signature, then garbage
                     b = (h5 ? std::string("\x89HDF\r\n\x1a\n", 8)
                             : std::string("HOPPER-JOURNAL\x01\x00", 16)) +
                         random_bytes(g, n);
                     break;
                 case 2:
                     b = "this is a text file, not a store\n";
                     break;
                 default:  // the real header, then garbage
                     b = read_file(f).substr(0, g.below(4096)) + random_bytes(g, n);
             }
             write_file(f, b);
             return f.filename().string() + " replaced by " + std::to_string(b.size()) +
                    " bytes of garbage";
         }},
        {"symlink",
         [](const Context&, const fs::path& d, Gen& g) {
             const int w = static_cast<int>(g.below(5));
             const fs::path f = w % 2 == 0 ? h5_of(d) : journal_of(d);
             fs::remove(f);
             switch (w) {
                 case 0:
                 case 1:
                     fs::create_symlink(f.filename(), f);  // a loop
                     return f.filename().string() + " is a symlink to itself";
                 case 2:
                 case 3:
                     fs::create_symlink("does-not-exist", f);
                     return f.filename().string() + " is a dangling symlink";
                 default:
                     fs::create_symlink("/dev/null", f);
                     return f.filename().string() + " is a symlink to /dev/null";
             }
         }},
        {"leftovers",
         [](const Context&, const fs::path& d, Gen& g) {
             // What an interrupted rebuild or journal creation leaves behind, made awkward.
             const fs::path rebuild = d / "s.h5.rebuild";
             const fs::path jnew = d / "s.h5.journal.new";
             std::string desc;
             switch (g.below(4)) {
                 case 0:
                     fs::create_directory(rebuild);
                     write_file(rebuild / "x", "x");
                     desc = "s.h5.rebuild is a non-empty directory";
                     break;
                 case 1:
                     write_file(rebuild, "garbage");
                     desc = "a stale s.h5.rebuild";
                     break;
                 case 2:
                     fs::create_directory(jnew);
                     desc = "s.h5.journal.new is a directory";
                     break;
                 default:
                     write_file(jnew, "stale");
                     desc = "a stale s.h5.journal.new";
             }
             if (g.chance(0.5)) {  // and a file that needs a rebuild (or a new store)
                 fs::remove(h5_of(d));
                 if (g.chance(0.5)) fs::remove(journal_of(d));
                 desc +=
                     ", " + std::string(fs::exists(journal_of(d)) ? "s.h5" : "both") + " missing";
             }
             return desc;
         }},
        {"combination",
         [](const Context&, const fs::path& d, Gen& g) {
             std::string a = g.chance(0.5) ? flip_bits(h5_of(d), g) : truncate_file(h5_of(d), g);
             std::string b = read_file(journal_of(d));
             std::string c = reseal(b, g);
             write_file(journal_of(d), b);
             return a + "; " + c;
         }},
    };
    return k;
}

}  // namespace

void prepare_stores(const Context& ctx) {
    for (const char* which : {"other", "clean", "crashed"})
        make_base(ctx, which);
}

void store_case(const Context& ctx, std::uint64_t id, Outcome& out) {
    Gen g(core::mix_seed(ctx.seed, id));
    const std::string base = g.chance(0.65) ? "clean" : "crashed";
    const fs::path dir = ctx.workdir / ("case-" + std::to_string(id));
    fs::create_directories(dir);
    for (const auto& e : fs::directory_iterator(base_dir(ctx, base)))
        if (e.path().filename().string().rfind("s.h5", 0) == 0)
            fs::copy_file(e.path(), dir / e.path().filename());
    const auto& all = kinds();
    const std::size_t k = g.below(all.size());
    out.kind = all[k].name;
    announce_operation("damage");
    std::string desc = all[k].apply(ctx, dir, g);
    if (desc.empty()) desc = "no damage applied (nothing to damage)";
    out.description = base + " store: " + desc;
    out.announce();
    const bool forged = out.kind == "journal_resealed" || out.kind == "combination";

    const fs::path p = h5_of(dir);
    op(out, "status", [&] {
        const store::StoreStatus s = store::read_status(p);
        check_status(out, s, forged);
    });
    op(out, "journal_read", [&] {
        check_realizations(out, "journal_read", store::read_journal_realizations(p), forged);
    });
    op(out, "h5_read",
       [&] { check_realizations(out, "h5_read", store::read_realizations(p), false); });
    analyze(out, p, false, "analyze");

    // The writer: open, a run that appends what is pending (one result, one error), end.
    const store::CampaignPlan plan = plan_of(ctx, "tiny.toml", 6);
    const bool ran = op(out, "store_run", [&] {
        store::StoreOptions opt;
        opt.flush_interval = 0.0;
        store::Store s(p, opt);
        for (const auto& n : s.notes())
            out.note("store_open", n);
        (void)s.status();
        s.begin_run(run_record(plan, "tiny.toml"));
        int appended = 0;
        for (const auto& pt : plan.points)
            for (int r = 0; r < pt.realizations() && appended < 2; ++r) {
                const store::TaskEntry* t = s.task(pt.label, r);
                if (t && t->state != store::TaskState::pending) continue;
                if (appended == 0)
                    s.append(result_record(pt, r, 100));
                else
                    s.append(store::ErrorRecord{pt.label, r, pt.seeds[static_cast<std::size_t>(r)],
                                                2, 1, 1.7e9, "fabricated error"});
                ++appended;
            }
        s.end_run(end_record(appended > 0 ? 1 : 0));
    });
    if (!ran) return;

    // A run that succeeded leaves a store in step, readable, and analyzable.
    op(out, "after_run", [&] {
        const store::StoreStatus s = store::read_status(p);
        check_status(out, s, forged);
        if (!s.hdf5_in_step) out.mark_bad("after_run: the HDF5 file is not in step after a run");
        const auto from_h5 = store::read_realizations(p);
        check_realizations(out, "after_run h5", from_h5, false);
        const auto from_journal = store::read_journal_realizations(p);
        if (from_h5.size() != from_journal.size())
            out.mark_bad("after_run: the HDF5 file has " + std::to_string(from_h5.size()) +
                         " realizations, the journal " + std::to_string(from_journal.size()));
        else if (by_task(from_h5) != by_task(from_journal))
            out.note("DIVERGED",
                     "after a run the HDF5 view holds other values than the journal "
                     "(damage inside a file that looked in step is not detected)");
    });
    analyze(out, p, true, "analyze_write");
}

}  // namespace hopper::fuzz
