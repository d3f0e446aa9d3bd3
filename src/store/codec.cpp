#include "hopper/store/codec.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include "hopper/core/error.hpp"

namespace hopper::store {

static_assert(std::endian::native == std::endian::little ||
              std::endian::native == std::endian::big);

void ByteWriter::u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void ByteWriter::u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void ByteWriter::f64(double v) {
    u64(std::bit_cast<std::uint64_t>(v));
}

void ByteWriter::str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
}

void ByteWriter::f64s(const std::vector<double>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (double x : v)
        f64(x);
}

void ByteWriter::i32s(const std::vector<int>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (int x : v)
        i32(x);
}

void ByteWriter::i64s(const std::vector<std::int64_t>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (std::int64_t x : v)
        i64(x);
}

void ByteWriter::bools(const std::vector<bool>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (bool x : v)
        u8(x ? 1 : 0);
}

ByteReader::ByteReader(std::span<const std::uint8_t> in, std::string what)
    : in_(in), what_(std::move(what)) {}

void ByteReader::fail(const std::string& problem) const {
    throw core::StoreError(what_ + ": " + problem + " (at byte " + std::to_string(pos_) + " of " +
                           std::to_string(in_.size()) + ")");
}

void ByteReader::need(std::size_t n) {
    if (n > remaining())
        fail("truncated: " + std::to_string(n) + " more bytes needed, " +
             std::to_string(remaining()) + " left");
}

std::uint8_t ByteReader::u8() {
    need(1);
    return in_[pos_++];
}

std::uint32_t ByteReader::u32() {
    need(4);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
        v |= static_cast<std::uint32_t>(in_[pos_++]) << (8 * i);
    return v;
}

std::uint64_t ByteReader::u64() {
    need(8);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i)
        v |= static_cast<std::uint64_t>(in_[pos_++]) << (8 * i);
    return v;
}

double ByteReader::f64() {
    return std::bit_cast<double>(u64());
}

std::uint32_t ByteReader::count(std::size_t element_size) {
    const std::uint32_t n = u32();
    if (static_cast<std::uint64_t>(n) * element_size > remaining())
        fail("a length of " + std::to_string(n) + " exceeds the " + std::to_string(remaining()) +
             " bytes left");
    return n;
}

std::string ByteReader::str() {
    const std::uint32_t n = count(1);
    std::string s(reinterpret_cast<const char*>(in_.data() + pos_), n);
    pos_ += n;
    return s;
}

std::span<const std::uint8_t> ByteReader::raw(std::size_t n) {
    need(n);
    auto s = in_.subspan(pos_, n);
    pos_ += n;
    return s;
}

std::vector<double> ByteReader::f64s() {
    std::vector<double> v(count(8));
    for (double& x : v)
        x = f64();
    return v;
}

std::vector<int> ByteReader::i32s() {
    std::vector<int> v(count(4));
    for (int& x : v)
        x = i32();
    return v;
}

std::vector<std::int64_t> ByteReader::i64s() {
    std::vector<std::int64_t> v(count(8));
    for (std::int64_t& x : v)
        x = i64();
    return v;
}

std::vector<bool> ByteReader::bools() {
    const std::uint32_t n = count(1);
    std::vector<bool> v(n);
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint8_t b = u8();
        if (b > 1) fail("a boolean byte holds " + std::to_string(b));
        v[i] = b == 1;
    }
    return v;
}

void ByteReader::expect_end() const {
    if (remaining() != 0) fail(std::to_string(remaining()) + " unexpected trailing bytes");
}

namespace {

constexpr std::array<std::uint32_t, 256> make_crc32c_table() {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
        std::uint32_t c = i;
        for (int k = 0; k < 8; ++k)
            c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
        t[i] = c;
    }
    return t;
}

constexpr auto crc32c_table = make_crc32c_table();

constexpr std::uint32_t result_magic = 0x31525248;  // "HRR1" little-endian

}  // namespace

std::uint32_t crc32c(std::span<const std::uint8_t> data, std::uint32_t crc) {
    crc = ~crc;
    for (std::uint8_t b : data)
        crc = crc32c_table[(crc ^ b) & 0xffu] ^ (crc >> 8);
    return ~crc;
}

