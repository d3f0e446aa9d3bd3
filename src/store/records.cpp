#include "hopper/store/records.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <vector>

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

// A typed setting: name, u8 kind (0: number, 1: text), then the f64 or the string.
void put(ByteWriter& w, const std::vector<core::Setting>& settings) {
    w.u32(static_cast<std::uint32_t>(settings.size()));
    for (const auto& s : settings) {
        w.str(s.name);
        if (const auto* x = std::get_if<double>(&s.value)) {
            w.u8(0);
            w.f64(*x);
        } else {
            w.u8(1);
            w.str(std::get<std::string>(s.value));
        }
    }
}

std::vector<core::Setting> get_settings(ByteReader& r) {
    const std::uint32_t n = r.u32();
    if (n > r.remaining()) r.fail("a setting count of " + std::to_string(n) + " is impossible");
    std::vector<core::Setting> out(n);
    for (auto& s : out) {
        s.name = r.str();
        const std::uint8_t kind = r.u8();
        if (kind == 0)
            s.value = r.f64();
        else if (kind == 1)
            s.value = r.str();
        else
            r.fail("setting '" + s.name + "' has an unknown kind " + std::to_string(kind));
    }
    return out;
}

// A list of seeds: its count, then each. Read back with the count checked against the bytes left.
void put_seeds(ByteWriter& w, const std::vector<std::uint64_t>& seeds) {
    w.u32(static_cast<std::uint32_t>(seeds.size()));
    for (auto s : seeds)
        w.u64(s);
}

std::vector<std::uint64_t> get_seeds(ByteReader& r) {
    const std::uint32_t n = r.u32();
    if (static_cast<std::uint64_t>(n) * 8 > r.remaining())
        r.fail("a realization count of " + std::to_string(n) + " exceeds the bytes left");
    std::vector<std::uint64_t> seeds(n);
    for (auto& s : seeds)
        s = r.u64();
    return seeds;
}

// The plan's sections after the seeds: settings (no marker: records ended after the seeds
// before them), then a format number and what it adds.
constexpr std::uint32_t plan_format_limits = 2;

void put(ByteWriter& w, const CampaignPlan& p) {
    w.str(p.name);
    w.u64(p.seed);
    w.u32(static_cast<std::uint32_t>(p.points.size()));
    for (const auto& pt : p.points) {
        w.str(pt.label);
        w.str(pt.scene);
        w.f64(pt.D_cm);
        w.f64(pt.theta_deg);
        w.i32(pt.particles);
        put_seeds(w, pt.seeds);
    }
    // Typed settings (added later, after every point, so that records written before them end
    // here and read back with empty vectors): per point its settings, then its parameters.
    for (const auto& pt : p.points) {
        put(w, pt.settings);
        put(w, pt.parameters);
    }
    // Plan format 2 (issue 29), after the settings so that records written before end there:
    // per point its limit (the seeds then list only the allotted realizations).
    w.u32(plan_format_limits);
    for (const auto& pt : p.points)
        w.i32(pt.max_realizations());
}

CampaignPlan get_plan(ByteReader& r) {
    CampaignPlan p;
    p.name = r.str();
    p.seed = r.u64();
    const std::uint32_t n = r.u32();
    if (n > r.remaining()) r.fail("a point count of " + std::to_string(n) + " is impossible");
    p.points.resize(n);
    for (auto& pt : p.points) {
        pt.label = r.str();
        pt.scene = r.str();
        pt.D_cm = r.f64();
        pt.theta_deg = r.f64();
        pt.particles = r.i32();
        pt.seeds = get_seeds(r);
    }
    if (r.remaining() > 0)
        for (auto& pt : p.points) {
            pt.settings = get_settings(r);
            pt.parameters = get_settings(r);
        }
    if (r.remaining() > 0) {
        const std::uint32_t format = r.u32();
        if (format != plan_format_limits)
            r.fail("plan format " + std::to_string(format) +
                   " is unknown (written by a newer "
                   "version?)");
        for (auto& pt : p.points) {
            pt.limit = r.i32();
            if (pt.limit < pt.realizations())
                r.fail("point '" + pt.label + "' has a limit of " + std::to_string(pt.limit) +
                       " realizations below its " + std::to_string(pt.realizations()) + " seeds");
        }
    } else {
        for (auto& pt : p.points)
            pt.limit = pt.realizations();  // plans before issue 29 list every seed
    }
    return p;
}

}  // namespace

Bytes encode(const RunStartRecord& r) {
    ByteWriter w;
    const RunInfo& i = r.run;
    for (const std::string* s :
         {&i.start_time, &i.code_version, &i.compiler, &i.command, &i.sweep_path, &i.sweep_text})
        w.str(*s);
    w.i32(i.mpi_size);
    w.i32(i.workers);
    w.u32(static_cast<std::uint32_t>(i.hosts.size()));
    for (const auto& h : i.hosts)
        w.str(h);
    w.i64(i.pid);
    put(w, r.plan);
    return w.take();
}

