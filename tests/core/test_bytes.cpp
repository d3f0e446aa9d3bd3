// core::ByteWriter / core::ByteReader: exact round trips, little-endian layout, checked reads.

#include "hopper/core/bytes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hopper/core/error.hpp"

namespace hopper::core {
namespace {

TEST(Bytes, RoundTripsEveryKindExactly) {
    ByteWriter w;
    w.u8(7);
    w.u32(0xdeadbeefu);
    w.u64(0x0123456789abcdefull);
    w.i32(-5);
    w.i64(-1234567890123ll);
    w.f64(0.1);
    w.f64(-std::numeric_limits<double>::denorm_min());
    w.str("hopper");
    w.f64s({1.5, -2.25});
    w.i32s({3, -4});
    w.i64s({std::numeric_limits<std::int64_t>::min()});
    w.bools({true, false, true});
    const Bytes b = w.take();
    ByteReader r(b, "test");
    EXPECT_EQ(r.u8(), 7);
    EXPECT_EQ(r.u32(), 0xdeadbeefu);
    EXPECT_EQ(r.u64(), 0x0123456789abcdefull);
    EXPECT_EQ(r.i32(), -5);
    EXPECT_EQ(r.i64(), -1234567890123ll);
    EXPECT_EQ(r.f64(), 0.1);
    const double d = r.f64();
    EXPECT_EQ(d, -std::numeric_limits<double>::denorm_min());
    EXPECT_TRUE(std::signbit(d));
    EXPECT_EQ(r.str(), "hopper");
    EXPECT_EQ(r.f64s(), (std::vector<double>{1.5, -2.25}));
    EXPECT_EQ(r.i32s(), (std::vector<int>{3, -4}));
    EXPECT_EQ(r.i64s(), (std::vector<std::int64_t>{std::numeric_limits<std::int64_t>::min()}));
    EXPECT_EQ(r.bools(), (std::vector<bool>{true, false, true}));
    EXPECT_EQ(r.remaining(), 0u);
    EXPECT_NO_THROW(r.expect_end());
}

TEST(Bytes, FixedWidthLittleEndianLayout) {
    ByteWriter w;
    w.u32(0x04030201u);
    w.str("ab");
    EXPECT_EQ(w.bytes(), (Bytes{1, 2, 3, 4, 2, 0, 0, 0, 'a', 'b'}));
}

TEST(Bytes, TruncatedOversizedAndTrailingInputIsADecodeErrorNamingTheData) {
    ByteWriter w;
    w.u64(42);
    const Bytes b = w.take();
    for (std::size_t n = 0; n < b.size(); ++n) {
        ByteReader r(std::span(b.data(), n), "a test message");
        EXPECT_THROW(r.u64(), DecodeError);
    }
    ByteReader r(b, "a test message");
    try {
        r.u32();
        r.expect_end();
        FAIL() << "trailing bytes accepted";
    } catch (const DecodeError& e) {
        EXPECT_NE(std::string(e.what()).find("a test message"), std::string::npos);
    }
    const Bytes huge = {0xff, 0xff, 0xff, 0x7f};  // a length prefix far beyond the bytes left
    ByteReader h(huge, "length");
    EXPECT_THROW(h.f64s(), DecodeError);
    const Bytes bad_bool = {1, 0, 0, 0, 2};
    ByteReader bb(bad_bool, "bools");
    EXPECT_THROW(bb.bools(), DecodeError);
}

class OtherError : public Error {
  public:
    using Error::Error;
};

class OtherReader : public ByteReader {
  public:
    using ByteReader::ByteReader;

  protected:
    [[noreturn]] void raise(const std::string& message) const override {
        throw OtherError(message);
    }
};

TEST(Bytes, ADerivedReaderChoosesItsErrorKind) {
    const Bytes b = {1};
    OtherReader r(b, "derived");
    EXPECT_THROW(r.u32(), OtherError);
}

}  // namespace
}  // namespace hopper::core
