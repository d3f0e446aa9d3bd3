#include "hopper/core/bytes.hpp"

#include <bit>

#include "hopper/core/error.hpp"

namespace hopper::core {

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

void ByteReader::raise(const std::string& message) const {
    throw DecodeError(message);
}

void ByteReader::fail(const std::string& problem) const {
    const std::string message = what_ + ": " + problem + " (at byte " + std::to_string(pos_) +
                                " of " + std::to_string(in_.size()) + ")";
    raise(message);
    throw DecodeError(message);  // not reached: raise() throws
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

}  // namespace hopper::core
