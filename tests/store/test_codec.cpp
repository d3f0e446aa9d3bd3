// The binary codec: checksums, and the result encoding's round trip and checks.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string_view>
#include <vector>

#include "fixtures.hpp"
#include "hopper/core/error.hpp"
#include "hopper/store/codec.hpp"

namespace hopper::store {
namespace {

std::span<const std::uint8_t> bytes_of(std::string_view s) {
    return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(Checksums, Crc32cCheckValue) {
    // The standard check value of CRC-32C (RFC 3720, appendix B.4 lists the algorithm).
    EXPECT_EQ(crc32c(bytes_of("123456789")), 0xE3069283u);
    EXPECT_EQ(crc32c(bytes_of("")), 0u);
    // Continuing a checksum equals checksumming the concatenation.
    EXPECT_EQ(crc32c(bytes_of("6789"), crc32c(bytes_of("12345"))), 0xE3069283u);
}

TEST(Checksums, Crc32cEqualsTheBitwiseDefinitionAtEveryLengthAndOffset) {
    // The 8-bytes-at-a-time path (SSE 4.2, issue 44) against the CRC's definition, bit by bit,
    // over every length 0..99 at every start 0..7 (unaligned heads and tails) and a long run.
    std::vector<std::uint8_t> data(5000);
    std::uint32_t x = 12345;
    for (auto& b : data) {
        x = x * 1664525u + 1013904223u;
        b = static_cast<std::uint8_t>(x >> 24);
    }
    auto bitwise = [](std::span<const std::uint8_t> d) {
        std::uint32_t c = ~0u;
        for (std::uint8_t b : d) {
            c ^= b;
            for (int k = 0; k < 8; ++k)
                c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
        }
        return ~c;
    };
    const std::span<const std::uint8_t> all(data);
    for (std::size_t start = 0; start < 8; ++start)
        for (std::size_t n = 0; n < 100; ++n)
            ASSERT_EQ(crc32c(all.subspan(start, n)), bitwise(all.subspan(start, n)))
                << "start " << start << ", length " << n;
    EXPECT_EQ(crc32c(all), bitwise(all));
    EXPECT_EQ(crc32c(all.subspan(1237), crc32c(all.first(1237))), bitwise(all));
}

TEST(Checksums, Fnv1a64KnownValues) {
    EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);  // the offset basis
    EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(hex64(0x0123456789abcdefull), "0123456789abcdef");
}

void expect_same(const engine::RealizationResult& a, const engine::RealizationResult& b) {
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.message, b.message);
    EXPECT_EQ(a.seed, b.seed);
    EXPECT_EQ(a.particles, b.particles);
    EXPECT_EQ(a.wall_particles, b.wall_particles);
    EXPECT_EQ(a.survival_times, b.survival_times);
    EXPECT_EQ(a.censored, b.censored);
    EXPECT_EQ(a.jam_onsets, b.jam_onsets);
    EXPECT_EQ(a.shakes_per_jam, b.shakes_per_jam);
    EXPECT_EQ(a.n_jams, b.n_jams);
    EXPECT_EQ(a.n_shakes, b.n_shakes);
    EXPECT_EQ(a.n_jams_multi_shake, b.n_jams_multi_shake);
    EXPECT_EQ(a.empty_time, b.empty_time);
    EXPECT_EQ(a.discharge_rate, b.discharge_rate);
    EXPECT_EQ(a.discharge_rate_mass, b.discharge_rate_mass);
    EXPECT_EQ(a.discharged, b.discharged);
    EXPECT_EQ(a.exit_times, b.exit_times);
    EXPECT_EQ(a.curve_time, b.curve_time);
    EXPECT_EQ(a.curve_count, b.curve_count);
    ASSERT_EQ(a.events.size(), b.events.size());
    for (std::size_t i = 0; i < a.events.size(); ++i) {
        EXPECT_EQ(a.events[i].kind, b.events[i].kind);
        EXPECT_EQ(a.events[i].time, b.events[i].time);
        EXPECT_EQ(a.events[i].sim_time, b.events[i].sim_time);
        EXPECT_EQ(a.events[i].in_hopper, b.events[i].in_hopper);
    }
    EXPECT_EQ(a.diagnostics.steps, b.diagnostics.steps);
    EXPECT_EQ(a.diagnostics.k_n, b.diagnostics.k_n);
    EXPECT_EQ(a.diagnostics.seconds_observers, b.diagnostics.seconds_observers);
    // Everything else: the encodings are byte-identical.
    EXPECT_EQ(encode_result(a), encode_result(b));
}

TEST(ResultCodec, RoundTripsEveryField) {
    for (int k = 0; k < 6; ++k) {
        const auto r = testing::fabricated(k, k % 2 == 0);
        const Bytes b = encode_result(r);
        expect_same(decode_result(b), r);
    }
}

TEST(ResultCodec, RejectsTruncationTrailingBytesAndBadValues) {
    const Bytes b = encode_result(testing::fabricated(4));
    for (std::size_t n = 0; n < b.size(); ++n)
        EXPECT_THROW(decode_result(std::span(b.data(), n)), core::StoreError) << "length " << n;
    Bytes longer = b;
    longer.push_back(0);
    try {
        decode_result(longer, "result of task 3");
        FAIL() << "trailing byte accepted";
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("result of task 3: 1 unexpected trailing bytes"),
                  std::string::npos)
            << e.what();
    }
    Bytes bad = b;
    bad[0] ^= 1;  // magic
    EXPECT_THROW(decode_result(bad), core::StoreError);
    bad = b;
    bad[4] = 99;  // version
    try {
        decode_result(bad);
        FAIL();
    } catch (const core::StoreError& e) {
        EXPECT_NE(std::string(e.what()).find("version 99 is not supported"), std::string::npos);
    }
    bad = b;
    bad[6] = 9;  // status
    EXPECT_THROW(decode_result(bad), core::StoreError);
}

