#include "hopper/store/codec.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "hopper/core/error.hpp"
#include "hopper/store/result_fields.hpp"

namespace hopper::store {

static_assert(std::endian::native == std::endian::little ||
              std::endian::native == std::endian::big);

void ByteReader::raise(const std::string& message) const {
    throw core::StoreError(message);
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

std::uint32_t crc32c_bytewise(const std::uint8_t* p, std::size_t n, std::uint32_t crc) {
    for (std::size_t i = 0; i < n; ++i)
        crc = crc32c_table[(crc ^ p[i]) & 0xffu] ^ (crc >> 8);
    return crc;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// SSE 4.2's crc32 instruction computes this very CRC (Castagnoli, reflected), 8 bytes at a
// time: the same value as the table, about 15x faster (issue 44: the table was 13 % of the
// master's time at 64 workers, and most of a journal replay's).
__attribute__((target("sse4.2"))) std::uint32_t crc32c_sse42(const std::uint8_t* p, std::size_t n,
                                                             std::uint32_t crc) {
    std::uint64_t c = crc;
    for (; n >= 8; n -= 8, p += 8) {
        std::uint64_t v;
        std::memcpy(&v, p, 8);
        c = __builtin_ia32_crc32di(c, v);
    }
    auto c32 = static_cast<std::uint32_t>(c);
    for (; n > 0; --n, ++p)
        c32 = __builtin_ia32_crc32qi(c32, *p);
    return c32;
}
bool have_sse42() {
    static const bool have = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("sse4.2") != 0;
    }();
    return have;
}
#endif

}  // namespace

std::uint32_t crc32c(std::span<const std::uint8_t> data, std::uint32_t crc) {
    crc = ~crc;
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if constexpr (std::endian::native == std::endian::little)
        if (have_sse42()) return ~crc32c_sse42(data.data(), data.size(), crc);
#endif
    return ~crc32c_bytewise(data.data(), data.size(), crc);
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

void encode_arch(ByteWriter& w, const engine::Arch& a) {
    w.i32s(a.ids);
    w.f64s(a.x);
    w.f64s(a.y);
    w.f64(a.span);
    w.f64(a.max_angle);
}

void decode_arch(ByteReader& in, engine::Arch& a) {
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
    if (!std::isfinite(a.span) || !std::isfinite(a.max_angle) || a.span < 0.0 || a.max_angle < 0.0)
        in.fail("arches: a span or angle that is negative or not finite");
}

// Bytes of one encoded event: the sum of its members' widths.
constexpr std::uint64_t event_bytes = [] {
    std::uint64_t n = 0;
    for_each_event_field([&n](const auto& f) {
        using M = std::remove_cvref_t<decltype(engine::Event{}.*f.member)>;
        n += std::is_same_v<M, engine::Event::Kind> ? 1 : sizeof(M);
    });
    return n;
}();
static_assert(event_bytes == 21);

// One member in the journal's encoding, chosen by its type. The result's version decides the
// fields' framing (version 2: bare; version 3: a presence byte first).
struct Encoder {
    ByteWriter& w;
    std::uint16_t version;

    void put(engine::Status v) { w.u8(static_cast<std::uint8_t>(v)); }
    void put(engine::Event::Kind v) { w.u8(static_cast<std::uint8_t>(v)); }
    void put(const std::string& v) { w.str(v); }
    void put(std::uint64_t v) { w.u64(v); }
    void put(std::int64_t v) { w.i64(v); }
    void put(int v) { w.i32(v); }
    void put(double v) { w.f64(v); }
    void put(const std::optional<double>& v) {
        w.u8(v ? 1 : 0);
        w.f64(v.value_or(0.0));
    }
    void put(const std::vector<double>& v) { w.f64s(v); }
    void put(const std::vector<int>& v) { w.i32s(v); }
    void put(const std::vector<bool>& v) { w.bools(v); }
    void put(const std::vector<engine::Event>& v) {
        w.u32(static_cast<std::uint32_t>(v.size()));
        for (const engine::Event& e : v)
            for_each_event_field([&](const auto& f) { put(e.*f.member); });
    }
    void put(const engine::Diagnostics& d) {
        for_each_diagnostic([&](const auto& f) {
            if (f.placement != Placement::nowhere && f.since <= version) put(d.*f.member);
        });
    }
    void put(const std::optional<engine::FieldMoments>& v) {
        if (version >= result_codec_version_science) {
            w.u8(v ? 1 : 0);
            if (v) encode_fields(w, *v);
        } else if (v) {
            encode_fields(w, *v);
        }
    }
    void put(const std::vector<engine::Arch>& v) {
        w.u32(static_cast<std::uint32_t>(v.size()));
        for (const engine::Arch& a : v)
            encode_arch(w, a);
    }
};

// The inverse of Encoder, checking what it reads; `r` is the result read so far (the arrays
// whose lengths follow another's are checked against it).
struct Decoder {
    ByteReader& in;
    std::uint16_t version;
    const engine::RealizationResult& r;

    void get(engine::Status& v) {
        const std::uint8_t status = in.u8();
        if (status > static_cast<std::uint8_t>(engine::Status::failed))
            in.fail("unknown status " + std::to_string(status));
        v = static_cast<engine::Status>(status);
    }
    void get(engine::Event::Kind& v) {
        const std::uint8_t kind = in.u8();
        if (kind > static_cast<std::uint8_t>(engine::Event::Kind::stop))
            in.fail("unknown event kind " + std::to_string(kind));
        v = static_cast<engine::Event::Kind>(kind);
    }
    void get(std::string& v) { v = in.str(); }
    void get(std::uint64_t& v) { v = in.u64(); }
    void get(std::int64_t& v) { v = in.i64(); }
    void get(int& v) { v = in.i32(); }
    void get(double& v) { v = in.f64(); }
    void get(std::optional<double>& v) {
        const bool has = in.u8() != 0;
        const double x = in.f64();
        if (has) v = x;
    }
    void get(std::vector<double>& v) { v = in.f64s(); }
    void get(std::vector<bool>& v) { v = in.bools(); }
    void get(std::vector<int>& v) {
        v = in.i32s();
        if (&v != &r.avalanche_sizes) return;
        if (v.size() != r.survival_times.size())
            in.fail("avalanche sizes: " + std::to_string(v.size()) + " values for " +
                    std::to_string(r.survival_times.size()) + " survival intervals");
        for (int s : v)
            if (s < 0) in.fail("avalanche sizes: a negative size " + std::to_string(s));
    }
    void get(std::vector<engine::Event>& v) {
        const std::uint32_t n = in.u32();
        if (static_cast<std::uint64_t>(n) * event_bytes > in.remaining())
            in.fail("an event count of " + std::to_string(n) + " exceeds the bytes left");
        v.resize(n);
        for (engine::Event& e : v)
            for_each_event_field([&](const auto& f) { get(e.*f.member); });
    }
    void get(engine::Diagnostics& d) {
        for_each_diagnostic([&](const auto& f) {
            if (f.placement != Placement::nowhere && f.since <= version) get(d.*f.member);
        });
    }
    void get(std::optional<engine::FieldMoments>& v) {
        if (version >= result_codec_version_science) {
            const std::uint8_t has_fields = in.u8();
            if (has_fields > 1) in.fail("a fields flag of " + std::to_string(has_fields));
            if (!has_fields) return;
        }
        v = decode_fields(in);
    }
    void get(std::vector<engine::Arch>& v) {
        const std::uint32_t n = in.u32();
        if (n != r.jam_onsets.size())
            in.fail("arches: " + std::to_string(n) + " arches for " +
                    std::to_string(r.jam_onsets.size()) + " jams");
        v.resize(n);
        for (engine::Arch& a : v)
            decode_arch(in, a);
    }
};

// An array of a ragged family has one value per element of the family's first array (read
// before it, in the description's order): survival intervals, jams, exits, curve samples.
template <class F>
void check_family_length(ByteReader& in, const F& f, const engine::RealizationResult& r) {
    using M = std::remove_cvref_t<decltype(r.*f.member)>;
    if constexpr (requires(const M& v) { v.size(); } && !std::is_same_v<M, std::string>) {
        const auto want = engine::family_length(r, f.family);
        if (want && (r.*f.member).size() != *want)
            in.fail(std::string(f.name) + ": " + std::to_string((r.*f.member).size()) +
                    " values for " + std::to_string(*want) + " elements of its family (" +
                    std::string(f.family == Family::survival ? "survival intervals"
                                : f.family == Family::jam    ? "jams"
                                                             : "samples") +
                    ")");
    }
}

}  // namespace

void encode_result(ByteWriter& w, const engine::RealizationResult& r) {
    // The version follows from the members the result holds (engine::result_version): a result
    // without the later members keeps the bytes it had before they existed.
    const std::uint16_t version = engine::result_version(r);
    w.u32(result_magic);
    w.u8(static_cast<std::uint8_t>(version & 0xff));
    w.u8(static_cast<std::uint8_t>(version >> 8));
    Encoder e{w, version};
    for_each_result_field([&](const auto& f) {
        if (f.since <= version) e.put(r.*f.member);
    });
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
    Decoder d{in, version, r};
    for_each_result_field([&](const auto& f) {
        if (f.since > version) return;
        d.get(r.*f.member);
        check_family_length(in, f, r);
    });
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
    for_each_diagnostic([&r](const auto& f) {
        if (f.wall_clock) r.diagnostics.*f.member = {};
    });
    return r;
}

std::uint64_t physics_digest(const engine::RealizationResult& r) {
    const Bytes b = encode_result(without_wall_clock(r));
    return fnv1a64(std::string_view(reinterpret_cast<const char*>(b.data()), b.size()));
}

}  // namespace hopper::store