std::uint64_t fnv1a64(std::string_view text, std::uint64_t h) {
    for (unsigned char c : text) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

std::string hex64(std::uint64_t v) {
    static constexpr char digits[] = "0123456789abcdef";
    std::string s(16, '0');
    for (int i = 15; i >= 0; --i, v >>= 4)
        s[static_cast<std::size_t>(i)] = digits[v & 0xf];
    return s;
}

namespace {

void encode_fields(ByteWriter& w, const engine::FieldMoments& m) {
    const engine::FieldGrid& g = m.grid;
    w.f64(g.x0);
    w.f64(g.y0);
    w.f64(g.cell);
    w.i32(g.nx);
    w.i32(g.ny);
    w.u8(static_cast<std::uint8_t>(g.kernel));
    w.f64(g.kernel_width);
    w.i64(m.total_windows);
    w.i64(m.samples);
    w.f64(m.t_first);
    w.f64(m.t_last);
    w.i64s(m.windows);
    w.f64s(m.weight);
    for (const auto& v : m.mean)
        w.f64s(v);
    for (const auto& v : m.m2)
        w.f64s(v);
    w.f64s(m.outline_x);
    w.f64s(m.outline_y);
    w.f64(m.wall_diameter);
}

// Bytes per grid node in the encoding: windows, weight, mean and M2 of every field.
constexpr std::uint64_t field_bytes_per_node = 8 * (2 + 2 * engine::field_count);

engine::FieldMoments decode_fields(ByteReader& in) {
    auto finite = [&](double v, const char* what) {
        if (!std::isfinite(v)) in.fail(std::string("fields: ") + what + " is not finite");
        return v;
    };
    engine::FieldMoments m;
    engine::FieldGrid& g = m.grid;
    g.x0 = finite(in.f64(), "the grid origin x0");
    g.y0 = finite(in.f64(), "the grid origin y0");
    g.cell = finite(in.f64(), "the cell size");
    if (!(g.cell > 0.0)) in.fail("fields: a cell size of " + std::to_string(g.cell) + " m");
    g.nx = in.i32();
    g.ny = in.i32();
    if (g.nx <= 0 || g.ny <= 0)
        in.fail("fields: a grid of " + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
                " nodes");
    const std::int64_t nodes = std::int64_t{g.nx} * std::int64_t{g.ny};
    if (nodes > max_field_nodes)
        in.fail("fields: a grid of " + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
                " nodes exceeds the limit of " + std::to_string(max_field_nodes));
    // Check the size before allocating anything: every node needs field_bytes_per_node bytes.
    if (static_cast<std::uint64_t>(nodes) * field_bytes_per_node > in.remaining())
        in.fail("fields: a grid of " + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
                " nodes needs more than the " + std::to_string(in.remaining()) + " bytes left");
    const std::uint8_t kernel = in.u8();
    if (kernel > static_cast<std::uint8_t>(engine::FieldKernel::gaussian))
        in.fail("fields: unknown kernel " + std::to_string(kernel));
    g.kernel = static_cast<engine::FieldKernel>(kernel);
    g.kernel_width = finite(in.f64(), "the kernel width");
    if (g.kernel_width < 0.0 ||
        (g.kernel == engine::FieldKernel::gaussian && g.kernel_width == 0.0))
        in.fail("fields: a kernel width of " + std::to_string(g.kernel_width) + " m");
    m.total_windows = in.i64();
    m.samples = in.i64();
    if (m.total_windows < 0 || m.samples < 0) in.fail("fields: negative window or sample count");
    m.t_first = finite(in.f64(), "t_first");
    m.t_last = finite(in.f64(), "t_last");
    const auto per_node = [&](auto v, const std::string& name) {
        if (v.size() != static_cast<std::size_t>(nodes))
            in.fail("fields: " + name + " has " + std::to_string(v.size()) + " values for " +
                    std::to_string(g.nx) + " x " + std::to_string(g.ny) + " nodes");
        return v;
    };
    m.windows = per_node(in.i64s(), "windows");
    for (std::int64_t n : m.windows)
        if (n < 0) in.fail("fields: a negative window count");
    m.weight = per_node(in.f64s(), "weight");
    for (int f = 0; f < engine::field_count; ++f)
        m.mean[f] =
            per_node(in.f64s(), "mean_" + std::string(engine::field_name(engine::Field(f))));
    for (int f = 0; f < engine::field_count; ++f)
        m.m2[f] = per_node(in.f64s(), "m2_" + std::string(engine::field_name(engine::Field(f))));
    const auto all_finite = [&](const std::vector<double>& v, const char* what) {
        for (double x : v)
            finite(x, what);
    };
    all_finite(m.weight, "a weight");
    for (int f = 0; f < engine::field_count; ++f) {
        all_finite(m.mean[f], "a mean");
        all_finite(m.m2[f], "an M2 value");
    }
    m.outline_x = in.f64s();
    m.outline_y = in.f64s();
    if (m.outline_x.size() != m.outline_y.size())
        in.fail("fields: the outline has " + std::to_string(m.outline_x.size()) + " x and " +
                std::to_string(m.outline_y.size()) + " y values");
    all_finite(m.outline_x, "an outline coordinate");
    all_finite(m.outline_y, "an outline coordinate");
    m.wall_diameter = finite(in.f64(), "the wall diameter");
    return m;
}

void encode_science(ByteWriter& w, const engine::RealizationResult& r) {
    w.i32s(r.avalanche_sizes);
    w.u32(static_cast<std::uint32_t>(r.arches.size()));
    for (const engine::Arch& a : r.arches) {
        w.i32s(a.ids);
        w.f64s(a.x);
        w.f64s(a.y);
        w.f64(a.span);
        w.f64(a.max_angle);
    }
}

void decode_science(ByteReader& in, engine::RealizationResult& r) {
    r.avalanche_sizes = in.i32s();
    if (r.avalanche_sizes.size() != r.survival_times.size())
        in.fail("avalanche sizes: " + std::to_string(r.avalanche_sizes.size()) + " values for " +
                std::to_string(r.survival_times.size()) + " survival intervals");
    for (int s : r.avalanche_sizes)
        if (s < 0) in.fail("avalanche sizes: a negative size " + std::to_string(s));
    const std::uint32_t n = in.u32();
    if (n != r.jam_onsets.size())
        in.fail("arches: " + std::to_string(n) + " arches for " +
                std::to_string(r.jam_onsets.size()) + " jams");
    r.arches.resize(n);
    for (engine::Arch& a : r.arches) {
        a.ids = in.i32s();
        a.x = in.f64s();
        a.y = in.f64s();
        if (a.x.size() != a.ids.size() || a.y.size() != a.ids.size())
            in.fail("arches: " + std::to_string(a.ids.size()) + " disk ids with " +
                    std::to_string(a.x.size()) + " x and " + std::to_string(a.y.size()) +
                    " y positions");
        a.span = in.f64();
        a.max_angle = in.f64();
        for (double v : a.x)
            if (!std::isfinite(v)) in.fail("arches: a non-finite position");
        for (double v : a.y)
            if (!std::isfinite(v)) in.fail("arches: a non-finite position");
        if (!std::isfinite(a.span) || !std::isfinite(a.max_angle) || a.span < 0.0 ||
            a.max_angle < 0.0)
            in.fail("arches: a span or angle that is negative or not finite");
    }
}

}  // namespace

void encode_result(ByteWriter& w, const engine::RealizationResult& r) {
    const bool science = !r.avalanche_sizes.empty() || !r.arches.empty();
    const std::uint16_t version = science    ? result_codec_version
                                  : r.fields ? result_codec_version_fields
                                             : result_codec_version_without_fields;
    w.u32(result_magic);
    w.u8(static_cast<std::uint8_t>(version & 0xff));
    w.u8(static_cast<std::uint8_t>(version >> 8));
    w.u8(static_cast<std::uint8_t>(r.status));
    w.str(r.message);
    w.u64(r.seed);
    w.i32(r.particles);
    w.i32(r.wall_particles);
    w.f64s(r.survival_times);
    w.bools(r.censored);
    w.f64s(r.jam_onsets);
    w.i32s(r.shakes_per_jam);
    w.i32(r.n_jams);
    w.i32(r.n_shakes);
    w.i32(r.n_jams_multi_shake);
    w.u8(r.empty_time ? 1 : 0);
    w.f64(r.empty_time.value_or(0.0));
    w.u8(r.discharge_rate ? 1 : 0);
    w.f64(r.discharge_rate.value_or(0.0));
    w.f64(r.discharge_rate_mass);
    w.i32(r.discharged);
    w.f64s(r.exit_times);
    w.f64s(r.curve_time);
    w.i32s(r.curve_count);
    w.u32(static_cast<std::uint32_t>(r.events.size()));
    for (const auto& e : r.events) {
        w.u8(static_cast<std::uint8_t>(e.kind));
        w.f64(e.time);
        w.f64(e.sim_time);
        w.i32(e.in_hopper);
    }
    const auto& d = r.diagnostics;
    w.i64(d.steps);
    w.i64(d.settle_steps);
    w.i64(d.neighbor_rebuilds);
    for (double v :
         {d.settle_time, d.shake_time, d.wall_seconds, d.ns_per_particle_step, d.max_overlap_ratio,
          d.settled_kinetic_energy, d.potential_energy_released, d.dt, d.tau_c, d.k_n,
          d.seconds_forces, d.seconds_integration, d.seconds_neighbors, d.seconds_observers})
        w.f64(v);
    if (version == result_codec_version) {
        w.u8(r.fields ? 1 : 0);
        if (r.fields) encode_fields(w, *r.fields);
        encode_science(w, r);
    } else if (r.fields) {
        encode_fields(w, *r.fields);
    }
}

Bytes encode_result(const engine::RealizationResult& r) {
    ByteWriter w;
    encode_result(w, r);
    return w.take();
}

engine::RealizationResult decode_result(ByteReader& in) {
    if (in.u32() != result_magic) in.fail("not an encoded realization result (bad magic)");
    const std::uint16_t version = static_cast<std::uint16_t>(in.u8() | (in.u8() << 8));
    if (version < result_codec_version_without_fields || version > result_codec_version)
        in.fail("result encoding version " + std::to_string(version) + " is not supported (this " +
                "build reads versions " + std::to_string(result_codec_version_without_fields) +
                " to " + std::to_string(result_codec_version) + ")");
    engine::RealizationResult r;
    const std::uint8_t status = in.u8();
    if (status > static_cast<std::uint8_t>(engine::Status::failed))
        in.fail("unknown status " + std::to_string(status));
    r.status = static_cast<engine::Status>(status);
    r.message = in.str();
    r.seed = in.u64();
    r.particles = in.i32();
    r.wall_particles = in.i32();
    r.survival_times = in.f64s();
    r.censored = in.bools();
    r.jam_onsets = in.f64s();
    r.shakes_per_jam = in.i32s();
    r.n_jams = in.i32();
    r.n_shakes = in.i32();
    r.n_jams_multi_shake = in.i32();
    const bool has_empty = in.u8() != 0;
    const double empty = in.f64();
    if (has_empty) r.empty_time = empty;
    const bool has_rate = in.u8() != 0;
    const double rate = in.f64();
    if (has_rate) r.discharge_rate = rate;
    r.discharge_rate_mass = in.f64();
    r.discharged = in.i32();
    r.exit_times = in.f64s();
    r.curve_time = in.f64s();
    r.curve_count = in.i32s();
    const std::uint32_t n_events = in.u32();
    if (static_cast<std::uint64_t>(n_events) * 21 > in.remaining())
        in.fail("an event count of " + std::to_string(n_events) + " exceeds the bytes left");
    r.events.resize(n_events);
    for (auto& e : r.events) {
        const std::uint8_t kind = in.u8();
        if (kind > static_cast<std::uint8_t>(engine::Event::Kind::stop))
            in.fail("unknown event kind " + std::to_string(kind));
        e.kind = static_cast<engine::Event::Kind>(kind);
        e.time = in.f64();
        e.sim_time = in.f64();
        e.in_hopper = in.i32();
    }
    auto& d = r.diagnostics;
    d.steps = in.i64();
    d.settle_steps = in.i64();
    d.neighbor_rebuilds = in.i64();
    for (double* v : {&d.settle_time, &d.shake_time, &d.wall_seconds, &d.ns_per_particle_step,
                      &d.max_overlap_ratio, &d.settled_kinetic_energy, &d.potential_energy_released,
                      &d.dt, &d.tau_c, &d.k_n, &d.seconds_forces, &d.seconds_integration,
                      &d.seconds_neighbors, &d.seconds_observers})
        *v = in.f64();
    if (version == result_codec_version_fields) r.fields = decode_fields(in);
    if (version == result_codec_version) {
        const std::uint8_t has_fields = in.u8();
        if (has_fields > 1) in.fail("a fields flag of " + std::to_string(has_fields));
        if (has_fields) r.fields = decode_fields(in);
        decode_science(in, r);
    }
    return r;
}

engine::RealizationResult decode_result(std::span<const std::uint8_t> bytes,
                                        const std::string& what) {
    ByteReader in(bytes, what);
    engine::RealizationResult r = decode_result(in);
    in.expect_end();
    return r;
}

engine::RealizationResult without_wall_clock(engine::RealizationResult r) {
    auto& d = r.diagnostics;
    d.wall_seconds = d.ns_per_particle_step = 0.0;
    d.seconds_forces = d.seconds_integration = d.seconds_neighbors = d.seconds_observers = 0.0;
    return r;
}

std::uint64_t physics_digest(const engine::RealizationResult& r) {
    const Bytes b = encode_result(without_wall_clock(r));
    return fnv1a64(std::string_view(reinterpret_cast<const char*>(b.data()), b.size()));
}

}  // namespace hopper::store