void expect_same_fields(const engine::FieldMoments& a, const engine::FieldMoments& b) {
    EXPECT_EQ(a.grid, b.grid);
    EXPECT_EQ(a.windows, b.windows);
    EXPECT_EQ(a.weight, b.weight);
    EXPECT_EQ(a.mean, b.mean);
    EXPECT_EQ(a.m2, b.m2);
    EXPECT_EQ(a.total_windows, b.total_windows);
    EXPECT_EQ(a.samples, b.samples);
    EXPECT_EQ(a.t_first, b.t_first);
    EXPECT_EQ(a.t_last, b.t_last);
    EXPECT_EQ(a.outline_x, b.outline_x);
    EXPECT_EQ(a.outline_y, b.outline_y);
    EXPECT_EQ(a.wall_diameter, b.wall_diameter);
}

TEST(ResultCodec, RoundTripsFields) {
    for (int k = 0; k < 4; ++k) {
        const auto r = testing::with_fields(testing::fabricated(k, k % 2 == 0), k, 3 + k, 2 + k);
        const Bytes b = encode_result(r);
        EXPECT_EQ(b[4], 2) << "a result with fields is encoding version 2";
        const auto back = decode_result(b);
        ASSERT_TRUE(back.fields.has_value());
        expect_same_fields(*back.fields, *r.fields);
        expect_same(back, r);
    }
}

// fabricated(3, false) as encoded by the version-1 encoder, before fields existed (the bytes of a
// result record in a store written then).
constexpr std::string_view version1_record =
    "485252310100030c0000006d657373616765203320c3a9eb03000000000000530000002b00000001000000fca9f1d2"
    "4d"
    "62c03f0100000001000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00"
    "0000000000004900000008000000e0413adc11c5293eec5bc2aee17a843f3338387be17a943f70420f1f52b89e3f57"
    "26"
    "7361e17aa43f76ab5eb39999a93f94304a0552b8ae3fdada9a2b85ebb13f0700000000000000000000007b14ae47e1"
    "7a"
    "843f7b14ae47e17a943fb81e85eb51b89e3f7b14ae47e17aa43f9a9999999999a93fb81e85eb51b8ae3f0700000064"
    "00"
    "0000630000006200000061000000600000005f0000005e00000004000000000000000000000000333333333333d33f"
    "50"
    "000000010000000000000000333333333333d33f50000000029a9999999999d93f000000000000e83f2f0000000600"
    "00"
    "00000000f83f00000000000000400000000043e201000000000029090000000000004d000000000000003333333333"
    "33"
    "d33f343333333333c33f0000000000000e4000000000006054408d28ed0dbe30893f95d626e80b2e113e7b14ae47e1"
    "7a"
    "943f8dedb5a0f7c6f03e2d431cebe2364a3f0000000000f591409a9999999999d93f9a9999999999b93f9a99999999"
    "99"
    "a93f7b14ae47e17a843f";

