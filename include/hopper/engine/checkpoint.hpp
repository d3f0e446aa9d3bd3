#pragma once
// The engine's state as bytes, for checkpoints inside a realization (issue 15). The engine only
// turns its state into a byte buffer and back; where the bytes go (a file beside the store, a
// message to the master) is the campaign layer's business.
//
// What a checkpoint holds: every column of the System (positions, velocities, forces, Gear
// derivatives, the reference positions of the neighbour criterion), the neighbour list itself
// with the tangential springs and their saved history grouped by owner, the cell grids, the wall
// motion, the removal floor and pending removals, the counters; the realization's protocol state
// (phase, detector clocks, shake state, the observers' schedules, the result so far) and the
// field accumulator's open window. The random generator is used only to build the fill, which a
// resumed realization rebuilds from its seed before the state is restored, so no generator state
// is needed. Restoring all of it, and not recomputing any of it, is what makes a resumed
// realization end bit-identical to one that never stopped (the neighbour list's order decides
// the order in which forces are summed).
//
// Format: "HOPPERRS", a format version, then a fingerprint of the realization (seed, particle
// count, integrator, dt, k_n, fields on/off), then the state. restore refuses (core::ConfigError
// naming what differs) a buffer of another format version or of another realization; a
// truncated or damaged buffer is refused the same way. The campaign layer adds its own header
// (code version, physics) and a checksum around these bytes.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "hopper/core/bytes.hpp"

namespace hopper::engine {

// 2 (round 3): the springs saved across a rebuild (by id) are no longer part of the state.
// 3 (issue 42): the result so far walked by its description (engine/result.hpp), after the
// result format version that says which members the state holds, so that a member added there
// is saved without another list and older states still read; format 2 states are still read.
inline constexpr std::uint32_t state_format_version = 3;
inline constexpr std::uint32_t oldest_state_format_read = 2;

// Little-endian byte buffer writer/reader for the state (fixed-width values, vectors as a
// 64-bit count followed by the elements), on core::ByteWriter and core::ByteReader.
class StateWriter {
  public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        out_.raw({reinterpret_cast<const std::uint8_t*>(&v), sizeof(T)});
    }
    template <class T>
    void put_vector(const std::vector<T>& v) {
        out_.u64(v.size());
        if constexpr (std::is_same_v<T, bool>) {
            for (bool b : v)
                out_.u8(b ? 1 : 0);
        } else {
            out_.raw({reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T)});
        }
    }
    void put_string(std::string_view s) {
        out_.u64(s.size());
        out_.raw({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()});
    }
    std::vector<std::uint8_t> take() { return out_.take(); }

  private:
    core::ByteWriter out_;
};

class StateReader {
  public:
    explicit StateReader(std::span<const std::uint8_t> bytes) : in_(bytes, "checkpoint") {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T v;
        std::memcpy(&v, next(sizeof(T)).data(), sizeof(T));
        return v;
    }
    template <class T>
    void get_vector(std::vector<T>& v) {
        const auto n = get<std::uint64_t>();
        if constexpr (std::is_same_v<T, bool>) {
            const auto b = next(n);
            v.resize(n);
            for (std::uint64_t k = 0; k < n; ++k)
                v[k] = b[k] != 0;
        } else {
            if (n > in_.remaining() / sizeof(T)) fail();
            const auto b = next(n * sizeof(T));
            v.resize(n);
            if (n) std::memcpy(v.data(), b.data(), n * sizeof(T));
        }
    }
    std::string get_string() {
        const auto b = next(get<std::uint64_t>());
        return {reinterpret_cast<const char*>(b.data()), b.size()};
    }
    bool at_end() const { return in_.remaining() == 0; }
    std::size_t remaining() const { return in_.remaining(); }
    [[noreturn]] static void fail();

  private:
    // The next n bytes; fail() (core::ConfigError) when fewer are left.
    std::span<const std::uint8_t> next(std::uint64_t n) {
        if (n > in_.remaining()) fail();
        return in_.raw(static_cast<std::size_t>(n));
    }
    core::ByteReader in_;
};

// A state described once (the pattern of core/described.hpp, in the state format): one
// function names the members in byte order and both writes and reads them, walked by a
// StatePut (save) or a StateGet (restore). Plain values are their bytes, vectors and strings
// their 64-bit count first, a bool one byte, an enumeration 32 bits read back within its range;
// what a reader must check is said once with check() (a StateGet fails, a StatePut passes).
template <class T>
inline constexpr bool is_std_vector = false;
template <class T, class A>
inline constexpr bool is_std_vector<std::vector<T, A>> = true;

