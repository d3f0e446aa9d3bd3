#pragma once
// The seeded random generator. Results must be bit-for-bit reproducible across compilers and
// standard libraries, so we do not use <random>'s distributions (their algorithms are
// implementation-defined): xoshiro256** seeded through splitmix64, and our own uniform doubles.

#include <cstdint>
#include <string_view>

namespace hopper::core {

// splitmix64 step: a good 64-bit mixer, used to expand seeds and to hash seed material.
std::uint64_t splitmix64(std::uint64_t& state);

// Mixes a value into a seed (order-dependent), for deriving independent seeds from parts.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t value);

// Mixes a string (e.g. a parameter name or its canonical text) into a seed.
std::uint64_t mix_seed(std::uint64_t seed, std::string_view text);

class Rng {
  public:
    explicit Rng(std::uint64_t seed);

    std::uint64_t next_u64();
    // Uniform in [0, 1) with 53 random bits.
    double uniform();
    // Uniform in [lo, hi).
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // The whole state (4 words), for checkpoints: set_state(state()) continues the sequence.
    void state(std::uint64_t out[4]) const {
        for (int k = 0; k < 4; ++k)
            out[k] = s_[k];
    }
    void set_state(const std::uint64_t in[4]) {
        for (int k = 0; k < 4; ++k)
            s_[k] = in[k];
    }

  private:
    std::uint64_t s_[4];
};

}  // namespace hopper::core