Bytes from_hex(std::string_view hex) {
    Bytes b;
    for (std::size_t i = 0; i + 1 < hex.size(); i += 2)
        b.push_back(
            static_cast<std::uint8_t>(std::stoul(std::string(hex.substr(i, 2)), nullptr, 16)));
    return b;
}

TEST(ResultCodec, Version1RecordsStillDecodeAndResultsWithoutFieldsAreStillVersion1) {
    const Bytes old = from_hex(version1_record);
    ASSERT_EQ(old.size(), 490u);
    const auto r = decode_result(old, "old record");
    EXPECT_EQ(r.status, engine::Status::failed);
    EXPECT_EQ(r.message, "message 3 \xc3\xa9");
    EXPECT_EQ(r.seed, 1003u);
    EXPECT_EQ(r.particles, 83);
    EXPECT_EQ(r.exit_times.size(), 8u);
    EXPECT_EQ(r.events.size(), 4u);
    EXPECT_FALSE(r.empty_time.has_value());
    EXPECT_EQ(r.diagnostics.k_n, 1149.25);
    EXPECT_FALSE(r.fields.has_value());
    expect_same(r, testing::fabricated(3, false));
    // Without fields the encoding is unchanged byte for byte (version 1): stores without fields
    // look exactly as before, and older builds read them.
    EXPECT_EQ(encode_result(r), old);
}

// The byte offset of the fields block in an encoding (the version-1 part comes first).
std::size_t fields_offset(const engine::RealizationResult& r) {
    auto without = r;
    without.fields.reset();
    return encode_result(without).size();
}

std::string decode_error_of(const Bytes& b) {
    try {
        decode_result(b, "record");
    } catch (const core::StoreError& e) {
        return e.what();
    }
    return "(decoded)";
}

template <class T>
void put(Bytes& b, std::size_t at, T v) {
    for (std::size_t i = 0; i < sizeof v; ++i)
        b[at + i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i));
}

TEST(ResultCodec, DamagedFieldsAreCleanErrors) {
    const auto r = testing::with_fields(testing::fabricated(2), 1, 4, 3);  // 12 nodes
    const Bytes good = encode_result(r);
    const std::size_t at = fields_offset(r);
    // The fields block: x0 y0 cell (f64) nx ny (i32) kernel (u8) kernel_width total_windows
    // samples t_first t_last (8 bytes each), then the windows count.
    const std::size_t nx = at + 24, ny = at + 28, kernel = at + 32, windows = at + 73;
    auto with = [&](auto edit) {
        Bytes b = good;
        edit(b);
        return decode_error_of(b);
    };
    auto has = [](const std::string& s, const char* part) {
        return s.find(part) != std::string::npos;
    };
    // Absurd grids fail before anything is allocated.
    std::string e = with([&](Bytes& b) {
        put<std::int32_t>(b, nx, 1 << 30);
        put<std::int32_t>(b, ny, 1 << 30);
    });
    EXPECT_TRUE(has(e, "exceeds the limit")) << e;
    e = with([&](Bytes& b) { put<std::int32_t>(b, nx, 2000); });
    EXPECT_TRUE(has(e, "bytes left")) << e;
    e = with([&](Bytes& b) { put<std::int32_t>(b, ny, -3); });
    EXPECT_TRUE(has(e, "a grid of 4 x -3 nodes")) << e;
    // Per-node arrays whose length is not nx * ny.
    e = with([&](Bytes& b) { put<std::int32_t>(b, ny, 2); });
    EXPECT_TRUE(has(e, "windows has 12 values for 4 x 2 nodes")) << e;
    e = with([&](Bytes& b) { put<std::uint32_t>(b, windows, 11); });
    EXPECT_TRUE(has(e, "fields")) << e;
    e = with([&](Bytes& b) { b[kernel] = 7; });
    EXPECT_TRUE(has(e, "unknown kernel 7")) << e;
    e = with([&](Bytes& b) { put<std::int64_t>(b, windows + 4, -1); });
    EXPECT_TRUE(has(e, "negative window count")) << e;
    // Non-finite numbers anywhere in the fields.
    auto nonfinite = [&](auto set) {
        auto bad = r;
        set(*bad.fields);
        return decode_error_of(encode_result(bad));
    };
    const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.mean[1][5] = nan; }), "a mean is not finite"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.m2[3][0] = inf; }), "M2 value is not finite"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.weight[2] = -inf; }), "weight is not finite"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.grid.cell = nan; }), "cell size is not finite"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.outline_y[1] = nan; }), "outline"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.t_last = inf; }), "t_last is not finite"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.outline_y.pop_back(); }), "the outline has"));
    EXPECT_TRUE(has(nonfinite([&](auto& m) { m.weight.pop_back(); }), "weight has 11 values"));
    // Truncated anywhere: an error, never a crash.
    for (std::size_t n = at; n < good.size(); ++n)
        EXPECT_THROW(decode_result(std::span(good.data(), n)), core::StoreError) << n;
    // Every byte of the fields block replaced by a few values: decodes or a StoreError, nothing
    // else (no crash, no other exception, no huge allocation).
    for (std::size_t i = at; i < good.size(); ++i)
        for (std::uint8_t v : {0x00, 0x01, 0x7f, 0x80, 0xff}) {
            Bytes b = good;
            b[i] = v;
            try {
                decode_result(b);
            } catch (const core::StoreError&) {
            }
        }
}