class StatePut {
  public:
    explicit StatePut(StateWriter& w) : w_(w) {}
    template <class T>
    void operator()(const T& v) {
        if constexpr (is_std_vector<T>)
            w_.put_vector(v);
        else if constexpr (std::is_same_v<T, std::string>)
            w_.put_string(v);
        else if constexpr (std::is_same_v<T, bool>)
            w_.put<std::uint8_t>(v);
        else
            w_.put(v);
    }
    // An enumeration as 32 bits; the reader takes values up to `last` only.
    template <class E>
    void enumeration(const E& v, E /*last*/) {
        w_.put(static_cast<std::int32_t>(v));
    }
    // A member stored as another type: `to` makes the stored value, `from` (the reader's)
    // makes the member again.
    template <class Stored, class T, class To, class From>
    void as(const T& member, To&& to, From&& /*from*/) {
        (*this)(static_cast<Stored>(to(member)));
    }
    // An optional value: a flag, then the value (its type's zero when absent).
    template <class T>
    void flagged(const std::optional<T>& o) {
        (*this)(o.has_value());
        (*this)(o.value_or(T{}));
    }
    // An optional part: a flag, then the part as `each` describes it when present.
    template <class T, class F>
    void optional(const std::optional<T>& o, F&& each) {
        (*this)(o.has_value());
        if (o) each(*o);
    }
    // A list of described elements: its count (64 bits), then each; `min_bytes` (the fewest
    // bytes an element takes) bounds the count the reader accepts.
    template <class T, class F>
    void list(const std::vector<T>& v, std::size_t /*min_bytes*/, F&& each) {
        w_.put<std::uint64_t>(v.size());
        for (const T& e : v)
            each(e);
    }
    template <class Ok>
    void check(Ok&& /*ok*/) {}

  private:
    StateWriter& w_;
};

class StateGet {
  public:
    explicit StateGet(StateReader& r) : r_(r) {}
    template <class T>
    void operator()(T& v) {
        if constexpr (is_std_vector<T>)
            r_.get_vector(v);
        else if constexpr (std::is_same_v<T, std::string>)
            v = r_.get_string();
        else if constexpr (std::is_same_v<T, bool>)
            v = r_.get<std::uint8_t>() != 0;
        else
            v = r_.get<T>();
    }
    template <class E>
    void enumeration(E& v, E last) {
        const auto raw = r_.get<std::int32_t>();
        if (raw < 0 || raw > static_cast<std::int32_t>(last)) StateReader::fail();
        v = static_cast<E>(raw);
    }
    template <class Stored, class T, class To, class From>
    void as(T& member, To&& /*to*/, From&& from) {
        Stored stored{};
        (*this)(stored);
        member = from(stored);
    }
    template <class T>
    void flagged(std::optional<T>& o) {
        bool has = false;
        T value{};
        (*this)(has);
        (*this)(value);
        o = has ? std::optional<T>(value) : std::nullopt;
    }
    template <class T, class F>
    void optional(std::optional<T>& o, F&& each) {
        bool has = false;
        (*this)(has);
        o.reset();
        if (has) each(o.emplace());
    }
    template <class T, class F>
    void list(std::vector<T>& v, std::size_t min_bytes, F&& each) {
        const auto n = r_.get<std::uint64_t>();
        if (n > r_.remaining() / std::max<std::size_t>(min_bytes, 1)) StateReader::fail();
        v.assign(static_cast<std::size_t>(n), T{});
        for (T& e : v)
            each(e);
    }
    template <class Ok>
    void check(Ok&& ok) {
        if (!ok()) StateReader::fail();
    }

  private:
    StateReader& r_;
};

class System;
class FieldAccumulator;
struct FieldMoments;
struct RealizationResult;

// Friend of System and FieldAccumulator: the only code that reads or writes their private state
// for checkpoints (src/engine/checkpoint.cpp).
struct CheckpointAccess {
    static void save(const System& s, StateWriter& w);
    // `s` must have been built with the same SystemConfig (the realization rebuilds it from its
    // parameters); its whole state is replaced.
    static void restore(System& s, StateReader& r);
    // Throws core::ConfigError naming the first invariant a restored state breaks (sizes,
    // indices in range, finite values): a state with a valid checksum may still be wrong.
    static void check_invariants(const System& s);
    static void save(const FieldAccumulator& a, StateWriter& w);
    static void restore(FieldAccumulator& a, StateReader& r);

  private:
    // Each state described once, walked by StatePut or StateGet (checkpoint.cpp).
    template <class Io, class S>
    static void system(Io& io, S& s);
    template <class Io, class A>
    static void accumulator(Io& io, A& a);
};

// The result so far: written in state_format_version, read in the format a state was written.
void save_result(const RealizationResult& res, StateWriter& w);
void restore_result(RealizationResult& res, StateReader& r, std::uint32_t format);

}  // namespace hopper::engine
