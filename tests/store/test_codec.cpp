// The binary codec: checksums, and the result encoding's round trip and checks.

#include <gtest/gtest.h>

#include <cmath>
#include <string_view>

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