TEST(ResultCodec, AvalanchesAndArchesAreVersion3AndRoundTrip) {
    for (int k = 0; k < 6; ++k) {
        auto r = testing::with_science(testing::fabricated(k), k);
        if (k % 2) r = testing::with_fields(r, k);
        const Bytes b = encode_result(r);
        EXPECT_EQ(b[4] | (b[5] << 8), 3) << k;
        const auto back = decode_result(b);
        EXPECT_EQ(back.avalanche_sizes, r.avalanche_sizes);
        ASSERT_EQ(back.arches.size(), r.arches.size());
        for (std::size_t j = 0; j < r.arches.size(); ++j) {
            EXPECT_EQ(back.arches[j].ids, r.arches[j].ids);
            EXPECT_EQ(back.arches[j].y, r.arches[j].y);
            EXPECT_EQ(back.arches[j].max_angle, r.arches[j].max_angle);
        }
        EXPECT_EQ(back.fields.has_value(), r.fields.has_value());
        EXPECT_EQ(encode_result(back), b);
    }
}

TEST(ResultCodec, InconsistentAvalanchesAndArchesAreCleanErrors) {
    auto r = testing::with_science(testing::fabricated(2), 1);  // 3 intervals, 2 jams
    auto bad = r;
    bad.avalanche_sizes.pop_back();
    EXPECT_NE(decode_error_of(encode_result(bad)).find("avalanche sizes: 2 values for 3 survival"),
              std::string::npos)
        << decode_error_of(encode_result(bad));
    bad = r;
    bad.arches.pop_back();
    EXPECT_NE(decode_error_of(encode_result(bad)).find("arches: 1 arches for 2 jams"),
              std::string::npos);
    bad = r;
    bad.arches[1].x.pop_back();
    EXPECT_NE(decode_error_of(encode_result(bad)).find("disk ids with"), std::string::npos);
    bad = r;
    bad.avalanche_sizes[0] = -1;
    EXPECT_NE(decode_error_of(encode_result(bad)).find("negative size"), std::string::npos);
}

// Every array of a family has as many values as the family's first array (the check follows
// the description, so an array added to a family later is checked too).
TEST(ResultCodec, AnArrayOfAFamilyWithAnotherLengthIsACleanError) {
    const auto r = testing::with_science(testing::fabricated(2), 1);  // 3 intervals, 2 jams
    auto bad = r;
    bad.shakes_per_jam.pop_back();
    EXPECT_NE(decode_error_of(encode_result(bad))
                  .find("shakes_per_jam: 1 values for 2 elements of its family (jams)"),
              std::string::npos)
        << decode_error_of(encode_result(bad));
    bad = r;
    bad.censored.push_back(true);
    EXPECT_NE(decode_error_of(encode_result(bad))
                  .find("censored: 4 values for 3 elements of its family (survival intervals)"),
              std::string::npos)
        << decode_error_of(encode_result(bad));
    bad = r;
    bad.curve_count.push_back(1);
    EXPECT_NE(decode_error_of(encode_result(bad)).find("curve_count: "), std::string::npos);
}

