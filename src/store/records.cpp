#include "hopper/store/records.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <vector>

#include "hopper/core/described.hpp"
#include "hopper/core/error.hpp"

namespace hopper::store {

std::uint64_t CampaignPlan::physics_hash() const {
    std::vector<std::pair<std::string, std::uint64_t>> parts;
    for (const auto& p : points)
        parts.emplace_back(p.label, p.physics_hash());
    std::sort(parts.begin(), parts.end());
    std::uint64_t h = fnv1a64("campaign_seed=" + std::to_string(seed) + "\n");
    for (const auto& [label, hash] : parts)
        h = fnv1a64(label + "\n" + hex64(hash) + "\n", h);
    return h;
}

const PointPlan* CampaignPlan::find(const std::string& label) const {
    for (const auto& p : points)
        if (p.label == label) return &p;
    return nullptr;
}

namespace {

using core::Is;

// Each journal record described once (core/described.hpp): `fields` names its members in byte
// order, and encode() and decode_*() below both walk it. Members added after a record type was
// first written come last, under `since`, so that older records still read.

// A typed setting: name, u8 kind (0: number, 1: text), then the f64 or the string.
template <class Io, Is<core::Setting> S>
void fields(Io& io, S& s) {
    io(s.name);
    io.choice(s.value);
}

template <class Io, class V>
void settings(Io& io, V& list) {
    io.list(list, "setting", 6, [&](auto& s) { fields(io, s); });
}

// A list of seeds: its count, then each.
template <class Io, class V>
void seeds(Io& io, V& list) {
    io.list(list, "realization", 8, [&](auto& seed) { io(seed); });
}

// The plan's sections after the points: their typed settings (no marker: records ended after
// the seeds before them), then a format number and what it adds (issue 29: per point its limit;
// the seeds list only the allotted realizations, where plans before listed every seed).
constexpr std::uint32_t plan_format_limits = 2;

template <class Io, Is<CampaignPlan> P>
void fields(Io& io, P& p) {
    io(p.name);
    io(p.seed);
    io.list(p.points, "point", 28, [&](auto& pt) {
        io(pt.label);
        io(pt.scene);
        io(pt.D_cm);
        io(pt.theta_deg);
        io(pt.particles);
        seeds(io, pt.seeds);
    });
    io.since(
        [&] {
            for (auto& pt : p.points) {
                settings(io, pt.settings);
                settings(io, pt.parameters);
            }
        },
        [] {});
    io.since(
        [&] {
            io.format(plan_format_limits, "plan");
            for (auto& pt : p.points) {
                io.derived(pt.limit, [&] { return pt.max_realizations(); });
                io.check(pt.limit >= pt.realizations(), [&] {
                    return "point '" + pt.label + "' has a limit of " + std::to_string(pt.limit) +
                           " realizations below its " + std::to_string(pt.realizations()) +
                           " seeds";
                });
            }
        },
        [&] {
            if constexpr (!std::is_const_v<P>)  // (read only)
                for (auto& pt : p.points)
                    pt.limit = pt.realizations();  // plans before issue 29 list every seed
        });
}

template <class Io, Is<RunStartRecord> R>
void fields(Io& io, R& r) {
    auto& i = r.run;
    for (auto* s :
         {&i.start_time, &i.code_version, &i.compiler, &i.command, &i.sweep_path, &i.sweep_text})
        io(*s);
    io(i.mpi_size);
    io(i.workers);
    io.list(i.hosts, "host", 4, [&](auto& h) { io(h); });
    io(i.pid);
    fields(io, r.plan);
}

// What the result, error and dispatch records begin with: the attempt of a task they are about.
template <class Io, class R>
void attempt(Io& io, R& r) {
    io(r.label);
    io(r.realization);
    io(r.seed);
    io(r.rank);
    io(r.attempt);
}

template <class Io, Is<ResultRecord> R>
void fields(Io& io, R& r) {
    attempt(io, r);
    io(r.task_seconds);
    io(r.finished_unix);
    io.blob(r.result);
}

template <class Io, Is<ErrorRecord> R>
void fields(Io& io, R& r) {
    attempt(io, r);
    io(r.time_unix);
    io(r.reason);
}

template <class Io, Is<DispatchRecord> R>
void fields(Io& io, R& r) {
    attempt(io, r);
    io(r.time_unix);
}

template <class Io, Is<RunEndRecord> R>
void fields(Io& io, R& r) {
    io(r.end_time);
    io(r.reason);
    io(r.stored);
    io(r.wall_seconds);
    io(r.master_cpu_seconds);
    io.since(  // absent in records written before issue 15 (read as 0)
        [&] {
            io(r.lost_worker_seconds);
            io(r.saved_worker_seconds);
        },
        [] {});
}

template <class Io, Is<SyncRecord> R>
void fields(Io& io, R& r) {
    io(r.token);
    io(r.journal_bytes);
    io(r.rows);
    io.optional(r.file, [&](auto& f) {  // written since checksums were added
        io(f.bytes);
        io(f.crc32c);
    });
}

template <class Io, Is<AllotmentRecord> R>
void fields(Io& io, R& r) {
    io.list(r.points, "point", 12, [&](auto& p) {
        io(p.label);
        io(p.first);
        io.check(p.first >= 0,
                 [&] { return "a negative first realization " + std::to_string(p.first); });
        seeds(io, p.seeds);
    });
}

template <class R>
Bytes encode_record(const R& r) {
    ByteWriter w;
    core::Put io(w);
    fields(io, r);
    return w.take();
}

template <class R>
R decode_record(std::span<const std::uint8_t> b, const char* what) {
    ByteReader in(b, what);
    core::Get io(in);
    R r;
    fields(io, r);
    in.expect_end();
    return r;
}

}  // namespace

Bytes encode(const RunStartRecord& r) {
    return encode_record(r);
}
Bytes encode(const ResultRecord& r) {
    return encode_record(r);
}
Bytes encode(const ErrorRecord& r) {
    return encode_record(r);
}
Bytes encode(const DispatchRecord& r) {
    return encode_record(r);
}
Bytes encode(const RunEndRecord& r) {
    return encode_record(r);
}
Bytes encode(const SyncRecord& r) {
    return encode_record(r);
}
Bytes encode(const AllotmentRecord& r) {
    return encode_record(r);
}

RunStartRecord decode_run_start(std::span<const std::uint8_t> b) {
    return decode_record<RunStartRecord>(b, "journal run record");
}
ResultRecord decode_result_record(std::span<const std::uint8_t> b) {
    return decode_record<ResultRecord>(b, "journal result record");
}
ErrorRecord decode_error(std::span<const std::uint8_t> b) {
    return decode_record<ErrorRecord>(b, "journal error record");
}
DispatchRecord decode_dispatch(std::span<const std::uint8_t> b) {
    return decode_record<DispatchRecord>(b, "journal dispatch record");
}
RunEndRecord decode_run_end(std::span<const std::uint8_t> b) {
    return decode_record<RunEndRecord>(b, "journal run-end record");
}
SyncRecord decode_sync(std::span<const std::uint8_t> b) {
    return decode_record<SyncRecord>(b, "journal sync record");
}
AllotmentRecord decode_allotment(std::span<const std::uint8_t> b) {
    return decode_record<AllotmentRecord>(b, "journal allotment record");
}

FileChecksum checksum_file(const std::filesystem::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        throw core::StoreError("cannot read '" + path.string() + "': " + std::strerror(errno));
    FileChecksum f;
    std::vector<std::uint8_t> buf(1 << 20);
    for (;;) {
        const ssize_t n = ::read(fd, buf.data(), buf.size());
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            const int err = errno;
            ::close(fd);
            throw core::StoreError("cannot read '" + path.string() + "': " + std::strerror(err));
        }
        if (n == 0) break;
        f.crc32c = crc32c(std::span<const std::uint8_t>(buf.data(), static_cast<std::size_t>(n)),
                          f.crc32c);
        f.bytes += static_cast<std::uint64_t>(n);
    }
    ::close(fd);
    return f;
}

std::string utc_now() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

double unix_now() {
    using namespace std::chrono;
    return duration<double>(system_clock::now().time_since_epoch()).count();
}

}  // namespace hopper::store
