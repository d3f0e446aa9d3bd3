#pragma once
// A persisted record described once (issue 42): one function names the record's members in their
// byte order, and the same function both writes and reads them, walked by a Put (onto a
// ByteWriter) or a Get (from a ByteReader). The pattern:
//
//     template <class Io, core::Is<ErrorRecord> R>
//     void fields(Io& io, R& r) {  // R: ErrorRecord, or const ErrorRecord to write one
//         io(r.label);
//         io(r.realization);
//         io.since([&] { io(r.reason); }, [] {});  // a member added later, at the end
//     }
//
// What a reader must check (a count against the bytes left, a value's range) is said once as
// well: Put passes over `check`, Get fails with the message.

#include <concepts>
#include <cstdint>
#include <optional>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "hopper/core/bytes.hpp"

namespace hopper::core {

// R is T or const T: a description serves both the writer (const) and the reader.
template <class R, class T>
concept Is = std::same_as<std::remove_const_t<R>, T>;

// Writes what a description names.
class Put {
  public:
    explicit Put(ByteWriter& w) : w_(w) {}
    void operator()(const std::string& s) { w_.str(s); }
    void operator()(std::uint8_t v) { w_.u8(v); }
    void operator()(std::int32_t v) { w_.i32(v); }
    void operator()(std::int64_t v) { w_.i64(v); }
    void operator()(std::uint32_t v) { w_.u32(v); }
    void operator()(std::uint64_t v) { w_.u64(v); }
    void operator()(double v) { w_.f64(v); }
    // Bytes as they are, after their length (u32).
    void blob(const Bytes& b) {
        w_.u32(static_cast<std::uint32_t>(b.size()));
        w_.raw(b);
    }
    // A list: its length (u32), then each element as `each` describes it. `noun` and
    // `min_bytes` (the fewest bytes an element takes) serve the reader's check.
    template <class T, class F>
    void list(const std::vector<T>& v, const char* /*noun*/, std::size_t /*min_bytes*/, F&& each) {
        w_.u32(static_cast<std::uint32_t>(v.size()));
        for (const T& e : v)
            each(e);
    }
    // Members added to the record later, at its end: always written; a reader of a record
    // written before them finds no bytes left and runs `before` instead.
    template <class Then, class Before>
    void since(Then&& then, Before&& /*before*/) {
        then();
    }
    // An optional part at the record's end: written when present (a reader finds bytes left).
    template <class T, class F>
    void optional(const std::optional<T>& o, F&& each) {
        if (o) each(*o);
    }
    // One of the variant's alternatives: its index (u8), then its value.
    template <class... T>
    void choice(const std::variant<T...>& v) {
        w_.u8(static_cast<std::uint8_t>(v.index()));
        std::visit([this](const auto& x) { (*this)(x); }, v);
    }
    // A member the writer derives (`value()`) and the reader reads into `member`.
    template <class T, class F>
    void derived(const T& /*member*/, F&& value) {
        (*this)(static_cast<T>(value()));
    }
    // An enumeration as one byte; the reader takes values in [first, last] only.
    template <class E>
    void enumeration(const E& v, E /*first*/, E /*last*/) {
        w_.u8(static_cast<std::uint8_t>(v));
    }
    // A format number (u32) that says what follows.
    void format(std::uint32_t v, const char* /*what*/) { w_.u32(v); }
    template <class Message>
    void check(bool /*ok*/, Message&& /*message*/) {}

  private:
    ByteWriter& w_;
};

// Reads what a description names; fails through the reader (its error type and position).
class Get {
  public:
    explicit Get(ByteReader& r) : r_(r) {}
    void operator()(std::string& s) { s = r_.str(); }
    void operator()(std::uint8_t& v) { v = r_.u8(); }
    void operator()(std::int32_t& v) { v = r_.i32(); }
    void operator()(std::int64_t& v) { v = r_.i64(); }
    void operator()(std::uint32_t& v) { v = r_.u32(); }
    void operator()(std::uint64_t& v) { v = r_.u64(); }
    void operator()(double& v) { v = r_.f64(); }
    void blob(Bytes& b) {
        const auto raw = r_.raw(r_.u32());
        b.assign(raw.begin(), raw.end());
    }
    template <class T, class F>
    void list(std::vector<T>& v, const char* noun, std::size_t min_bytes, F&& each) {
        const std::uint32_t n = r_.u32();
        if (static_cast<std::uint64_t>(n) * min_bytes > r_.remaining())
            r_.fail(std::string("a ") + noun + " count of " + std::to_string(n) +
                    " exceeds the bytes left");
        v.resize(n);
        for (T& e : v)
            each(e);
    }
    template <class Then, class Before>
    void since(Then&& then, Before&& before) {
        if (r_.remaining() > 0)
            then();
        else
            before();
    }
    template <class T, class F>
    void optional(std::optional<T>& o, F&& each) {
        if (r_.remaining() == 0) return;
        each(o.emplace());
    }
    template <class... T>
    void choice(std::variant<T...>& v) {
        read_alternative<0, T...>(v, r_.u8());
    }
    template <class T, class F>
    void derived(T& member, F&& /*value*/) {
        (*this)(member);
    }
    template <class E>
    void enumeration(E& v, E first, E last) {
        const std::uint8_t raw = r_.u8();
        if (raw < static_cast<std::uint8_t>(first) || raw > static_cast<std::uint8_t>(last))
            r_.fail("an unknown kind " + std::to_string(raw));
        v = static_cast<E>(raw);
    }
    void format(std::uint32_t v, const char* what) {
        const std::uint32_t got = r_.u32();
        if (got != v)
            r_.fail(std::string(what) + " format " + std::to_string(got) +
                    " is unknown (written by a newer version?)");
    }
    template <class Message>
    void check(bool ok, Message&& message) {
        if (!ok) r_.fail(message());
    }

  private:
    template <std::size_t I, class... T>
    void read_alternative(std::variant<T...>& v, std::uint8_t index) {
        if constexpr (I < sizeof...(T)) {
            if (index != I) return read_alternative<I + 1, T...>(v, index);
            (*this)(v.template emplace<I>());
        } else {
            r_.fail("an unknown kind " + std::to_string(index) + " (of " +
                    std::to_string(sizeof...(T)) + ")");
        }
    }

    ByteReader& r_;
};

}  // namespace hopper::core