// Every journal record type, fabricated with every member set, keeps the bytes it was written
// with (frozen: the FNV-1a 64 of each encoding, taken when the records were first described
// once, issue 42), decodes back to what was encoded, and reads the shapes older writers left
// (a run end before issue 15, a sync record before checksums, a plan before its settings and
// its limits).
struct RecordSamples {
    RunStartRecord start;
    ResultRecord result;
    ErrorRecord error{"D_cm=3 theta_deg=60", 2, 77, 3, 2, 1.7e9 + 0.25, "std::bad_alloc \xc3\xa9"};
    DispatchRecord dispatch{"D_cm=3 theta_deg=60", 4, 99, 2, 1, 1.7e9 + 0.5};
    RunEndRecord end{"2026-11-29T19:00:00Z", "interrupted by SIGTERM", 12, 34.5, 0.75, 3.25, 8.5};
    SyncRecord sync{0x1234567890abcdefull, 4096, 12, FileChecksum{1 << 20, 0xdeadbeefu}};
    AllotmentRecord allot{{{"D_cm=3 theta_deg=60", 4, {5, 6, 7}}, {"D_cm=4 theta_deg=60", 0, {8}}}};
    RecordSamples() {
        start = testing::run_record({testing::point("D_cm=3 theta_deg=60", 3),
                                     testing::point("D_cm=4 theta_deg=60 material.mu=0.5", 2)},
                                    11);
        start.run.start_time = "2026-11-29T18:00:00Z";
        start.run.hosts = {"node1", "node2", "node2"};
        start.run.mpi_size = 3;
        start.run.workers = 2;
        start.run.pid = 4242;
        start.plan.points[0].settings = {{"D_cm", 3.0}, {"theta_deg", 60.0}};
        start.plan.points[0].parameters = {{"material.mu", 0.5}, {"integrator.scheme", "gear4"}};
        start.plan.points[1].limit = 9;
        result = testing::result_record(start.plan.points[0], 1, testing::fabricated(2), 2);
    }
};

TEST(Records, EveryTypeKeepsItsBytesAndDecodesBack) {
    const RecordSamples s;
    const auto frozen = [](const Bytes& b) {
        return hex64(fnv1a64(std::string(b.begin(), b.end()))) + " " + std::to_string(b.size());
    };
    EXPECT_EQ(frozen(encode(s.start)), "a8304f8599551d33 554");
    EXPECT_EQ(frozen(encode(s.result)), "62ad7ad6f3b36f35 575");
    EXPECT_EQ(frozen(encode(s.error)), "8f12ffdc35f6f76a 72");
    EXPECT_EQ(frozen(encode(s.dispatch)), "1ca588249650e0a7 51");
    EXPECT_EQ(frozen(encode(s.end)), "abc467f14c44590b 86");
    EXPECT_EQ(frozen(encode(s.sync)), "7c25376c061cd5a0 36");
    EXPECT_EQ(frozen(encode(s.allot)), "e02f70b563e6c230 98");
    // Decoded and encoded again: the same bytes (every member came back).
    EXPECT_EQ(encode(decode_run_start(encode(s.start))), encode(s.start));
    EXPECT_EQ(encode(decode_result_record(encode(s.result))), encode(s.result));
    EXPECT_EQ(encode(decode_error(encode(s.error))), encode(s.error));
    EXPECT_EQ(encode(decode_dispatch(encode(s.dispatch))), encode(s.dispatch));
    EXPECT_EQ(encode(decode_run_end(encode(s.end))), encode(s.end));
    EXPECT_EQ(encode(decode_sync(encode(s.sync))), encode(s.sync));
    EXPECT_EQ(encode(decode_allotment(encode(s.allot))), encode(s.allot));
    const RunStartRecord back = decode_run_start(encode(s.start));
    ASSERT_EQ(back.plan.points.size(), 2u);
    EXPECT_EQ(back.plan.points[0].parameters, s.start.plan.points[0].parameters);
    EXPECT_EQ(back.plan.points[1].limit, 9);
    EXPECT_EQ(back.run.hosts, s.start.run.hosts);
    EXPECT_EQ(decode_sync(encode(s.sync)).file, s.sync.file);
    EXPECT_EQ(decode_allotment(encode(s.allot)).points[1].seeds, std::vector<std::uint64_t>{8});
}