RunStartRecord decode_run_start(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal run record");
    RunStartRecord r;
    RunInfo& i = r.run;
    for (std::string* s :
         {&i.start_time, &i.code_version, &i.compiler, &i.command, &i.sweep_path, &i.sweep_text})
        *s = in.str();
    i.mpi_size = in.i32();
    i.workers = in.i32();
    const std::uint32_t nh = in.u32();
    if (nh > in.remaining()) in.fail("a host count of " + std::to_string(nh) + " is impossible");
    i.hosts.resize(nh);
    for (auto& h : i.hosts)
        h = in.str();
    i.pid = in.i64();
    r.plan = get_plan(in);
    in.expect_end();
    return r;
}

Bytes encode(const ResultRecord& r) {
    ByteWriter w;
    w.str(r.label);
    w.i32(r.realization);
    w.u64(r.seed);
    w.i32(r.rank);
    w.i32(r.attempt);
    w.f64(r.task_seconds);
    w.f64(r.finished_unix);
    w.u32(static_cast<std::uint32_t>(r.result.size()));
    w.raw(r.result);
    return w.take();
}

ResultRecord decode_result_record(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal result record");
    ResultRecord r;
    r.label = in.str();
    r.realization = in.i32();
    r.seed = in.u64();
    r.rank = in.i32();
    r.attempt = in.i32();
    r.task_seconds = in.f64();
    r.finished_unix = in.f64();
    const std::uint32_t n = in.u32();
    const auto raw = in.raw(n);
    r.result.assign(raw.begin(), raw.end());
    in.expect_end();
    return r;
}

Bytes encode(const ErrorRecord& r) {
    ByteWriter w;
    w.str(r.label);
    w.i32(r.realization);
    w.u64(r.seed);
    w.i32(r.rank);
    w.i32(r.attempt);
    w.f64(r.time_unix);
    w.str(r.reason);
    return w.take();
}

ErrorRecord decode_error(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal error record");
    ErrorRecord r;
    r.label = in.str();
    r.realization = in.i32();
    r.seed = in.u64();
    r.rank = in.i32();
    r.attempt = in.i32();
    r.time_unix = in.f64();
    r.reason = in.str();
    in.expect_end();
    return r;
}

Bytes encode(const DispatchRecord& r) {
    ByteWriter w;
    w.str(r.label);
    w.i32(r.realization);
    w.u64(r.seed);
    w.i32(r.rank);
    w.i32(r.attempt);
    w.f64(r.time_unix);
    return w.take();
}

DispatchRecord decode_dispatch(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal dispatch record");
    DispatchRecord r;
    r.label = in.str();
    r.realization = in.i32();
    r.seed = in.u64();
    r.rank = in.i32();
    r.attempt = in.i32();
    r.time_unix = in.f64();
    in.expect_end();
    return r;
}

Bytes encode(const RunEndRecord& r) {
    ByteWriter w;
    w.str(r.end_time);
    w.str(r.reason);
    w.i32(r.stored);
    w.f64(r.wall_seconds);
    w.f64(r.master_cpu_seconds);
    w.f64(r.lost_worker_seconds);
    w.f64(r.saved_worker_seconds);
    return w.take();
}

RunEndRecord decode_run_end(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal run-end record");
    RunEndRecord r;
    r.end_time = in.str();
    r.reason = in.str();
    r.stored = in.i32();
    r.wall_seconds = in.f64();
    r.master_cpu_seconds = in.f64();
    if (in.remaining() > 0) {  // absent in records written before issue 15
        r.lost_worker_seconds = in.f64();
        r.saved_worker_seconds = in.f64();
    }
    in.expect_end();
    return r;
}

Bytes encode(const SyncRecord& r) {
    ByteWriter w;
    w.u64(r.token);
    w.u64(r.journal_bytes);
    w.u64(r.rows);
    if (r.file) {
        w.u64(r.file->bytes);
        w.u32(r.file->crc32c);
    }
    return w.take();
}

SyncRecord decode_sync(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal sync record");
    SyncRecord r;
    r.token = in.u64();
    r.journal_bytes = in.u64();
    r.rows = in.u64();
    if (in.remaining() > 0) {  // written since checksums were added
        FileChecksum f;
        f.bytes = in.u64();
        f.crc32c = in.u32();
        r.file = f;
    }
    in.expect_end();
    return r;
}

Bytes encode(const AllotmentRecord& r) {
    ByteWriter w;
    w.u32(static_cast<std::uint32_t>(r.points.size()));
    for (const auto& p : r.points) {
        w.str(p.label);
        w.i32(p.first);
        put_seeds(w, p.seeds);
    }
    return w.take();
}

AllotmentRecord decode_allotment(std::span<const std::uint8_t> b) {
    ByteReader in(b, "journal allotment record");
    AllotmentRecord r;
    const std::uint32_t n = in.u32();
    if (n > in.remaining()) in.fail("a point count of " + std::to_string(n) + " is impossible");
    r.points.resize(n);
    for (auto& p : r.points) {
        p.label = in.str();
        p.first = in.i32();
        if (p.first < 0) in.fail("a negative first realization " + std::to_string(p.first));
        p.seeds = get_seeds(in);
    }
    in.expect_end();
    return r;
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
