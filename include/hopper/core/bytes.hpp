#pragma once
// Byte buffers: a small checked binary writer and reader (little-endian, fixed widths, every
// double as its IEEE-754 bits so that it round-trips exactly). The store's journal records, the
// master/worker messages and the engine's checkpoints are all written with them.
//
// Reading is checked: a truncated buffer or a length prefix larger than the bytes left throws
// core::DecodeError naming what was being read and where. A layer that reports decoding
// failures as its own kind of error derives from ByteReader and overrides raise().

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hopper::core {

using Bytes = std::vector<std::uint8_t>;

class ByteWriter {
  public:
    void u8(std::uint8_t v) { out_.push_back(v); }
    void u32(std::uint32_t v);
    void u64(std::uint64_t v);
    void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
    void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
    void f64(double v);  // the IEEE-754 bits, so every value round-trips exactly
    void str(std::string_view s);
    void raw(std::span<const std::uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
    void f64s(const std::vector<double>& v);
    void i32s(const std::vector<int>& v);
    void i64s(const std::vector<std::int64_t>& v);
    void bools(const std::vector<bool>& v);

    const Bytes& bytes() const { return out_; }
    Bytes take() { return std::move(out_); }
    std::size_t size() const { return out_.size(); }

  private:
    Bytes out_;
};

class ByteReader {
  public:
    // `what` names the data in error messages ("result record of task 3", ...).
    ByteReader(std::span<const std::uint8_t> in, std::string what);
    virtual ~ByteReader() = default;
    ByteReader(const ByteReader&) = default;
    ByteReader& operator=(const ByteReader&) = default;

    std::uint8_t u8();
    std::uint32_t u32();
    std::uint64_t u64();
    std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
    std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
    double f64();
    std::string str();
    std::span<const std::uint8_t> raw(std::size_t n);
    std::vector<double> f64s();
    std::vector<int> i32s();
    std::vector<std::int64_t> i64s();
    std::vector<bool> bools();

    std::size_t remaining() const { return in_.size() - pos_; }
    std::size_t position() const { return pos_; }
    // Throws unless every byte was read.
    void expect_end() const;
    // Throws "<what>: <problem> (at byte p of n)" through raise().
    [[noreturn]] void fail(const std::string& problem) const;

  protected:
    // Throws the complete message; core::DecodeError unless a derived reader says otherwise.
    [[noreturn]] virtual void raise(const std::string& message) const;

  private:
    std::uint32_t count(std::size_t element_size);  // a length prefix, checked against the rest
    void need(std::size_t n);

    std::span<const std::uint8_t> in_;
    std::size_t pos_ = 0;
    std::string what_;
};

}  // namespace hopper::core