TEST(Records, OlderShapesStillDecode) {
    const RecordSamples s;
    // A run end before issue 15: no worker seconds.
    Bytes end = encode(s.end);
    end.resize(end.size() - 16);
    const RunEndRecord e = decode_run_end(end);
    EXPECT_EQ(e.reason, s.end.reason);
    EXPECT_EQ(e.master_cpu_seconds, 0.75);
    EXPECT_EQ(e.lost_worker_seconds, 0.0);
    EXPECT_EQ(e.saved_worker_seconds, 0.0);
    // A sync record before checksums.
    SyncRecord bare = s.sync;
    bare.file.reset();
    EXPECT_EQ(encode(bare).size(), 24u);
    EXPECT_FALSE(decode_sync(encode(bare)).file.has_value());
    // A plan before its limits (issue 29: every seed listed, the limit is their count), and
    // before its typed settings.
    RunStartRecord old = s.start;
    for (auto& pt : old.plan.points)
        pt.limit = 0;
    Bytes start = encode(old);
    start.resize(start.size() - 4 - 4 * old.plan.points.size());  // the format and the limits
    const RunStartRecord no_limits = decode_run_start(start);
    EXPECT_EQ(no_limits.plan.points[1].limit, 2);
    EXPECT_EQ(no_limits.plan.points[0].parameters, s.start.plan.points[0].parameters);
    for (auto& pt : old.plan.points)
        pt.settings.clear(), pt.parameters.clear();
    Bytes bare_plan = encode(old);
    bare_plan.resize(bare_plan.size() - 4 - 4 * old.plan.points.size() - 8 * 2);
    const RunStartRecord no_settings = decode_run_start(bare_plan);
    EXPECT_TRUE(no_settings.plan.points[0].parameters.empty());
    EXPECT_EQ(no_settings.plan.points[0].seeds, s.start.plan.points[0].seeds);
    // Damage is named: an impossible count, a negative first realization, a plan format from
    // a newer writer, bytes left over.
    const auto refusal = [](const std::function<void()>& f) -> std::string {
        try {
            f();
        } catch (const core::StoreError& e) {
            return e.what();
        }
        return "(decoded)";
    };
    Bytes allot = encode(s.allot);
    allot[0] = 0xff;
    EXPECT_NE(refusal([&] { decode_allotment(allot); }).find("a point count of"),
              std::string::npos);
    AllotmentRecord negative = s.allot;
    negative.points[0].first = -1;
    EXPECT_NE(refusal([&] {
                  decode_allotment(encode(negative));
              }).find("a negative first realization -1"),
              std::string::npos);
    Bytes newer = encode(s.start);
    newer[newer.size() - 4 - 4 * 2] = 3;  // the plan format after the settings
    EXPECT_NE(refusal([&] { decode_run_start(newer); }).find("plan format 3 is unknown"),
              std::string::npos);
    Bytes longer = encode(s.error);
    longer.push_back(0);
    EXPECT_NE(refusal([&] { decode_error(longer); }).find("journal error record: 1 unexpected"),
              std::string::npos);
}

TEST(ResultCodec, PhysicsDigestIgnoresOnlyWallClock) {
    const auto a = testing::fabricated(2);
    auto b = a;
    b.diagnostics.wall_seconds += 10;
    b.diagnostics.ns_per_particle_step *= 2;
    b.diagnostics.seconds_forces += 1;
    EXPECT_EQ(physics_digest(a), physics_digest(b));
    EXPECT_NE(encode_result(a), encode_result(b));
    b.survival_times[0] = std::nextafter(b.survival_times[0], 1.0);  // one ulp
    EXPECT_NE(physics_digest(a), physics_digest(b));
}

}  // namespace
}  // namespace hopper::store
